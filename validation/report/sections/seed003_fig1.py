"""Seed 003 Fig. 1 reproduced: the Snell shift of facet transmission (FacetBTDF)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scatterbench import models
from scatterbench.validation.checks.fig1 import EFFECTIVE_INDEX_DEG, N_INDEX, SIGMAS, THETA_I
from scatterbench.validation.checks.seed003 import fig1_rows

from ..core import figure_block, table_block, text_block
from ._common import finish, plt, signed

__all__ = ["Fig1Data", "compute", "render"]

DEG = math.pi / 180.0
_FMT = {
    "peak theta_t (deg)": ".3f",
    "peak - Snell (deg)": "+.3f",
    "n_eff": ".4f",
    "max |sin - line|": ".2e",
}


@dataclass(frozen=True)
class Fig1Data:
    """``x``: signed theta_t (deg); ``curves``: per sigma, (sigma, BTDF / peak over ``x``,
    n_eff); ``sin_in``, ``sin_out``: sin(theta_i) and, per sigma, sin(mean theta_t)."""

    n_index: float
    theta_i_deg: float
    snell_deg: float
    sigmas: tuple
    x: np.ndarray
    curves: tuple
    sin_in: np.ndarray
    sin_out: tuple
    rows: tuple
    tracked: dict


def _curves(rows, x):
    """Per sigma: the in-plane BTDF over ``x`` divided by its peak, and sin(mean theta_t) at
    :data:`scatterbench.validation.checks.fig1.EFFECTIVE_INDEX_DEG`."""

    curves = []
    for r in rows:
        m = models.FacetBTDF(slopes=models.GaussianSlopes(sigma=r["sigma"]), substrate=N_INDEX)
        f = m.brdf(THETA_I, *signed(x))
        curves.append((r["sigma"], f / f.max(), r["n_eff"]))
    return tuple(curves), tuple(r["sin_out"] for r in rows)  # the check's points, not recomputed


def _table_row(r, snell):
    return {
        "sigma": r["sigma"],
        "peak theta_t (deg)": r["peak_deg"],
        "peak - Snell (deg)": r["peak_deg"] - snell,
        "n_eff": r["n_eff"],
        "max |sin - line|": r["linear_residual"],
    }


def compute(ctx):

    rows = [dict(r) for r in fig1_rows()]  # the Fig. 1 check's analysis (validation/checks/fig1.py)
    snell = math.degrees(math.asin(math.sin(THETA_I) / N_INDEX))
    x = np.linspace(-89.0, 89.0, 357 if ctx.quick else 1781)
    ti_deg = np.asarray(EFFECTIVE_INDEX_DEG, dtype=float)
    curves, sin_out = _curves(rows, x)
    tracked = {}
    for r in rows:
        tracked[f"fig1|{r['sigma']:g}|peak_deg"] = {"value": r["peak_deg"], "tol": 0.01}
        tracked[f"fig1|{r['sigma']:g}|n_eff"] = {"value": r["n_eff"], "tol": 1e-4}
    return Fig1Data(
        n_index=N_INDEX,
        theta_i_deg=math.degrees(THETA_I),
        snell_deg=snell,
        sigmas=SIGMAS,
        x=x,
        curves=curves,
        sin_in=np.sin(ti_deg * DEG),
        sin_out=sin_out,
        rows=tuple(_table_row(r, snell) for r in rows),
        tracked=tracked,
    )


def _draw(d):
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    for (sigma, f, n_eff), s_out in zip(d.curves, d.sin_out, strict=True):
        (line,) = ax.plot(d.x, f, label=f"sigma = {sigma:g}")
        bx.plot(d.sin_in, s_out, "o", ms=3, color=line.get_color())
        bx.plot(d.sin_in, d.sin_in / n_eff, "-", lw=0.8, color=line.get_color(), label=f"n_eff = {n_eff:.3f}")
    ax.axvline(d.snell_deg, color="k", lw=0.6, ls=":")
    ax.set_xlabel("signed transmitted angle theta_t (deg, + forward)")
    ax.set_ylabel("BTDF / peak")
    ax.set_xlim(-20, 89)
    ax.legend(fontsize=7)
    bx.plot([0, 1], [0, 1 / d.n_index], "k:", lw=0.8, label=f"Snell, n = {d.n_index:g}")
    return finish(fig, bx, "sin(theta_i)", "sin(BTDF-weighted mean theta_t)", 7)


def render(s, d: Fig1Data):
    s.blocks.append(
        figure_block(
            _draw(d),
            f"Left: in-plane BTDF of FacetBTDF(GaussianSlopes(sigma), n = {d.n_index:g}) at theta_i = "
            f"{d.theta_i_deg:g} deg, unpolarized, each curve divided by its peak; dotted: Snell angle "
            f"{d.snell_deg:.2f} deg. Right: sine of the BTDF-weighted mean signed transmitted angle (in-plane, "
            "2000-node Gauss-Legendre) versus sin(theta_i) for theta_i = 0..80 deg (dots) and the least-squares "
            "line through the origin with slope 1/n_eff.",
        )
    )
    s.blocks.append(
        text_block(
            "The paper prints neither the sigma values nor the weighting's domain; the sigmas are "
            + ", ".join(f"{v:g}" for v in d.sigmas)
            + ". The peak is the 0.01-deg grid maximum refined by a parabola; the effective index n_eff is "
            "1/slope of sin(mean theta_t) = sin(theta_i)/n_eff (validation/checks/fig1.py)."
        )
    )
    caption = (
        f"peak angles at theta_i = {d.theta_i_deg:g} deg (Snell: {d.snell_deg:.3f} deg) and effective indices"
    )
    s.blocks.append(table_block(s, "fig1", list(d.rows[0]), d.rows, caption=caption, fmt=_FMT))
    s.tracked.update(d.tracked)
