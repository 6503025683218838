"""Speed and accuracy: error against cost for each accuracy knob, and per-geometry throughput."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..core import figure_block, table_block
from ._common import default_models, is_heavy, plt

__all__ = ["SpeedData", "compute", "render"]

#: compiled SCATMECH microseconds per Mueller evaluation (DESIGN.md, one geometry per call)
QUOTED_US = {"FacetBRDF": 0.5, "SubsurfaceFacetBRDF": 5.2}
_THROUGHPUT = ["model", "us per geometry (mueller)", "compiled SCATMECH us (quoted, DESIGN.md)", "ratio"]


@dataclass(frozen=True)
class SpeedData:
    """``knobs``: the trade-off study's results (each with every measured point);
    ``pareto``: per knob, its non-dominated points' rows; ``geometries``: throughput sample size."""

    knobs: tuple
    pareto: tuple
    geometries: int
    throughput_rows: tuple


def _throughput(n, seed):
    rng = np.random.default_rng(seed)
    ti, tr = rng.uniform(0, 1.45, (2, n))
    pr = rng.uniform(-math.pi, math.pi, n)
    rows = []
    for m in default_models():
        k = 200 if is_heavy(m) else n  # per-geometry cost is what is compared
        best = math.inf
        for _ in range(3):
            t0 = time.perf_counter()
            m.mueller(ti[:k], tr[:k], pr[:k])
            best = min(best, time.perf_counter() - t0)
        us = best / k * 1e6
        q = QUOTED_US.get(type(m).__name__)
        rows.append(
            {
                "model": type(m).__name__,
                "us per geometry (mueller)": us,
                "compiled SCATMECH us (quoted, DESIGN.md)": q,
                "ratio": (q / us) if q else None,
            }
        )
    return tuple(rows)


def compute(ctx):
    from validation.studies.tradeoff import pareto, study

    knobs = tuple(study(quick=ctx.quick))
    fronts = tuple(
        tuple(
            {"setting": p.setting, "error": p.error, "seconds": p.seconds, "evaluations": p.evaluations}
            for p in pareto(r.points)
        )
        for r in knobs
    )
    n = 20_000 if ctx.quick else 200_000
    return SpeedData(knobs, fronts, n, _throughput(n, ctx.seed))


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
    caption = f"throughput over {d.geometries} random geometries, best of 3, one process"
    s.blocks.append(table_block(s, "throughput", _THROUGHPUT, d.throughput_rows, caption=caption))
