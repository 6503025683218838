"""``scatterbench table1``: seed 000 Table I beside the printed values.

Exit 1 when an entry's integration error estimate is above ``--tol`` (the
requested accuracy was not reached), 0 otherwise.
"""

from __future__ import annotations

from scatterbench.validation.checks.table1 import compute_table1, format_table1

from .args import positive_float

__all__ = ["register"]


def _cmd_table1(args) -> int:

    rows, seconds = compute_table1(tol=args.tol)
    print(format_table1(rows))
    print(f"{len(rows)} entries in {seconds:.2f} s (tol {args.tol:g})")
    # the integrals stop at their evaluation budget or float64's floor: say when short of --tol
    unmet = [r for r in rows if not r.error <= args.tol]
    if unmet:
        worst = max(unmet, key=lambda r: r.error)
        print(
            f"tolerance NOT met: {len(unmet)} of {len(rows)} entries have an error estimate above "
            f"--tol {args.tol:g} (largest {worst.error:.2g}: {worst.substrate}, n = {worst.coating:g}, "
            f"sigma = {worst.sigma:g})"
        )
        return 1
    return 0


def register(sub):
    p = sub.add_parser("table1", help="seed 000 Table I beside the printed values")
    p.add_argument("--tol", type=positive_float, default=1e-4, help="absolute integration tolerance (> 0)")
    p.set_defaults(func=_cmd_table1)
