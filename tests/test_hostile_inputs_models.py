"""Hostile inputs of issue 31 (classes 4-6, models side): each refused with a ValueError (or
TypeError) naming the parameter, or evaluated to finite numbers."""

import math

import numpy as np
import pytest

from scatterbench import models, validation
from scatterbench.models import fresnel, point_source, polarization, shadowing

G = (np.array([0.0, 0.3, 1.2, 0.5 * math.pi]), np.array([0.0, 0.4, 1.2, 0.5 * math.pi]), 0.5)


@pytest.mark.parametrize(
    "build, name",
    [
        (lambda: models.FilmStack(layers=((1.5, 1e308),), substrate=1.5), "thickness_nm"),
        (lambda: models.FilmStack(layers=((1.5, np.array([1.0, 2.0])),), substrate=1.5), "thickness_nm"),
        (lambda: models.Films(layers=((1.5, 100.0),), wavelength_nm=1e-300), "wavelength_nm"),
        (lambda: 1e306 * models.FacetBRDF(), "weight"),
        (lambda: models.MaxwellBeardBRDF(rho_v=1e306), "rho_v"),
        (lambda: models.RoughDiffuseBRDF(single=1.7e308, pairs=20), "single"),
        (lambda: fresnel.fresnel_coefficients(0.5, 1.0, -1.5), "n2"),
        (lambda: fresnel.fresnel_coefficients(2.0, 1.0, 1.5), "cos_i"),
        (lambda: fresnel.fresnel_coefficients(0.5, 0.0, 1.5), "n1"),
        (lambda: models.TabulatedIndex(n=(True, 1.6)), "n"),
        (lambda: models.TabulatedIndex(n=("1.5", "1.6")), "n"),
        (lambda: models.Sum(terms=(("2", models.FacetBRDF()),)), "weight"),
        (lambda: models.FacetBRDF() * True, "weight"),
        (lambda: validation.integrated_reflectance(None, 0.3), "model"),
        (
            lambda: validation.integrated_reflectance(models.FacetBRDF(), 0.3, max_evaluations=-5),
            "max_evaluations",
        ),
        (
            lambda: validation.integrated_reflectance(models.FacetBRDF(), 0.3, max_evaluations=True),
            "max_evaluations",
        ),
        (
            lambda: validation.integrated_reflectance(models.FacetBRDF(), 0.3, max_evaluations=1.5),
            "max_evaluations",
        ),
        (lambda: models.PointSourceBRDF(model=models.FacetBRDF(), resolution=8, tol=1e-3), "tol"),
    ],
)
def test_refused_naming_the_parameter(build, name):
    with pytest.raises(ValueError, match=name):
        build()


def test_small_film_index_is_finite_directly_and_as_coating_films():
    """A film index of 1e-12 (in range) gave NaN at normal incidence: m^2 - 1 + c^2 cancelled."""
    films = models.Films(layers=((1e-12, 100.0),))
    for m in (
        models.FacetBRDF(substrate=models.FilmStack(layers=((1e-12, 100.0),), substrate=1.5)),
        models.SubsurfaceFacetBRDF(coating_films=films),
        models.SingleScatterBRDF(coating_films=films),
        models.DiffuseSubsurfaceBRDF(coating_films=films),
    ):
        assert np.isfinite(m.mueller(*G)).all(), m


def test_smith_g1_at_tiny_cosine_is_finite():
    g = shadowing.smith_g1(models.GGXSlopes(0.1), np.array([1e-300]), 1.0, 1.0, 0.0)
    assert np.isfinite(g).all() and 0.0 <= g[0] < 1e-290


def test_factors_at_their_bound_give_finite_values():
    top = models.constraints.FACTOR_MAX
    for m in (top * models.FacetBRDF(), top * models.MaxwellBeardBRDF(rho_v=top, rho_d=top)):
        assert np.isfinite(m.mueller(*G)).all()


def test_float32_far_azimuth_and_lobe_beyond_float32():
    m = models.FacetBRDF()
    got = m.mueller(0.3, 0.4, 1e300, precision="float32")
    assert np.isfinite(got).all()
    np.testing.assert_allclose(got, m.mueller(0.3, 0.4, 1e300), rtol=1e-5, atol=1e-7)
    lobe = models.FacetBRDF(slopes=models.GGXSlopes(1e-8))
    t = np.array([0.5 * math.pi - 1e-15])
    assert lobe.brdf(t, t, 0.0) > 3.5e38
    with pytest.raises(ValueError, match="precision"):
        lobe.brdf(t, t, 0.0, precision="float32")


def test_types_and_arrays():
    assert models.GaussianSlopes(sigma=np.array(0.2)).sigma == 0.2
    assert models.FacetBRDF(substrate=np.array(1.5 + 0.1j)).substrate == 1.5 + 0.1j
    m = models.FacetBRDF()
    ro = np.empty((16, 3))
    ro.flags.writeable = False
    with pytest.raises(ValueError, match="out"):
        m.mueller(np.array([0.1, 0.2, 0.3]), 0.4, 0.5, out=ro)
    with pytest.raises(TypeError, match="out"):
        m.mueller(np.array([0.1, 0.2, 0.3]), 0.4, 0.5, out=[[0.0] * 3] * 16)
    J = np.array([[1.0, 0.2j], [0.1, -0.5]])
    np.testing.assert_array_equal(polarization.jones_to_mueller(J), polarization.jones_to_mueller(J[None])[0])
    assert polarization.jones_to_mueller(J).shape == (4, 4)


def test_integral_stays_within_its_budget():
    r = validation.integrated_reflectance(models.FacetBRDF(), 0.3, tol=1e-8, max_evaluations=100)
    assert r.evaluations <= 100 and not r.converged
    r = validation.integrated_reflectance(models.FacetBRDF(), 0.3, tol=1e-9, max_evaluations=5000)
    assert r.evaluations <= 5000 and not r.converged
    full = validation.integrated_reflectance(models.FacetBRDF(), 0.3, tol=1e-4)
    assert full.converged and full.evaluations <= 20_000_000


def test_point_source_chunks_give_the_same_numbers(monkeypatch):
    m = models.PointSourceBRDF(
        model=models.CookTorranceBRDF(convention="corrected"), distance=10.0, resolution=6
    )
    ti, tr, pr = np.linspace(0.1, 1.2, 5), np.linspace(0.2, 1.0, 5), np.linspace(-2, 2, 5)
    whole = m.mueller(ti, tr, pr)
    monkeypatch.setattr(point_source, "NODE_BYTES", 1)  # one geometry per chunk
    np.testing.assert_array_equal(m.mueller(ti, tr, pr), whole)
