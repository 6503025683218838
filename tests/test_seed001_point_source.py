"""Seed 001 Eq. 25-30: the point-source wrapper (exact superposition and shift approximation)."""

import math
import subprocess
import sys

import numpy as np
import pytest

from scatterbench import models, references
from scatterbench.validation.checks import seed001 as c
from scatterbench.validation.numerics.reciprocity import reciprocity_error

BASE = c.energy_published(models.VarnishedCookTorranceBRDF())


def test_infinite_distance_is_the_model(rng):
    ti, tr = rng.uniform(0, 1.5, (2, 500))
    pr = rng.uniform(-3, 3, 500)
    for method in ("exact", "shift"):
        ps = models.PointSourceBRDF(model=BASE, distance=math.inf, method=method)
        np.testing.assert_array_equal(ps.mueller(ti, tr, pr), BASE.mueller(ti, tr, pr))


@pytest.mark.parametrize("method", ["exact", "shift"])
def test_tends_to_collimated_second_order(method):
    e = c.point_source_collimated_error((1e2, 1e3, 1e4), method=method)
    assert e[1e4] < 1e-6
    assert 70 < e[1e3] / e[1e4] < 130 and 70 < e[1e2] / e[1e3] < 130  # (R/d)^2


def test_nodes_and_incidence_range():
    ps = models.PointSourceBRDF(model=BASE, distance=1.0, sample_radius=1.0, resolution=12)
    psi, Phi, w = ps.source_nodes(0.0)
    np.testing.assert_allclose(w.sum(), 1.0, rtol=1e-14)
    assert psi.max() < math.pi / 4 and psi.max() > math.pi / 4 - 0.02
    assert ps.incidence_range(0.0) == pytest.approx((0.0, math.pi / 4))
    # Quadrature weights integrate the disc area exactly (before the cos^3 weight).
    px, py, wa = ps._disc_nodes(ps.resolution)
    assert wa.sum() == pytest.approx(math.pi, rel=1e-13)
    assert np.sum(wa * (px * px + py * py)) == pytest.approx(math.pi / 2, rel=1e-12)


def test_exact_converges_with_resolution():
    ti = math.radians(17)
    tr = np.radians(np.linspace(5, 30, 101))
    ref = models.PointSourceBRDF(model=BASE, distance=3.0, resolution=48).brdf(ti, tr, 0.0)
    errs = [
        np.abs(models.PointSourceBRDF(model=BASE, distance=3.0, resolution=r).brdf(ti, tr, 0.0) - ref).max()
        / ref.max()
        for r in (4, 8, 16)
    ]
    assert errs[0] > errs[1] > errs[2] and errs[2] < 1e-6


def test_shift_grid_matches_pointwise_shift():
    """Eq. 30 by FFT correlation reproduces the pointwise Eq. 29 sum up to the
    bilinear interpolation of the central BRDF, which falls as the grid is refined
    (measured 2.9e-4, 9.5e-5, 5.3e-5 of the peak for 61, 121, 241 theta nodes)."""
    m = models.CookTorranceBRDF(slopes=models.GaussianSlopes(0.3), convention="corrected")
    ti = math.radians(30)
    errs = []
    for n in (61, 121, 241):
        tr = np.radians(np.linspace(0, 60, n))
        pr = np.radians(np.linspace(-20, 20, n // 2 + 1))
        ps = models.PointSourceBRDF(model=m, distance=3.0, resolution=8, method="shift")
        T, P = np.meshgrid(tr, pr, indexing="ij")
        a = ps.brdf_grid(ti, tr, pr)
        b = ps.brdf(ti, T, P)
        errs.append(np.abs(a - b).max() / b.max())
    # Falls roughly linearly with the spacing: the negative-theta continuation through
    # the normal has a kink at theta = 0 that bilinear interpolation resolves to O(h).
    assert errs[0] > errs[1] > errs[2] and errs[2] < 1e-4


def test_exact_grid_is_pointwise():
    ps = models.PointSourceBRDF(model=BASE, distance=5.0, resolution=4)
    tr = np.radians(np.linspace(10, 20, 5))
    pr = np.radians(np.linspace(-1, 1, 3))
    T, P = np.meshgrid(tr, pr, indexing="ij")
    np.testing.assert_array_equal(ps.brdf_grid(0.3, tr, pr), ps.brdf(0.3, T, P))


def test_anisotropic_path_equals_isotropic_path():
    """An anisotropic-type model with equal widths goes through the per-node
    rotation loop; it must agree with the vectorized isotropic path."""
    iso = models.FacetBRDF(slopes=models.GaussianSlopes(0.2), substrate=2.29 + 3.37j)
    ani = models.FacetBRDF(slopes=models.AnisotropicGaussianSlopes(0.2, 0.2, 0.4), substrate=2.29 + 3.37j)
    tr = np.radians(np.linspace(0, 80, 17))
    a = models.PointSourceBRDF(model=iso, distance=2.0, resolution=5).mueller(0.4, tr, 0.3)
    b = models.PointSourceBRDF(model=ani, distance=2.0, resolution=5).mueller(0.4, tr, 0.3)
    np.testing.assert_allclose(b, a, rtol=1e-10, atol=1e-14 * np.abs(a).max())


def test_not_reciprocal_and_by_how_much():
    """The wrapper is declared non-reciprocal; measured over geometries carrying >= 1e-3
    of the peak: ~100% at d = R, ~57% at d = 10 R, ~0.9% at d = 100 R (validate reports it)."""
    ps = models.PointSourceBRDF(model=BASE, distance=1.0, resolution=8)
    assert ps.reciprocal is False
    nr = c.point_source_nonreciprocity((1.0, 10.0, 100.0), n=120)
    assert nr[1.0] > 0.5 and nr[10.0] > 0.1 and nr[100.0] > 1e-3
    assert nr[1.0] > nr[10.0] > nr[100.0]
    # and the collimated model is reciprocal at the same geometries
    rng = np.random.default_rng(0)
    ti, tr = rng.uniform(0, 1.4, (2, 50))
    assert reciprocity_error(BASE, ti, tr, 0.1).scalar < 1e-12


def test_preset_ranges():
    for lo, hi in references.IRON_PLATE["incidence_ranges_deg"]:
        psi_c, d = models.point_source_geometry(lo, hi)
        ps = models.PointSourceBRDF(model=BASE, distance=d)
        a, b = ps.incidence_range(psi_c)
        assert math.degrees(a) == pytest.approx(lo, abs=1e-9) and math.degrees(b) == pytest.approx(
            hi, abs=1e-9
        )
    # the models built from the preset: iron 2.29+3.37i at 650 nm, m = 0.03, varnish n_v = 1.5
    bare, varnished = c.iron_plate_models()
    iron = 2.29 + 3.37j
    assert bare == models.CookTorranceBRDF(
        slopes=models.GaussianSlopes(0.03), substrate=iron, convention="paper"
    )
    assert varnished == models.VarnishedCookTorranceBRDF(
        slopes=models.StrokeSlopes(0.03, 0.03), coating=1.5, substrate=iron, convention="paper"
    )
    assert {m.convention for m in c.iron_plate_models("corrected")} == {"corrected"}


@pytest.mark.parametrize(
    "kw, name",
    [
        ({"distance": 0.0}, "distance"),
        ({"distance": -1.0}, "distance"),
        ({"distance": "far"}, "distance"),
        ({"distance": float("nan")}, "distance"),
        ({"sample_radius": 0.0}, "sample_radius"),
        ({"resolution": 0}, "resolution"),
        ({"method": "fft"}, "method"),
        ({"model": "CookTorrance"}, "model"),
    ],
)
def test_bad_input(kw, name):
    args = {"model": BASE, **kw}
    with pytest.raises(ValueError, match=name):
        models.PointSourceBRDF(**args)


def test_bad_grid():
    ps = models.PointSourceBRDF(model=BASE, distance=5.0, method="shift")
    with pytest.raises(ValueError, match="theta_r"):
        ps.brdf_grid(0.3, np.array([0.1, 0.3, 0.35]), np.array([0.0, 0.1]))


def test_importing_the_models_leaves_scipy_signal_and_numba_unloaded():
    """``import scatterbench.models`` stays light (0.5 s where it took 0.9 s with scipy.signal,
    which also loads scipy.stats): the point source's grid loads scipy.signal when it first
    correlates, the kernels load numba when one first runs."""
    code = (
        "import sys, scatterbench.models; "
        "heavy = [m for m in ('scipy.signal', 'scipy.stats', 'numba') if m in sys.modules]; "
        "assert not heavy, heavy"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
