"""Fresnel amplitude coefficients of a single planar interface (Born & Wolf).

All functions take the cosine of the angle of incidence ``c`` in medium ``n1``
and the relative index ``m = n2 / n1`` (complex ``n + ik`` with ``k >= 0`` for
absorbing media, ``math.inf`` for a perfect conductor).  With
``w = m cos(theta_t) = sqrt(m^2 - 1 + c^2)`` on the principal branch
(``+i|...|`` beyond the critical angle, the decaying evanescent wave):

    r_s = (c - w) / (c + w)            t_s = 2 c / (c + w)
    r_p = (m^2 c - w) / (m^2 c + w)    t_p = 2 m c / (m^2 c + w)

This is the sign convention of SCATMECH (``Thin_Film_Transfer_Matrix`` with no
films): ``r_p = -r_s`` at normal incidence.  Seed 000 Appendix Eq. A.2 as
printed has ``(n2/n1) cos(theta)`` where ``(n2/n1)^2 cos(theta)`` belongs (with
it ``r_p`` would vanish at normal incidence for every material), and Eq. A.3-A.4
carry stray factors ``n1`` and ``n1/n2``; the standard forms above are used and
tested (``R + T = 1`` with the ``Re(w)/c`` flux factor, agreement with SCATMECH).
A perfect conductor has ``r_s = -1``, ``r_p = +1``, ``t_s = t_p = 0``.
"""

from __future__ import annotations

import math

import numpy as np

from .constraints import INDEX_MAX, INDEX_MIN, ComplexIndex, Interval

__all__ = [
    "fresnel_coefficients",
    "fresnel_reflectance",
    "fresnel_transmittance",
    "reflection_rs_k",
    "coating_transmission",
    "coating_cos",
    "critical_angle",
]


def _w(c, m):
    # m^2 - sin^2 in the form that keeps its digits: (m^2 - 1) + c^2 for |m| near 1 or above
    # (exact at grazing under m = 1), m^2 - (1 - c)(1 + c) for a small index, where the first
    # cancels at normal incidence (m = 1e-12: 1e-24 - 1 + 1 = 0, so w = 0 for w = m, and a
    # film's interfaces then met as 1 + r r' = 0: 0/0)
    c = np.asarray(c)
    small = np.abs(m) < 0.5
    arg = np.where(small, m * m - (1.0 - c) * (1.0 + c), m * m - 1.0 + c * c)
    arg = np.asarray(arg, dtype=complex)
    arg = np.where(arg.imag == 0, arg.real + 0j, arg)  # +0 imaginary part: TIR branch +i
    return np.sqrt(arg)


def _checked(cos_i, n1, n2):
    """The public functions' arguments validated: ``cos_i`` finite in [0, 1] (float64 array),
    ``n1`` a real index (the incident medium is non-absorbing), ``n2`` an index ``n + ik``
    or ``math.inf`` (:class:`~.constraints.ComplexIndex`); a ``ValueError`` naming the
    parameter and its range otherwise (n2 = -1.5 and cos_i = 2 gave numbers, n1 = 0 a
    ZeroDivisionError)."""
    c = np.asarray(cos_i)
    if c.dtype.kind not in "iuf":
        raise ValueError(f"cos_i must be a real number or array in [0, 1]; got {c.dtype}")
    c = c.astype(float, copy=False)
    if c.size and not (np.all(np.isfinite(c)) and c.min() >= 0.0 and c.max() <= 1.0):
        bad = c[~((c >= 0.0) & (c <= 1.0))].reshape(-1)[0]
        raise ValueError(
            f"cos_i must lie in [0, 1] (the cosine of an angle of incidence); got {float(bad)!r}"
        )
    return c, _N1.check("n1", n1), _N2.check("n2", n2)


_N1 = Interval(INDEX_MIN, INDEX_MAX)
_N2 = ComplexIndex()


def fresnel_coefficients(cos_i, n1, n2):
    """``(r_s, r_p, t_s, t_p)`` for light in ``n1`` (real) hitting ``n2``.

    ``cos_i`` is the cosine of the angle of incidence (array, in [0, 1]).
    ``n2`` may be complex (``k >= 0``) or ``math.inf``.  Out-of-range arguments raise a
    ``ValueError`` naming them.
    """
    return _coefficients(*_checked(cos_i, n1, n2))


def _coefficients(cos_i, n1, n2):
    """:func:`fresnel_coefficients` of arguments the caller validated (the models' internal
    calls, whose local cosines may carry a rounding beyond 1)."""
    c = np.asarray(cos_i, dtype=float)
    if n2 == math.inf:
        one = np.ones_like(c, dtype=complex)
        return -one, one.copy(), 0 * one, 0 * one
    m = complex(n2) / complex(n1)
    if m == 1:
        zero = np.zeros_like(c, dtype=complex)
        return zero, zero.copy(), zero + 1, zero + 1
    w = _w(c, m)
    m2c = m * m * c
    rs = (c - w) / (c + w)
    rp = (m2c - w) / (m2c + w)
    ts = 2 * c / (c + w)
    tp = 2 * m * c / (m2c + w)
    return rs, rp, ts, tp


def fresnel_reflectance(cos_i, n1, n2):
    """Intensity reflectances ``(R_s, R_p)`` (arguments as :func:`fresnel_coefficients`)."""
    return _reflectance(*_checked(cos_i, n1, n2))


def _reflectance(cos_i, n1, n2):
    """:func:`fresnel_reflectance` of validated arguments (internal calls)."""
    rs, rp, _, _ = _coefficients(cos_i, n1, n2)
    return np.abs(rs) ** 2, np.abs(rp) ** 2


def fresnel_transmittance(cos_i, n1, n2):
    """Intensity transmittances ``(T_s, T_p)`` into a non-absorbing ``n2``.

    ``T = Re(n2 cos t) / (n1 cos i) |t|^2 = Re(w) / c |t|^2``: the ratio of the
    normal components of the Poynting vectors, zero beyond the critical angle.
    """
    c, n1, n2 = _checked(cos_i, n1, n2)
    if n2 == math.inf:
        z = np.zeros_like(c)
        return z, z.copy()
    m = complex(n2) / complex(n1)
    if m.imag != 0:
        raise ValueError("fresnel_transmittance needs a non-absorbing n2 (k = 0)")
    _, _, ts, tp = _coefficients(c, n1, n2)
    w = _w(c, m)
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(c > 0, w.real / np.where(c > 0, c, 1.0), 0.0)
    return f * np.abs(ts) ** 2, f * np.abs(tp) ** 2


def reflection_rs_k(cos_i, m):
    """``r_s`` and ``K = (r_s + r_p) / sin^2(theta)`` for a reflection at cosine ``cos_i``.

    ``K = 2 (1 - m^2) / ((c + w)(m^2 c + w))`` is smooth at normal incidence,
    where ``r_s + r_p`` and ``sin^2`` both vanish.  The facet Jones matrices are
    written with ``r_s`` and ``K`` so that they need no division by
    ``sin^2(2 alpha)`` (seed 000 Eq. 19a), which is what makes exact
    retroreflection (alpha = 0) finite.  ``m`` is the relative index (complex,
    scalar) or ``math.inf``.
    """
    c = np.asarray(cos_i, dtype=float)
    if m == math.inf:
        return np.full(c.shape, -1.0 + 0j), np.zeros(c.shape, dtype=complex)
    m = complex(m)
    if m == 1:
        z = np.zeros(c.shape, dtype=complex)
        return z, z.copy()
    w = _w(c, m)
    cw = c + w
    m2 = m * m
    rs = (c - w) / cw
    k = 2.0 * (1.0 - m2) / (cw * (m2 * c + w))
    return rs, k


def coating_cos(cos_theta, n):
    """Cosine of the refracted angle inside a non-absorbing coating ``n >= 1`` entered from
    the ambient (index 1) at external cosine ``cos_theta``: ``sqrt(n^2 - 1 + c^2) / n``.

    This form, not ``sqrt(1 - sin^2 / n^2)``: near grazing under a thin coating (``n ~ 1``)
    the difference of two numbers near 1 loses the digits of ``c^2`` (in float32 all of
    them), and for ``n = 1`` it is ``c`` exactly.  :mod:`scatterbench.models.kernels.common` has its
    scalar twin."""
    return np.sqrt(n * n - 1.0 + cos_theta * cos_theta) * (1.0 / n)


def coating_transmission(cos_theta, n):
    """Real ``t_s(theta; 1, n)`` and ``t_p(theta; 1, n)`` into a non-absorbing ``n >= 1``.

    From the ambient (index 1) into the coating there is no total internal
    reflection, so these are real; ``cos_theta`` is the external cosine.
    """
    c = np.asarray(cos_theta, dtype=float)
    n = float(n)
    w = np.sqrt(n * n - 1.0 + c * c)
    ts = 2.0 * c / (c + w)
    tp = 2.0 * n * c / (n * n * c + w)
    return ts, tp


def critical_angle(n1, n2):
    """Critical angle (radians) for light in ``n1`` hitting a real ``n2 < n1``; ``None`` if none."""
    n1 = float(np.real(n1))
    if n2 == math.inf:
        return None
    n2 = complex(n2)
    if n2.imag != 0 or n2.real >= n1:
        return None
    return math.asin(n2.real / n1)
