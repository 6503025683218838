"""Fresnel coefficients: Born & Wolf forms, energy, TIR, perfect conductor."""

import math

import numpy as np
import pytest

from scatterbench.models.fresnel import (
    critical_angle,
    fresnel_coefficients,
    fresnel_reflectance,
    fresnel_transmittance,
    reflection_rs_k,
)

C = np.linspace(0.0, 1.0, 1001)


@pytest.mark.parametrize("n1, n2", [(1.0, 1.5), (1.5, 1.0), (1.0, 4.0), (2.2, 1.5), (1.0, 1.0 + 1e-9)])
def test_energy_conservation_dielectric(n1, n2):
    rs2, rp2 = fresnel_reflectance(C, n1, n2)
    ts2, tp2 = fresnel_transmittance(C, n1, n2)
    np.testing.assert_allclose(rs2 + ts2, 1.0, atol=1e-13)
    np.testing.assert_allclose(rp2 + tp2, 1.0, atol=1e-13)


def test_normal_incidence_signs():
    for n in (1.5, 3.88 + 0.02j, 1.37 + 7.62j):
        rs, rp, ts, tp = fresnel_coefficients(np.array([1.0]), 1.0, n)
        assert rp[0] == pytest.approx((n - 1) / (n + 1), abs=1e-15)
        assert rs[0] == pytest.approx(-(n - 1) / (n + 1), abs=1e-15)
        assert ts[0] == pytest.approx(2 / (n + 1), abs=1e-15)
        assert tp[0] == pytest.approx(2 / (n + 1), abs=1e-15)


def test_printed_A2_is_wrong():
    """Seed 000 Eq. A.2 as printed gives r_p = 0 at normal incidence for every material."""
    n = 1.5
    printed = (n * 1.0 - math.sqrt(n * n)) / (n * 1.0 + math.sqrt(n * n))
    assert printed == 0.0
    _, rp, _, _ = fresnel_coefficients(np.array([1.0]), 1.0, n)
    assert abs(rp[0]) > 0.19


def test_brewster_angle():
    n = 1.5
    c = math.cos(math.atan(n))
    _, rp, _, _ = fresnel_coefficients(np.array([c]), 1.0, n)
    assert abs(rp[0]) < 1e-15


def test_total_internal_reflection():
    tc = critical_angle(1.5, 1.0)
    assert tc == pytest.approx(math.asin(1 / 1.5))
    c = np.cos(np.linspace(tc + 1e-9, math.pi / 2, 50))
    rs, rp, _, _ = fresnel_coefficients(c, 1.5, 1.0)
    np.testing.assert_allclose(np.abs(rs), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.abs(rp), 1.0, atol=1e-12)
    ts2, tp2 = fresnel_transmittance(c, 1.5, 1.0)
    assert np.all(ts2 == 0) and np.all(tp2 == 0)
    # evanescent branch: phase of r_s in (-pi, 0] for exp(-i w t) convention of SCATMECH
    assert np.all(rs.imag <= 0)


def test_perfect_conductor():
    rs, rp, ts, tp = fresnel_coefficients(C, 1.0, math.inf)
    assert np.all(rs == -1) and np.all(rp == 1) and np.all(ts == 0) and np.all(tp == 0)
    # a huge finite index tends to it, r_p non-uniformly: |r_p - 1| ~ 2 / (|m| cos) away
    # from grazing, while at exact grazing r_p = -1 for every finite index
    m = 1e8 * (1 + 1j)
    rs_big, rp_big, _, _ = fresnel_coefficients(C, 1.0, m)
    np.testing.assert_allclose(rs_big, -1, atol=2e-8)
    away = C >= 1e-3
    assert np.all(np.abs(rp_big[away] - 1) <= 3 / (abs(m) * C[away]))
    assert rp_big[0] == -1


def test_absorbing_reflectance_below_one():
    rs2, rp2 = fresnel_reflectance(C, 1.0, 1.37 + 7.62j)
    assert np.all(rs2 <= 1) and np.all(rp2 <= 1) and np.all(rp2 >= 0)


@pytest.mark.parametrize("m", [1.5, 1 / 1.5, 1.37 + 7.62j, (3.88 + 0.02j) / 1.5, math.inf, 1.0])
def test_rs_k_matches_definition(m):
    c = np.linspace(0.05, 0.999, 200)
    rs, K = reflection_rs_k(c, m)
    rs2, rp2, _, _ = fresnel_coefficients(c, 1.0, m)
    np.testing.assert_allclose(rs, rs2, atol=1e-14)
    np.testing.assert_allclose(K, (rs2 + rp2) / (1 - c * c), rtol=1e-9, atol=1e-12)
    # K is finite and smooth at normal incidence, where the ratio is 0/0
    rs0, K0 = reflection_rs_k(np.array([1.0]), m)
    assert np.all(np.isfinite(K0))
