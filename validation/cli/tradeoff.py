"""``scatterbench tradeoff``: error versus cost of every accuracy knob."""

from __future__ import annotations

from .args import positive_float, writable_folder

__all__ = ["register"]


def _cmd_tradeoff(args) -> int:
    import os

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from validation.atomic import atomic_savefig, atomic_write_json
    from validation.studies.tradeoff import choose, pareto, study

    writable_folder(args.out, "--out")
    results = study(quick=args.quick)
    os.makedirs(args.out, exist_ok=True)
    atomic_write_json(os.path.join(args.out, "tradeoff.json"), [r.as_dict() for r in results])
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
        ax.set_xlabel("cost (s)")
        ax.set_ylabel("error vs reference")
        ax.set_title(r.knob)
        ax.legend(fontsize=8)
    fig.tight_layout()
    atomic_savefig(fig, os.path.join(args.out, "tradeoff.png"), dpi=110)
    plt.close(fig)
    for r in results:
        print(f"{r.knob}: {r.quantity}")
        print(f"  reference: {r.reference}")
        print(f"  {'setting':>10} {'error':>11} {'seconds':>10} {'evals':>9}  pareto")
        front = pareto(r.points)
        for p in r.points:
            mark = "*" if p in front else ""
            print(f"  {p.setting:>10g} {p.error:>11.3g} {p.seconds:>10.4f} {p.evaluations:>9}  {mark}")
        if args.tol is not None:
            pick = choose(r, args.tol)
            if pick is None:
                print(f"  --tol {args.tol:g}: no measured setting reaches it")
            else:
                print(f"  --tol {args.tol:g}: chose {pick.setting:g} (measured error {pick.error:.3g})")
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
