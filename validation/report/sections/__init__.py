"""The report's sections, one module each, and :data:`SECTIONS`, the page in order.

Each module has ``compute(ctx)``, which returns a small frozen dataclass of the
numbers the section shows (computed by the run, nothing typed in; shared with
the checks through ``ctx.compute``), and ``render(section, data)``, which only
draws and tabulates from it.
"""

from __future__ import annotations

from scatterbench.validation.fitting import diagnostics

from ..core import SectionSpec
from . import (
    conservation,
    contributed,
    edge_findings,
    model_comparison,
    provenance,
    ptfe,
    scatmech,
    scenes,
    seed000,
    seed001,
    seed003_fig1,
    seed003_presets,
    speed,
    summary,
    table1,
    thin_film,
    uncertainty,
)
from .summary import report_checks

__all__ = ["SECTIONS", "report_checks"]


def _spec(sid, title, module, stage=0, beside=False, compiles=(), preloads=(), alone=False):
    return SectionSpec(sid, title, module.compute, module.render, stage, beside, compiles, preloads, alone)


#: the page, in order; the summary runs last (it shows every check and every section that
#: raised), provenance just before it (it shows the others' run times)
SECTIONS = (
    _spec("summary", "Summary: every check", summary, stage=2),
    _spec("table1", "Seed 000 Table I: paper, scatterbench, SCATMECH", table1),
    _spec("seed000", "Seed 000 Fig. 2 and Fig. 3 reproduced", seed000),
    _spec("conservation", "Conservation: reciprocity and albedo", conservation),
    _spec("scatmech", "Agreement with SCATMECH", scatmech),
    _spec("seed003_fig1", "Seed 003 Fig. 1 reproduced: Snell shift of facet transmission", seed003_fig1),
    _spec(
        "seed003_presets",
        "Seed 003 Fig. 2-3: preset model curves beside Maxwell-Beard",
        seed003_presets,
        beside=True,
    ),
    _spec("seed001", "Seed 001: published vs energy Cook-Torrance, varnish, point source", seed001),
    _spec("thin_film", "Beyond the seeds: thin-film interference flakes and their colour travel", thin_film),
    _spec(
        "uncertainty", "Uncertainty: an example posterior and the recovery coverage", uncertainty, beside=True
    ),
    _spec(
        "model_comparison",
        "Model comparison: seed 003's combination against Maxwell-Beard",
        model_comparison,
        beside=True,
        preloads=(diagnostics.load,),  # ArviZ: the between-chain R-hat
    ),
    _spec(
        "ptfe",
        "Real data: NIST's sintered PTFE, five models compared and cross-validated",
        ptfe,
        beside=True,
        preloads=(diagnostics.load,),  # ArviZ: PSIS-LOO, WAIC and their comparison
    ),
    # the float32 facet: only the trade-off study's precision knob runs it (the loops the beside
    # sections run, recorded at their first call in one process: ad hoc, 2026-12-06)
    _spec("speed", "Speed and accuracy", speed, compiles=(("facet", "float32", None, True),), alone=True),
    _spec("stability", "Stability sweep at the extremes", edge_findings, beside=True),
    _spec("scenes", "Scenes and the mechanisms they build", scenes),
    _spec("contributed", "Contributed models (scatterbench.models entry points)", contributed),
    _spec("provenance", "Provenance", provenance, stage=1),
)
