"""The Maxwell-Beard kernel (:class:`models.MaxwellBeardBRDF`): the facet term of
:mod:`models.kernels.facet` times the shadowing/obscuration function, plus the Lambertian
and volumetric terms, one geometry per call, as :mod:`models.maxwell_beard` computes them."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .common import diag16, mueller16, polar_from, scaled16
from .facet import FACET_ROWS, facet_jones_at
from .vector_math import sqrt

#: parameter rows: the facet kernel's, then rho_d, rho_v, tau, omega
MAXWELL_ROWS = FACET_ROWS + ("rho_d", "rho_v", "tau", "omega")


@njit(error_model="numpy")
def shadow(si, ci, sr, cr, cp, tau, omega):
    """Shadowing/obscuration ``SO(theta_N, beta)`` (:func:`models.maxwell_beard.maxwell_beard_shadow`)
    from the angles' sines and cosines."""
    T = type(si)
    t = si * si - T(2.0) * si * sr * cp + sr * sr
    den = ci + cr
    slope = sqrt(max(t, T(0.0))) / (den if den > T(0.0) else T(1.0))
    theta_n = math.atan(slope)
    cos_beta = sqrt(min(max(T(0.5) * (T(1.0) - si * sr * cp + ci * cr), T(0.0)), T(1.0)))
    beta = math.acos(min(cos_beta, T(1.0)))
    x = theta_n / omega
    e = math.exp(-T(2.0) * beta / tau)
    if math.isinf(x):  # theta_N / Omega overflowed (a tiny Omega): SO's limit
        return e
    return (T(1.0) + x * e) / (T(1.0) + x)


@njit(error_model="numpy", inline="always")
def maxwell(geo, p, o):
    """Maxwell-Beard at one geometry; ``o[2]``: the facet Mueller matrix on the specular term."""
    ti, tr, pr = geo[0], geo[1], geo[2]
    T = type(ti)
    # the C library's cosines and sines, as numpy's: near retroreflection ``beta = acos(~1)``
    # in :func:`shadow` turns an ulp of them into 1e-10 of the result
    # (the polar cosines in float64 once: the facet term's sines come from them, :func:`polar`)
    ci64, cr64 = math.cos(np.float64(ti)), math.cos(np.float64(tr))
    si, ci, sr, cr = math.sin(ti), T(ci64), math.sin(tr), T(cr64)
    cp, sp = math.cos(pr), math.sin(pr)
    so = shadow(si, ci, sr, cr, cp, p[9], p[10])
    pol_i, pol_r = polar_from(ci64, ti), polar_from(cr64, tr)
    a, b, c, d, e, f, g, h = facet_jones_at((ti, tr, pr, cp, sp), pol_i, pol_r, p, o)
    if o[2] == 1:
        m = scaled16(mueller16(a, b, c, d, e, f, g, h), so)
    else:
        m = diag16(T(0.5) * ((a * a + b * b) + (c * c + d * d) + (e * e + f * f) + (g * g + h * h)) * so)
    den = ci + cr
    vol = T(2.0) * p[8] / (den if den > T(0.0) else T(1.0))
    half_pi = T(0.5 * math.pi)
    if ti >= half_pi or tr >= half_pi:
        return m
    return (m[0] + (p[7] + vol),) + m[1:]
