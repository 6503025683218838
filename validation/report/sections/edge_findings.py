"""Stability sweep at the extremes: findings grouped by model, kind and verdict."""

from __future__ import annotations

from dataclasses import dataclass

from scatterbench.validation.checks.stability import sweep_findings
from scatterbench.validation.studies.edge_sweep import classify, group_findings, load_accepted

from ..core import store_rows, table_block, text_block

__all__ = ["StabilityData", "summarize", "compute", "render"]

_FINDING_COLUMNS = ["model", "kind", "value", "where", "accepted", "reason"]
_GROUP_COLUMNS = [
    "model",
    "kind",
    "accepted",
    "count",
    "worst value",
    "worst parameters",
    "worst at",
    "reason",
]


@dataclass(frozen=True)
class StabilityData:
    """``findings``: one row per finding (results.json only); ``groups``: one row per
    model, kind and verdict with the count and the worst finding (the page's table)."""

    quick: bool
    n_accepted: int
    n_unaccepted: int
    findings: tuple
    groups: tuple


def _group_row(g):
    return {
        "model": g.model,
        "kind": g.kind,
        "accepted": "yes" if g.reason else "NO",
        "count": g.count,
        "worst value": g.worst.value,
        "worst parameters": g.worst.params,
        "worst at": g.worst.where,
        "reason": g.reason or "",
    }


def summarize(findings, accepted, quick=False):
    """The section's data from the sweep's ``findings`` and the ``accepted`` entries
    (:func:`scatterbench.validation.studies.edge_sweep.load_accepted`)."""

    ok, bad = classify(findings, accepted)
    rows = tuple(
        {
            "model": f.model,
            "kind": f.kind,
            "value": f.value,
            "where": f.where,
            "accepted": "yes" if r else "NO",
            "reason": r or "",
        }
        for f, r in ok + bad
    )
    groups = tuple(_group_row(g) for g in group_findings(findings, accepted))
    return StabilityData(quick, len(ok), len(bad), rows, groups)


def compute(ctx):

    return summarize(sweep_findings(ctx), load_accepted(), ctx.quick)  # the stability check's sweep


def render(s, d: StabilityData):
    if d.quick:
        s.blocks.append(
            text_block(
                "Quick run: the energy integrals of the sweep are skipped (the full report runs them)."
            )
        )
    s.blocks.append(
        text_block(
            f"{len(d.findings)} findings: {d.n_accepted} accepted (each with its reason), {d.n_unaccepted} "
            f"unaccepted, in {len(d.groups)} groups of one model, kind and verdict (unaccepted first), each with "
            "its count, its worst finding (largest magnitude: its parameters and geometry) and its reason. "
            "Every finding is in results.json (sections.stability.numbers.stability)."
        )
    )
    store_rows(s, "stability", _FINDING_COLUMNS, d.findings)
    s.blocks.append(table_block(s, "stability_groups", _GROUP_COLUMNS, d.groups))
