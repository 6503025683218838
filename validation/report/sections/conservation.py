"""Conservation: reciprocity error maps, albedo of every deterministic reciprocal model, and a
perfect conductor's albedo with and without Smith shadowing (the curves the check
``check_smith_albedo`` judges, computed once per run)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scatterbench.validation.checks.shadowing import ANGLES_DEG, QUICK_ANGLES_DEG, conductor_albedo_curves
from scatterbench.validation.numerics.integrate import integrated_reflectance
from scatterbench.validation.numerics.reciprocity import reciprocity_errors

from ..core import figure_block, table_block, text_block
from ._common import default_models, finish, is_heavy, plt

__all__ = ["ConservationData", "compute", "render"]

PHI_R = 0.7  # rad, the maps' azimuth
GRID_DEG = (0.5, 88.5)


@dataclass(frozen=True)
class ConservationData:
    """``maps``: per model, (name, relative reciprocity error over theta_i x theta_r);
    ``albedo``: per reflecting model, (name, theta_i in deg, albedo); ``smith``: the
    perfect-conductor :class:`~scatterbench.validation.checks.shadowing.AlbedoCurve` s, with and without
    Smith shadowing."""

    skipped: tuple[str, ...]
    maps: tuple
    reciprocity_rows: tuple
    albedo: tuple
    albedo_rows: tuple
    smith: tuple
    smith_rows: tuple


def _worst(errors, live):
    return float(np.max(errors[live])) if live.any() else 0.0


def _reciprocity(m, t):
    """The relative reciprocity errors over the theta_i x theta_r grid: the map, and its row of
    maxima (scalar, Mueller, Jones) over the same geometries."""
    TI, TR = np.meshgrid(t, t, indexing="ij")
    e = reciprocity_errors(m, TI, TR, PHI_R)  # the reversed path, rotated sample if anisotropic
    row = {
        "model": type(m).__name__,
        "scalar": _worst(e.scalar, e.live),
        "Mueller": _worst(e.mueller, e.live),
    }
    row["Jones"] = None if e.jones is None else _worst(e.jones, e.live)
    return e.scalar.reshape(TI.shape), row


def _albedo(ms, tis):
    curves, rows = [], []
    for m in ms:
        if m.transmission:
            continue
        vals = [integrated_reflectance(m, float(a), tol=1e-4).value for a in tis]
        curves.append((type(m).__name__, np.degrees(tis), vals))
        for a, v in zip(tis, vals, strict=True):
            rows.append({"model": type(m).__name__, "theta_i (deg)": float(np.degrees(a)), "albedo": v})
    return tuple(curves), tuple(rows)


def _smith(ctx):
    # the same call as the check's, so the run integrates these curves once
    angles = QUICK_ANGLES_DEG if ctx.quick else ANGLES_DEG
    curves = tuple(ctx.compute(conductor_albedo_curves, angles_deg=angles))
    rows = tuple(
        {
            "slopes": c.label.split(", shadowing")[0],
            "shadowing": c.shadowing,
            "max albedo": max(c.albedo),
            "at theta_i (deg)": c.theta_i_deg[c.albedo.index(max(c.albedo))],
            "its error": c.error[c.albedo.index(max(c.albedo))],
        }
        for c in curves
    )
    return curves, rows


def compute(ctx):
    every = default_models()
    ms = [m for m in every if not is_heavy(m) and m.reciprocal]
    t = np.radians(np.linspace(*GRID_DEG, 30 if ctx.quick else 60))
    maps, rows = [], []
    for m in ms:
        err, row = _reciprocity(m, t)
        maps.append((type(m).__name__, err))
        rows.append(row)
    albedo, albedo_rows = _albedo(ms, np.radians(np.linspace(0, 85, 6 if ctx.quick else 18)))
    skipped = tuple(type(m).__name__ for m in every if m not in ms)
    smith, smith_rows = _smith(ctx)
    return ConservationData(skipped, tuple(maps), tuple(rows), albedo, albedo_rows, smith, smith_rows)


def _draw_maps(d):
    fig, axes = plt.subplots(1, len(d.maps), figsize=(4.2 * len(d.maps), 3.6), squeeze=False)
    for ax, (name, err) in zip(axes[0], d.maps, strict=True):
        im = ax.imshow(
            np.log10(err + 1e-17),
            origin="lower",
            extent=[*GRID_DEG, *GRID_DEG],
            vmin=-17,
            vmax=-6,
            aspect="auto",
        )
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("theta_r (deg)")
        ax.set_ylabel("theta_i (deg)")
        fig.colorbar(im, ax=ax, label="log10 rel. error")
    fig.tight_layout()
    return fig


def _draw_albedo(d):
    fig, ax = plt.subplots(figsize=(7, 4))
    for name, ti_deg, vals in d.albedo:
        ax.plot(ti_deg, vals, "o-", label=name)
    ax.axhline(1.0, color="k", lw=0.6)
    return finish(fig, ax, "theta_i (deg)", "integrated reflectance", 8)


def _draw_smith(d):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
    for ax, family in zip(axes, ("gaussian", "ggx"), strict=True):
        for c in d.smith:
            if c.family == family:
                style = "o-" if c.shadowing == "smith" else "s--"
                ax.semilogy(c.theta_i_deg, c.albedo, style, label=c.label.split(family + " ")[1], ms=4)
        ax.axhline(1.0, color="k", lw=0.6)
        ax.set_title("Gaussian (Beckmann) slopes" if family == "gaussian" else "GGX slopes", fontsize=9)
        finish(fig, ax, "theta_i (deg)", "perfect-conductor albedo", 7)
    return fig


def render(s, d: ConservationData):
    s.blocks.append(
        text_block(
            "Deterministic reciprocal models at their defaults. Not mapped here: "
            + ", ".join(d.skipped)
            + " (the Monte Carlo model is reciprocal and energy-bounded only within its standard error, "
            "tested statistically with the model; the point-source wrapper is not reciprocal by construction "
            "and its albedo is a weighted mean of its inner model's)."
        )
    )
    s.blocks.append(
        figure_block(
            _draw_maps(d),
            "Reciprocity error maps: |f(i->r) - f(r->i)| / f at phi_r = 0.7 rad, default parameters",
        )
    )
    fmt = {"scalar": ".2e", "Mueller": ".2e", "Jones": ".2e"}
    s.blocks.append(
        table_block(s, "reciprocity", ["model", "scalar", "Mueller", "Jones"], d.reciprocity_rows, fmt=fmt)
    )
    s.blocks.append(
        figure_block(
            _draw_albedo(d),
            "Albedo (hemispherical integral, tol 1e-4) versus theta_i for each model at its defaults",
        )
    )
    s.blocks.append(table_block(s, "albedo", ["model", "theta_i (deg)", "albedo"], d.albedo_rows))
    s.blocks.append(
        figure_block(
            _draw_smith(d),
            "Perfect-conductor albedo of FacetBRDF versus incidence, without shadowing (dashed; bounded "
            "by the hit fraction, above 1 near grazing) and with Smith shadowing-masking (solid; <= 1)",
        )
    )
    s.blocks.append(
        table_block(
            s,
            "smith_albedo",
            ["slopes", "shadowing", "max albedo", "at theta_i (deg)", "its error"],
            d.smith_rows,
            fmt={"max albedo": ".6g", "its error": ".1e"},
        )
    )
