"""Cosine, sine, ``exp(-x)``, ``atan2``, ``hypot`` and ``erfc`` in float64 without a call: code the compiler vectorizes.

A call to the C library's ``cos``, ``sin`` or ``exp`` costs about 5-10 ns per value and
keeps any loop around it scalar: in the facet kernel those calls were a fifth of a
geometry's cost, and they stopped the whole loop from running on SIMD lanes.  The
functions here are polynomials with no branch and no call, so a loop over geometries that
uses them (and only arithmetic and ``sqrt`` besides) compiles to vector instructions
(:mod:`scatterbench.models.kernels.vector`).

:func:`sincos` uses Cody and Waite's reduction and Taylor series: ``x = k pi/2 + r`` with
``k`` the nearest integer to ``2x/pi`` and ``|r| <= pi/4``; ``pi/2`` is split in three
parts, the first two of 30 significant bits, so ``k * part`` is exact for ``|k| < 2^23``
and ``r`` is exact to about an ulp of ``x`` up to :data:`REDUCED_MAX`.  On ``|r| <= pi/4``
the series of ``sin`` to ``r^17`` and of ``cos`` to ``r^16`` leave less than 1e-17 (the
next terms).  Beyond :data:`REDUCED_MAX` (an azimuth of 1e6 rad) the result is wrong: the
callers use the C library there (:func:`scatterbench.models.kernels.common.azimuth` for one value,
:func:`scatterbench.models.kernels.common.azimuths` for an array).

:func:`exp_neg` reduces ``-x = k ln 2 + r`` (``ln 2`` in two parts), ``|r| <= ln2 / 2``,
takes the Taylor series of ``exp r`` to ``r^13`` (the next term: 4e-18) and scales by
``2^k`` built from its bits.  From ``x = 700`` on it is exactly zero, as the numpy path's
:func:`scatterbench.models.slopes._exp_neg`.


:func:`atan2` takes ``t = min(|x|, |y|) / max(|x|, |y|)`` in [0, 1] and, above
``tan(pi/8)``, ``u = (t - 1) / (t + 1)`` (one division either way: the numerator and the
denominator are selected), so ``|u| <= tan(pi/8)``; ``atan u = u + u^3 f(u^2)`` with ``f``
a polynomial of degree 10 in ``u^2`` (Chebyshev fit of ``(atan u - u) / u^3`` on
``[0, tan^2(pi/8)]`` in 50-digit arithmetic, ``scripts/fit_atan_coefficients.py``: largest
error 3.2e-17, which enters ``atan u`` times ``u^2 <= 0.17``); the quadrant is then restored
with ``pi/4``, ``pi/2`` and ``pi`` each in two parts.

:func:`hypot` scales both arguments by the power of two that brings the larger near 1 (an exact
scale, :func:`inverse_binade`) before the square root, so that nothing overflows or underflows.

:func:`erfc` (Smith's ``Lambda`` of Gaussian slopes) writes ``erfc x = exp(-x^2) f(t) / (1 + 2 x)``,
``t = (x - 4) / (x + 4)``, for ``x >= 0`` (Shepherd and Laframboise's transformation: ``f`` is
smooth on all of ``[0, inf)``), ``f`` a polynomial of degree 23 (Chebyshev fit in 40-digit
arithmetic, ``scripts/fit_erfc_coefficients.py``: largest error 1.8e-18), and ``exp(-x^2)`` from
the exactly split square (:func:`exp_neg_square`).  Within 5 ulp of the exact value
(``scripts/fit_erfc_coefficients.py``: 2460 points of ``[-6, 27]`` and of 4e-18 to 1 against mpmath
at 40 digits) and of the C library's.

The first four agree with the C library within 2 ulp, ``erfc`` within 5 (``tests/test_vector_kernels.py``
measures it).
Float32 arguments are computed in float64 and rounded.
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import config, types
from numba.extending import intrinsic

from .helper import helper

#: ``pi/2`` in three parts: 30 + 30 significant bits, and the rest
_P1, _P2, _P3 = 1.570796325802803, 9.920935791635221e-10, 5.170182981794105e-19
_TWO_OVER_PI = 0.6366197723675814
#: the largest ``|x|`` :func:`sincos` reduces exactly (``k < 2^23`` with margin)
REDUCED_MAX = 1.0e6
# Taylor coefficients, sin: (-1)^k / (2k + 1)!, cos: (-1)^k / (2k)!, k = 1 .. 8
S1, S2, S3, S4, S5, S6, S7, S8 = ((-1) ** k / math.factorial(2 * k + 1) for k in range(1, 9))
C1, C2, C3, C4, C5, C6, C7, C8 = ((-1) ** k / math.factorial(2 * k) for k in range(1, 9))
#: ``ln 2`` in two parts (the first with 32 significant bits: ``k * _LN2_HI`` exact)
_LN2_HI, _LN2_LO = 6.93147180369123816490e-01, 1.90821492927058770002e-10
_INV_LN2 = 1.4426950408889634
# 1 / k!, k = 2 .. 13
E2, E3, E4, E5, E6, E7, E8, E9, E10, E11, E12, E13 = (1.0 / math.factorial(k) for k in range(2, 14))
#: from here on ``exp(-x)`` is exactly zero (as the numpy path's)
EXP_ZERO = 700.0
#: ``(atan u - u) / u^3`` as a polynomial in ``z = u^2``, constant term first
#: (``scripts/fit_atan_coefficients.py``)
A0, A1, A2, A3, A4, A5 = (-0.3333333333333333, 0.1999999999999552, -0.14285714284666542,
                          0.11111111015256361, -0.09090904578123903, 0.07692183190826087)  # fmt: skip
A6, A7, A8, A9, A10 = (-0.06664511447381948, 0.0585814891280221, -0.0508544973794026,
                       0.03923165829558719, -0.01917688711906226)  # fmt: skip
_TAN_PI_8 = 0.41421356237309503
#: ``pi/4``, ``pi/2``, ``pi``: the double nearest, and the rest
_PIO4_HI, _PIO4_LO = 0.7853981633974483, 3.061616997868383e-17
_PIO2_HI, _PIO2_LO = 1.5707963267948966, 6.123233995736766e-17
_PI_HI, _PI_LO = 3.141592653589793, 1.2246467991473532e-16
#: :func:`erfc`'s ``f(t)``, ``t = (x - 4) / (x + 4)``, constant term first
#: (``scripts/fit_erfc_coefficients.py``: largest error 1.8e-18 on ``0 <= x <= 27``)
F0, F1, F2, F3 = (1.2329951186255526, -0.13962111684056253, 0.015379652102619597, 0.0680970542546937)  # fmt: skip
F4, F5, F6, F7 = (-0.1010390660362968, 0.09373283499831267, -0.06633036581236375, 0.03716751553807599)  # fmt: skip
F8, F9, F10, F11 = (-0.01619773405644002, 0.005031969972796012, -0.0007577732952568108, -0.0001992566670501857)  # fmt: skip
F12, F13, F14, F15 = (0.00015062169378406569, -2.4399307369455275e-05, -1.1222059302484185e-05, 5.709928255278233e-06)  # fmt: skip
F16, F17, F18, F19 = (2.9385425601992844e-07, -8.256625187282693e-07, 7.455868029297701e-08, 1.1018756180763166e-07)  # fmt: skip
F20, F21, F22, F23 = (-1.7835527002435904e-08, -1.4103503645230917e-08, 1.8018631131624461e-09, 1.2428778155837613e-09)  # fmt: skip
#: :func:`erfc`'s ``K`` and the ``x`` from which ``erfc x`` is below the normal range
_ERFC_K, _ERFC_XMAX = 4.0, 27.0
#: Dekker's splitting constant, ``2^27 + 1``: ``x`` into two halves of 26 bits, whose
#: products are exact
_SPLIT = 134217729.0
#: :func:`hypot` scales its arguments by the binade of at most this
_TOP = 2.0**1022


@intrinsic
def _from_bits(typingctx, bits):
    """The float64 whose IEEE bits are the int64 ``bits`` (a register move, vectorizable)."""
    sig = types.float64(types.int64)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())

    return sig, codegen


@intrinsic
def _to_bits(typingctx, x):
    """The IEEE bits of the float64 ``x`` as an int64 (a register move, vectorizable)."""
    sig = types.int64(types.float64)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return sig, codegen


@helper
def inverse_binade(x):
    """``2^-e`` for the float64 ``x > 0`` of exponent ``e`` (``1 <= x 2^-e < 2`` for a normal
    ``x``): an exact scale that brings ``x`` near 1 without a division (subnormal ``x``: the
    scale ``2^1023``, which still lifts it above 1e-16)."""
    return binade_scales(x)[0]


@helper
def binade_scales(x):
    """:func:`inverse_binade`'s scale and its inverse (``2^-1023``, subnormal, for a subnormal
    ``x``), both exact: a product by the inverse undoes the scaling without a division (the
    same correctly rounded number; the divider is the SIMD lanes' narrowest unit)."""
    e = (_to_bits(np.float64(x)) >> 52) & 0x7FF
    return _from_bits((2046 - e) << 52), (_from_bits(e << 52) if e > 0 else _from_bits(np.int64(1) << 51))


@intrinsic
def sqrt(typingctx, x):
    """``math.sqrt`` as the ``llvm.sqrt`` intrinsic: numba calls the C library's ``sqrt``,
    which the vectorizer leaves alone (same IEEE result; NaN below zero, as both)."""
    if not isinstance(x, types.Float):
        return None

    def codegen(context, builder, signature, args):
        fn = builder.module.declare_intrinsic("llvm.sqrt", [context.get_value_type(signature.args[0])])
        return builder.call(fn, args)

    return x(x), codegen


if config.DISABLE_JIT:
    # NUMBA_DISABLE_JIT=1 (a debugging switch) runs the kernels as Python, where an
    # @intrinsic cannot be called: the same operations in numpy, bit for bit.

    def _from_bits(bits):  # noqa: F811 - the interpreted twin of the intrinsic above
        return np.int64(bits).view(np.float64)

    def _to_bits(x):  # noqa: F811
        return np.float64(x).view(np.int64)

    def sqrt(x):  # noqa: F811 - IEEE sqrt, NaN below zero (as llvm.sqrt), without numpy's warning
        with np.errstate(invalid="ignore"):
            return np.sqrt(x)


@helper
def sincos(x):
    """``(sin x, cos x)`` in float64 for ``|x| <= REDUCED_MAX`` (no branch, no call)."""
    v = np.float64(x)
    q = np.rint(v * _TWO_OVER_PI)
    r = ((v - q * _P1) - q * _P2) - q * _P3
    r2 = r * r
    s = r + r * r2 * (S1 + r2 * (S2 + r2 * (S3 + r2 * (S4 + r2 * (S5 + r2 * (S6 + r2 * (S7 + r2 * S8)))))))
    c = 1.0 + r2 * (C1 + r2 * (C2 + r2 * (C3 + r2 * (C4 + r2 * (C5 + r2 * (C6 + r2 * (C7 + r2 * C8)))))))
    quad = np.int64(q) & 3
    odd = (quad & 1) == 1
    sv = c if odd else s
    cv = s if odd else c
    return (-sv if quad >= 2 else sv), (-cv if (quad == 1 or quad == 2) else cv)


@helper
def exp_neg(x):
    """``exp(-x)`` in the precision of ``x >= 0``, exactly zero from :data:`EXP_ZERO` on."""
    T = type(x)
    v = np.float64(x)
    y = -min(v, EXP_ZERO)
    k = np.rint(y * _INV_LN2)
    r = (y - k * _LN2_HI) - k * _LN2_LO
    p = E9 + r * (E10 + r * (E11 + r * (E12 + r * E13)))
    p = 1.0 + r * (1.0 + r * (E2 + r * (E3 + r * (E4 + r * (E5 + r * (E6 + r * (E7 + r * (E8 + r * p))))))))
    e = p * _from_bits((np.int64(k) + 1023) << 52)
    return T(e if v < EXP_ZERO else 0.0)


@helper
def exp_neg_square(x):
    """``exp(-x^2)`` for ``x >= 0`` (no branch, no call), the square taken exactly: ``x^2 = p + e``
    (Dekker's product), ``exp(-p) (1 - e)``; rounding ``x^2`` would cost up to ``x^2`` ulps of
    the result.  Zero from ``x^2 = EXP_ZERO`` on, as :func:`exp_neg`."""
    T = type(x)
    v = np.float64(x)
    v = 30.0 if v > 30.0 else v  # exp(-900) is zero; an infinite x splits into NaN
    p = v * v
    c = _SPLIT * v
    hi = c - (c - v)
    lo = v - hi
    e = ((hi * hi - p) + 2.0 * hi * lo) + lo * lo
    return T(exp_neg(p) * (1.0 - e))


@helper
def erfc(x):
    """The complementary error function in float64 (no branch, no call): for ``a = |x|``,
    ``exp(-a^2) f(t) / (1 + 2 a)`` with ``t = (a - 4) / (a + 4)`` and ``f`` a polynomial of degree
    23 (:data:`F0` ...), ``2 - erfc(a)`` below zero.  Zero from ``a = sqrt(EXP_ZERO)`` (26.46,
    where ``erfc`` is below 2e-306) on, as :func:`exp_neg`."""
    T = type(x)
    v = np.float64(x)
    a = abs(v)
    a = _ERFC_XMAX if a > _ERFC_XMAX else a  # NaN passes; infinity is zero's
    t = (a - _ERFC_K) / (a + _ERFC_K)
    f = F16 + t * (F17 + t * (F18 + t * (F19 + t * (F20 + t * (F21 + t * (F22 + t * F23))))))
    f = F8 + t * (F9 + t * (F10 + t * (F11 + t * (F12 + t * (F13 + t * (F14 + t * (F15 + t * f)))))))
    f = F0 + t * (F1 + t * (F2 + t * (F3 + t * (F4 + t * (F5 + t * (F6 + t * (F7 + t * f)))))))
    r = exp_neg_square(a) * f / (1.0 + 2.0 * a)
    return T(2.0 - r if v < 0.0 else r)


@helper
def hypot(x, y):
    """``hypot(x, y)`` without overflow or underflow and without a call: both scaled by the
    power of two that brings the larger near 1 (exact), within about an ulp of the C
    library's."""
    ax, ay = abs(x), abs(y)
    hi, lo = max(ax, ay), min(ax, ay)
    # (2^1022 at most: inverse_binade's scale of the top binade, 2^-1023, is not a normal
    # number; from there ``a`` is in [2, 4), as harmless)
    scale, back = binade_scales(min(hi, _TOP) if hi > 0.0 else 1.0)
    a, b = hi * scale, lo * scale
    return sqrt(a * a + b * b) * back


@helper
def atan2(y, x):
    """``atan2(y, x)`` in float64 for finite ``x``, ``y`` (no branch, no call): the angle of
    ``(x, y)`` in [-pi, pi], with the C library's signs at zeros (``atan2(+-0, -0) = +-pi``)."""
    ay, ax = abs(np.float64(y)), abs(np.float64(x))
    hi, lo = max(ax, ay), min(ax, ay)
    big = lo > _TAN_PI_8 * hi
    num = lo - hi if big else lo
    den = lo + hi if big else hi
    u = num / (den if den > 0.0 else 1.0)
    z = u * u
    p = A8 + z * (A9 + z * A10)
    p = A0 + z * (A1 + z * (A2 + z * (A3 + z * (A4 + z * (A5 + z * (A6 + z * (A7 + z * p)))))))
    r = (u + (u * z * p + (_PIO4_LO if big else 0.0))) + (_PIO4_HI if big else 0.0)
    r = _PIO2_HI - (r - _PIO2_LO) if ay > ax else r
    r = _PI_HI - (r - _PI_LO) if math.copysign(1.0, x) < 0.0 else r
    return math.copysign(r, y)
