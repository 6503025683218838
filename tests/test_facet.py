"""FacetBRDF and SubsurfaceFacetBRDF: SCATMECH agreement, limits, extremes, shapes."""

import math

import numpy as np
import pytest

from scatterbench import models, references
from scatterbench.models.kernel_tolerance import kernel_tolerance
from scatterbench.validation.numerics.flat import flat_coated_reflectance
from scatterbench.validation.numerics.integrate import integrated_reflectance


def test_scatmech_reference_set_is_broad():
    ref = references.scatmech_facet()
    n = len(ref["model"])
    assert n >= 500
    assert set(ref["model"]) == {"facet", "subsurface"}
    assert set(ref["sdf"]) == {"Exponential", "Gaussian"}
    assert np.any(ref["substrate_k"] == 0) and np.any(ref["substrate_k"] > 1)
    sub = ref["model"] == "subsurface"
    assert ref["coating"][sub].min() < 1.1 and ref["coating"][sub].max() > 2.1
    assert ref["sigma"].min() < 0.06 and ref["sigma"].max() > 0.9
    assert ref["phi_r"].min() < -3 and ref["phi_r"].max() > 3
    assert "pyscatmech" in references.provenance("scatmech_facet.csv")


def test_coating_one_equals_facet(rng):
    ti, tr = rng.uniform(0, 1.5, (2, 500))
    pr = rng.uniform(-4, 4, 500)
    s = models.ExponentialSlopes(0.3)
    a = models.SubsurfaceFacetBRDF(slopes=s, coating=1.0, substrate=1.37 + 7.62j).mueller(ti, tr, pr)
    b = models.FacetBRDF(slopes=s, substrate=1.37 + 7.62j).mueller(ti, tr, pr)
    np.testing.assert_allclose(a, b, rtol=1e-14, atol=0)


@pytest.mark.parametrize("substrate", [math.inf, 1.37 + 7.62j, 3.88 + 0.02j])
@pytest.mark.parametrize("coating", [1.0, 1.5, 2.0])
def test_sigma_to_zero_gives_flat_column(substrate, coating):
    """sigma -> 0 reproduces the flat-interface specular reflectance through the coating.

    The slope density is even, so the deviation from the flat value is second
    order in sigma; the test checks the limit and that order (the deviation
    falls ~100x from sigma = 1e-3 to 1e-4; coefficients measured up to ~11).
    """
    ti = math.radians(60)
    flat = flat_coated_reflectance(ti, coating, substrate)
    dev = {}
    for sigma in (1e-3, 1e-4):
        m = models.SubsurfaceFacetBRDF(
            slopes=models.ExponentialSlopes(sigma), coating=coating, substrate=substrate
        )
        r = integrated_reflectance(m, ti, tol=1e-8)
        dev[sigma] = r.value - flat
        assert abs(dev[sigma]) <= r.error + 20 * sigma**2
    if abs(dev[1e-3]) > 1e-6:
        assert 70 < dev[1e-3] / dev[1e-4] < 130


def test_brdf_is_m00_and_jones_gives_mueller(rng):
    m = models.SubsurfaceFacetBRDF(slopes=models.GaussianSlopes(0.4), coating=1.7, substrate=2.0)
    ti, tr = rng.uniform(0, 1.5, (2, 300))
    pr = rng.uniform(-4, 4, 300)
    M = m.mueller(ti, tr, pr)
    np.testing.assert_allclose(m.brdf(ti, tr, pr), M[:, 0, 0], rtol=1e-13, atol=0)
    # the Jones matrices are numpy's, M the kernel's: within the kernel's tolerance of each
    # geometry's M00 (models/kernel_tolerance.py), not of each element: an element far below
    # M00 carries M00's roundings (relative to itself up to 2.9e-12 before the kernel's
    # one-division Fresnel coefficients, 1.1e-10 after, 3e-15 of M00 both; ad hoc, seeds 0-2)
    ref = models.jones_to_mueller(m.jones(ti, tr, pr))
    err = np.max(np.abs(M - ref), axis=(1, 2)) / np.abs(ref[:, 0, 0])
    assert np.max(err) <= kernel_tolerance(m), np.max(err)


def test_broadcasting_and_chunks():
    m = models.SubsurfaceFacetBRDF()
    ti = np.linspace(0, 1.2, 3)[:, None, None]
    tr = np.linspace(0, 1.5, 4)[None, :, None]
    pr = np.linspace(-3, 3, 5)
    M = m.mueller(ti, tr, pr)
    assert M.shape == (3, 4, 5, 4, 4)
    assert m.brdf(ti, tr, pr).shape == (3, 4, 5)
    assert m.jones(0.3, 0.4, 0.5).shape == (2, 2)
    assert m.mueller(0.3, 0.4).shape == (4, 4)
    # more geometries than one chunk: identical to element-wise evaluation
    n = models.CHUNK * 2 + 17
    t = np.linspace(0, 1.5, n)
    big = m.mueller(0.5, t, 0.7)
    few = np.array([m.mueller(0.5, x, 0.7) for x in t[[0, models.CHUNK - 1, models.CHUNK, n - 1]]])
    np.testing.assert_array_equal(big[[0, models.CHUNK - 1, models.CHUNK, n - 1]], few)


def test_float32_inputs():
    m = models.SubsurfaceFacetBRDF()
    a = m.mueller(np.float32(0.5), np.float32(0.6), np.float32(0.1))
    b = m.mueller(float(np.float32(0.5)), float(np.float32(0.6)), float(np.float32(0.1)))
    np.testing.assert_array_equal(a, b)


def test_exact_retroreflection_is_continuous():
    """alpha = 0 (Eq. 18's a1 = 0) is the limit of nearby geometries, not a special case."""
    m = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.5), coating=1.5, substrate=1.37 + 7.62j)
    t = math.radians(40)
    exact = m.mueller(t, t, math.pi)
    near = m.mueller(t, t + 1e-7, math.pi - 1e-7)
    np.testing.assert_allclose(near, exact, rtol=1e-5, atol=1e-6 * exact[0, 0])
    # Exposed surface: at retroreflection the facet is seen at normal incidence, where
    # r_p = -r_s, so the Jones matrix is a multiple of the identity (no diattenuation).
    bare = models.FacetBRDF(slopes=models.ExponentialSlopes(0.5), substrate=1.37 + 7.62j).mueller(
        t, t, math.pi
    )
    off = bare - np.diag(np.diag(bare))
    assert np.max(np.abs(off)) < 1e-14 * bare[0, 0]


def test_exact_specular_plane_of_incidence():
    m = models.FacetBRDF(slopes=models.GaussianSlopes(0.2), substrate=1.5)
    M = m.mueller(0.7, 0.7, 0.0)
    # in the plane of incidence s and p do not mix
    for i, j in [(0, 2), (0, 3), (2, 0), (3, 0), (1, 2), (2, 1)]:
        assert abs(M[i, j]) < 1e-15 * M[0, 0]
    rs2, rp2 = models.fresnel_reflectance(np.array(math.cos(0.7)), 1.0, 1.5)
    assert M[0, 1] / M[0, 0] == pytest.approx(float((rs2 - rp2) / (rs2 + rp2)), rel=1e-12)


def test_tir_at_facet_gives_unit_facet_reflectance():
    """A facet beyond its critical angle reflects totally: |r_s| = |r_p| = 1.

    (Under a coating the local angle alpha never exceeds the coating's critical
    angle asin(1/n), so facet TIR needs a relative index below sin(alpha); an
    exposed facet on an index-0.5 medium shows it for alpha > 30 deg.)
    """
    s = models.GaussianSlopes(1.0)
    m = models.FacetBRDF(slopes=s, substrate=0.5)
    perfect = models.FacetBRDF(slopes=s, substrate=math.inf)
    ti = np.radians([60.0, 45.0, 70.0])
    tr = np.radians([60.0, 50.0, 20.0])
    pr = np.radians([0.0, 30.0, -60.0])
    np.testing.assert_allclose(m.brdf(ti, tr, pr), perfect.brdf(ti, tr, pr), rtol=1e-12)
    # ...and below the critical angle it does not
    assert m.brdf(0.1, 0.1, 0.0) < 0.5 * perfect.brdf(0.1, 0.1, 0.0)


def test_polarization_helper():
    m = models.SubsurfaceFacetBRDF()
    out = m.polarization(1.0, np.linspace(0, 1.4, 5), 0.3, incident="linear:45")
    assert set(out) == {"brdf", "eta", "P_C", "P"}
    np.testing.assert_allclose(out["P"], 1.0, atol=1e-12)  # non-depolarizing model, pure input


def test_streaming_and_out_match_mueller(tmp_path):
    m = models.SubsurfaceFacetBRDF()
    tr = np.linspace(0, 1.5, 700)[:, None]
    pr = np.linspace(-3, 3, 13)[None, :]
    full = m.mueller(0.4, tr, pr)
    streamed = np.concatenate([b for _, b in m.iter_mueller(0.4, tr, pr)])
    np.testing.assert_array_equal(streamed, full.reshape(-1, 4, 4))
    buf = np.lib.format.open_memmap(tmp_path / "m.npy", mode="w+", shape=(16, full[..., 0, 0].size))
    via_out = m.mueller(0.4, tr, pr, out=buf)
    np.testing.assert_array_equal(via_out, full)
    with pytest.raises(ValueError, match="out"):
        m.mueller(0.4, tr, pr, out=np.empty((16, 3)))
