"""The height-correlated Smith term in transmission (issue 31): ``B(1 + Lambda_i, 1 + Lambda_o)``,
not the reflection form ``1 / (1 + Lambda_i + Lambda_o)``, held to a direct integration of the
height-correlated model over the heights of the microsurface."""

import math

import numpy as np
import pytest
from scipy import integrate, stats

from scatterbench import models
from scatterbench.models import evaluation
from scatterbench.models.shadowing import correlated_g, smith_lambda

#: (Lambda_i, Lambda_o) pairs: normal incidence, small, the issue's 85/60 deg case at GGX
#: alpha 0.5, and large (near grazing)
PAIRS = [(0.0, 0.0), (0.0, 3.0), (0.02, 0.008), (2.40092760642889, 0.16143782776614757), (12.0, 35.0)]
#: heights of the microsurface: the Smith masking at height h is C(h)^Lambda whatever the
#: height distribution; two of them, integrated in h (not in u = C(h))
HEIGHTS = [stats.norm(0.0, 1.0), stats.uniform(-1.0, 2.0)]


def _height_integral(dist, lam_i, lam_o, transmission):
    """``int p(h) G1(i, h) G1(o, h) dh`` with the facet seen from above (``C(h)^Lambda``) or,
    in transmission, from below (``(1 - C(h))^Lambda``) by the second direction."""

    def integrand(h):
        c = dist.cdf(h)
        seen_o = (1.0 - c) ** lam_o if transmission else c**lam_o
        return dist.pdf(h) * c**lam_i * seen_o

    lo, hi = dist.ppf(1e-15), dist.ppf(1.0 - 1e-15)
    val, err = integrate.quad(integrand, lo, hi, epsabs=1e-14, epsrel=1e-12, limit=400)
    return val


@pytest.mark.parametrize("dist", HEIGHTS, ids=["gaussian heights", "uniform heights"])
@pytest.mark.parametrize("lam_i, lam_o", PAIRS)
def test_correlated_g_is_the_height_integral(dist, lam_i, lam_o):
    for transmission in (True, False):
        want = _height_integral(dist, lam_i, lam_o, transmission)
        got = float(correlated_g(lam_i, lam_o, transmission))
        assert abs(got - want) <= 1e-9 * want + 1e-14, (transmission, got, want)


def test_the_reflection_form_is_not_the_transmission_integral():
    """The check above can tell the two forms apart: at the issue's 85/60 deg case they differ
    by 28%, far beyond its 1e-9."""
    lam_i, lam_o = PAIRS[3]
    want = _height_integral(HEIGHTS[0], lam_i, lam_o, transmission=True)
    reflection_form = 1.0 / (1.0 + lam_i + lam_o)
    assert reflection_form / want - 1.0 == pytest.approx(0.2845, abs=5e-4)


def test_grazing_gives_zero_and_the_forms_agree_where_a_lambda_is_zero():
    assert float(correlated_g(np.inf, 0.5, True)) == 0.0 == float(correlated_g(0.5, np.inf, False))
    for lam in (0.0, 0.3, 7.0):
        assert float(correlated_g(0.0, lam, True)) == pytest.approx(1.0 / (1.0 + lam), rel=1e-14)


def _directions(ti, tt, pt):
    """Incident (towards the source, azimuth pi) and transmitted (below) directions."""
    return (np.cos(ti), np.sin(ti), -1.0, 0.0), (-np.cos(tt), np.sin(tt), np.cos(pt), np.sin(pt))


@pytest.mark.parametrize(
    "slopes", [models.GGXSlopes(0.5), models.GaussianSlopes(0.3)], ids=["ggx 0.5", "gaussian 0.3"]
)
def test_facet_btdf_uses_the_transmission_form(slopes):
    """FacetBTDF(shadowing="smith-correlated") is the unshadowed BTDF times B(1 + L_i, 1 + L_t)
    where both directions see the facet's front (every geometry below is such a one)."""
    rng = np.random.default_rng(31)
    ti, tt, pt = rng.uniform(0.05, 1.45, 200), rng.uniform(0.05, 1.2, 200), rng.uniform(-0.4, 0.4, 200)
    bare = models.FacetBTDF(slopes=slopes, substrate=1.5).brdf(ti, tt, pt)
    shadowed = models.FacetBTDF(slopes=slopes, substrate=1.5, shadowing="smith-correlated")
    assert evaluation.compiled(shadowed) is None  # the Beta function is numpy's path
    d_i, d_t = _directions(ti, tt, pt)
    g = correlated_g(smith_lambda(slopes, *d_i), smith_lambda(slopes, *d_t), True)
    live = bare > 0
    assert live.sum() > 100
    np.testing.assert_allclose(shadowed.brdf(ti, tt, pt)[live], (bare * g)[live], rtol=1e-12, atol=0)


def test_reflection_keeps_the_reflection_form():
    """FacetBRDF's correlated term is still 1 / (1 + L_i + L_o), kernel and numpy alike."""
    slopes = models.GGXSlopes(0.5)
    ti, tr, pr = np.radians([85.0, 40.0]), np.radians([60.0, 30.0]), np.array([0.0, 2.0])
    bare = models.FacetBRDF(slopes=slopes).brdf(ti, tr, pr)
    m = models.FacetBRDF(slopes=slopes, shadowing="smith-correlated")
    lam_i = smith_lambda(slopes, np.cos(ti), np.sin(ti), -1.0, 0.0)
    lam_o = smith_lambda(slopes, np.cos(tr), np.sin(tr), np.cos(pr), np.sin(pr))
    want = bare / (1.0 + lam_i + lam_o)
    for backend in ("numba", "numpy"):
        with models.backend(backend):
            np.testing.assert_allclose(m.brdf(ti, tr, pr), want, rtol=1e-12, atol=0)
    assert math.isfinite(float(m.brdf(0.3, 0.3, 0.0)))
