"""Seed 003 Sec. 2.4: FacetBTDF and the Fig. 1 Snell shift."""

import math

import numpy as np
import pytest

from scatterbench import models
from scatterbench.validation.checks import seed003 as c3
from scatterbench.validation.checks.fig1 import (
    EFFECTIVE_INDEX_DEG,
    effective_index,
    fit_effective_index,
    peak_angle,
    sin_mean_angles,
)
from scatterbench.validation.numerics.integrate import integrated_reflectance


def test_scatmech_btdf():
    e, lit = c3.scatmech_seed003_errors("btdf")
    assert len(e) >= 150 and lit >= 100 and e.max() < 1e-6


def test_jacobian_compact_form_equals_scatmech_form(rng):
    """dOmega_n/dOmega_t = n^2 cos(iota_t)/D^2 equals SCATMECH's jacobian (printed Eq. 39
    with theta_i restored where it prints theta_t)."""
    n = 1.7
    ti, tt, pt = rng.uniform(0, 1.4, 50), rng.uniform(0, 1.4, 50), rng.uniform(-3, 3, 50)
    c, s = np.cos, np.sin
    D2 = 1 - 2 * n * c(ti) * c(tt) - 2 * n * c(pt) * s(ti) * s(tt) + n * n
    sc = (
        n**2
        * (
            -(n * c(ti) * (3 + c(2 * tt)))
            + c(pt) * s(2 * ti) * s(tt)
            + c(tt) * c(ti) ** 2
            + c(tt) * (1 - 2 * n * c(pt) * s(ti) * s(tt) + 2 * n * n - s(ti) ** 2)
        )
        / (2 * (-c(ti) + n * c(tt)) * D2**1.5)
    )
    cg = s(ti) * s(tt) * c(pt) + c(ti) * c(tt)
    np.testing.assert_allclose(np.abs(sc), n * n * (n - cg) / D2**1.5, rtol=1e-10)


def test_unreachable_geometries_are_exact_zeros():
    m = models.FacetBTDF(slopes=models.GaussianSlopes(0.3), substrate=1.5)
    # transmitted beyond the incident direction on the forward side: n cos(gamma) < 1 or m_z < 0
    ti = math.radians(30.0)
    tt = np.radians([80.0, 89.0, 60.0])
    M = m.mueller(ti, tt, 0.0)
    assert np.all(M == 0.0)  # every one of the three
    assert np.all(m.mueller(math.pi / 2, 0.3, 0.0) == 0.0)
    assert np.all(m.mueller(0.3, math.pi / 2, 0.0) == 0.0)


def test_jones_consistent_with_mueller(rng):
    m = models.FacetBTDF(slopes=models.ExponentialSlopes(0.4), substrate=2.0)
    ti, tt, pt = rng.uniform(0, 1.4, 100), rng.uniform(0, 1.4, 100), rng.uniform(-1, 1, 100)
    np.testing.assert_allclose(
        models.jones_to_mueller(m.jones(ti, tt, pt)), m.mueller(ti, tt, pt), atol=1e-14
    )


def test_exact_normalization_conserves_energy_with_facet_reflection():
    """Exact Eq. 36 normalization: FacetBRDF (same normalization) + FacetBTDF = 1 when no
    ray is sent below the horizon (narrow slopes, moderate angle)."""
    s = models.GaussianSlopes(0.05)
    ti = math.radians(30.0)
    t = integrated_reflectance(
        models.FacetBTDF(slopes=s, substrate=1.5, convention="corrected"), ti, tol=1e-7
    )
    r = integrated_reflectance(models.FacetBRDF(slopes=s, substrate=1.5), ti, tol=1e-7)
    N = models.facet_btdf.projected_area(s, np.array([math.cos(ti)]))[0]
    assert abs(t.value + r.value * math.cos(ti) / N - 1.0) < 1e-5


def test_paper_normalization_exceeds_one_for_wide_slopes():
    printed, exact = c3.btdf_transmittances()
    assert printed > 1.0 > exact


def test_fig1_peak_and_monotonic_shift():
    sig = (0.05, 0.1, 0.3, 1.0)
    peaks = [peak_angle(s) for s in sig]
    assert abs(peaks[1] - 36.0) < 0.5  # the paper: ~36 deg for its narrowest distribution
    assert 35.26 < peaks[0] < peaks[1]
    assert np.all(np.diff(peaks) > 0) and peaks[-1] < 60.0


def test_fig1_effective_index():
    n_narrow, res = effective_index(0.05)
    assert abs(n_narrow - 1.5) / 1.5 < 0.01 and res < 0.01
    n_mid, _ = effective_index(0.3)
    n_wide, _ = effective_index(1.0)
    assert n_narrow > n_mid > n_wide and n_wide < 1.2


def test_effective_index_takes_one_form():
    """effective_index computes its own sines from sigma (no s_out to disagree with them);
    fit_effective_index fits given sines, one per incidence, and refuses any other count."""
    assert effective_index(0.3) == fit_effective_index(EFFECTIVE_INDEX_DEG, sin_mean_angles(0.3))
    with pytest.raises(TypeError):
        effective_index(0.3, s_out=sin_mean_angles(0.3))  # the old two-form call
    deg = np.array([0.0, 20.0, 40.0, 70.0])
    n_eff, res = fit_effective_index(deg, np.sin(np.radians(deg)) / 1.3)  # exactly Snell, n = 1.3
    assert abs(n_eff - 1.3) <= 1e-15 and res <= 1e-16
    for bad in (np.zeros(3), np.zeros(5), np.zeros((4, 1))):
        with pytest.raises(ValueError, match=r"s_out must hold one value per theta_i_deg \(shape \(4,\)\)"):
            fit_effective_index(deg, bad)


@pytest.mark.parametrize(
    "make, name",
    [
        (lambda: models.FacetBTDF(substrate=1.0), "substrate"),
        (lambda: models.FacetBTDF(substrate=1.5 + 0.2j), "substrate"),
        (lambda: models.FacetBTDF(slopes=0.1), "slopes"),
        (lambda: models.FacetBTDF(normalization="approx"), "normalization"),
    ],
)
def test_bad_input(make, name):
    with pytest.raises(ValueError, match=name):
        make()


def test_angle_validation_names_theta_t():
    with pytest.raises(ValueError, match="theta_t"):
        models.FacetBTDF().mueller(0.1, 2.0, 0.0)


def test_exact_normalization_refuses_anisotropic_slopes():
    with pytest.raises(ValueError, match="convention 'corrected' needs isotropic slopes"):
        models.FacetBTDF(slopes=models.AnisotropicGaussianSlopes(1.6, 0.2), convention="corrected")
