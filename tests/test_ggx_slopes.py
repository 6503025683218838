"""GGX (Trowbridge-Reitz) slope distributions: normalizations (seed 000 Eq. 31-40),
conversions, sampling, and the consequences of an infinite rms slope."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, stats

from scatterbench import models
from scatterbench.models.geometry import incident_direction, scattered_direction
from scatterbench.validation.checks.seed000 import slope_conversion_errors, slope_normalization_errors

DISTRIBUTIONS = [
    models.GGXSlopes(alpha=0.01),
    models.GGXSlopes(alpha=0.3, coverage=0.7),
    models.GGXSlopes(alpha=1.0),
    models.AnisotropicGGXSlopes(alpha_x=0.1, alpha_y=0.4, rotation=0.3, coverage=0.8),
    # (beyond ~10:1 the 256-azimuth rules of the checker and of SlopeDistribution._p4_unit
    # lose digits, for every anisotropic family alike: 5e-6 at 20:1)
    models.AnisotropicGGXSlopes(alpha_x=1.0, alpha_y=0.2, rotation=-2.0),
]


@pytest.mark.parametrize("dist", DISTRIBUTIONS, ids=repr)
def test_normalizations(dist):
    """xy densities integrate to C, A densities to 1 (Eq. 31-34, 37-40), to 1e-12."""
    errors = slope_normalization_errors(dist)
    assert max(abs(v) for v in errors.values()) < 1e-12, errors


@pytest.mark.parametrize("dist", DISTRIBUTIONS, ids=repr)
def test_conversions(dist):
    errors = slope_conversion_errors(dist)
    assert max(errors.values()) < 1e-13, errors


def test_density_and_mean_sec_closed_forms():
    g = models.GGXSlopes(alpha=0.2, coverage=0.5)
    assert g.p3(0.0, 0.0) == pytest.approx(0.5 / (math.pi * 0.04), rel=1e-15)
    # <sec> = int sqrt(1 + u) alpha^2 / (alpha^2 + u)^2 du; at alpha = 1 it is 2
    assert models.GGXSlopes(alpha=1.0).mean_sec() == pytest.approx(2.0, rel=1e-12)
    # P1^xy / C = P3 / (C cos^3) = D cos with Walter et al.'s D = alpha^2 / (pi cos^4 (alpha^2 + tan^2)^2)
    t = 0.7
    d = 0.04 / (math.pi * math.cos(t) ** 4 * (0.04 + math.tan(t) ** 2) ** 2)
    assert g.p1(t, 0.3) / g.coverage == pytest.approx(d * math.cos(t), rel=1e-13)


def test_rms_slope_is_infinite_and_scale_is_alpha():
    """<zeta^2> truncated at Z grows like 2 alpha^2 ln(Z): no rms slope, so ``scale`` is alpha."""
    g = models.GGXSlopes(alpha=0.1)
    m2 = [
        integrate.quad(lambda z: z * z * float(g.p4(np.array(z))), 0, zmax, limit=200)[0]
        for zmax in (1e2, 1e4)
    ]
    assert m2[1] - m2[0] == pytest.approx(2 * 0.01 * math.log(100.0), rel=1e-6)
    assert g.scale == 0.1
    assert models.AnisotropicGGXSlopes(alpha_x=0.1, alpha_y=0.3).scale == 0.3
    assert not hasattr(g, "sigma")


def test_sampling_is_seeded_and_follows_the_radial_cdf():
    g = models.GGXSlopes(alpha=0.25)
    zx, zy = g.sample(20000, seed=7)
    zx2, zy2 = g.sample(20000, seed=7)
    assert np.array_equal(zx, zx2) and np.array_equal(zy, zy2)
    r = np.hypot(zx, zy)
    # P4 / C has CDF zeta^2 / (alpha^2 + zeta^2)
    assert stats.kstest(r, lambda z: z * z / (0.0625 + z * z)).pvalue > 1e-3
    assert stats.kstest(np.arctan2(zy, zx), stats.uniform(-math.pi, 2 * math.pi).cdf).pvalue > 1e-3


def test_anisotropic_sampling_follows_the_axis_marginals():
    """Along each rotated axis the marginal of GGX is alpha^2 / (2 (alpha^2 + u^2)^(3/2)),
    CDF (1 + u / sqrt(alpha^2 + u^2)) / 2."""
    a = models.AnisotropicGGXSlopes(alpha_x=0.1, alpha_y=0.4, rotation=0.6)
    zx, zy = a.sample(20000, seed=3)
    c, s = math.cos(0.6), math.sin(0.6)
    u, v = c * zx + s * zy, -s * zx + c * zy
    for x, al in ((u, 0.1), (v, 0.4)):
        assert stats.kstest(x, lambda t, al=al: 0.5 * (1 + t / np.sqrt(al * al + t * t))).pvalue > 1e-3


def test_anisotropic_reduces_to_isotropic_and_rotates():
    iso = models.GGXSlopes(alpha=0.3)
    ani = models.AnisotropicGGXSlopes(alpha_x=0.3, alpha_y=0.3, rotation=1.1)
    z = np.linspace(-2, 2, 41)
    assert np.allclose(ani.p3(z, 0.5 * z), iso.p3(z, 0.5 * z), rtol=1e-14, atol=0)
    rot = models.AnisotropicGGXSlopes(alpha_x=0.1, alpha_y=0.4).rotated(0.5)
    assert rot.rotation == 0.5
    assert rot.p3(0.2 * math.cos(0.5), 0.2 * math.sin(0.5)) == pytest.approx(
        models.AnisotropicGGXSlopes(alpha_x=0.1, alpha_y=0.4).p3(0.2, 0.0), rel=1e-13
    )


@pytest.mark.parametrize(
    "cls, kwargs, name",
    [
        (models.GGXSlopes, dict(alpha=0.0), "alpha"),
        (models.GGXSlopes, dict(alpha=-1.0), "alpha"),
        (models.GGXSlopes, dict(coverage=1.5), "coverage"),
        (models.AnisotropicGGXSlopes, dict(alpha_y=math.nan), "alpha_y"),
    ],
)
def test_bad_input(cls, kwargs, name):
    with pytest.raises(ValueError, match=name):
        cls(**kwargs)


def test_facet_model_with_ggx_matches_mitsubas_microfacet_form():
    """FacetBRDF(GGX) M00 = D F / (4 cos ti cos tr) with Walter's D (no shadowing)."""
    a, n = 0.3, 1.37 + 7.62j
    m = models.FacetBRDF(slopes=models.GGXSlopes(alpha=a), substrate=n)
    ti, tr, pr = 0.4, 0.9, 0.8
    ki = -incident_direction(ti)  # towards the source, as ko is towards the viewer
    ko = scattered_direction(tr, pr)
    h = (ki + ko) / np.linalg.norm(ki + ko)
    t2 = (1 - h[2] ** 2) / h[2] ** 2
    d = a * a / (math.pi * h[2] ** 4 * (a * a + t2) ** 2)
    rs2, rp2 = models.fresnel_reflectance(np.array([ki @ h]), 1.0, n)
    want = d * 0.5 * (rs2[0] + rp2[0]) / (4 * math.cos(ti) * math.cos(tr))
    assert m.brdf(ti, tr, pr) == pytest.approx(want, rel=1e-13)
