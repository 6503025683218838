"""``scatterbench tradeoff``: error versus cost of every accuracy knob."""

from __future__ import annotations

import os

from scatterbench.validation.atomic import atomic_savefig, atomic_write_json
from scatterbench.validation.studies.tradeoff import BATCH, MIN_BATCHES, MIN_WORK, choose, pareto, study

from .args import positive_float, writable_folder

__all__ = ["register"]


def _plot(results, path):
    import matplotlib  # matplotlib (heavy): loaded only where a figure is drawn

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib (heavy): loaded only where a figure is drawn

    fig, axes = plt.subplots(1, len(results), figsize=(5.5 * len(results), 4.2), squeeze=False)
    for ax, r in zip(axes[0], results, strict=True):
        secs = [p.seconds for p in r.points]
        errs = [max(p.error, 1e-18) for p in r.points]
        ax.loglog(secs, errs, "o-", label="measured")
        front = pareto(r.points)
        ax.loglog(
            [p.seconds for p in front], [max(p.error, 1e-18) for p in front], "s", mfc="none", label="Pareto"
        )
        for p in r.points:
            ax.annotate(f"{p.setting:g}", (p.seconds, max(p.error, 1e-18)), fontsize=7)
        ax.set_xlabel("cost: CPU s per call (best of repeated batches)")
        ax.set_ylabel("error vs reference")
        ax.set_title(r.knob)
        ax.legend(fontsize=8)
    fig.tight_layout()
    atomic_savefig(fig, path, dpi=110)
    plt.close(fig)


def _print_knob(r, tol):

    print(f"{r.knob}: {r.quantity}")
    print(f"  reference: {r.reference}")
    print(
        f"  {'setting':>10} {'error':>11} {'CPU s':>11} {'spread':>7} {'calls':>6} {'wall s':>11} {'evals':>9}  pareto"
    )
    front = pareto(r.points)
    for p in r.points:
        mark = "*" if p in front else ""
        print(
            f"  {p.setting:>10g} {p.error:>11.3g} {p.seconds:>11.4g} {p.spread:>7.0%} {p.calls:>6} "
            f"{p.wall_seconds:>11.4g} {p.evaluations:>9}  {mark}"
        )
    if tol is not None:
        pick = choose(r, tol)
        if pick is None:
            print(f"  --tol {tol:g}: no measured setting reaches it")
        else:
            print(f"  --tol {tol:g}: chose {pick.setting:g} (measured error {pick.error:.3g})")


def _cmd_tradeoff(args) -> int:

    writable_folder(args.out, "--out")  # refused before the study, not after
    skipped = {}
    results = study(quick=args.quick, skipped=skipped)
    os.makedirs(args.out, exist_ok=True)
    atomic_write_json(
        os.path.join(args.out, "tradeoff.json"),
        [r.as_dict() for r in results] + [{"knob": k, "skipped": why} for k, why in skipped.items()],
    )
    _plot(results, os.path.join(args.out, "tradeoff.png"))
    print(
        f"cost: CPU seconds per call (this process, every thread) in the best of >= {MIN_BATCHES} "
        f"batches of ~{BATCH * 1e3:g} ms, >= {MIN_WORK:g} s of work per setting; spread: (median - best) / best "
        "batch; wall s: the best batch on the wall clock (inflated by other work on the machine)"
    )
    for r in results:
        _print_knob(r, args.tol)
    for k, why in skipped.items():
        print(f"{k}: skipped: {why}")
    print(f"wrote {os.path.join(args.out, 'tradeoff.json')} and tradeoff.png")
    return 0


def register(sub):
    p = sub.add_parser("tradeoff", help="measure error versus cost for every accuracy knob")
    p.add_argument("--out", default="reports/tradeoff", help="output folder (JSON and PNG)")
    p.add_argument("--quick", action="store_true", help="fewer settings per knob")
    p.add_argument(
        "--tol",
        type=positive_float,
        default=None,
        help="report the cheapest setting meeting this error (> 0)",
    )
    p.set_defaults(func=_cmd_tradeoff)
