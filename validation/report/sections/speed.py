"""Speed and accuracy: error against cost for each accuracy knob, per-geometry throughput, and
the peers' timings measured by ``benchmarks/peers.py`` (committed data, read here)."""

from __future__ import annotations

import functools
from dataclasses import dataclass

from scatterbench import references
from scatterbench.models.kernels import PARALLEL_MIN
from scatterbench.validation.studies import tradeoff
from scatterbench.validation.studies.tradeoff import pareto, throughput

from ..core import figure_block, table_block
from ._common import default_models, is_heavy, plt

__all__ = ["SpeedData", "compute", "render"]

_THROUGHPUT = [
    "model",
    "geometries per call",
    "kernel threads",
    "us per geometry (CPU)",
    "us per geometry (wall)",
]
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
    ``throughput_rows``: per model, its cost per geometry and the kernel threads it ran on;
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


def _throughput_tasks(n, seed):
    """Per model, a :func:`~scatterbench.validation.studies.tradeoff.throughput` task (for
    ``tradeoff.run``): one ``mueller`` call on ``n`` random geometries
    (:data:`HEAVY_GEOMETRIES` of them for the Monte Carlo and wrapper models)."""
    tasks = []
    for m in default_models():
        k = HEAVY_GEOMETRIES if is_heavy(m) else n  # per-geometry cost is what is compared
        tasks.append(functools.partial(throughput, m, k, seed))
    return tasks


def _throughput_row(task, measured):
    """The throughput table's row of ``task`` (:func:`_throughput_tasks`) from what it measured."""
    model, k = task.args[0], task.args[1]
    t, threads = measured
    return {
        "model": type(model).__name__,
        "geometries per call": k,
        "kernel threads": threads,
        "us per geometry (CPU)": t.seconds / k * 1e6,
        "us per geometry (wall)": t.wall_seconds / k * 1e6,
    }


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
    # the knobs and the models' throughput in one map, a task each: on many workers the speed
    # section, which runs alone (it times code), takes about its longest task; before, the
    # throughput ran after the knobs in this process, 2.0-2.3 s on 2 cores (ad hoc, 2026-12-08)
    n = 20_000 if ctx.quick else 200_000
    names, knob_tasks = tradeoff.knob_tasks(quick=ctx.quick)
    rates = _throughput_tasks(n, ctx.seed)
    done = ctx.runner().map(tradeoff.run, knob_tasks + rates, tasks=len(knob_tasks) + len(rates))
    knobs = tuple(tradeoff.collected(names, done[: len(names)]))
    fronts = tuple(
        tuple(
            {"setting": p.setting, "error": p.error, "seconds": p.seconds, "evaluations": p.evaluations}
            for p in pareto(r.points)
        )
        for r in knobs
    )
    rows = tuple(_throughput_row(task, out) for task, out in zip(rates, done[len(names) :], strict=True))
    return SpeedData(knobs, fronts, n, rows, *_peers())


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
        "Monte Carlo and wrapper models), this run, each model a task on the run's executor beside the "
        "knobs' tasks; best batch of validation.studies.tradeoff.time_call, CPU time of every thread of "
        "the process that timed it and wall time; the kernels run on that process's kernel threads (a "
        f"worker's share of the cores) from {PARALLEL_MIN} geometries"
    )
    s.blocks.append(table_block(s, "throughput", _THROUGHPUT, d.throughput_rows, caption=caption))
    run = d.peer_run
    caption = f"scatterbench beside its peers, not measured by this run: {run['what']}"
    if run["skipped"]:
        caption += "; skipped: " + "; ".join(run["skipped"])
    s.blocks.append(table_block(s, "peer_run", _PEER_RUN, [run], caption="the run that measured the peers"))
    fmt = {"max rel diff": ".1e"}
    s.blocks.append(table_block(s, "peers", _PEERS, d.peer_rows, caption=caption, fmt=fmt))
