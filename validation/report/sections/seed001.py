"""Seed 001: published against energy-normalized Cook-Torrance, the varnish, the point source."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scatterbench import models, references
from scatterbench.validation.checks.seed001 import (
    RATIO_GEOMETRIES,
    _pair,
    iron_plate_models,
    point_source_collimated_error,
    published_albedos,
    published_over_energy_error,
    varnish_ratio_map,
)
from scatterbench.validation.numerics.integrate import integrated_reflectance

from ..core import figure_block, table_block, text_block
from ._common import plt

__all__ = ["Seed001Data", "ct_albedo_rows", "point_source_scan", "compute", "render"]

#: source heights d/R of the point source -> collimated table
DISTANCES = (3.0, 10.0, 30.0, 100.0, 1e3, 1e4)
#: radial disc nodes of the point-source scans (2 x as many in azimuth) and their in-plane angles
SCAN_RESOLUTION = 16
SCAN_ANGLES = 801


@dataclass(frozen=True)
class VarnishMaps:
    """Varnish / subsurface ratio maps over (theta_r, phi_r) in deg: Eq. 24's at theta_i = 0
    and 60 deg (``published``: ((theta_i, ratio), ...)) and the refracted one at 60 deg."""

    theta_r_deg: np.ndarray
    phi_r_deg: np.ndarray
    published: tuple
    refracted: np.ndarray


@dataclass(frozen=True)
class PointSourceScan:
    """The iron plate in plane, collimated and under the point source for one printed range."""

    lo: float
    hi: float
    d: float
    theta_r_deg: np.ndarray
    collimated: np.ndarray
    point: np.ndarray


@dataclass(frozen=True)
class Seed001Data:
    ratio_err: float
    albedo_rows: tuple
    n_t: int
    n_p: int
    maps: VarnishMaps
    ratio_rows: tuple
    scans: tuple
    point_rows: tuple
    convergence_rows: tuple
    tracked: dict


def ct_albedo_rows(published):
    """Per incidence of ``published`` (:func:`scatterbench.validation.checks.seed001.published_albedos`' ``{deg:
    albedo}``), the energy-normalized albedo of the same iron plate model and the ratio / (4 pi)."""
    rows = []
    for t, v in published.items():
        e = integrated_reflectance(
            models.CookTorranceBRDF(slopes=models.GaussianSlopes(0.03), convention="corrected"),
            math.radians(t),
            tol=1e-3,
        )
        rows.append(
            {
                "theta_i (deg)": t,
                "published albedo": v,
                "energy albedo": e.value,
                "energy integration error": e.error,
                "ratio / (4 pi)": v / e.value / (4 * math.pi),
            }
        )
    return tuple(rows)


def _ratio(a, b):
    """a / b where both are non-zero, else NaN (blank on the map)."""
    return np.where((a > 0) & (b > 0), a / np.where(b > 0, b, 1.0), np.nan)


def _varnish(n_t, n_p):
    """The varnish ratio maps and their summary rows (validation.checks.seed001.varnish_ratio_map)."""

    rows = [
        {
            "theta_i (deg)": t,
            "geometries": d["n"],
            "ratio min": float(d["ratio"].min()),
            "ratio median": float(np.median(d["ratio"])),
            "ratio max": float(d["ratio"].max()),
            "Jacobian min": float(d["jacobian"].min()),
            "Jacobian max": float(d["jacobian"].max()),
            "refracted/subsurface min": float(d["residual"].min()),
            "refracted/subsurface max": float(d["residual"].max()),
        }
        for t, d in varnish_ratio_map(n_t=n_t, n_p=n_p).items()
    ]
    v, sub = _pair()
    vr, _ = _pair(solid_angle="refracted")
    tr = np.radians(np.linspace(0.0, 88.0, n_t))
    pr = np.linspace(0.0, math.pi, n_p)
    T, P = np.meshgrid(tr, pr, indexing="ij")
    published = tuple(
        (t, _ratio(v.brdf(math.radians(t), T, P), sub.brdf(math.radians(t), T, P))) for t in (0.0, 60.0)
    )
    refracted = _ratio(vr.brdf(math.radians(60.0), T, P), sub.brdf(math.radians(60.0), T, P))
    return VarnishMaps(np.degrees(tr), np.degrees(pr), published, refracted), tuple(rows)


def point_source_scan(vn, lo, hi):
    """One printed incidence range ``[lo, hi]`` (deg): the in-plane scan of ``vn`` collimated and under
    the point source that spans it, and its table row."""
    psi_c, d = models.point_source_geometry(lo, hi)
    ps = models.PointSourceBRDF(model=vn, distance=d, sample_radius=1.0, resolution=SCAN_RESOLUTION)
    a_lo, a_hi = ps.incidence_range(psi_c)
    tr = np.radians(
        np.linspace(max(math.degrees(psi_c) - 10.0, 0.0), math.degrees(psi_c) + 10.0, SCAN_ANGLES)
    )
    fc = vn.brdf(psi_c, tr, 0.0)
    fp = ps.brdf(psi_c, tr, 0.0)
    kc, kp = int(np.argmax(fc)), int(np.argmax(fp))
    row = {
        "printed range (deg)": f"[{lo:g}, {hi:g}]",
        "psi_c (deg)": math.degrees(psi_c),
        "d/R": d,
        "model range (deg)": f"[{math.degrees(a_lo):.2f}, {math.degrees(a_hi):.2f}]",
        "collimated peak (1/sr)": float(fc[kc]),
        "collimated peak at (deg)": float(np.degrees(tr[kc])),
        "point-source peak (1/sr)": float(fp[kp]),
        "point-source peak at (deg)": float(np.degrees(tr[kp])),
    }
    return PointSourceScan(lo, hi, d, np.degrees(tr), fc, fp), row


def _point_source():
    """The iron plate (references.IRON_PLATE) under each printed incidence range, and the
    point source's approach to the collimated beam as it recedes."""

    _, vn = iron_plate_models()
    scans, rows = zip(
        *(point_source_scan(vn, lo, hi) for lo, hi in references.IRON_PLATE["incidence_ranges_deg"]),
        strict=True,
    )
    conv = point_source_collimated_error(distances=DISTANCES)
    crow = tuple({"d/R": d, "max |f_point - f_collimated| / max f": e} for d, e in conv.items())
    return tuple(scans), tuple(rows), crow


def compute(ctx):

    ratio_err = ctx.compute(published_over_energy_error)  # the check's value, computed once
    albedo_rows = ct_albedo_rows(ctx.compute(published_albedos))  # the energy check's integrals
    n_t, n_p = (30, 31) if ctx.quick else (60, 61)
    maps, ratio_rows = _varnish(n_t, n_p)
    scans, point_rows, convergence = _point_source()
    tracked = {
        f"point_source|{r['printed range (deg)']}|peak": {
            "value": r["point-source peak (1/sr)"],
            "tol": 1e-9 * r["point-source peak (1/sr)"],
        }
        for r in point_rows
    }
    return Seed001Data(
        ratio_err, albedo_rows, n_t, n_p, maps, ratio_rows, scans, point_rows, convergence, tracked
    )


def _draw_varnish(m: VarnishMaps):
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    for ax, (t, r) in zip(axes[:2], m.published, strict=True):
        im = ax.pcolormesh(m.phi_r_deg, m.theta_r_deg, np.log10(r), shading="auto", vmin=0.0, vmax=2.5)
        ax.set_title(f"log10 varnish(Eq. 24) / subsurface, theta_i = {t:g} deg", fontsize=8)
        ax.set_xlabel("phi_r (deg)")
        ax.set_ylabel("theta_r (deg)")
        fig.colorbar(im, ax=ax)
    im = axes[2].pcolormesh(m.phi_r_deg, m.theta_r_deg, m.refracted, shading="auto")
    axes[2].set_title("refracted varnish / subsurface, theta_i = 60 deg", fontsize=8)
    axes[2].set_xlabel("phi_r (deg)")
    fig.colorbar(im, ax=axes[2])
    fig.tight_layout()
    return fig


def _draw_point_source(scans):
    fig, axes = plt.subplots(1, len(scans), figsize=(13, 3.6))
    for ax, sc in zip(axes, scans, strict=True):
        ax.semilogy(sc.theta_r_deg, sc.collimated, "-", label="collimated")
        ax.semilogy(sc.theta_r_deg, np.maximum(sc.point, 1e-6), "--", label=f"point source, d/R = {sc.d:.1f}")
        ax.set_title(f"incidence range [{sc.lo:g}, {sc.hi:g}] deg", fontsize=9)
        ax.set_xlabel("theta_r in plane (deg)")
        ax.legend(fontsize=7)
    axes[0].set_ylabel("BRDF (1/sr)")
    fig.tight_layout()
    return fig


def _render_albedo(s, d):
    s.blocks.append(
        text_block(
            "Eq. 7-8 as printed have no 1/pi in D and no 4 in the denominator: the published BRDF is 4 pi times "
            f"the energy-normalized one. Measured max |published / energy / (4 pi) - 1| = {d.ratio_err:.2e} over "
            f"{RATIO_GEOMETRIES} random geometries (CookTorranceBRDF m = 0.2 and an anisotropic varnished model, its refraction "
            "Jacobian divided out). Albedos "
            "(hemispherical integral of M00 cos theta_r, tol 1e-3) of the iron plate model (m = 0.03, iron "
            "2.29+3.37i, Blinn shadowing):"
        )
    )
    s.numbers["published_over_energy_max_rel_error"] = d.ratio_err
    fmt = {"energy integration error": ".1e", "ratio / (4 pi)": ".6f"}
    s.blocks.append(table_block(s, "ct_albedo", list(d.albedo_rows[0]), d.albedo_rows, fmt=fmt))


def _render_varnish(s, d):
    s.blocks.append(
        figure_block(
            _draw_varnish(d.maps),
            "VarnishedCookTorranceBRDF (energy, G = 1, m = 0.1, n_v = 1.5, iron) over SubsurfaceFacetBRDF "
            f"(GaussianSlopes(0.1), coating 1.5, iron) on a {d.n_t} x {d.n_p} (theta_r 0..88, phi_r 0..180 deg) "
            "grid; white/blank: zero in either model. Right: with the refraction Jacobian (solid_angle='refracted') "
            "the remaining ratio is the polarization coupling.",
        )
    )
    caption = "ratio maps summarized (validation.checks.seed001.varnish_ratio_map)"
    s.blocks.append(table_block(s, "varnish_ratio", list(d.ratio_rows[0]), d.ratio_rows, caption=caption))


def _render_point_source(s, d):
    step = float(np.diff(d.scans[0].theta_r_deg[:2])[0])
    s.blocks.append(
        figure_block(
            _draw_point_source(d.scans),
            "Iron plate (references.IRON_PLATE: m = 0.03, n_v = 1.5, iron 2.29+3.37i, published normalization), "
            "in-plane varnished BRDF for a collimated beam and for a point source at the height d/R that makes "
            "a disc of radius R span the printed incidence range (PointSourceBRDF exact Eq. 28 superposition, "
            f"{SCAN_RESOLUTION} x {2 * SCAN_RESOLUTION} disc nodes; {step:g} deg grid).",
        )
    )
    s.blocks.append(table_block(s, "point_source_preset", list(d.point_rows[0]), d.point_rows))
    s.blocks.append(
        table_block(
            s,
            "point_source_convergence",
            list(d.convergence_rows[0]),
            d.convergence_rows,
            caption="point source -> collimated as the source recedes (energy-normalized iron plate, theta_i = 17 deg, "
            "in-plane 0..60 deg, exact method, resolution 8; validation.checks.seed001.point_source_collimated_error)",
            fmt={"max |f_point - f_collimated| / max f": ".3e"},
        )
    )
    s.tracked.update(d.tracked)


def render(s, d: Seed001Data):
    _render_albedo(s, d)
    _render_varnish(s, d)
    _render_point_source(s, d)
