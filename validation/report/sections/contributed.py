"""Contributed models: every model another package registers in the ``scatterbench.models``
entry-point group, with its conformance kit results (:func:`scatterbench.validation.testing.contributed_section`)."""

from __future__ import annotations

from dataclasses import dataclass

from scatterbench.validation.testing import ENTRY_POINT_GROUP, contributed_section

from ..core import table_block, text_block

__all__ = ["ContributedData", "compute", "render"]

_MODELS = [
    "entry point",
    "distribution",
    "module:attr",
    "model",
    "verdict",
    "pass",
    "findings",
    "fail",
    "skipped",
]
_RESULTS = ["entry point", "check", "measured", "limit", "status", "message"]


@dataclass(frozen=True)
class ContributedData:
    """``group``: the entry-point group; ``rows``: one :class:`scatterbench.validation.testing.ContributedRow`
    per entry, in name order (empty: none installed)."""

    group: str
    rows: tuple


def compute(ctx):

    return ContributedData(ENTRY_POINT_GROUP, tuple(contributed_section(ctx)))


def _model_row(r):
    if r.report is None:
        n, verdict = {}, f"not loaded: {r.error}"
    else:
        n, verdict = r.report["summary"], "passed" if r.report["passed"] else "FAILED"
    return {
        "entry point": r.name,
        "distribution": r.dist,
        "module:attr": r.value,
        "model": r.model,
        "verdict": verdict,
        "pass": n.get("n_pass"),
        "findings": n.get("n_finding"),
        "fail": n.get("n_fail"),
        "skipped": n.get("n_skip"),
    }


def _result_rows(r):
    for c in (r.report or {}).get("results", ()):
        skipped = c["status"] == "skip"
        yield {
            "entry point": r.name,
            "check": c["name"],
            "measured": None if skipped else c["measured"],
            "limit": "" if skipped else f"{c['op']} {c['tolerance']:.4g}",
            "status": c["status"].upper(),
            "message": c["detail"] if skipped else c["message"],
        }


def render(s, d: ContributedData):
    if not d.rows:
        s.blocks.append(text_block(f"no contributed models installed (entry-point group {d.group})"))
        s.numbers["contributed"] = []
        return
    s.blocks.append(
        text_block(
            f"Models other packages register in the entry-point group {d.group}, each run through the "
            "conformance kit (validation.testing.check_model, quick in a quick report). Their results are "
            "shown, not judged: they do not change this report's exit status."
        )
    )
    rows = [_model_row(r) for r in d.rows]
    s.blocks.append(table_block(s, "contributed", _MODELS, rows, caption="contributed models"))
    results = [c for r in d.rows for c in _result_rows(r)]
    caption = "every conformance result of the contributed models"
    s.blocks.append(table_block(s, "contributed_checks", _RESULTS, results, caption=caption))
