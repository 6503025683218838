"""Speed and accuracy: error against cost for each accuracy knob, per-geometry throughput, and
the peers' timings measured by ``benchmarks/peers.py`` (committed data, read here)."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from scatterbench import references
from scatterbench.models.kernels import PARALLEL_MIN
from scatterbench.validation.studies.tradeoff import pareto, study, time_call

from ..core import figure_block, table_block
from ._common import default_models, is_heavy, plt

__all__ = ["SpeedData", "compute", "render"]

_THROUGHPUT = ["model", "geometries per call", "us per geometry (CPU)", "us per geometry (wall)"]
_PEERS = [
    "model",
    "peer",
    "ours per call (us)",
    "peer per call (us)",
    "per call: peer / ours",
    "ours per geometry (us)",
    "peer per geometry (us)",
    "per geometry: peer / ours",
    "max rel diff",
]
_PEER_RUN = ["date", "machine", "load average (1 min, start / end)", "threads", "geometries (array / loop)"]


@dataclass(frozen=True)
class SpeedData:
    """``knobs``: the trade-off study's results (each with every measured point);
    ``pareto``: per knob, its non-dominated points' rows; ``geometries``: throughput sample size;
    ``peer_rows``, ``peer_run``: :func:`scatterbench.references.peer_timings`' pairs with their ratios, and
    the run that measured them (date, machine, load, threads)."""

    knobs: tuple
    pareto: tuple
    geometries: int
    throughput_rows: tuple
    peer_rows: tuple
    peer_run: dict


#: geometries per call for the Monte Carlo and wrapper models (``n`` for the closed forms)
HEAVY_GEOMETRIES = 200


def _throughput(n, seed):
    """Per model, the cost of one ``mueller`` call on ``n`` random geometries
    (:data:`HEAVY_GEOMETRIES` for the Monte Carlo and wrapper models), timed by the
    trade-off study's :func:`time_call`."""

    rng = np.random.default_rng(seed)
    ti, tr = rng.uniform(0, 1.45, (2, n))
    pr = rng.uniform(-math.pi, math.pi, n)
    rows = []
    for m in default_models():
        k = HEAVY_GEOMETRIES if is_heavy(m) else n  # per-geometry cost is what is compared
        _, t = time_call(functools.partial(m.mueller, ti[:k], tr[:k], pr[:k]))
        rows.append(
            {
                "model": type(m).__name__,
                "geometries per call": k,
                "us per geometry (CPU)": t.seconds / k * 1e6,
                "us per geometry (wall)": t.wall_seconds / k * 1e6,
            }
        )
    return tuple(rows)


def _peers():
    """The committed peer timings: one row per pair with the ratios, and the run's description."""
    table = references.peer_timings()
    rows = tuple(
        {
            "model": r["model"],
            "peer": f"{r['peer']} {r['variant']}",
            "ours per call (us)": r["ours_call_us"],
            "peer per call (us)": r["peer_call_us"],
            "per call: peer / ours": r["peer_call_us"] / r["ours_call_us"],
            "ours per geometry (us)": r["ours_geometry_us"],
            "peer per geometry (us)": r["peer_geometry_us"],
            "per geometry: peer / ours": r["peer_geometry_us"] / r["ours_geometry_us"],
            "max rel diff": r["max_rel_diff"],
        }
        for r in table["rows"]
    )
    mach = table["machine"]
    threads = mach.get("threads")
    run = {
        "date": table["date"],
        "machine": f"{mach['cpu']}, {mach['cores']} cores, {mach['platform']}",
        "load average (1 min, start / end)": (
            f"{mach['load_average_at_start'][0]:.2f} / {mach['load_average_at_end'][0]:.2f}"
        ),
        "threads": ", ".join(f"{k}: {v}" for k, v in threads.items()) if threads else "not recorded",
        "geometries (array / loop)": f"{table['geometries']['array']} / {table['geometries']['loop']}",
        "what": table["what"],
        "skipped": tuple(table["skipped"]),
    }
    return rows, run


def compute(ctx):

    knobs = tuple(study(quick=ctx.quick, executor=ctx.runner()))  # knobs one task each
    fronts = tuple(
        tuple(
            {"setting": p.setting, "error": p.error, "seconds": p.seconds, "evaluations": p.evaluations}
            for p in pareto(r.points)
        )
        for r in knobs
    )
    n = 20_000 if ctx.quick else 200_000
    return SpeedData(knobs, fronts, n, _throughput(n, ctx.seed), *_peers())


def _draw(d):
    fig, axes = plt.subplots(1, len(d.knobs), figsize=(5.5 * len(d.knobs), 4), squeeze=False)
    for ax, r in zip(axes[0], d.knobs, strict=True):
        ax.loglog([p.seconds for p in r.points], [max(p.error, 1e-18) for p in r.points], "o-")
        for p in r.points:
            ax.annotate(f"{p.setting:g}", (p.seconds, max(p.error, 1e-18)), fontsize=7)
        ax.set_title(r.knob)
        ax.set_xlabel("cost (s)")
        ax.set_ylabel("error vs independent reference")
    fig.tight_layout()
    return fig


def render(s, d: SpeedData):
    s.blocks.append(figure_block(_draw(d), "Measured error versus cost for each accuracy knob"))
    for r, rows in zip(d.knobs, d.pareto, strict=True):
        s.blocks.append(
            table_block(
                s,
                f"pareto|{r.knob}",
                ["setting", "error", "seconds", "evaluations"],
                rows,
                caption=f"Pareto front: {r.knob} ({r.reference})",
            )
        )
    caption = (
        f"throughput: one mueller call on {d.geometries} random geometries ({HEAVY_GEOMETRIES} for "
        "Monte Carlo and wrapper models), this run; best batch of validation.studies.tradeoff.time_call, "
        "CPU time of every thread of the process (the kernels run on every core from "
        f"{PARALLEL_MIN} geometries) and wall time"
    )
    s.blocks.append(table_block(s, "throughput", _THROUGHPUT, d.throughput_rows, caption=caption))
    run = d.peer_run
    caption = f"scatterbench beside its peers, not measured by this run: {run['what']}"
    if run["skipped"]:
        caption += "; skipped: " + "; ".join(run["skipped"])
    s.blocks.append(table_block(s, "peer_run", _PEER_RUN, [run], caption="the run that measured the peers"))
    fmt = {"max rel diff": ".1e"}
    s.blocks.append(table_block(s, "peers", _PEERS, d.peer_rows, caption=caption, fmt=fmt))
