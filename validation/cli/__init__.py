"""``scatterbench`` command line."""

from __future__ import annotations

import argparse
import sys
import time

__all__ = ["main"]


def _cmd_validate(args) -> int:
    from validation.checks.seed000 import all_sections, format_checks, run_checks

    t0 = time.perf_counter()
    results = run_checks()
    print(format_checks(results))
    for section in all_sections():
        out = section(results)
        if out:
            title, text = out
            print(f"\n{title}:")
            print(text)
    print(f"\nvalidate finished in {time.perf_counter() - t0:.1f} s")
    return 1 if any(c.status == "fail" for c in results) else 0


def _cmd_table1(args) -> int:
    from validation.checks.table1 import compute_table1, format_table1

    rows, seconds = compute_table1(tol=args.tol)
    print(format_table1(rows))
    print(f"27 entries in {seconds:.2f} s (tol {args.tol:g})")
    return 0


def _cmd_stability(args) -> int:
    from validation.studies.stability import classify, format_sweep, sweep

    t0 = time.perf_counter()
    findings = sweep(energy=not args.no_energy)
    print(format_sweep(findings))
    print(f"stability sweep finished in {time.perf_counter() - t0:.1f} s")
    _, bad = classify(findings)
    return 1 if bad else 0


def _cmd_tradeoff(args) -> int:
    import os

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from validation.atomic import atomic_savefig, atomic_write_json
    from validation.studies.tradeoff import choose, pareto, study

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


def _cmd_scene(args) -> int:
    from models import scene as scene_mod
    from validation.studies.scenes import write_scene_outputs

    try:
        sc = scene_mod.load(args.file)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(sc.describe())
    if args.tol is None:
        csv_path, png_path = write_scene_outputs(sc, args.out)
    else:
        csv_path, png_path, notes = write_scene_outputs(sc, args.out, tol=args.tol)
        for n in notes:
            print(f"  --tol: {n}")
    print(f"wrote {csv_path} and {png_path}")
    return 0


def _cmd_models(args) -> int:
    import models

    print(models.list_models())
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog="scatterbench",
        description="Validation and benchmark harness for polarized light-scattering models.",
    )
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("validate", help="run every check; print a table; exit 1 if any fails")
    p.set_defaults(func=_cmd_validate)
    p = sub.add_parser("table1", help="seed 000 Table I beside the printed values")
    p.add_argument("--tol", type=float, default=1e-4, help="absolute integration tolerance")
    p.set_defaults(func=_cmd_table1)
    p = sub.add_parser("stability", help="sweep every model at its extremes; exit 1 on unaccepted findings")
    p.add_argument("--no-energy", action="store_true", help="skip the integrated-reflectance checks")
    p.set_defaults(func=_cmd_stability)
    p = sub.add_parser("tradeoff", help="measure error versus cost for every accuracy knob")
    p.add_argument("--out", default="reports/tradeoff", help="output folder (JSON and PNG)")
    p.add_argument("--quick", action="store_true", help="fewer settings per knob")
    p.add_argument("--tol", type=float, default=None, help="report the cheapest setting meeting this error")
    p.set_defaults(func=_cmd_tradeoff)
    p = sub.add_parser("scene", help="evaluate a scene file: in-plane and out-of-plane scans (CSV + PNG)")
    p.add_argument("file", help="scene TOML file")
    p.add_argument("--out", default="reports/scenes", help="output folder")
    p.add_argument(
        "--tol",
        type=float,
        default=None,
        help="pick grid, Monte Carlo pairs and point-source resolution from the measured curves",
    )
    p.set_defaults(func=_cmd_scene)
    p = sub.add_parser("models", help="list the models and their declared parameters")
    p.set_defaults(func=_cmd_models)
    for mod in _command_modules():
        mod.register(sub)
    args = ap.parse_args(argv)
    return args.func(args)


def _command_modules():
    """The command modules besides this one: each defines ``register(subparsers)``."""
    from . import fit, report, study

    return [fit, report, study]
