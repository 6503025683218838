"""Bad input raises ValueError naming the parameter and its allowed range."""

import math

import numpy as np
import pytest

import models


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
    with pytest.raises(ValueError, match=r"\(0, inf\)"):
        models.ExponentialSlopes(sigma=-1)
    with pytest.raises(ValueError, match="k >= 0"):
        models.FacetBRDF(substrate=1 - 1j)


def test_parameters_are_declared_and_listed():
    names = [p.name for p in models.SubsurfaceFacetBRDF.parameters()]
    assert names == ["slopes", "coating", "substrate", "shadowing"]
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
