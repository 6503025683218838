"""Seed 003 Sec. 2.1-2.3: HenyeyGreenstein, SingleScatterBRDF, DiffuseSubsurfaceBRDF."""

import math

import numpy as np
import pytest
from scipy import integrate

from scatterbench import models
from scatterbench.validation.checks import seed003 as c3
from scatterbench.validation.numerics.integrate import integrated_reflectance


@pytest.mark.parametrize("g", [-0.95, -0.5, 0.0, 0.3, 0.8, 0.95])
@pytest.mark.parametrize("polarized", [True, False])
def test_hg_normalization_and_mean_cos(g, polarized):
    norm, mean = c3.hg_moments(g, polarized)
    assert abs(norm) < 1e-10
    assert abs(mean) < 1e-10


def test_printed_eq2_sign_gives_minus_g():
    """The slip: with 1 + 2 g cos + g^2 (Eq. 2 as printed) <cos theta> = -g."""
    g = 0.6

    def printed(c):
        return (1 - g * g) / (4 * math.pi * (1 + 2 * g * c + g * g) ** 1.5)

    mean = 2 * math.pi * integrate.quad(lambda c: c * printed(c), -1, 1, epsabs=1e-13)[0]
    assert mean == pytest.approx(-g, abs=1e-10)


def test_polarized_phase_unpolarized_probability_is_hg(rng):
    """Eq. 6-7: in any bases, M00 of the polarized phase matrix is the scalar HG density.
    At n = 1 (no interface) f = P(k1, k2) / (cos ti + cos tr), so M00 checks Eq. 13's
    internal Jones elements too (the printed signs of q_ps and q_pp would break it)."""
    ph = models.HenyeyGreenstein(0.4, polarized=True)
    m = models.SingleScatterBRDF(coating=1.0, phase=ph)
    ti, tr, pr = rng.uniform(0, 1.5, 200), rng.uniform(0, 1.5, 200), rng.uniform(-3, 3, 200)
    cos_scat = np.sin(ti) * np.sin(tr) * np.cos(pr) - np.cos(ti) * np.cos(tr)
    want = ph.density(cos_scat) / (np.cos(ti) + np.cos(tr))
    np.testing.assert_allclose(m.brdf(ti, tr, pr), want, rtol=1e-13)
    np.testing.assert_allclose(m.mueller(ti, tr, pr)[..., 0, 0], want, rtol=1e-13)
    # a Rayleigh-Gans matrix is non-depolarizing: it comes from the Jones matrix
    J = m.jones(ti, tr, pr)
    np.testing.assert_allclose(models.jones_to_mueller(J), m.mueller(ti, tr, pr), atol=1e-15)


def test_scatmech_single_and_diffuse():
    e, _ = c3.scatmech_seed003_errors("single")
    assert len(e) >= 150 and e.max() < 1e-6
    e, _ = c3.scatmech_seed003_errors("diffuse")
    assert len(e) >= 150 and e.max() < 2e-3


def test_rbar_exact():
    for n in (1.01, 1.5, 2.5):
        assert abs(models.DiffuseSubsurfaceBRDF(coating=n).rbar - c3._rbar_composite(n)) < 1e-12
    assert models.DiffuseSubsurfaceBRDF(coating=1.0).rbar == 0.0


@pytest.mark.parametrize("n", [1.0, 1.3, 1.5, 2.0, 2.5])
def test_unit_albedo(n):
    m = models.DiffuseSubsurfaceBRDF(coating=n, rho=1.0)
    for t in (0.0, 40.0, 85.0):
        ti = math.radians(t)
        r = integrated_reflectance(m, ti, tol=1e-9)
        assert abs(c3._specular(n, ti) + r.value - 1.0) < 1e-6


def test_printed_eq22_breaks_unit_albedo():
    assert c3.printed_eq22_albedo() < 0.99


def test_broadcast_shapes_and_grazing_zeros():
    for m in (
        models.SingleScatterBRDF(coating=1.5, phase=models.HenyeyGreenstein(0.3)),
        models.SingleScatterBRDF(coating=1.0, phase=models.HenyeyGreenstein(-0.99, polarized=False)),
        models.DiffuseSubsurfaceBRDF(coating=1.0, rho=1.0),
    ):
        M = m.mueller(np.array([[0.1], [0.5], [1.0]]), np.array([0.2, 0.4, 0.6, 0.8]), 0.3)
        assert M.shape == (3, 4, 4, 4)
        assert np.all(m.mueller(math.pi / 2, [0.0, 0.5, math.pi / 2], 0.0) == 0.0)
        assert np.all(np.isfinite(m.mueller(math.radians(89.99), math.radians(89.99), 0.0)))


def test_depolarizing_single_structure():
    m = models.SingleScatterBRDF(coating=1.5, phase=models.HenyeyGreenstein(0.3, polarized=False))
    M = m.mueller(0.4, 0.9, 1.0)
    assert np.all(M[2:, :] == 0) and np.all(M[:, 2:] == 0)
    assert m.depolarizing and not models.SingleScatterBRDF().depolarizing
    with pytest.raises(NotImplementedError):
        m.jones(0.4, 0.9, 1.0)


@pytest.mark.parametrize(
    "make, name",
    [
        (lambda: models.HenyeyGreenstein(g=1.0), "g"),
        (lambda: models.HenyeyGreenstein(g=-1.2), "g"),
        (lambda: models.HenyeyGreenstein(g=0.1, polarized="yes"), "polarized"),
        (lambda: models.DiffuseSubsurfaceBRDF(rho=1.01), "rho"),
        (lambda: models.DiffuseSubsurfaceBRDF(coating=0.9), "^coating"),
        (lambda: models.SingleScatterBRDF(coating=1.5 + 0.1j), "^coating"),
        (lambda: models.SingleScatterBRDF(phase=0.3), "phase"),
    ],
)
def test_bad_input(make, name):
    with pytest.raises(ValueError, match=name):
        make()


def test_rbar_float_integrand_gives_the_complex_forms_bits():
    """R-bar's quadrature integrates 0.5 (Rs + Rp) 2c in floats (a fit meets a new index per
    walker and wavelength at every step); it gives the bits of fresnel's complex form, and so
    the same R-bar, from just above 1 to the largest index."""
    from scatterbench.models.fresnel import _reflectance
    from scatterbench.models.smooth_interface import _rbar

    def complex_form(n):
        def f(c):
            rs, rp = _reflectance(np.array([c]), 1.0, n)
            return float(rs[0] + rp[0]) * c

        pts = [min(0.5, 10.0 * math.sqrt(n * n - 1.0))]
        val, _ = integrate.quad(f, 0.0, 1.0, points=pts, epsabs=1e-14, epsrel=1e-12, limit=200)
        return 1.0 - (1.0 - val) / (n * n)

    rng = np.random.default_rng(7)
    for n in [1.0 + 1e-9, 1.0003, 1.33, 1.5, 2.4, 7.0, 1e4, 4.0 / np.finfo(float).eps] + list(
        rng.uniform(1.0, 3.0, 12)
    ):
        _rbar.cache_clear()
        assert _rbar(float(n)) == complex_form(float(n)), n
    assert _rbar(math.inf) == 1.0


def test_rbar_compiled_integrand_gives_the_python_quadratures_bits(monkeypatch):
    """R-bar's quadrature with the compiled integrand (``kernels.rbar``, through QUADPACK's
    ``qagpe`` directly: 20x faster, a fit meets 96 new indices per batch) gives the bits of
    ``quad`` with the Python integrand, over a dense grid of indices from just above 1 to
    1e150; where QUADPACK reports a problem (an index whose square overflows) it gives nothing
    and ``_rbar`` takes ``quad``, which warns as before; without numba (no ``ctypes``) too."""
    from scatterbench.models import kernels  # noqa: F401  (loading the kernels hands R-bar its integrand)
    from scatterbench.models import smooth_interface as si

    ns = np.concatenate(
        [1.0 + np.logspace(-15.5, 0.0, 600), np.linspace(1.0001, 4.0, 600), np.logspace(0.6, 150.0, 300)]
    )
    for n in ns:
        point = min(0.5, 10.0 * math.sqrt(n * n - 1.0))
        got = si._compiled_quad(n * n, point)
        assert got is not None and got == si._python_quad(n * n, point), n
    assert si._compiled_quad(math.inf, 0.5) is None  # n^2 overflowed: the integrand is NaN
    si._rbar.cache_clear()
    fast = [si._rbar(float(n)) for n in ns[::10]]
    monkeypatch.setattr(si, "_compiled_integrand", lambda: None)
    si._rbar.cache_clear()
    assert fast == [si._rbar(float(n)) for n in ns[::10]]
    si._rbar.cache_clear()
