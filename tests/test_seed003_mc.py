"""Seed 003 Sec. 2.5: RoughDiffuseBRDF (Monte Carlo), presets and combinations."""

import math

import numpy as np
import pytest

from scatterbench import models, references
from scatterbench.models import scene
from scatterbench.models.geometry import incident_direction
from scatterbench.validation.checks import seed003 as c3

KW = dict(slopes=models.ExponentialSlopes(0.5), coating=1.5, phase=models.HenyeyGreenstein(0.3), rho=0.3)
G = c3._GEOM


def test_same_seed_same_numbers_and_generator():
    a = models.RoughDiffuseBRDF(pairs=300, seed=4, **KW).mueller(*G)
    b = models.RoughDiffuseBRDF(pairs=300, seed=4, **KW).mueller(*G)
    c = models.RoughDiffuseBRDF(pairs=300, seed=np.random.default_rng(4), **KW).mueller(*G)
    d = models.RoughDiffuseBRDF(pairs=300, seed=5, **KW).mueller(*G)
    assert np.array_equal(a, b) and np.array_equal(a, c) and not np.array_equal(a, d)


def test_batching_independent():
    m = models.RoughDiffuseBRDF(pairs=400, seed=1, **KW)
    whole = m.mueller(*G)
    single = np.stack([m.mueller(G[0][k], G[1][k], G[2][k]) for k in range(len(G[0]))])
    np.testing.assert_allclose(whole, single, rtol=1e-13, atol=1e-300)
    assert m.mueller(np.zeros((2, 3)), 0.4, 0.1).shape == (2, 3, 4, 4)


@pytest.mark.parametrize("polarized", [True, False])
def test_converges_to_smooth_models(polarized):
    z, rel = c3.mc_convergence_z(sigma=0.001, pairs=2000, polarized=polarized)
    assert z < 4.0 and rel < 1e-3


def test_error_falls_as_inverse_sqrt_pairs():
    kw = dict(KW, surface=False)
    se = [
        models.RoughDiffuseBRDF(pairs=p, seed=0, **kw).mueller_with_error(*G)[1][..., 0, 0]
        for p in (500, 8000)
    ]
    ratio = se[0] / se[1]
    assert np.all(np.abs(ratio / 4.0 - 1.0) < 0.15)  # sqrt(8000/500) = 4


def test_surface_term_is_the_exposed_facet_brdf():
    with_s = models.RoughDiffuseBRDF(pairs=200, seed=0, surface=True, **KW)
    without = models.RoughDiffuseBRDF(pairs=200, seed=0, surface=False, **KW)
    facet = models.FacetBRDF(slopes=KW["slopes"], substrate=1.5)
    np.testing.assert_allclose(
        with_s.mueller(*G) - without.mueller(*G), facet.mueller(*G), rtol=1e-12, atol=1e-15
    )
    _, e1 = with_s.mueller_with_error(*G)
    _, e2 = without.mueller_with_error(*G)
    assert np.array_equal(e1, e2)


def test_acceptance_generator_matches_weights():
    """The acceptance scheme (second generator) and the importance weights the model uses
    describe the same distribution of struck facets: compare moments."""
    s = models.ExponentialSlopes(0.5)
    ti = math.radians(60)
    k = incident_direction(ti)
    zx, zy = models.rough_diffuse.sample_normals_seen_by(s, k, 40000, seed=1)
    x, y = s.sample(400000, 2)
    w = np.maximum(math.cos(ti) - k[0] * x, 0.0)
    for f_acc, f_w in ((zx, x), (zx * zx + zy * zy, x * x + y * y)):
        a = f_acc.mean()
        b = np.sum(w * f_w) / np.sum(w)
        assert abs(a - b) < 4 * f_acc.std() / math.sqrt(len(f_acc)) + 2e-3
    N = models.facet_btdf.projected_area(s, np.array([math.cos(ti)]))[0]
    assert abs(N - w.mean()) < 4 * w.std() / math.sqrt(len(w))
    assert zx.mean() < -0.05  # facets tilted toward the source are struck more often


@pytest.mark.parametrize(
    "kw, name",
    [
        (dict(seed=-1), "seed"),
        (dict(seed=1.5), "seed"),
        (dict(pairs=1), "pairs"),
        (dict(rho=2.0), "rho"),
        (dict(slopes=models.AnisotropicGaussianSlopes(sigma_x=0.1, sigma_y=0.2)), "slopes"),
        (dict(phase="hg"), "phase"),
        (dict(slopes=models.GaussianSlopes(0.3, coverage=0.5)), "slopes"),
    ],
)
def test_bad_input(kw, name):
    with pytest.raises(ValueError, match=name):
        models.RoughDiffuseBRDF(**{**KW, "pairs": 10, **kw})


def test_presets():
    presets = references.seed003_presets()
    assert list(presets) == ["glossy_white", "green_carc", "red_paint"]
    for p in presets.values():
        assert {"sample", "figure", "source", "printed", "scene"} <= set(p)
        sc = scene.load(p["scene"])
        assert sc.wavelength_nm > 0 and sc.theta_i == math.radians(60)
        M = sc.build().mueller(math.radians(60), np.radians([10, 40, 70]), 0.0)
        assert np.all(np.isfinite(M)) and np.all(M[..., 0, 0] > 0)
    white = scene.load(presets["glossy_white"]["scene"]).build()
    pol = white.polarization(math.radians(60), np.radians([20, 70]), 0.0, "+45")
    np.testing.assert_allclose(np.abs(pol["eta"]), math.pi / 2)  # the paper: eta = +-90 deg


def test_combination_errors():
    mc = models.RoughDiffuseBRDF(pairs=500, seed=0, **KW)
    det = models.DiffuseSubsurfaceBRDF(coating=1.5, rho=0.5)
    s = 0.5 * mc + 2.0 * det
    M, E = models.mueller_with_error(s, *G)
    Mm, Em = mc.mueller_with_error(*G)
    np.testing.assert_allclose(M, 0.5 * Mm + 2.0 * det.mueller(*G), rtol=1e-13, atol=1e-16)
    np.testing.assert_allclose(E, 0.5 * Em, rtol=1e-13)
    np.testing.assert_allclose(s.mueller(*G), M, rtol=1e-13, atol=1e-16)


def test_maxwell_beard_shadow_is_exact_at_retroreflection():
    """At retroreflection the source and the detector coincide: beta = 0 and SO = 1
    (Maxwell-Beard's obscuration vanishes).  ``np.pi`` is 1.2e-16 short of pi, so at
    (t, t, np.pi) beta = sin(t) sin(np.pi) / 2 and theta_N = t, and SO is known to an ulp;
    beta = arccos(sqrt((1 + a.b) / 2)) turned an ulp of that cosine into beta ~ 1e-8, SO off
    by ~1e-6 at tau = 0.01 (it fails so).  1e-7 rad away from it the kernel holds the numpy
    path to 1e-12 (the polynomial cosines on SIMD lanes gave 1.7e-10 there)."""
    t = np.linspace(0.0, 1.5, 301)
    pi = np.full(t.size, np.pi)
    for omega in (0.01, 1.0):
        so = models.maxwell_beard.maxwell_beard_shadow(t, t, pi, 0.01, omega)
        x = t / omega
        want = (1.0 + x * np.exp(-np.sin(t) * np.sin(np.pi) / 0.01)) / (1.0 + x)
        assert np.max(np.abs(so - want)) < 1e-15
    m = models.MaxwellBeardBRDF(slopes=models.GaussianSlopes(0.3), tau=0.01, omega=0.01, polarized=True)
    rng = np.random.default_rng(5)
    ti = rng.uniform(0.0, 1.5, 2000)
    tr, pr = np.abs(ti + rng.uniform(-1e-7, 1e-7, ti.size)), np.pi + rng.uniform(-1e-7, 1e-7, ti.size)
    with models.backend("numpy"):
        ref = m.mueller(ti, tr, pr)
        assert np.max(np.abs(m.mueller(t, t, pi)[..., 0, 0] - m._facet.brdf(t, t, pi))) <= 1e-14 * np.max(ref)
    got = m.mueller(ti, tr, pr)
    assert np.max(np.abs(got - ref)) <= 1e-12 * np.max(ref[..., 0, 0])


def test_maxwell_beard_against_scatmech_and_terms():
    e, lit = c3.scatmech_seed003_errors("mb")
    assert len(e) == 100 and lit > 80 and e.max() < 1e-6
    s = models.GaussianSlopes(0.2)
    mb = models.MaxwellBeardBRDF(slopes=s, substrate=1.5, rho_d=0.1, rho_v=0.05, tau=0.3, omega=0.6)
    ti, tr, pr = G
    so = models.maxwell_beard.maxwell_beard_shadow(ti, tr, pr, 0.3, 0.6)
    assert np.all((so > 0) & (so <= 1))
    want = (
        models.FacetBRDF(slopes=s, substrate=1.5).brdf(ti, tr, pr) * so
        + 0.1
        + 0.1 / (np.cos(ti) + np.cos(tr))
    )
    np.testing.assert_allclose(mb.brdf(ti, tr, pr), want, rtol=1e-13)
    M = mb.mueller(ti, tr, pr)
    assert np.all(M[..., 1:, :] == 0) and np.all(M[..., :, 1:] == 0)  # published form: scalar
    with pytest.raises(ValueError, match="tau"):
        models.MaxwellBeardBRDF(tau=0.0)
