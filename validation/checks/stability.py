"""The stability sweep as a check: every model at the extremes of its parameters and
geometries (:mod:`scatterbench.validation.studies.edge_sweep`), no finding left unaccepted.

The sweep runs once per run (:func:`sweep_findings`); the report's stability section
draws the same one.  Quick runs skip its energy integrals, as the quick report does.
"""

from __future__ import annotations

from scatterbench.validation.studies.edge_sweep import classify, sweep

from .registry import check, judge

__all__ = ["sweep_findings"]


def sweep_findings(ctx):
    """The sweep's findings for the run (energy integrals only in full runs), once per run on the
    run's executor."""

    return ctx.study(sweep, energy=not ctx.quick)


@check(paper="every model at its extremes (stability sweep, accepted_findings.toml)")
def check_stability(ctx, findings=None):
    """``findings``: :func:`sweep_findings`; each must be accepted, with its reason."""

    ok, bad = classify(sweep_findings(ctx) if findings is None else findings)
    shown = "; ".join(f"{f.model} {f.kind} at {f.where}" for f, _ in bad[:3])
    return judge(
        "stability sweep: unaccepted findings",
        len(bad),
        0.0,
        f"{len(ok)} accepted findings" + (f"; unaccepted: {shown}" if bad else ""),
    )
