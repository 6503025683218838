"""Transmission through a smooth non-absorbing interface, shared by the seed 003 models.

For a ray at external polar angle ``theta`` (cosine ``c``) entering a medium of
real index ``n >= 1`` (internal cosine ``c'``), the Fresnel amplitudes are
``t_s = 2c / (c + n c')``, ``t_p = 2c / (n c + c')`` (Born & Wolf, as in
:mod:`models.fresnel`, with ``w = n c'``).  Seed 003 Eq. 14, 20, 24-27 always
multiply ``|t|^2`` by ``c'/c``; the amplitudes carrying that factor,

    a_s = t_s sqrt(c'/c) = 2 sqrt(c c') / (c + n c'),
    a_p = t_p sqrt(c'/c) = 2 sqrt(c c') / (n c + c'),

have no division by ``cos(theta)`` and vanish at grazing incidence, so the
models need no special case there.  ``n a^2 = T`` (intensity transmittance).
By reciprocity of the transmittance the same amplitudes describe the exit of a
ray leaving at ``theta`` (seed 003 Eq. 11, 25).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy import integrate

from .fresnel import coating_cos, fresnel_reflectance

__all__ = ["interface_amplitudes", "internal_hemispherical_reflectance", "depolarized_between"]

_TINY = 1e-300


def interface_amplitudes(cos_ext, n):
    """``(sin_int, cos_int, a_s, a_p)`` for external cosines ``cos_ext`` (any shape)."""
    c = np.asarray(cos_ext, dtype=float)
    # np.cos(pi/2) = 6e-17: cosines below 1e-15 (within ~1e-15 rad of grazing, a few
    # ulps of pi/2) are exactly grazing, so theta = pi/2 gives exact zeros.
    c = np.where(c < 1e-15, 0.0, c)
    s_int = np.sqrt(1.0 - c * c) * (1.0 / n)
    c_int = coating_cos(c, n)  # not sqrt(1 - s_int^2): that cancels near grazing
    root = 2.0 * np.sqrt(c * c_int)
    # For n = 1 at grazing both terms of the denominators vanish with the numerator
    # (a = 1 in the limit, but the ray carries no projected flux): 0/tiny = 0.
    a_s = root / np.maximum(c + n * c_int, _TINY)
    a_p = root / np.maximum(n * c + c_int, _TINY)
    return s_int, c_int, a_s, a_p


def depolarized_between(a_s_in, a_p_in, a_s_out, a_p_out, scale):
    """Mueller elements ``(16, n)`` of light transmitted in, fully depolarized, and transmitted
    out: ``scale x M(t_out)[:, 0] (x) M(t_in)[0, :]`` (seed 003 Eq. 28's structure) from the
    interface amplitudes (:func:`interface_amplitudes`) of the two crossings.  Only the
    intensity and the linear s/p diattenuation survive (elements 00, 01, 10, 11)."""
    a, b = a_s_out * a_s_out, a_p_out * a_p_out
    c, d = a_s_in * a_s_in, a_p_in * a_p_in
    s_out, d_out = 0.5 * (a + b) * scale, 0.5 * (a - b) * scale
    s_in, d_in = 0.5 * (c + d), 0.5 * (c - d)
    out = np.zeros((16,) + np.shape(s_in * s_out))
    out[0] = s_out * s_in
    out[1] = s_out * d_in
    out[4] = d_out * s_in
    out[5] = d_out * d_in
    return out


def internal_hemispherical_reflectance(n: float) -> float:
    """``R-bar`` of seed 003 Eq. 22 with the cos-weighted average normalized by ``1/pi``.

    ``R-bar = (1/pi) int R_int(theta') cos(theta') dOmega'`` for light inside a
    medium of index ``n`` hitting the interface with air.  Seed 003 Eq. 22
    prints ``1/(2 pi)``, which would average to 1/2 for a perfect reflector; the
    cos-weighted hemispherical average needs ``1/pi`` (DESIGN.md; with it
    the model has unit albedo at ``rho = 1``, checked in the tests).

    Computed exactly (to ~1e-15): with ``u = sin^2(theta')`` the average is
    ``int_0^1 R du``; beyond the critical angle ``R = 1`` (contributing
    ``1 - 1/n^2``), and below it the internal reflectance equals the external
    one at the refracted angle (Stokes relations), so with the external cosine
    ``c``: ``R-bar = 1 - (1 - int_0^1 R_ext(c) 2c dc) / n^2``.  The last
    integrand is analytic on [0, 1] and is integrated adaptively, once per index (cached:
    a model set, or each chunk of one, asks again for the indices it holds).
    """
    return _rbar(float(n))


@functools.lru_cache(maxsize=4096)
def _rbar(n: float) -> float:
    if n == 1.0:
        return 0.0

    def f(c):
        rs, rp = fresnel_reflectance(np.array([c]), 1.0, n)
        return float(rs[0] + rp[0]) * c  # 0.5 (Rs + Rp) * 2c

    # The integrand has a branch point at c = i sqrt(n^2 - 1): near n = 1 it is
    # sharp close to c = 0, so give quad breakpoints there.
    pts = [min(0.5, 10.0 * math.sqrt(n * n - 1.0))]
    val, _ = integrate.quad(f, 0.0, 1.0, points=pts, epsabs=1e-14, epsrel=1e-12, limit=200)
    return 1.0 - (1.0 - val) / (n * n)
