"""Agreement with SCATMECH: committed reference values and, where installed, live pySCATMECH."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scatterbench import models
from scatterbench.validation.checks.seed000 import scatmech_facet_errors
from scatterbench.validation.checks.seed003 import scatmech_error_distributions

from ..core import figure_block, table_block, text_block
from ._common import AL, finish, plt

__all__ = ["ScatmechData", "compute", "render"]


@dataclass(frozen=True)
class ScatmechData:
    """``errors``: per reference set, (label, ``max |M - M_scatmech| / M00`` per case);
    ``live``: whether pySCATMECH was importable (its row is then the last of ``rows``)."""

    errors: tuple
    rows: tuple
    live: bool


def _live_scatmech(ctx):
    from pySCATMECH.brdf import (
        BRDF_Model,  # pySCATMECH (optional peer: most machines have only the committed data)
    )

    rng = np.random.default_rng(ctx.seed)
    out = []
    for _ in range(5 if ctx.quick else 20):
        coat = float(rng.uniform(1.0, 2.2))
        sigma = float(rng.uniform(0.05, 1.0))
        ours = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(sigma), coating=coat, substrate=AL)
        ref = BRDF_Model(
            "Subsurface_Facet_BRDF_Model",
            substrate="(1.37,7.62)",
            overcoat=f"({coat!r},0)",
            sdf="Exponential_Slope_Distribution_Function",
            **{"sdf.s": sigma},
        )
        for _ in range(10):
            ti, tr = rng.uniform(0, 1.4, 2)
            pr = rng.uniform(-3, 3)
            R = np.array(ref.MuellerBRDF(ti, tr, pr))
            out.append(float(np.max(np.abs(ours.mueller(ti, tr, pr) - R)) / max(R[0, 0], 1e-300)))
    return np.array(out)


def _row(label, e):
    return {"model": label, "cases": int(e.size), "median": float(np.median(e)), "max": float(e.max())}


def compute(ctx):

    errs = {f"{k} (committed)": v for k, v in scatmech_facet_errors().items()}
    errs.update(scatmech_error_distributions())
    errors = tuple((label, np.asarray(e, dtype=float)) for label, e in errs.items())
    rows = [_row(label, e) for label, e in errors]
    try:
        from pySCATMECH.brdf import BRDF_Model  # noqa: F401
    except ImportError:
        return ScatmechData(errors, tuple(rows), live=False)
    rows.append(_row("SubsurfaceFacetBRDF (live pySCATMECH)", _live_scatmech(ctx)))
    return ScatmechData(errors, tuple(rows), live=True)


def _draw(d):
    fig, ax = plt.subplots(figsize=(7, 4))
    for label, e in d.errors:
        ax.hist(np.log10(np.maximum(e, 1e-18)), bins=40, histtype="step", label=label)
    return finish(fig, ax, "log10 max |M - M_scatmech| / M00 per case", "cases", 8)


def render(s, d: ScatmechData):
    if not d.live:
        s.blocks.append(
            text_block("pySCATMECH is not installed on this machine: no live comparison in this run.")
        )
    s.blocks.append(figure_block(_draw(d), "Error distributions against SCATMECH reference values"))
    fmt = {"median": ".2e", "max": ".2e"}
    s.blocks.append(table_block(s, "scatmech", ["model", "cases", "median", "max"], d.rows, fmt=fmt))
