"""Seed 000 Fig. 2 and Fig. 3 reproduced: in-plane BRDF and polarization of coated flakes."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scatterbench import models
from scatterbench.validation.numerics.integrate import integrated_reflectance

from ..core import figure_block, table_block
from ._common import AL, inplane, plt

__all__ = ["Seed000Data", "compute", "draw_fig2", "draw_fig3", "render"]

THETA_I = math.radians(60)
SIGMAS = (0.1, 0.2)
COATINGS = (1.0, 1.5, 2.0)
#: Fig. 3's tabulated angles (signed, deg)
FIG3_ANGLES = (-30.0, 0.0, 30.0, 75.0)


@dataclass(frozen=True)
class Seed000Data:
    """``x``: signed theta_r (deg); ``fig2``: per sigma, (sigma, ((coating, brdf), ...));
    ``fig3``: per model, (label, eta_deg, P, P_C) over ``x``; tables' rows; tracked values."""

    x: np.ndarray
    fig2: tuple
    fig2_rows: tuple
    fig3: tuple
    fig3_rows: tuple
    tracked: dict


def _fig2(x):
    curves, rows, tracked = [], [], {}
    for sigma in SIGMAS:
        per_sigma = []
        for n in COATINGS:
            m = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(sigma), coating=n, substrate=AL)
            per_sigma.append((n, inplane(m, THETA_I, x)["brdf"]))
            spec = float(m.brdf(THETA_I, THETA_I, 0.0))
            rows.append(
                {
                    "sigma": sigma,
                    "coating": n,
                    "BRDF at specular": spec,
                    "BRDF at theta_r = 0": float(m.brdf(THETA_I, 0.0, 0.0)),
                    "integrated reflectance": integrated_reflectance(m, THETA_I, tol=1e-4).value,
                }
            )
            tracked[f"fig2|{sigma:g}|{n:g}|specular"] = {"value": spec, "tol": 1e-9 * spec}
        curves.append((sigma, tuple(per_sigma)))
    return tuple(curves), tuple(rows), tracked


def _fig3(x):
    """Light polarized at 45 deg: aluminium under n = 1.5 versus an exposed polymer."""
    coated = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.2), coating=1.5, substrate=AL)
    polymer = models.FacetBRDF(slopes=models.ExponentialSlopes(0.2), substrate=1.5)
    curves, rows = [], []
    for model, label in ((coated, "aluminium under n = 1.5 coating"), (polymer, "exposed polymer (n = 1.5)")):
        p = inplane(model, THETA_I, x, incident="linear:45")
        curves.append((label, np.degrees(p["eta"]), p["P"], p["P_C"]))
        q = inplane(model, THETA_I, np.array(FIG3_ANGLES), incident="linear:45")
        for k, ang in enumerate(FIG3_ANGLES):
            rows.append(
                {
                    "model": label,
                    "theta_r (signed, deg)": ang,
                    "eta (deg)": float(np.degrees(q["eta"][k])),
                    "P": float(q["P"][k]),
                    "P_C": float(q["P_C"][k]),
                }
            )
    return tuple(curves), tuple(rows)


def compute(ctx):
    x = np.linspace(-89, 89, 179 if ctx.quick else 713)
    fig2, fig2_rows, tracked = _fig2(x)
    fig3, fig3_rows = _fig3(x)
    return Seed000Data(x, fig2, fig2_rows, fig3, fig3_rows, tracked)


def draw_fig2(d):
    """Fig. 2: the in-plane BRDF per sigma and coating (the section's figure; also the gallery's)."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for ax, (sigma, curves) in zip(axes, d.fig2, strict=True):
        for (n, f), style in zip(curves, ("-", "--", ":"), strict=True):
            ax.semilogy(d.x, np.maximum(f, 1e-10), style, label=f"n = {n:g}")
        ax.set_title(f"aluminium, exponential slopes sigma = {sigma:g}")
        ax.set_xlabel("scattering angle theta_r (deg, negative = incidence side)")
        ax.legend()
    axes[0].set_ylabel("BRDF (1/sr)")
    fig.tight_layout()
    return fig


def draw_fig3(d):
    """Fig. 3: eta, P and P_C for 45 deg light (the section's figure; also the gallery's)."""
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 8), sharex=True)
    for (label, eta, p, pc), style in zip(d.fig3, ("-", "--"), strict=True):
        axes[0].plot(d.x, eta, style, label=label)
        axes[1].plot(d.x, p, style, label=label)
        axes[2].plot(d.x, pc, style, label=label)
    axes[0].set_ylabel("eta (deg)")
    axes[1].set_ylabel("P")
    axes[2].set_ylabel("P_C")
    axes[2].set_xlabel("scattering angle theta_r (deg)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def render(s, d: Seed000Data):
    s.tracked.update(d.tracked)
    s.blocks.append(
        figure_block(
            draw_fig2(d),
            "Fig. 2: BRDF for unpolarized light at theta_i = 60 deg, coatings 1.0, 1.5, 2.0 on aluminium",
        )
    )
    columns = ["sigma", "coating", "BRDF at specular", "BRDF at theta_r = 0", "integrated reflectance"]
    s.blocks.append(table_block(s, "fig2", columns, d.fig2_rows))
    s.blocks.append(
        figure_block(
            draw_fig3(d),
            "Fig. 3 style: principal angle eta, degree of polarization P and of circular polarization P_C for "
            "incident light polarized at 45 deg (theta_i = 60 deg, sigma = 0.2)",
        )
    )
    s.blocks.append(
        table_block(s, "fig3", ["model", "theta_r (signed, deg)", "eta (deg)", "P", "P_C"], d.fig3_rows)
    )
