"""The Maxwell-Beard kernel (:class:`scatterbench.models.MaxwellBeardBRDF`): the facet term of
:mod:`scatterbench.models.kernels.facet` times the shadowing/obscuration function, plus the Lambertian
and volumetric terms, one geometry per call, as :mod:`scatterbench.models.maxwell_beard` computes them."""

from __future__ import annotations

import math

from .common import diag16, mueller16, polar_from, scaled16
from .facet import coating, facet_jones_through
from .helper import helper
from .vector_math import atan2, exp_neg, sincos, sqrt


@helper
def shadow(si, ci, sr, cr, cp, sp, tau, omega):
    """Shadowing/obscuration ``SO(theta_N, beta)`` (:func:`scatterbench.models.maxwell_beard.maxwell_beard_shadow`,
    whose docstring derives the two ``atan2``) from the angles' sines and cosines."""
    T = type(si)
    hx, hy = sr * cp - si, sr * sp
    t = hx * hx + hy * hy
    den = ci + cr
    theta_n = T(atan2(sqrt(t), den if den > T(0.0) else T(1.0)))
    dx, dz = sr * cp + si, cr - ci
    beta = T(atan2(sqrt(dx * dx + hy * hy + dz * dz), sqrt(t + den * den)))
    x = theta_n / omega
    e = exp_neg(T(2.0) * beta / tau)
    so = (T(1.0) + x * e) / (T(1.0) + x)
    return e if x == T(math.inf) else so  # theta_N / Omega overflowed (a tiny Omega): SO's limit


@helper
def maxwell(geo, p, o):
    """Maxwell-Beard at one geometry; ``o[0]``: the slope kind, ``o[2]``: the facet Mueller
    matrix on the specular term.  No C library call: a loop over it runs on SIMD lanes
    (:mod:`scatterbench.models.kernels.vector`)."""
    ti, tr, _, cp, sp = geo
    T = type(ti)
    # the facet term takes the sines as sqrt(1 - cos^2) (:func:`polar`), the shadow the sines
    # themselves, as the numpy path's: near normal incidence the two differ by 1e-10, which
    # the shadow's slope near its origin made 5e-12 of a Gaussian lobe's far tail
    (s_i, c_i), (s_r, c_r) = sincos(ti), sincos(tr)
    pol_i, pol_r = polar_from(c_i, ti), polar_from(c_r, tr)
    ci, cr = pol_i[0], pol_r[0]
    so = shadow(T(s_i), ci, T(s_r), cr, cp, sp, p[9], p[10])
    # uncoated (its coating row is 1, MaxwellBeardBRDF._kernel_spec): the constant folds the
    # coating away, where reading the row had a loop on SIMD lanes compute it for every geometry
    coat = coating(pol_i, pol_r, T(1.0))
    a, b, c, d, e, f, g, h = facet_jones_through(geo, pol_i, pol_r, coat, p, o)
    if o[2] == 1:
        m = scaled16(mueller16(a, b, c, d, e, f, g, h), so)
    else:
        m = diag16(T(0.5) * ((a * a + b * b) + (c * c + d * d) + (e * e + f * f) + (g * g + h * h)) * so)
    den = ci + cr
    vol = T(2.0) * p[8] / (den if den > T(0.0) else T(1.0))
    half_pi = T(0.5 * math.pi)
    grazing = ti >= half_pi or tr >= half_pi
    return (m[0] + (T(0.0) if grazing else p[7] + vol),) + m[1:]
