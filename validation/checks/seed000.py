"""Checks of the seed 000 models (Germer & Marx: flakes and rough surfaces under a coating).

Fresnel coefficients, slope distributions, SCATMECH agreement, reciprocity,
realizability, extremes, Table I and energy; each registered with
:func:`scatterbench.validation.checks.registry.check`.
"""

from __future__ import annotations

import math

import numpy as np

from scatterbench import models, references
from scatterbench.validation.numerics.energy import exposed_reflectance, hit_fraction
from scatterbench.validation.numerics.integrate import integrated_reflectance
from scatterbench.validation.numerics.probes import extreme_geometries, random_geometries
from scatterbench.validation.numerics.reciprocity import reciprocity_error
from scatterbench.validation.studies.findings import Finding

from .common import count_extremes, facet_suite, slope_conversion_errors, slope_normalization_errors
from .conformance_scatmech import scatmech_tolerance
from .registry import check, judge, text_section
from .table1 import compute_table1, format_table1

__all__ = ["scatmech_facet_model", "scatmech_facet_errors", "extreme_models", "energy_samples"]


# ----------------------------------------------------------------------------- Fresnel
@check(paper="seed 000 App. A, Eq. A.2-A.4 (Born & Wolf)")
def check_fresnel_energy(ctx):
    """R + T = 1 for dielectric interfaces (both directions, TIR included)."""
    c = np.linspace(0.0, 1.0, 2001)
    worst = 0.0
    for n1, n2 in [(1.0, 1.5), (1.5, 1.0), (1.0, 3.5), (2.2, 1.5), (1.33, 1.0), (1.0, 1.0001)]:
        rs2, rp2 = models.fresnel_reflectance(c, n1, n2)
        ts2, tp2 = models.fresnel_transmittance(c, n1, n2)
        worst = max(worst, float(np.max(np.abs(rs2 + ts2 - 1))), float(np.max(np.abs(rp2 + tp2 - 1))))
    return judge("fresnel: |R + T - 1| (dielectrics, TIR)", worst, 1e-12, "Born & Wolf coefficients")


@check(paper="seed 000 Eq. A.2 (slip: the square on n2/n1)")
def check_fresnel_normal(ctx):
    """At normal incidence r_p = -r_s = (n - 1)/(n + 1) (fixes seed 000 Eq. A.2)."""
    worst = 0.0
    for n2 in (1.5, 3.88 + 0.02j, 1.37 + 7.62j):
        rs, rp, ts, tp = models.fresnel_coefficients(np.array([1.0]), 1.0, n2)
        want = (n2 - 1) / (n2 + 1)
        worst = max(worst, abs(rp[0] - want), abs(rs[0] + want), abs(ts[0] - tp[0]))
    return judge("fresnel: r_p = -r_s at normal incidence", worst, 1e-15)


# ----------------------------------------------------------------------------- slopes
def _distributions():
    return [
        models.ExponentialSlopes(sigma=0.2, coverage=0.8),
        models.GaussianSlopes(sigma=0.3),
        models.AnisotropicExponentialSlopes(sigma_x=0.1, sigma_y=0.4, rotation=0.3),
        models.AnisotropicGaussianSlopes(sigma_x=0.5, sigma_y=0.2, rotation=-1.0, coverage=0.6),
        models.GaussianAngles(sigma=0.3, coverage=0.9),
        models.ExponentialAngles(sigma=0.2),
    ]


def _worst(errors_of):
    worst, where = 0.0, ""
    for d in _distributions():
        for k, v in errors_of(d).items():
            if abs(v) > worst:
                worst, where = abs(v), f"{type(d).__name__} {k}"
    return worst, where


@check(paper="seed 000 Eq. 31-34, 37-40")
def check_slope_normalizations(ctx):
    worst, where = _worst(slope_normalization_errors)
    return judge("slopes: normalizations Eq. 31-34, 37-40", worst, 1e-8, f"worst: {where}")


@check(paper="seed 000 Eq. 29, 30, 35, 41")
def check_slope_conversions(ctx):
    worst, where = _worst(slope_conversion_errors)
    return judge("slopes: conversions Eq. 29, 30, 35, 41", worst, 1e-12, f"worst: {where}")


# ----------------------------------------------------------------------------- SCATMECH
def scatmech_facet_model(ref, i):
    """``(model, coating)``: scatterbench's counterpart of case ``i`` of the committed SCATMECH
    facet references ``ref`` (:func:`scatterbench.references.scatmech_facet`) and the coating index it
    reflects under: :class:`scatterbench.models.FacetBRDF` (coating 1) for SCATMECH's
    ``Facet_BRDF_Model``, :class:`scatterbench.models.SubsurfaceFacetBRDF` with the case's coating for
    ``Subsurface_Facet_BRDF_Model`` (an overcoat of 1 included)."""
    cls = models.ExponentialSlopes if ref["sdf"][i] == "Exponential" else models.GaussianSlopes
    slopes = cls(sigma=float(ref["sigma"][i]))
    sub = complex(ref["substrate_n"][i], ref["substrate_k"][i])
    if ref["model"][i] == "facet":
        return models.FacetBRDF(slopes=slopes, substrate=sub), 1.0
    n = float(ref["coating"][i])
    return models.SubsurfaceFacetBRDF(slopes=slopes, coating=n, substrate=sub), n


def scatmech_facet_errors():
    """Per-case max ``|M - M_scatmech| / M00`` over the committed references, by model."""
    ref = references.scatmech_facet()
    errs = {"facet": [], "subsurface": []}
    for i in range(len(ref["model"])):
        m, _ = scatmech_facet_model(ref, i)
        M = m.mueller(ref["theta_i"][i], ref["theta_r"][i], ref["phi_r"][i])
        R = ref["mueller"][i]
        scale = max(abs(R[0, 0]), 1e-300)
        errs[ref["model"][i]].append(float(np.max(np.abs(M - R)) / scale))
    return {k: np.array(v) for k, v in errs.items()}


@check(paper="seed 000 Eq. 47-50 (SCATMECH Facet_BRDF_Model, Subsurface_Facet_BRDF_Model)")
def check_scatmech_facet(ctx):
    e = scatmech_facet_errors()
    return [
        judge(
            f"SCATMECH: {label} Mueller, max |dM|/M00",
            float(e[key].max()),
            scatmech_tolerance(scatmech),
            f"{len(e[key])} committed cases",
        )
        for key, label, scatmech in (
            ("facet", "FacetBRDF", "Facet_BRDF_Model"),
            ("subsurface", "SubsurfaceFacetBRDF", "Subsurface_Facet_BRDF_Model"),
        )
    ]


# ----------------------------------------------------------------------------- models
@check(paper="seed 000 Eq. 47-50 (coating n = 1 is the exposed surface)")
def check_coating_one(ctx):
    ti, tr, pr = random_geometries(2000)
    worst = 0.0
    for sub in (1.37 + 7.62j, 1.5, math.inf):
        s = models.GaussianSlopes(0.3)
        a = models.SubsurfaceFacetBRDF(slopes=s, coating=1.0, substrate=sub).mueller(ti, tr, pr)
        b = models.FacetBRDF(slopes=s, substrate=sub).mueller(ti, tr, pr)
        worst = max(worst, float(np.max(np.abs(a - b)) / np.max(np.abs(b))))
    return judge("SubsurfaceFacetBRDF(coating=1) = FacetBRDF", worst, 1e-14)


@check(paper="seed 000 Sec. 2 (Helmholtz reciprocity of Eq. 17-20, 47-50)")
def check_reciprocity(ctx):
    ti, tr, pr = random_geometries(400, seed=3)
    worst = {"scalar": 0.0, "mueller": 0.0, "jones": 0.0}
    for m in facet_suite():
        r = reciprocity_error(m, ti, tr, pr)
        worst["scalar"] = max(worst["scalar"], r.scalar)
        worst["mueller"] = max(worst["mueller"], r.mueller)
        worst["jones"] = max(worst["jones"], r.jones or 0.0)
    return [
        judge(
            "reciprocity: scalar f(i->r) = f(r->i)", worst["scalar"], 1e-10, "facet models, 400 geometries"
        ),
        judge("reciprocity: Mueller M_rev = D M^T D", worst["mueller"], 1e-10),
        judge("reciprocity: Jones J_rev = Z J^T Z", worst["jones"], 1e-10),
    ]


@check(paper="seed 000 Eq. 17-20 (a Jones matrix gives a realizable Mueller matrix)")
def check_realizability(ctx):
    ti, tr, pr = random_geometries(2000, seed=5)
    worst = 0.0
    for m in facet_suite():
        M = m.mueller(ti, tr, pr)
        ev = models.polarization.coherency_eigenvalues(M)
        scale = np.maximum(M[..., 0, 0], 1e-300)
        worst = max(worst, float(np.max(-ev[..., 0] / scale)))
    return judge("Mueller realizability: -min coherency eigenvalue / M00", worst, 1e-10)


def extreme_models():
    out = []
    for sigma in (1e-4, 0.1, 5.0):
        for cls in (models.ExponentialSlopes, models.GaussianSlopes):
            s = cls(sigma=sigma)
            for sub in (1.37 + 7.62j, 1.5, 1.0 + 0j, 1.2, math.inf):
                out.append(models.FacetBRDF(slopes=s, substrate=sub))
                for coat in (1.0, 1.5, 2.2):
                    out.append(models.SubsurfaceFacetBRDF(slopes=s, coating=coat, substrate=sub))
    return out


@check(paper="seed 000 Eq. 47-50 at the extremes (grazing, TIR, perfect conductor)")
def check_extremes(ctx):
    ti, tr, pr = extreme_geometries()
    ms = extreme_models()
    bad, warned, Ms = count_extremes(ms, ti, tr, pr, jones=True)
    grazing = (ti == math.pi / 2) | (tr == math.pi / 2)
    nonzero_grazing = sum(int(np.sum(M[grazing] != 0)) for M in Ms)
    total = bad + warned + nonzero_grazing
    return judge(
        "extremes: non-finite, negative M00, warnings",
        total,
        0,
        f"{len(ms)} models x {len(ti)} geometries (89.99 deg, specular, retro, "
        f"sigma 1e-4..5, TIR, perfect conductor): {bad} bad, {warned} warnings, "
        f"{nonzero_grazing} non-zero at exactly 90 deg",
    )


# ----------------------------------------------------------------------------- integrals
TABLE1_ROUNDING = "Table I: entries within the printed rounding"


@check(paper="seed 000 Table I", findings=(TABLE1_ROUNDING,))
def check_table1(ctx, rows=None):
    """Table I against SCATMECH, the flat limit and the printed values (``rows``:
    :func:`scatterbench.validation.checks.table1.compute_table1`'s, computed once per run)."""
    rows = ctx.compute(compute_table1)[0] if rows is None else rows
    rough = [r for r in rows if r.sigma > 0]
    flat = [r for r in rows if r.sigma == 0]
    n_round = sum(r.within_rounding for r in rows)
    unresolved = [r for r in rows if not r.within_rounding and not r.independent_agrees]
    off = "; ".join(
        f"{r.substrate} n={r.coating:g} sigma={r.sigma:g}: paper {r.printed:.2f}, here {r.computed:.4f}"
        for r in rows
        if not r.within_rounding
    )
    return [
        judge(
            "Table I: scatterbench vs SCATMECH slope-space integrals",
            max(abs(r.computed - r.independent) for r in rough),
            1e-3,
            "18 rough entries",
        ),
        judge(
            "Table I: sigma -> 0 integral vs flat closed form",
            max(abs(r.computed - r.independent) for r in flat),
            2e-4,
            "9 flat entries; sigma = 1e-3 narrow-lobe integrals",
        ),
        judge(
            TABLE1_ROUNDING,
            n_round,
            len(rows),
            (off + " (independent calculations agree with scatterbench)") if off else "",
            op=">=",
            finding=Finding(
                fails=bool(unresolved),
                fails_if="an entry outside the printed rounding is not confirmed by its independent "
                "calculation (SCATMECH or the flat limit, within 1e-3)",
            ),
        ),
    ]


@text_section
def table1_text(ctx):
    rows, seconds = ctx.compute(compute_table1)
    return f"Seed 000 Table I (theta_i = 60 deg), computed in {seconds:.2f} s", format_table1(rows)


def energy_samples():
    """``[(label, theta_i, value, error, H, exposed prediction or None)]``: integrated
    reflectances of the facet suite and the hit fractions H (validation.numerics.energy)."""
    out = []
    for m in facet_suite():
        n = getattr(m, "coating", 1.0)
        label = f"{type(m).__name__}({m.slopes}, substrate={m.substrate})"
        for ti in (0.0, 0.6, 1.2, 1.5):
            r = integrated_reflectance(m, ti, tol=1e-4)
            pred = None
            if n == 1.0 and m.slopes.isotropic:
                pred = exposed_reflectance(m.slopes, ti, m.substrate)
            out.append((label, ti, r.value, r.error, hit_fraction(m.slopes, ti, n), pred))
    return out


NO_SHADOWING = "energy: largest integrated reflectance (no-shadowing model)"


@check(paper="seed 000 Sec. 2.A, Eq. 47-50 (no shadowing)", findings=(NO_SHADOWING,))
def check_energy(ctx, samples=None):
    """Integrated reflectances against slope-space predictions (``samples``: :func:`energy_samples`)."""
    samples = energy_samples() if samples is None else samples
    exact = [abs(v - p) for _, _, v, _, _, p in samples if p is not None]
    top = max(samples, key=lambda s: s[2])
    above_where_h_le_1 = [s for s in samples if s[2] > 1.0 and s[4] <= 1.0]
    return [
        judge(
            "energy: |exposed-facet integral - slope-space prediction|",
            max(exact, default=0.0),
            1e-4,
            "integrals at tol 1e-4 vs validation.numerics.energy.exposed_reflectance",
        ),
        judge(
            "energy: integrated reflectance - hit fraction H (<= 0)",
            max(v - h - e for _, _, v, e, h, _ in samples),
            0.0,
        ),
        judge(
            NO_SHADOWING,
            top[2],
            1.0,
            "exceeds 1 only where the hit fraction H > 1 (grazing incidence on rough surfaces): "
            f"the model has no shadowing (seed 000 Sec. 2.A), as SCATMECH's; {top[0]} at ti = {top[1]} rad",
            finding=Finding(
                fails=bool(above_where_h_le_1),
                fails_if="an integrated reflectance above 1 where the hit fraction H <= 1 "
                f"({len(above_where_h_le_1)} of {len(samples)} here)",
            ),
        ),
    ]
