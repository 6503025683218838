"""Seed 003 energy properties: integrated reflectance <= 1 over random parameters."""

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from scatterbench import models
from scatterbench.validation.checks import seed003 as c3
from scatterbench.validation.numerics.integrate import integrated_reflectance


@settings(max_examples=10, deadline=None)
@given(
    n=st.floats(1.0, 3.0),
    g=st.floats(-0.99, 0.99),
    polarized=st.booleans(),
    rho=st.floats(0.0, 1.0),
    sigma=st.floats(0.02, 5.0),
    theta_i=st.floats(0.0, math.radians(89.0)),
)
def test_integrated_reflectance_at_most_one(n, g, polarized, rho, sigma, theta_i):
    for m in (
        models.SingleScatterBRDF(coating=n, phase=models.HenyeyGreenstein(g, polarized=polarized)),
        models.DiffuseSubsurfaceBRDF(coating=n, rho=rho),
        models.FacetBTDF(slopes=models.GaussianSlopes(sigma), substrate=max(n, 1.01), convention="corrected"),
    ):
        r = integrated_reflectance(m, theta_i, tol=1e-4)
        assert r.value <= 1.0 + r.error


def test_monte_carlo_energy():
    for sigma, t in ((0.5, 85.0), (2.0, 0.0)):
        v, e = c3.mc_energy(sigma, t, pairs=500, rho=1.0, single=0.0, surface=True, convention="corrected")
        assert v - 3 * e <= 1.0
    # the flat R-bar feedback under a rough interface gives more light than the rough one
    v_flat, _ = c3.mc_energy(0.5, 0.0, pairs=500, rho=1.0, single=0.0, surface=False, feedback="flat")
    v_rough, _ = c3.mc_energy(0.5, 0.0, pairs=500, rho=1.0, single=0.0, surface=False)
    assert v_flat > v_rough
