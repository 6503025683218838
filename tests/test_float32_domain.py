"""The float32-safe domain (models.float32_domain): inside it the float32 kernels meet the
derived bound ``EPS * kappa`` on random and adversarial geometries; outside it a float32
request is the float64 result rounded to float32, decided once per model."""

import math

import numpy as np
import pytest
from numba import njit

from scatterbench import models as S
from scatterbench.models import float32_domain as fd
from scatterbench.models.evaluation import raw_float32
from scatterbench.models.kernels import common, drive
from scatterbench.models.params import INDEX_MIN
from scatterbench.validation.numerics.probes import random_geometries
from scatterbench.validation.studies import tradeoff

G, X = S.GaussianSlopes, S.ExponentialSlopes
TOP = math.radians(89.0)  # the bound is stated for polar angles up to 89 deg


def _width(m):
    """The narrowest lobe width of ``m``'s slopes (0.1 for models without slopes)."""
    names = ("sigma", "alpha", "sigma_x", "sigma_y", "alpha_x", "alpha_y", "m_parallel", "m_perpendicular")
    s = getattr(m, "slopes", None)
    return min((getattr(s, a) for a in names if hasattr(s, a)), default=0.1)


def _geometries(m):
    """Random geometries and the worst ones for float32: near normal incidence (the kernels'
    sines, worst where cos(theta) rounds to 1, theta ~ sqrt(EPS / 2)), across the lobe
    (+-3 widths around the specular or refracted direction), exact retro and specular, and
    for a BTDF nearly vertical facets (n cos(theta_t) = cos(theta_i))."""
    rng = np.random.default_rng(7)
    parts = [random_geometries(2000, seed=7, max_deg=89.0)]
    t = np.r_[np.geomspace(1e-6, 0.1, 60), fd.SINE * np.array([0.999, 1.001, 1.4, 1.42, 1.7, 2.0])]
    T, R, P = np.meshgrid(t, t, [0.0, math.pi, 1.0, 2.0], indexing="ij")
    parts.append((T.ravel(), R.ravel(), P.ravel()))
    base = rng.uniform(0.0, 1.4, 60)
    u = np.linspace(-3.0, 3.0, 13)
    B, U, V = (a.ravel() for a in np.meshgrid(base, u, u, indexing="ij"))
    w = _width(m)
    if m.transmission:
        n = m.substrate
        parts.append((B, np.arcsin(np.sin(B) / n) + w * U / n, w * V))
        e = np.r_[-np.geomspace(1e-7, 0.1, 30), np.geomspace(1e-7, 0.1, 30)]
        Bz, Ez, Pz = (
            a.ravel() for a in np.meshgrid(base, e, np.linspace(-math.pi, math.pi, 9), indexing="ij")
        )
        parts.append((Bz, np.arccos(np.cos(Bz) / n) + Ez, Pz))
    else:
        parts.append((B, B + w * U, w * V))
        parts.append((base, base, np.full_like(base, math.pi)))
        parts.append((base, base, np.zeros_like(base)))
    ti, tr, pr = (np.concatenate(p) for p in zip(*parts, strict=True))
    return np.clip(ti, 0.0, TOP), np.clip(tr, 0.0, TOP), pr


def _kappa(m):
    """The model's stated condition number (its worst element)."""
    code, rows, opts = m._kernel_spec()
    values = np.broadcast_arrays(*(np.asarray(r, dtype=float) for r in rows))
    named = {k: v.reshape(-1) for k, v in zip(drive.ROWS[code], values, strict=True)}
    return float(np.max(fd.condition(code, named, opts)[0]))


INSIDE = [
    S.FacetBRDF(),  # exponential sigma 0.1: the bound is within 1.2x of the error at theta ~ 2.4e-4
    S.SubsurfaceFacetBRDF(),
    S.FacetBRDF(slopes=S.GGXSlopes(0.05)),
    S.FacetBRDF(slopes=S.AnisotropicGaussianSlopes(0.05, 0.3, rotation=1e8 + 0.5)),  # reduced to (-pi, pi]
    S.FacetBRDF(slopes=G(0.3), shadowing="smith"),
    S.FacetBRDF(substrate=0.3, slopes=G(0.5)),  # a critical angle at 17 deg
    S.SubsurfaceFacetBRDF(coating=2.0, substrate=1.2, slopes=G(0.5)),  # TIR at the flakes
    S.SubsurfaceFacetBRDF(coating=1.5, substrate=1.5 * (1 + 1e-3), slopes=G(0.5)),
    S.FacetBTDF(),
    S.FacetBTDF(substrate=1.05, slopes=G(0.3)),
    S.FacetBTDF(slopes=G(1000.0)),  # peaked at nearly vertical facets
    S.SingleScatterBRDF(coating=1.5, phase=S.HenyeyGreenstein(-0.95, True)),
    S.SingleScatterBRDF(coating=1.0, phase=S.HenyeyGreenstein(0.9, False)),
    S.DiffuseSubsurfaceBRDF(coating=1.0001),
    S.CookTorranceBRDF(),
    S.VarnishedCookTorranceBRDF(),
    S.MaxwellBeardBRDF(polarized=True),
    S.MaxwellBeardBRDF(tau=1.0, omega=1.0, rho_d=0.1, rho_v=0.05),
]


@pytest.mark.parametrize("model", INSIDE, ids=repr)
def test_inside_the_domain_float32_meets_the_derived_bound(model):
    assert model.float32_fallback is None
    kappa = _kappa(model)
    assert fd.EPS * kappa <= fd.TOLERANCE
    ti, tr, pr = _geometries(model)
    m64 = model.mueller(ti, tr, pr)
    m32 = model.mueller(ti, tr, pr, precision="float32")
    assert m32.dtype == np.float32
    assert not np.array_equal(m32, m64.astype(np.float32))  # computed in float32, not rounded
    err = tradeoff.precision_error(m32, m64)
    assert err <= fd.EPS * kappa, f"error {err:.3g} above the bound {fd.EPS * kappa:.3g}"


OUTSIDE = [
    (S.FacetBRDF(substrate=INDEX_MIN), "critical angle"),  # float32 loses m^2 beside 1
    (S.FacetBRDF(substrate=1 + 1e-7), "relative index near 1"),  # rounds to 1 in float32
    (S.SubsurfaceFacetBRDF(coating=1.5, substrate=1.5 + 1e-7), "relative index near 1"),
    (S.DiffuseSubsurfaceBRDF(coating=1e15), "scale"),  # (2 / n)^4 ~ 1e-59 underflows float32
    (S.FacetBRDF(slopes=X(0.01)), "lobe width"),
    (S.CookTorranceBRDF(slopes=G(1e-3)), "lobe width"),
    # the float32 kernel divides by zero here; (n + 1) / (n - 1) scales the lobe term most
    (S.FacetBTDF(substrate=1 + 1e-8), "lobe width"),
    (S.FacetBTDF(slopes=G(1e5)), "lobe width"),
    (S.SingleScatterBRDF(phase=S.HenyeyGreenstein(-0.999)), "phase g"),
    (S.MaxwellBeardBRDF(tau=1e-3), "tau"),
    (S.MaxwellBeardBRDF(rho_d=1e30), "rho_d"),  # above sqrt of float32's largest
    (S.FacetBRDF(slopes=X(0.3, coverage=1e-45)), "coverage"),  # subnormal in float32
]


@pytest.mark.parametrize("model, term", OUTSIDE, ids=lambda x: repr(x) if isinstance(x, S.Model) else x)
def test_outside_the_domain_float32_is_the_float64_result_rounded(model, term):
    assert term in model.float32_fallback
    ti, tr, pr = random_geometries(300, seed=2, max_deg=89.0)
    ref = model.mueller(ti, tr, pr).astype(np.float32)
    assert np.array_equal(model.mueller(ti, tr, pr, precision="float32"), ref)  # the small call
    shape, m16 = model.mueller16(ti, tr, pr, precision="float32")  # the general path
    assert m16.dtype == np.float32 and np.array_equal(m16, model.mueller16(ti, tr, pr)[1].astype(np.float32))
    assert np.array_equal(model.brdf(ti, tr, pr, precision="float32"), ref[:, 0, 0])
    one = model.mueller(0.5, 0.6, 0.1, precision="float32")
    assert one.dtype == np.float32 and np.array_equal(one, model.mueller(0.5, 0.6, 0.1).astype(np.float32))


def test_a_model_set_falls_back_as_a_whole():
    """One element outside the domain sends the whole set to float64 (decided once per model)."""
    m = S.FacetBRDF(slopes=X(np.array([[0.3], [0.01]])))
    assert "lobe width" in m.float32_fallback
    ti, tr, pr = random_geometries(200, seed=3)
    assert np.array_equal(
        m.mueller(ti, tr, pr, precision="float32"), m.mueller(ti, tr, pr).astype(np.float32)
    )
    wide = S.FacetBRDF(slopes=X(np.array([[0.3], [0.5]])))
    assert wide.float32_fallback is None
    assert not np.array_equal(
        wide.mueller(ti, tr, pr, precision="float32"), wide.mueller(ti, tr, pr).astype(np.float32)
    )


def test_the_decision_is_made_once_per_model(monkeypatch):
    calls = []
    real = fd.model_unsafe
    monkeypatch.setattr(fd, "model_unsafe", lambda m: calls.append(m) or real(m))
    m = S.FacetBRDF(slopes=X(0.01))
    ti, tr, pr = random_geometries(100, seed=4)
    for _ in range(3):
        m.mueller(ti, tr, pr, precision="float32")
        m.brdf(0.5, 0.6, 0.1, precision="float32")
        m.mueller16(ti, tr, pr, precision="float32")
    assert calls == [m]
    m.mueller(ti, tr, pr)  # float64 never asks
    S.FacetBRDF(slopes=X(0.3)).mueller(ti, tr, pr)
    assert calls == [m]


def test_raw_float32_runs_the_kernels_outside_the_domain():
    m = S.FacetBRDF(substrate=1 + 1e-6, slopes=G(1.0))  # float32 rounds m - 1 by 10%
    ti, tr, pr = random_geometries(300, seed=5, max_deg=89.0)
    ref = m.mueller(ti, tr, pr)
    assert np.array_equal(m.mueller(ti, tr, pr, precision="float32"), ref.astype(np.float32))
    with raw_float32():
        assert m.float32_fallback is None
        raw = m.mueller(ti, tr, pr, precision="float32")
    assert tradeoff.precision_error(raw, ref) > 1e-2  # the garbage the fallback avoids
    assert m.float32_fallback is not None


def test_the_sine_error_of_the_kernels_is_the_stated_one():
    """``sqrt(1 - cos^2)`` in float32 is off by up to ``SINE = sqrt(EPS / 2)`` near normal
    incidence (cos rounds to 1 below that angle), and not much less: the term is needed."""
    t = np.geomspace(1e-6, 0.05, 200001)
    c = np.cos(t.astype(np.float32))
    s = np.sqrt(np.float32(1.0) - c * c)
    err = np.max(np.abs(s.astype(float) - np.sin(t)))
    assert fd.SINE / 2 < err <= fd.SINE


#: the float32 kernels' sine error (:func:`scatterbench.models.kernels.common.polar`): float64's
#: ``sqrt(1 - cos^2)`` is off by up to ``2^-26`` near normal incidence, rounding to float32
#: adds ``EPS / 2``, a coating's Snell sine ``s / n`` another ``EPS / 2``
KERNEL_SINE = fd.EPS + 2.0**-26


@njit
def _polar_each(t):
    """The kernels' ``polar`` of every value of ``t`` (helpers compile where a compiled function
    calls them), kept in float64 arrays: a float64 result would show in its bits."""
    c, s = np.empty(t.size), np.empty(t.size)
    for i in range(t.size):
        c[i], s[i] = common.polar(t[i])
    return c, s


@njit
def _internal_sine_each(c, s, n):
    """The sine inside a coating of index ``n`` from the float32 cosines ``c`` and sines ``s``."""
    out = np.empty(c.size)
    for i in range(c.size):
        out[i] = common.internal_sine(np.float32(common.coating_cos(c[i], n)), s[i], n)
    return out


def test_the_kernels_sines_are_accurate_in_float32():
    """The float32 kernels' sines, and Snell's ``s / n`` in a coating, are within
    :data:`KERNEL_SINE` of the sine of the float32 angle they were given at every polar angle,
    where float32's own ``sqrt(1 - cos^2)`` is off by up to ``SINE`` (the test above); and a
    float32 FacetBRDF near normal incidence is accurate to float32 (the float32 formula was off
    by 6e-3 of the peak at 2.4e-4 rad)."""
    t = np.concatenate([np.geomspace(1e-7, 0.05, 4001), np.linspace(0.05, 0.5 * math.pi, 4001)])
    t32 = t.astype(np.float32)
    exact = np.sin(t32.astype(float))
    cosines, sines = _polar_each(t32)  # float32 arguments: the float32 specialization
    assert np.array_equal(sines, sines.astype(np.float32)) and sines[0] > 0  # float32 values
    assert np.max(np.abs(sines - exact)) <= KERNEL_SINE
    inside = _internal_sine_each(cosines.astype(np.float32), sines.astype(np.float32), np.float32(1.5))
    assert np.max(np.abs(inside - exact / 1.5)) <= KERNEL_SINE
    m, th = S.FacetBRDF(), np.geomspace(1e-6, 0.05, 2001)
    err = tradeoff.precision_error(
        m.mueller(th, th, math.pi, precision="float32"), m.mueller(th, th, math.pi)
    )
    assert err <= 10 * fd.EPS


def test_the_domain_still_needs_its_sine_allowance():
    """Charging the sines the kernels' own 1.125 EPS instead of ``SINE`` would give a bound that
    a narrow lobe exceeds (the angles' rounding near grazing is not in it: the module docstring),
    so the domain keeps ``SINE``; this fails once the bound without the allowance holds."""
    m = S.VarnishedCookTorranceBRDF(slopes=S.StrokeSlopes(1e-3, 0.01, 0.3))
    code, rows, opts = m._kernel_spec()
    values = np.broadcast_arrays(*(np.asarray(r, dtype=float) for r in rows))
    named = {k: v.reshape(-1) for k, v in zip(drive.ROWS[code], values, strict=True)}
    _, terms = fd.condition(code, named, opts)
    r = KERNEL_SINE / fd.SINE  # the terms proportional to the sine error, rescaled
    kappa = sum(
        v * (r if k in ("sines near normal incidence", "lobe width") else 1.0) for k, v in terms.items()
    )
    ti, tr, pr = _geometries(m)
    with raw_float32():
        err = tradeoff.precision_error(m.mueller(ti, tr, pr, precision="float32"), m.mueller(ti, tr, pr))
    assert err > fd.EPS * float(np.max(kappa))


def test_the_precision_knob_reports_the_fallback_instead_of_timing_it():
    m = S.SubsurfaceFacetBRDF(slopes=X(0.01))
    assert tradeoff.precision_option(m) is None
    assert "falls back to float64" in tradeoff.float32_unavailable(m)
    with pytest.raises(tradeoff.KnobUnavailable, match="falls back to float64 .*lobe width"):
        tradeoff.knob_precision(quick=True, model=m)
    with pytest.raises(ValueError, match="precision: SubsurfaceFacetBRDF falls back"):
        tradeoff.at_precision(m, "float32")
    assert tradeoff.precision_option(S.SubsurfaceFacetBRDF()) == "keyword"
