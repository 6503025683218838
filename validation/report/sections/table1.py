"""Seed 000 Table I: the paper, scatterbench and SCATMECH, entry by entry."""

from __future__ import annotations

import math
from dataclasses import dataclass

from scatterbench.validation.checks import table1

from ..core import table_block, text_block

__all__ = ["Table1Data", "compute", "render"]

_COLUMNS = [
    "substrate",
    "coating",
    "sigma",
    "paper",
    "scatterbench",
    "integration error",
    "independent",
    "independent method",
    "within rounding",
]
_FMT = {
    "scatterbench": ".4f",
    "independent": ".4f",
    "paper": ".2f",
    "coating": ".1f",
    "sigma": ".1f",
    "integration error": ".1e",
}


@dataclass(frozen=True)
class Table1Data:
    """``rows``: one per entry; ``outside``: (substrate, coating, sigma, verdict) of the
    entries outside the printed rounding; ``seconds``: the integrals' run time."""

    rows: tuple
    outside: tuple
    seconds: float
    theta_i_deg: float
    tol: float
    limit_sigma: float
    tracked: dict


def _row(r):
    return {
        "substrate": r.substrate,
        "coating": r.coating,
        "sigma": r.sigma,
        "paper": r.printed,
        "scatterbench": r.computed,
        "integration error": r.error,
        "independent": r.independent,
        "independent method": "SCATMECH slope integral" if r.sigma > 0 else "sigma -> 0 integral",
        "within rounding": "yes" if r.within_rounding else "NO",
    }


def compute(ctx):
    """Table I as the Table I check computed it (shared through ``ctx.compute``)."""
    computed, seconds = ctx.compute(table1.compute_table1)
    # nightly: an entry may move by twice its integration error estimate, at least 2e-4
    tracked = {
        f"table1|{r.substrate}|{r.coating:g}|{r.sigma:g}": {
            "value": r.computed,
            "tol": max(2e-4, 2 * r.error),
        }
        for r in computed
    }
    outside = tuple((r.substrate, r.coating, r.sigma, r.verdict) for r in computed if not r.within_rounding)
    return Table1Data(
        rows=tuple(_row(r) for r in computed),
        outside=outside,
        seconds=seconds,
        theta_i_deg=math.degrees(table1.THETA_I),
        tol=table1.TOL,
        limit_sigma=table1.LIMIT_SIGMA,
        tracked=tracked,
    )


def render(s, d: Table1Data):
    s.tracked.update(d.tracked)
    s.blocks.append(
        text_block(
            f"{len(d.rows)} integrals (theta_i = {d.theta_i_deg:g} deg, unpolarized, exponential "
            f"slopes) computed in {d.seconds:.2f} s at tolerance {d.tol:g}. The flat column is the closed form; "
            f"its independent value is the model's integral at sigma = {d.limit_sigma:g}. Rough entries are "
            "compared with SCATMECH's model integrated over facet slopes (references/data/table1_scatmech.csv)."
        )
    )
    s.blocks.append(table_block(s, "table1", _COLUMNS, d.rows, fmt=_FMT))
    if d.outside:
        s.blocks.append(
            text_block(
                "Entries outside the printed rounding:\n"
                + "\n".join(f"* {sub}, n = {n:g}, sigma = {sig:g}: {why}" for sub, n, sig, why in d.outside)
            )
        )
