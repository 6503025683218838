"""Energy with GGX slopes and Smith shadowing (issue 15): the hit fraction of power-law
slopes, the albedo curves and their registered check (which fails on a broken input)."""

import dataclasses
import math

import numpy as np
import pytest

from scatterbench import models
from scatterbench.models.shadowing import smith_lambda
from scatterbench.validation.checks import registry
from scatterbench.validation.checks.registry import CheckContext
from scatterbench.validation.checks.shadowing import AlbedoCurve, conductor_albedo_curves
from scatterbench.validation.numerics.energy import TAIL_TOL, exposed_reflectance, hit_fraction, tail_radius
from scatterbench.validation.numerics.integrate import integrated_reflectance

SLOPES = [
    models.GGXSlopes(1e-4),
    models.GGXSlopes(0.1),
    models.GGXSlopes(1.0),
    models.GGXSlopes(10.0),
    models.GGXSlopes(0.3, coverage=0.4),
    models.AnisotropicGGXSlopes(alpha_x=0.1, alpha_y=0.5, rotation=0.3),
    models.GaussianSlopes(0.3),
    models.ExponentialSlopes(0.3),
]


@pytest.mark.parametrize("slopes", SLOPES, ids=repr)
def test_hit_fraction_is_coverage_times_one_plus_smith_lambda(slopes):
    # H = C (1 + Lambda(cot ti)) since the mean slope is zero (validation.numerics.energy):
    # the slope-space quadrature against models.shadowing's closed forms and tables.
    # Measured (worst relative error over SLOPES, hit_fraction against the line below):
    # 0 deg 4.9e-13; 30 deg 1.8e-6, 60 deg 6.3e-6 and 85 deg 3.0e-5 (all GGX alpha 10);
    # 89.99 deg 1.9e-5 (GGX alpha 0.1; Gaussian and exponential 1.7e-5).
    for deg, tol in ((0.0, 1e-12), (30.0, 1e-5), (60.0, 1e-5), (85.0, 1e-4), (89.99, 1e-4)):
        ti = math.radians(deg)
        lam = float(smith_lambda(slopes, math.cos(ti), math.sin(ti), -1.0, 0.0))
        want = slopes.coverage * (1.0 + lam)
        assert abs(hit_fraction(slopes, ti) - want) <= tol * want, deg


def test_tail_radius_is_derived_for_power_law_slopes_only():
    assert tail_radius(models.GaussianSlopes(0.3), 5.0) is None
    assert tail_radius(models.ExponentialSlopes(0.3), 5.0) is None
    a, tan = 0.5, 100.0
    r = tail_radius(models.GGXSlopes(a), tan)
    # the bound C a^2 (1/R^2 + 4 tan / (pi R)) it was derived from is met
    assert a * a * (1 / r**2 + 4 * tan / (math.pi * r)) <= TAIL_TOL * (1 + 1e-12)
    # the tail of the hit-fraction integrand beyond R, in closed form for GGX, is below it
    tail = a * a / (a * a + r * r) + tan * (2 / math.pi) * a * a * (math.pi / 2 - math.atan(r / a)) / a
    assert tail <= TAIL_TOL


def test_exposed_reflectance_of_ggx_matches_the_integrator():
    # within 3 x the integrator's own error estimate (measured: |difference| <= 0.51 of it,
    # 3.3e-6 to 4.6e-6 against estimates of 8.8e-6 to 9.2e-6)
    for alpha, deg in ((0.1, 30.0), (0.3, 60.0), (1.0, 75.0)):
        ti = math.radians(deg)
        s = models.GGXSlopes(alpha)
        r = integrated_reflectance(models.FacetBRDF(slopes=s, substrate=math.inf), ti, tol=1e-5)
        assert abs(exposed_reflectance(s, ti, math.inf) - r.value) <= 3 * r.error


def test_albedo_curves_with_and_without_smith():
    curves = conductor_albedo_curves(widths=(("ggx", 1.0), ("gaussian", 1.0)), angles_deg=(0.0, 89.99))
    by = {(c.family, c.shadowing): c for c in curves}
    for fam in ("ggx", "gaussian"):
        smith, none = by[fam, "smith"], by[fam, "none"]
        assert all(smith.converged) and all(none.converged)
        assert all(v <= 1 + e for v, e in zip(smith.albedo, smith.error, strict=True))
        assert none.albedo[1] - none.error[1] > 1.0  # the unshadowed model creates energy at grazing
        # G <= 1 only removes light
        assert all(a <= b + e for a, b, e in zip(smith.albedo, none.albedo, none.error, strict=True))
    with pytest.raises(ValueError, match="family"):
        conductor_albedo_curves(widths=(("cauchy", 1.0),), angles_deg=(0.0,))


def _curve(albedo, error=1e-4, shadowing="smith", converged=True):
    n = len(albedo)
    return AlbedoCurve(
        "ggx", 0.3, shadowing, tuple(np.linspace(0, 89.99, n)), tuple(albedo), (error,) * n, (converged,) * n
    )


def test_smith_albedo_check_passes_and_goes_red_on_a_broken_input():
    spec = registry.select(["shadowing.check_smith_albedo"])[0]
    ok = [_curve((0.99, 0.98, 1.00005)), _curve((1.0, 3.0, 40.0), shadowing="none")]
    r = spec.func(CheckContext(), curves=ok)
    assert r.status == "pass" and "without shadowing up to 40" in r.detail
    broken = [_curve((0.99, 1.01, 0.98)), ok[1]]  # 1e-2 above 1, error 1e-4
    r = spec.func(CheckContext(), curves=broken)
    assert r.status == "fail" and r.measured == pytest.approx(0.01 - 1e-4)
    unconverged = dataclasses.replace(ok[0], converged=(True, False, True))
    assert spec.func(CheckContext(), curves=[unconverged, ok[1]]).status == "fail"
    # wherever the unconverged curve stands among the Smith curves
    assert spec.func(CheckContext(), curves=[ok[0], unconverged, ok[1]]).status == "fail"
