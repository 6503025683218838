"""Summary: every check the report judges, from the check registry."""

from __future__ import annotations

from dataclasses import dataclass

from scatterbench.validation.checks.registry import check_record, registered, run_checks

from ..core import checks_block, text_block

__all__ = ["SummaryData", "report_checks", "compute", "render"]


@dataclass(frozen=True)
class SummaryData:
    """``checks``: the records of the registered checks and of the sections that raised;
    ``previous``: the previous run's check records (None: no previous run);
    ``skipped``: the slow checks a default quick run leaves out (None: not such a run)."""

    checks: tuple
    previous: tuple | None
    quick: bool
    skipped: tuple[str, ...] | None


def report_checks(ctx):
    """The records of the checks this report judges: ``ctx.cache["check_specs"]`` if set,
    else every registered check for ``ctx.quick`` (the set ``validate`` runs).  Each runs
    once per context, sharing its computations with the sections that draw them."""
    specs = ctx.cache.get("check_specs")
    return [check_record(r) for r in run_checks(registered(ctx.quick) if specs is None else specs, ctx)]


def compute(ctx):
    """The checks (run last: it also collects the sections' failures)."""
    checks = report_checks(ctx) + ctx.cache.get("section_failures", [])
    prev = (ctx.previous or {}).get("checks")
    skipped = None
    if ctx.quick and "check_specs" not in ctx.cache:
        skipped = tuple(spec.id for spec in registered() if spec.slow)
    return SummaryData(tuple(checks), None if prev is None else tuple(prev), ctx.quick, skipped)


def render(s, d: SummaryData):
    s.blocks.append(
        text_block(
            "Each check: the value this run measured, the limit it is held to, the status (FINDING marks a "
            "property of a paper that the run established, not an implementation failure; each finding says "
            "under which condition it would fail instead) and the change since the previous report. The "
            "same checks, with the same settings, are run by `scatterbench validate` "
            f"{'--quick ' if d.quick else ''}and the test suite."
        )
    )
    if d.skipped is not None:
        s.blocks.append(
            text_block(
                "Quick run: these slow checks were not run (the full report and `scatterbench validate` run them): "
                + ", ".join(d.skipped)
            )
        )
    s.blocks.append(checks_block(d.checks, d.previous))
    s.checks = list(d.checks)
