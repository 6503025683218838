"""Slope and angle distributions: normalizations and conversions of seed 000 Sec. 2.C."""

import math

import numpy as np
import pytest
from scipy import stats

from scatterbench import models
from scatterbench.validation.checks.common import slope_conversion_errors, slope_normalization_errors

DISTS = [
    models.ExponentialSlopes(sigma=0.2, coverage=0.8),
    models.ExponentialSlopes(sigma=2.0),
    models.GaussianSlopes(sigma=0.05),
    models.GaussianSlopes(sigma=0.7, coverage=0.5),
    models.AnisotropicExponentialSlopes(sigma_x=0.1, sigma_y=0.4, rotation=0.3),
    models.AnisotropicGaussianSlopes(sigma_x=0.5, sigma_y=0.2, rotation=-1.0, coverage=0.6),
    models.GaussianAngles(sigma=0.3, coverage=0.9),
    models.ExponentialAngles(sigma=0.1),
]


@pytest.mark.parametrize("dist", DISTS, ids=lambda d: repr(d))
def test_normalizations(dist):
    """Eq. 31-34 integrate to C, Eq. 37-40 to 1 (numerical quadrature, not assumed)."""
    for key, err in slope_normalization_errors(dist).items():
        assert abs(err) < 1e-8, (key, err)


@pytest.mark.parametrize("dist", DISTS, ids=lambda d: repr(d))
def test_conversions(dist):
    """Eq. 29, 30, 35, 41 hold pointwise between the representations."""
    for key, err in slope_conversion_errors(dist).items():
        assert err < 1e-12, (key, err)


def test_exponential_is_eq42_with_rms_sigma():
    d = models.ExponentialSlopes(sigma=0.3)
    z = np.linspace(0, 2, 7)
    np.testing.assert_allclose(d.p3(z, 0 * z), 3 / (math.pi * 0.09) * np.exp(-math.sqrt(6) * z / 0.3))
    # rms slope: <zeta^2> = sigma^2
    from scipy import integrate

    m2 = integrate.quad(lambda s: s * s * float(d.p4(np.array(s))), 0, np.inf)[0]
    assert m2 == pytest.approx(0.09, rel=1e-10)


def test_gaussian_rms():
    from scipy import integrate

    d = models.GaussianSlopes(sigma=0.4)
    m2 = integrate.quad(lambda s: s * s * float(d.p4(np.array(s))), 0, np.inf)[0]
    assert m2 == pytest.approx(0.16, rel=1e-10)


def test_mean_sec_matches_definition():
    d = models.GaussianSlopes(sigma=0.5, coverage=0.7)
    from scipy import integrate

    val = integrate.quad(lambda t: float(d.p2(np.array(t))) / math.cos(t), 0, math.pi / 2)[0] / 0.7
    assert d.mean_sec() == pytest.approx(val, rel=1e-9)


def test_anisotropic_reduces_to_isotropic():
    a = models.AnisotropicExponentialSlopes(sigma_x=0.3, sigma_y=0.3, rotation=1.1)
    b = models.ExponentialSlopes(sigma=0.3)
    zx, zy = np.meshgrid(np.linspace(-1, 1, 9), np.linspace(-1, 1, 9))
    np.testing.assert_allclose(a.p3(zx, zy), b.p3(zx, zy), rtol=1e-13)


def test_anisotropic_rotation():
    a = models.AnisotropicGaussianSlopes(sigma_x=0.1, sigma_y=0.5, rotation=0.0)
    b = a.rotated(math.pi / 2)
    assert b.p3(0.0, 0.3) == pytest.approx(a.p3(0.3, 0.0))


@pytest.mark.parametrize("dist", DISTS[:6], ids=lambda d: repr(d))
def test_sampling_follows_p4(dist):
    """Sampled slope magnitudes follow P4/C (Kolmogorov-Smirnov, fixed seed)."""
    zx, zy = dist.sample(20000, seed=7)
    r = np.hypot(zx, zy)
    grid = np.concatenate([[0], np.geomspace(dist.scale * 1e-6, dist.scale * 40, 4000)])
    pdf = dist.p4(grid) / dist.coverage
    cdf = np.concatenate([[0], np.cumsum(0.5 * (pdf[1:] + pdf[:-1]) * np.diff(grid))])
    res = stats.kstest(r, lambda x: np.interp(x, grid, cdf))
    assert res.pvalue > 1e-3


def test_sampling_reproducible():
    d = models.ExponentialSlopes(0.2)
    a = d.sample(100, seed=3)
    b = d.sample(100, seed=3)
    np.testing.assert_array_equal(a[0], b[0])
    c = d.sample(100, seed=4)
    assert not np.array_equal(a[0], c[0])


def test_tabulated_reproduces_exponential_and_reports_coverage():
    e = models.ExponentialSlopes(sigma=0.2)
    z = np.linspace(0, 3.0, 400)
    t = models.TabulatedSlopes(zeta=tuple(z), values=tuple(0.77 * e.p3(z, 0 * z)))
    # coverage is the Eq. 33 integral of the table (truncated at zeta = 3: ~1e-15 missing)
    assert t.coverage == pytest.approx(0.77, rel=1e-9)
    probe = np.array([0.013, 0.5, 1.7])
    np.testing.assert_allclose(t.p3(probe, 0 * probe), 0.77 * e.p3(probe, 0 * probe), rtol=1e-12)
    assert t.p3(3.5, 0.0) == 0.0
    assert t.normalized().coverage == pytest.approx(1.0, rel=1e-12)


def test_tabulated_rejects_bad_tables():
    with pytest.raises(ValueError, match="increasing"):
        models.TabulatedSlopes(zeta=(0.0, 0.2, 0.1), values=(1, 1, 1))
    with pytest.raises(ValueError, match="values"):
        models.TabulatedSlopes(zeta=(0.0, 0.2), values=(1, -1))


@pytest.mark.parametrize("a, b", [(0.05, 0.3), (0.2, 0.2), (0.4, 0.1)])
def test_stroke_slopes_second_moments(a, b):
    """Eq. 19's m_parallel and m_perpendicular are not the rms slopes along and across the
    strokes: <u^2> = a^2 b / (a + b), <v^2> = b^2 a / (a + b) (declared descriptions)."""
    s = models.StrokeSlopes(a, b, 0.0)
    # polar quadrature: Gauss-Legendre in |zeta| up to 12 m(beta)'s worth, uniform in beta
    beta = (np.arange(2048) + 0.5) * (2 * math.pi / 2048)
    x, w = np.polynomial.legendre.leggauss(200)
    rmax = 12 * max(a, b)
    r = 0.5 * rmax * (x + 1)
    R, B = np.meshgrid(r, beta, indexing="ij")
    u, v = R * np.cos(B), R * np.sin(B)
    dens = s.p3(u, v) * R * (0.5 * rmax * w)[:, None] * (2 * math.pi / 2048)
    assert abs(dens.sum() - 1) < 1e-12
    np.testing.assert_allclose((u * u * dens).sum(), a * a * b / (a + b), rtol=1e-10)
    np.testing.assert_allclose((v * v * dens).sum(), b * b * a / (a + b), rtol=1e-10)
    assert abs((u * v * dens).sum()) < 1e-15
