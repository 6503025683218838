"""``scatterbench`` command line."""

from __future__ import annotations

import argparse
import sys
import time

__all__ = ["main"]


def _cmd_validate(args) -> int:
    from .checks import all_sections, format_checks, run_checks

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
    from .table1 import compute_table1, format_table1

    rows, seconds = compute_table1(tol=args.tol)
    print(format_table1(rows))
    print(f"27 entries in {seconds:.2f} s (tol {args.tol:g})")
    return 0


def _cmd_stability(args) -> int:
    from .stability import classify, format_sweep, sweep

    t0 = time.perf_counter()
    findings = sweep(energy=not args.no_energy)
    print(format_sweep(findings))
    print(f"stability sweep finished in {time.perf_counter() - t0:.1f} s")
    _, bad = classify(findings)
    return 1 if bad else 0


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
    p = sub.add_parser("models", help="list the models and their declared parameters")
    p.set_defaults(func=_cmd_models)
    args = ap.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
