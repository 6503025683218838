"""The node algebra of :class:`scatterbench.models.PointSourceBRDF`'s ``"auto"`` quadrature, compiled:
each quadrature point of the disc turned into the local incidence ``(psi, Phi)`` and the
irradiance weight ``J`` (:meth:`scatterbench.models.disc_cubature.Disc.angles`, the numpy reference the
tests hold this to).

A geometry's points all lie in one of the three coordinate systems of
:class:`scatterbench.models.disc_cubature.Disc` (polar about the source's foot ``H``, polar about the
centre, or the wedge of rays from ``H``), so the choice is made once per geometry and the
loop over its points has no branch and no C library call
(:mod:`~scatterbench.models.kernels.vector_math`'s sines, cosines and arctangents, the ``sqrt``
intrinsic): LLVM runs it on SIMD lanes.  The hypotenuses are
:func:`~scatterbench.models.kernels.vector_math.hypot`'s, scaled, because the disc's radius over the
source's height, ``k``, reaches 1e300 (and ``1 / k`` with it).
"""

from __future__ import annotations

import math

import numpy as np

from .helper import entry_point, helper
from .vector_math import atan2, hypot, sincos, sqrt

_TWO_PI = 2.0 * math.pi


@helper
def _t_of_v(v, h, krho):
    """:func:`scatterbench.models.disc_cubature._t_of_v`."""
    a = (krho / h) * (krho / (h + 1.0))
    s = max(1.0 - v * v * a, 1.0 / h)
    return min(v * sqrt(2.0 - v * v * a) / (sqrt(h) * sqrt(h + 1.0) * s), 1.0)


@helper
def _polar(k, h1, tan_c, sec_c, about_h, ox, v, chi, w):
    """``(psi, Phi, J)`` of the point ``(v, chi)`` (weight ``w``) in polar coordinates about
    ``O`` (``ox`` from the centre): about ``H`` when ``about_h``, else about the centre."""
    s, c = sincos(chi)
    os_ = ox * s
    rho = sqrt(max(1.0 - os_ * os_, 0.0)) - ox * c
    krho = k * rho
    h = hypot(1.0, krho)
    t = _t_of_v(v, h, krho) if about_h else v
    r = rho * t
    x = tan_c + k * (ox + r * c)
    y = k * r * s
    tan_psi = hypot(x, y)
    cos_ratio = sec_c / hypot(1.0, tan_psi)
    j = 2.0 * v * (h1 / h) * ((h1 + 1.0) / (h + 1.0)) if about_h else t * (cos_ratio * cos_ratio * cos_ratio)
    return atan2(tan_psi, 1.0), atan2(y, x), w * rho * rho * j


@helper
def _share(r, h):
    """:func:`scatterbench.models.disc_cubature._share`."""
    return r * (r / (h * (h + 1.0)))


@helper
def _wedge(k, xc, u, alpha, w):
    """``(psi, Phi, J)`` of the wedge's point ``(u, alpha)`` (:func:`scatterbench.models.disc_cubature._wedge`)."""
    phi = 0.5 * (np.remainder(alpha + math.pi, _TWO_PI) - math.pi)
    sp, cp = sincos(phi)
    sc = sp / xc
    cc = sqrt(1.0 - sc * sc)
    r_f = xc * cc + cp
    r_n = (xc - 1.0) * (xc + 1.0) / r_f if r_f > 0.0 else 0.0
    h_n, h_f = hypot(1.0, k * r_n), hypot(1.0, k * r_f)
    g = (1.0 - u) * _share(r_n, h_n) + u * _share(r_f, h_f)
    a = (1.0 - u) / h_n + u / h_f
    r = sqrt(g * (1.0 + a)) / a
    x, y = k * r * cc, k * r * sc
    j = 2.0 * cp * cp / (h_n * h_f * (h_n + h_f))
    return atan2(hypot(x, y), 1.0), atan2(y, x), j * w


@entry_point
def points(k, h1, tan_c, sec_c, on_h, ox, xc, v, chi, w, psi, phi, jac):
    """The local incidences ``psi``, ``phi`` and irradiance weights ``jac`` (each ``(m, P)``,
    written) of the points ``(v, chi)`` with quadrature weights ``w`` (each ``(m, P)``) of
    ``m`` geometries, each given by its row of ``tan_c``, ``sec_c = hypot(1, tan_c)``,
    ``on_h``, ``ox`` and ``xc`` (nan: not the wedge); ``k``, ``h1``: the disc's
    (:class:`scatterbench.models.disc_cubature.Disc`)."""
    m, P = v.shape
    for i in range(m):
        if not math.isnan(xc[i]):
            for j in range(P):
                psi[i, j], phi[i, j], jac[i, j] = _wedge(k, xc[i], v[i, j], chi[i, j], w[i, j])
            continue
        about_h = on_h[i]  # the same for the geometry's points: the loop's select folds away
        for j in range(P):
            psi[i, j], phi[i, j], jac[i, j] = _polar(
                k, h1, tan_c[i], sec_c[i], about_h, ox[i], v[i, j], chi[i, j], w[i, j]
            )
