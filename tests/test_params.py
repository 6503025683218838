"""Bad input raises ValueError naming the parameter and its allowed range."""

import math

import numpy as np
import pytest

from scatterbench import models


@pytest.mark.parametrize(
    "make, name",
    [
        (lambda: models.ExponentialSlopes(sigma=-0.1), "sigma"),
        (lambda: models.ExponentialSlopes(sigma=0.0), "sigma"),
        (lambda: models.GaussianSlopes(sigma=float("nan")), "sigma"),
        (lambda: models.GaussianSlopes(sigma=0.1, coverage=1.5), "coverage"),
        (lambda: models.AnisotropicExponentialSlopes(sigma_x=0.1, sigma_y=-1), "sigma_y"),
        (lambda: models.FacetBRDF(substrate=1.5 - 0.1j), "substrate"),
        (lambda: models.FacetBRDF(substrate=complex("nan")), "substrate"),
        (lambda: models.FacetBRDF(substrate=-1.0), "substrate"),
        (lambda: models.FacetBRDF(slopes=0.1), "slopes"),
        (lambda: models.SubsurfaceFacetBRDF(coating=0.9), "coating"),
        (lambda: models.SubsurfaceFacetBRDF(coating=1.5 + 0.1j), "coating"),
        (lambda: models.SubsurfaceFacetBRDF(coating=math.inf), "coating"),
        (lambda: models.GaussianAngles(sigma=4.0), "sigma"),
    ],
)
def test_bad_parameters_name_themselves(make, name):
    with pytest.raises(ValueError, match=name):
        make()


@pytest.mark.parametrize(
    "args, name",
    [
        ((-0.1, 0.3, 0.0), "theta_i"),
        ((0.1, 1.6, 0.0), "theta_r"),
        ((0.1, 0.3, float("nan")), "phi_r"),
        ((float("nan"), 0.3, 0.0), "theta_i"),
        ((0.1, np.array([0.2, np.inf]), 0.0), "theta_r"),
        (("a", 0.3, 0.0), "theta_i"),
    ],
)
def test_bad_angles_name_themselves(args, name):
    m = models.SubsurfaceFacetBRDF()
    with pytest.raises(ValueError, match=name) as exc:
        m.mueller(*args)
    if name.startswith("theta") and "must lie" in str(exc.value):
        assert "[0, pi/2]" in str(exc.value)


def test_range_in_message():
    with pytest.raises(ValueError, match=r"\[1e-08, 1e\+08\]"):
        models.ExponentialSlopes(sigma=-1)
    with pytest.raises(ValueError, match="k >= 0"):
        models.FacetBRDF(substrate=1 - 1j)


def test_parameters_are_declared_and_listed():
    names = [p.name for p in models.SubsurfaceFacetBRDF.parameters()]
    assert names == ["slopes", "coating", "substrate", "shadowing", "coating_films"]
    text = models.list_models()
    assert "SubsurfaceFacetBRDF" in text and "coating" in text and "perfect conductor" in text


def test_models_are_frozen_and_replace_validates():
    m = models.SubsurfaceFacetBRDF()
    with pytest.raises(AttributeError):
        m.coating = 2.0
    assert m.replace(coating=2.0).coating == 2.0
    with pytest.raises(ValueError, match="coating"):
        m.replace(coating=0.5)


def test_negative_zero_k_normalized():
    m = models.FacetBRDF(substrate=complex(1.5, -0.0))
    assert math.copysign(1.0, m.substrate.imag) == 1.0


# ----------------------------------------------------------------------- one vocabulary, old names
@pytest.mark.parametrize(
    "old, new",
    [
        (lambda: models.SingleScatterBRDF(n=1.6), lambda: models.SingleScatterBRDF(coating=1.6)),
        (
            lambda: models.DiffuseSubsurfaceBRDF(n=1.3, rho=0.4),
            lambda: models.DiffuseSubsurfaceBRDF(coating=1.3, rho=0.4),
        ),
        (
            lambda: models.RoughDiffuseBRDF(n=1.4, pairs=20, surface_normalization="exact"),
            lambda: models.RoughDiffuseBRDF(coating=1.4, pairs=20, convention="corrected"),
        ),
        (
            lambda: models.FacetBTDF(normalization="exact"),
            lambda: models.FacetBTDF(convention="corrected"),
        ),
        (
            lambda: models.CookTorranceBRDF(m=0.2, normalization="energy"),
            lambda: models.CookTorranceBRDF(slopes=models.GaussianSlopes(0.2), convention="corrected"),
        ),
        (
            lambda: models.VarnishedCookTorranceBRDF(
                m_parallel=0.05,
                m_perpendicular=0.3,
                stroke_angle=0.4,
                varnish=1.7,
                normalization="energy",
                solid_angle="refracted",
            ),
            lambda: models.VarnishedCookTorranceBRDF(
                slopes=models.StrokeSlopes(0.05, 0.3, 0.4), coating=1.7, convention="corrected"
            ),
        ),
        (
            lambda: models.VarnishedCookTorranceBRDF(m_perpendicular=0.1),
            lambda: models.VarnishedCookTorranceBRDF(slopes=models.StrokeSlopes(0.03, 0.1)),
        ),
    ],
)
def test_old_keywords_build_the_same_model(old, new):
    assert old() == new()


def test_replace_accepts_old_names_from_the_current_values():
    v = models.VarnishedCookTorranceBRDF(m_parallel=0.05, m_perpendicular=0.3, stroke_angle=0.4)
    assert v.replace(m_perpendicular=0.2).slopes == models.StrokeSlopes(0.05, 0.2, 0.4)
    c = v.replace(convention="corrected")
    assert c.replace(normalization="energy") == c  # completed with the current solid angle: refracted
    with pytest.raises(ValueError, match="solid_angle='refracted'"):
        c.replace(normalization="published")
    assert models.SingleScatterBRDF().replace(n=2.0).coating == 2.0


def test_old_names_are_listed_read_and_named_in_errors():
    info = {p.name: p for p in models.VarnishedCookTorranceBRDF.parameters()}
    assert info["coating"].aliases == ("varnish",)
    assert info["convention"].aliases == ("normalization", "solid_angle")
    assert info["slopes"].aliases == ("m", "m_parallel", "m_perpendicular", "stroke_angle")
    assert "old name n" in models.SingleScatterBRDF.info()
    assert models.SingleScatterBRDF(coating=1.7).n == 1.7  # a plain rename reads as before
    with pytest.raises(AttributeError):
        models.CookTorranceBRDF().m  # noqa: B018 - a converted old name has no attribute
    with pytest.raises(ValueError, match=r"^n \(old name of coating\): coating must be"):
        models.DiffuseSubsurfaceBRDF(n=0.5)
    with pytest.raises(ValueError, match="give coating alone"):
        models.DiffuseSubsurfaceBRDF(n=1.5, coating=1.5)
    with pytest.raises(ValueError, match="surface_normalization .* must be one of 'paper', 'exact'"):
        models.RoughDiffuseBRDF(surface_normalization="corrected")


@pytest.mark.parametrize("cls", [models.PointSourceBRDF, models.DetectorAperture])
def test_wrappers_require_their_model(cls):
    with pytest.raises(ValueError, match="model is required"):
        cls()
    assert {p.name: p for p in cls.parameters()}["model"].required


@pytest.mark.parametrize(
    "at, value, name",
    [(0, float("nan"), "theta_i"), (-1, math.pi / 2 + 1e-12, "theta_i"), (12345, -0.0001, "theta_r"),
     (7, float("inf"), "phi_r"), (-1, float("-inf"), "phi_r")],
)  # fmt: skip
def test_large_angle_arrays_are_checked_on_the_kernels_threads_and_name_a_bad_value(
    at, value, name, monkeypatch
):
    """From PARALLEL_CHECK values a float64 angle array is checked by one compiled pass
    (kernels.within); one bad value anywhere in it still gives numpy's error naming the angle."""
    from scatterbench.models import evaluation, kernels

    assert evaluation._WITHIN == [kernels.within]  # registered when the kernels load
    n = evaluation.PARALLEL_CHECK
    good = {
        "theta_i": np.full(n, 0.3),
        "theta_r": np.linspace(0.0, math.pi / 2, n),
        "phi_r": np.linspace(-7, 7, n),
    }
    m = models.FacetBRDF()
    with pytest.MonkeyPatch.context() as mp:  # valid: the numpy checks never run
        mp.setattr(evaluation, "check_polar_angle", None)
        mp.setattr(evaluation, "check_finite_array", None)
        shape, M = m.mueller16(*good.values())
    assert M.shape == (16, n) and np.isfinite(M).all()
    bad = dict(good)
    bad[name] = good[name].copy()
    bad[name][at] = value
    with pytest.raises(ValueError, match=name):
        m.mueller16(*bad.values())
