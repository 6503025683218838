"""RoughSubsurfaceBRDF: seed 003 Sec. 2.5's totally diffuse term as its expectation over facet
pairs, by quadrature; held to the Monte Carlo model, to its own rule at high order, to energy
conservation at unit albedo, and (compiled) to its numpy reference."""

import math

import numpy as np
import pytest

from scatterbench import models
from scatterbench.models import GaussianSlopes, RoughDiffuseBRDF, RoughSubsurfaceBRDF
from scatterbench.models.rough_subsurface import transmission_at, transmission_factor

GEOMETRIES = (
    np.array([0.2, 1.0, 1.2, 0.0, 1.45]),
    np.array([0.5, 0.7, 1.3, 0.9, 0.1]),
    np.array([0.3, 2.0, -1.0, 0.0, 2.5]),
)


@pytest.mark.parametrize("feedback", ["flat", "rough"])
def test_equals_the_monte_carlo_expectation(feedback):
    """The Monte Carlo model without single scattering or surface term, 400 000 facet pairs:
    each of the four non-zero elements within 4 of its standard errors (fails if the exit
    factor were not the entry's, or ``cos 2 eta``'s sign were the other), the twelve others
    zero here and within 4 standard errors there."""
    kw = dict(slopes=GaussianSlopes(0.5), coating=1.35, rho=0.9, feedback=feedback)
    mc = RoughDiffuseBRDF(single=0.0, surface=False, pairs=400_000, seed=3, **kw)
    M, err = mc.mueller_with_error(*GEOMETRIES)
    Q = RoughSubsurfaceBRDF(**kw).mueller(*GEOMETRIES)
    live = err > 0
    z = np.abs(M - Q)[live] / err[live]
    assert np.max(z) < 4.0, np.max(z)
    assert np.all(M[~live] == Q[~live])  # the Monte Carlo's exact zeros are the model's
    assert np.all(Q[:, 2:, :] == 0) and np.all(Q[:, :2, 2:] == 0)


def test_within_its_stated_accuracy_of_the_rule_at_high_order():
    """The model (17 Chebyshev nodes a panel, 20 x 10 slope nodes) against the slope quadrature
    itself at 40 x 24 nodes, at each cosine without interpolation: within 1e-5 of ``t0`` at
    normal incidence for slope widths 0.01-1.5 and indices 1.2-1.7 (the module's statement;
    measured worst 2.7e-6, at sigma 1.5)."""
    us = np.concatenate([np.geomspace(1e-4, 0.1, 12), np.linspace(0.1, 0.9999, 18)])
    worst = 0.0
    for n in (1.2, 1.7):
        for sigma in (0.01, 0.05, 0.5, 1.5):
            t0, t1 = transmission_at(sigma, n, us, radial=40, arc=24)
            m = RoughSubsurfaceBRDF(slopes=GaussianSlopes(sigma), coating=n, rho=0.5)
            with models.backend("numpy"):
                M = m.mueller(np.arccos(us), 0.0, 0.0)  # M0b = S t0(1) t_b(theta_i)
            scale = M[-1, 0, 0] / t0[-1]
            worst = max(
                worst, np.max(np.abs(M[:, 0, 0] / scale - t0)), np.max(np.abs(M[:, 0, 1] / scale - t1))
            )
    assert worst < 1e-5, worst


def test_unit_albedo_returns_what_entered():
    """``rho = 1`` with the rough R-bar: the scattered light, integrated over the hemisphere,
    is the fraction that entered, ``t0(theta_i)`` (Gauss-Legendre in ``cos theta_r``: the
    integrand is the model's own series); the flat R-bar gains light under a rough interface."""
    m = RoughSubsurfaceBRDF(slopes=GaussianSlopes(0.6), coating=1.4, rho=1.0)
    x, w = np.polynomial.legendre.leggauss(64)
    u = 0.5 * (x + 1.0)
    for ti in (0.0, 0.6, 1.2):
        f = m.mueller(ti, np.arccos(u), 0.0)[:, 0, 0]
        total = 2.0 * math.pi * np.sum(0.5 * w * f * u)
        entered = transmission_at(0.6, 1.4, np.cos([ti]))[0][0]
        assert abs(total / entered - 1.0) < 1e-6
        flat = m.replace(feedback="flat").mueller(ti, np.arccos(u), 0.0)[:, 0, 0]
        assert 2.0 * math.pi * np.sum(0.5 * w * flat * u) > 1.001 * entered


def test_tends_to_the_smooth_interface():
    """A narrow interface (sigma 0.003) gives the smooth-interface diffuser of Sec. 2.3 (flat
    R-bar both) within 1e-4 of the largest M00 away from grazing (measured 1.0e-6)."""
    ti, tr, pr = np.array([0.0, 0.5, 1.0]), np.array([0.3, 0.8, 0.2]), np.array([0.0, 1.0, 3.0])
    rough = RoughSubsurfaceBRDF(slopes=GaussianSlopes(0.003), coating=1.5, rho=0.8, feedback="flat")
    smooth = models.DiffuseSubsurfaceBRDF(coating=1.5, rho=0.8)
    a, b = rough.mueller(ti, tr, pr), smooth.mueller(ti, tr, pr)
    assert np.max(np.abs(a - b)) < 1e-4 * np.max(b[:, 0, 0])


def test_kernel_holds_to_numpy_and_model_sets():
    """Compiled against numpy within 1e-12 of M00: one model, a model set (its elements' own
    tables), and a fit's fused route (``indexed_kernel``'s range writer, element per geometry)."""
    rng = np.random.default_rng(1)
    ti, tr, pr = rng.uniform(0, 1.5, 300), rng.uniform(0, 1.5, 300), rng.uniform(-3, 3, 300)
    sig = np.array([0.05, 0.4, 0.4, 1.2])
    n = np.array([1.3, 1.3, 1.6, 1.45])
    rho = np.array([0.9, 0.5, 1.0, 0.2])
    for m in (
        RoughSubsurfaceBRDF(slopes=GaussianSlopes(0.3), coating=1.4, rho=0.7),
        RoughSubsurfaceBRDF(slopes=GaussianSlopes(sig[:, None]), coating=n[:, None], rho=rho[:, None]),
    ):
        with models.backend("numpy"):
            ref = m.mueller(ti, tr, pr)
        got = m.mueller(ti, tr, pr)
        assert np.max(np.abs(got - ref)) <= 1e-12 * np.max(np.abs(ref[..., 0, 0]))
    flat = RoughSubsurfaceBRDF(slopes=GaussianSlopes(sig), coating=n, rho=rho)
    index = rng.integers(0, 4, 300)
    with models.backend("numpy"):
        ref = flat.flat_mueller16_indexed(index, ti, tr, pr, np.empty((16, 300)))
    kernel, idx = flat.indexed_kernel(index)
    buf = np.empty((16, 300))
    kernel.range_writer()(ti, tr, pr, idx, buf, 0, 300)
    assert np.max(np.abs(buf - ref)) <= 1e-12 * np.max(np.abs(ref[0]))
    with pytest.raises(ValueError, match="index"):
        flat.indexed_kernel(np.array([0, 4]))


def test_refuses_what_it_does_not_integrate():
    with pytest.raises(ValueError, match="slopes"):
        RoughSubsurfaceBRDF(slopes=models.ExponentialSlopes(0.3))
    with pytest.raises(ValueError, match="coverage"):
        RoughSubsurfaceBRDF(slopes=GaussianSlopes(0.3, coverage=0.5))
    with pytest.raises(ValueError, match="nodes"):
        RoughSubsurfaceBRDF(nodes=2)
    with pytest.raises(ValueError, match="coating"):
        RoughSubsurfaceBRDF(coating=0.9)


def test_transmission_factor_nodes_and_rbar_flat_limit():
    """The u-nodes lie inside (0, 1) on two panels; the rough R-bar of a narrow interface is the
    flat one (within 1e-5; measured 8.0e-7 at sigma 0.002)."""
    u, t0, t1 = transmission_factor(0.2, 1.5)
    assert u.shape == t0.shape == t1.shape == (34,) and 0 < u.min() and u.max() < 1
    flat = models.DiffuseSubsurfaceBRDF(coating=1.5).rbar
    assert abs(RoughSubsurfaceBRDF(slopes=GaussianSlopes(0.002), coating=1.5).rbar - flat) < 1e-5
