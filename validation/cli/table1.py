"""``scatterbench table1``: seed 000 Table I beside the printed values."""

from __future__ import annotations

from scatterbench.validation.checks.table1 import compute_table1, format_table1

from .args import positive_float

__all__ = ["register"]


def _cmd_table1(args) -> int:

    rows, seconds = compute_table1(tol=args.tol)
    print(format_table1(rows))
    print(f"27 entries in {seconds:.2f} s (tol {args.tol:g})")
    return 0


def register(sub):
    p = sub.add_parser("table1", help="seed 000 Table I beside the printed values")
    p.add_argument("--tol", type=positive_float, default=1e-4, help="absolute integration tolerance (> 0)")
    p.set_defaults(func=_cmd_table1)
