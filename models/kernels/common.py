"""Scalar building blocks of the compiled kernels (numba; not cached themselves: the
entries that inline them are, :mod:`scatterbench.models.kernels`).

Every function here works on one geometry's scalars in real arithmetic, in the precision
of its arguments: constants are written ``T(c)`` with ``T = type(x)`` so that the float32
kernels compute in float32 and the float64 ones exactly as written.  Complex numbers are
``(re, im)`` pairs.  The formulas mirror the numpy implementation they are tested against
(:mod:`scatterbench.models.fresnel`, :mod:`scatterbench.models.slopes`, :mod:`scatterbench.models.shadowing`,
:func:`scatterbench.models.polarization.mueller16_from_jones`); comments say where they differ.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..kernel_specs import (
    ANISO_EXPONENTIAL,
    ANISO_GAUSSIAN,
    ANISO_GGX,
    EXPONENTIAL,
    GAUSSIAN,
    GGX,
    SHADOWING_KINDS,
    UNIT,
)
from .helper import helper
from .vector_math import REDUCED_MAX, erfc, exp_neg, exp_neg_square, hypot, sincos, sqrt

NO_SHADOWING, SMITH = SHADOWING_KINDS["none"], SHADOWING_KINDS["smith"]

_SQRT6 = math.sqrt(6.0)
_INV_SQRT_PI = 1.0 / math.sqrt(math.pi)


@helper
def polar(t):
    """``(cos t, sin t)`` of a polar angle ``t`` in its precision, the sine as the numpy path
    takes it, ``sqrt(1 - cos^2)``, both computed in float64: in float32 that formula loses the
    sine near normal incidence (``cos`` rounds to 1 below 3.5e-4 rad: off by up to 2.4e-4);
    from float64 the float32 sine is off by at most 1.125 float32 epsilons
    (``tests/test_float32_domain.py``)."""
    return polar_from(sincos(t)[1], t)


@helper
def polar_from(c, t):
    """:func:`polar` of ``t`` from its cosine ``c``, computed in float64."""
    T = type(t)
    return T(c), T(sqrt(1.0 - c * c))


@helper
def azimuth(p):
    """``(cos p, sin p)`` of an azimuth (float64; :func:`~scatterbench.models.kernels.vector_math.sincos`,
    the C library beyond its range)."""
    if abs(p) <= REDUCED_MAX:
        s, c = sincos(p)
        return c, s
    v = np.float64(p)
    return math.cos(v), math.sin(v)


@helper
def azimuths(p, c, s):
    """:func:`azimuth` of every element of ``p`` into ``c``, ``s`` (float64 arrays of its
    length): :func:`azimuths_at` over the whole arrays."""
    azimuths_at(p, 0, c, 0, s, 0, p.shape[0])


@njit(error_model="numpy", inline="always")
def azimuths_at(p, pa, c, ca, s, sa, n):
    """:func:`azimuth` of ``p[pa:pa + n]`` into ``c[ca:ca + n]``, ``s[sa:sa + n]`` (flat float64
    arrays; one array thrice for the lanes' scratch rows, where views would count references),
    in two passes: the polynomial over all of them (a loop on SIMD lanes), then the C library
    for the rare ones beyond its range, only if there are any (a branch to it per value, as in
    :func:`azimuth`, would keep the first loop scalar)."""
    far = 0
    for k in range(n):
        v = p[pa + k]
        s[sa + k], c[ca + k] = sincos(v)
        far += not abs(v) <= REDUCED_MAX
    if far:
        for k in range(n):
            v = p[pa + k]
            if not abs(v) <= REDUCED_MAX:
                s[sa + k], c[ca + k] = math.sin(v), math.cos(v)


@helper
def internal_sine(c_int, s_ext, n):
    """Sine of the refracted angle in a coating ``n`` of cosine ``c_int``, external sine
    ``s_ext``: float64 ``sqrt(1 - c_int^2)`` (the numpy path's); float32 ``s_ext / n`` (Snell;
    the cosine near 1 has lost the sine, see :func:`polar`)."""
    T = type(c_int)
    if T(1e-300) > T(0.0):  # float64 (1e-300 is 0 in float32)
        return sqrt(T(1.0) - c_int * c_int)
    return s_ext / n


@helper
def csqrt(a, b):
    """Principal square root of ``a + ib`` (a ``+0`` imaginary part: the ``+i`` branch, TIR).
    No call (a loop that uses it vectorizes; its branches become selects there)."""
    T = type(a)
    if a == T(0.0) and b == T(0.0):
        return T(0.0), T(0.0)
    # |a|, |b| are index-sized (up to |n + ik|^2 ~ 3.3e32): their squares overflow float32 from
    # 1.8e19 and underflow below 1.1e-19; scaled by the larger, r (hence t) stays finite and
    # nonzero there.  float64 (1e-300 > 0: a constant per precision) holds them unscaled, with
    # r = |a + ib| >= max(|a|, |b|) imposed: where both squares underflow (|a|, |b| < 1e-154,
    # near INDEX_MIN) that keeps r, hence t, nonzero, and elsewhere sqrt(fl(x^2)) >= |x| leaves
    # the bits alone.  Without the scaled branch the Cook-Torrance loops stay within LLVM 22's
    # vectorization cost model (numba 0.68).
    s = max(abs(a), abs(b))
    if T(1e-300) > T(0.0):
        r = max(sqrt(a * a + b * b), s)
    elif T(1.0e-19) < s < T(1.0e19):
        r = sqrt(a * a + b * b)
    else:
        a_s, b_s = a / s, b / s
        r = s * sqrt(a_s * a_s + b_s * b_s)
    # the branch's operands selected before the root and the division, not its results: a
    # vector loop computes both sides of a select (here one root and one division, not two)
    right = a >= T(0.0)
    t = sqrt((a + r if right else r - a) * T(0.5))
    q = (b if right else abs(b)) / (T(2.0) * t)
    return (t, q) if right else (q, math.copysign(t, b))


@helper
def cdiv(a, b, c, d):
    """``(a + ib) / (c + id)`` as numpy divides complex numbers (Smith's algorithm with one
    reciprocal, ``scl = 1 / den``, and two products: bit for bit numpy's result, and one
    division fewer than dividing both parts by ``den``)."""
    T = type(a)
    # the larger part of the denominator selected first (a vector loop computes both sides of
    # a select: two divisions, not four); the same operations on the same values as the branches
    big = abs(c) >= abs(d)
    p, q = (c, d) if big else (d, c)
    r = q / p
    scl = T(1.0) / (p + q * r)
    if big:
        return (a + b * r) * scl, (b - a * r) * scl
    return (a * r + b) * scl, (b * r - a) * scl


@helper
def refraction_w(c, mr, mi):
    """``m^2`` and ``w = m cos(theta_t) = sqrt(m^2 - 1 + c^2)`` (principal branch) as
    ``(re, im)`` pairs, for cosine ``c`` and relative index ``m = mr + i mi``
    (:mod:`scatterbench.models.fresnel`'s ``w``)."""
    T = type(c)
    m2r = mr * mr - mi * mi
    m2i = mr * mi + mi * mr
    wr, wi = csqrt(m2r - T(1.0) + c * c, m2i)
    return m2r, m2i, wr, wi


@helper
def rs_k(c, mr, mi, pec):
    """``r_s`` and ``K = (r_s + r_p) / sin^2`` at cosine ``c`` for relative index ``m = mr + i mi``
    (:func:`scatterbench.models.fresnel.reflection_rs_k`); ``pec``: a perfect conductor."""
    T = type(c)
    if pec:
        return T(-1.0), T(0.0), T(0.0), T(0.0)
    if mr == T(1.0) and mi == T(0.0):
        return T(0.0), T(0.0), T(0.0), T(0.0)
    m2r, m2i, wr, wi = refraction_w(c, mr, mi)
    if T(1e-300) > T(0.0):  # float64: one division (its products stay in range; below)
        return _rs_k64(c, m2r, m2i, wr, wi)
    cwr, cwi = c + wr, wi
    rsr, rsi = cdiv(c - wr, -wi, cwr, cwi)
    # 2 (1 - m^2) / (m^2 c + w) / (c + w): two divisions, not one by the product, which
    # overflows float32 from |m| ~ 7e12 (|m^2 c + w| |c + w| ~ |m|^3; float32's largest: 3.4e38)
    qr, qi = cdiv(T(2.0) * (T(1.0) - m2r), -T(2.0) * m2i, m2r * c + wr, m2i * c + wi)
    kr, ki = cdiv(qr, qi, cwr, cwi)
    return rsr, rsi, kr, ki


@helper
def _rs_k64(c, m2r, m2i, wr, wi):
    """:func:`rs_k` in float64 with one division, where float32's takes six (three of
    :func:`cdiv`): ``r_s = (c - w) / D1`` and ``K = 2 (1 - m^2) / (D1 D2)``, ``D1 = c + w``,
    ``D2 = m^2 c + w``, both over ``|D1|^2 |D2|^2``, whose reciprocal gives ``1 / |D1|^2`` and
    ``1 / |D2|^2`` by products.  In range for every index the models take: ``|D1|^2 |D2|^2 ~
    |m|^6`` is 3e97 at ``|m|^2 = 3.3e32`` (float64's largest: 1.8e308), and ``|D1| >= c``,
    ``|D2| >= |m^2| c``.  Complex quotients by conjugates rather than Smith's algorithm (numpy's):
    within a few roundings of it (a rounding's relative size, normwise), which
    :mod:`scatterbench.models.kernel_tolerance`'s arithmetic term holds; the divider is the
    SIMD lanes' narrowest unit."""
    T = type(c)
    d1r, d1i = c + wr, wi
    d2r, d2i = m2r * c + wr, m2i * c + wi
    n1, n2 = d1r * d1r + d1i * d1i, d2r * d2r + d2i * d2i
    s = T(1.0) / (n1 * n2)
    s1 = s * n2
    ar, ai = c - wr, -wi
    rsr, rsi = (ar * d1r + ai * d1i) * s1, (ai * d1r - ar * d1i) * s1
    er, ei = T(2.0) * (T(1.0) - m2r), -T(2.0) * m2i
    pr, pi = d1r * d2r - d1i * d2i, d1r * d2i + d1i * d2r  # D1 D2
    return rsr, rsi, (er * pr + ei * pi) * s, (ei * pr - er * pi) * s


@helper
def coating_w(c, n):
    """``w = n cos(theta_t) = sqrt(n^2 - 1 + c^2)`` of refraction into a non-absorbing coating
    ``n`` at external cosine ``c``: what :func:`coating_cos` and :func:`coating_t` share."""
    T = type(c)
    return sqrt(n * n - T(1.0) + c * c)


@helper
def coating_cos(c, n):
    """Cosine of the refracted angle in a non-absorbing coating ``n`` from the external cosine
    ``c`` (:func:`scatterbench.models.fresnel.coating_cos`: no cancellation near grazing)."""
    T = type(c)
    return coating_w(c, n) * (T(1.0) / n)


@helper
def coating_t(c, n, w):
    """Real ``t_s``, ``t_p`` into a non-absorbing coating ``n`` (:func:`scatterbench.models.fresnel.coating_transmission`),
    given :func:`coating_w`'s ``w``."""
    T = type(c)
    a, b = c + w, n * n * c + w
    if T(1e-300) > T(0.0):  # float64: one division (a b ~ n^3 is in range for any index)
        r = T(2.0) * c / (a * b)
        return r * b, n * (r * a)
    return T(2.0) * c / a, T(2.0) * n * c / b


@helper
def dielectric_transmittance(c, n):
    """``1 - F`` for natural light at cosine ``c`` entering a non-absorbing ``n >= 1``
    (:func:`scatterbench.models.kernels.cook.fresnel_average` of a real index, in real arithmetic:
    ``w = sqrt(n^2 - 1 + c^2)`` is real, so neither the complex root nor the complex
    divisions, whose branches a vector loop computes both of, are needed: with them LLVM's
    cost model kept the varnished Cook-Torrance loop scalar)."""
    T = type(c)
    n2 = n * n
    w = sqrt(n2 - T(1.0) + c * c)
    rs = (c - w) / (c + w)
    rp = (n2 * c - w) / (n2 * c + w)
    return T(1.0) - T(0.5) * (rs * rs + rp * rp)


@helper
def hg_density(g, c):
    """Henyey-Greenstein density per sr at scattering cosine ``c``
    (:meth:`scatterbench.models.phase.HenyeyGreenstein.density`, the same form: its base
    ``1 + g^2 - 2 g c`` written as ``u^2 + 2 |g| v``, ``u = 1 - |g|``, ``v = 1 -+ c`` by the sign
    of ``g``, a sum of two non-negative terms: the printed form cancels to 0 at g -> -1 and
    backscatter, c = -1, where the density is large but finite)."""
    T = type(c)
    u = T(1.0) - abs(g)
    v = T(1.0) + c if g < T(0.0) else T(1.0) - c
    base = u * u + T(2.0) * abs(g) * max(v, T(0.0))
    return u * (T(2.0) - u) / (T(4.0 * math.pi) * base * sqrt(base))


@helper
def p3(kind, zx, zy, sx, sy, rot, cov):
    """Slope density ``P3^xy`` of ``kind`` at ``(zx, zy)``; ``sx``, ``sy`` the widths (sigma,
    alpha; ``m_parallel``, ``m_perpendicular`` for strokes), ``rot`` the axes' rotation."""
    T = type(zx)
    pi = T(math.pi)
    if kind == UNIT:
        return T(1.0)
    if kind == EXPONENTIAL:
        z = sqrt(zx * zx + zy * zy)
        return cov * ((T(3.0) / (pi * sx * sx)) * exp_neg(T(_SQRT6) * z / sx))
    if kind == GAUSSIAN:
        return cov * (exp_neg((zx * zx + zy * zy) / (sx * sx)) / (pi * sx * sx))
    if kind == GGX:
        a2 = sx * sx
        d = a2 + zx * zx + zy * zy
        return cov * (a2 / (pi * d * d))
    c, s = math.cos(rot), math.sin(rot)
    u = c * zx + s * zy
    v = -s * zx + c * zy
    if kind == ANISO_EXPONENTIAL:
        r = sqrt((u / sx) ** 2 + (v / sy) ** 2)
        return cov * (T(3.0) / (pi * sx * sy) * exp_neg(T(_SQRT6) * r))
    if kind == ANISO_GAUSSIAN:
        return cov * (exp_neg((u / sx) ** 2 + (v / sy) ** 2) / (pi * sx * sy))
    if kind == ANISO_GGX:
        d = T(1.0) + (u / sx) ** 2 + (v / sy) ** 2
        return cov * (T(1.0) / (pi * sx * sy * d * d))
    return cov * (stroke_d(zx, zy, T(1.0), sx, sy, c, s) / pi)


@helper
def stroke_d(hx, hy, hz2, m_par, m_perp, c, s):
    """``exp(-tan^2 alpha / m(beta)^2) / m(beta)^2`` for a bisector ``h`` (seed 001 Eq. 8, 19;
    :func:`scatterbench.models.stroke_slopes.stroke_d`); ``c``, ``s``: cosine and sine of the strokes' azimuth."""
    T = type(hx)
    a2 = T(1.0) / (m_par * m_par)
    if m_par == m_perp:
        return exp_neg((hx * hx + hy * hy) * a2 / hz2) * a2
    b2 = T(1.0) / (m_perp * m_perp)
    u = c * hx + s * hy
    v = c * hy - s * hx
    u2, v2 = u * u, v * v
    q = u2 * a2 + v2 * b2
    r2 = u2 + v2
    inv_m2 = q / r2 if r2 > T(0.0) else T(0.5) * (a2 + b2)
    return exp_neg(q / hz2) * inv_m2


@helper
def lam_unit(kind, mu):
    """Smith ``Lambda`` of the unit-width Gaussian or GGX family at ``mu = |cot theta|``: infinite
    at ``mu = 0``, zero at infinite ``mu``, without a branch or a call (the Gaussian's tail
    divides by zero at ``mu = 0``), so that a loop over geometries stays on SIMD lanes."""
    T = type(mu)
    if kind == GAUSSIAN or kind == ANISO_GAUSSIAN:
        tail = exp_neg_square(mu) * T(_INV_SQRT_PI) / (T(2.0) * mu)
        return tail - T(0.5) * erfc(mu)
    x = T(1.0) / mu
    # as shadowing.lambda_ggx: x^2 would overflow at grazing (float32 already at x ~ 2e19)
    lam = T(0.5) * x * (x / (T(1.0) + T(hypot(T(1.0), x))))
    return T(math.inf) if mu == T(0.0) else lam


@helper
def rotation(kind, rot):
    """Cosine and sine of slope kind ``kind``'s rotation ``rot`` (the elliptical kinds'; 1 and 0
    for the others, without a call): through the C library, so that a loop whose kind is a
    constant of an isotropic kind keeps no call (:mod:`~scatterbench.models.kernels.vector`)."""
    T = type(rot)
    if kind == GAUSSIAN or kind == GGX:
        return T(1.0), T(0.0)
    return math.cos(rot), math.sin(rot)


@helper
def smith_lambda(kind, c, s, cphi, sphi, sx, sy, cr, sr):
    """Smith ``Lambda`` (:func:`scatterbench.models.shadowing.smith_lambda`) of the Gaussian and GGX
    families, isotropic or elliptical, for a direction (cosine, sine, azimuth); ``cr``, ``sr``:
    the cosine and sine of the ellipse's rotation (:func:`rotation`, or parameter rows), so that
    no call is left here and a loop with a run-time kind stays on SIMD lanes (Cook-Torrance's
    Smith ``G``: isotropic or elliptical by its parameters)."""
    T = type(c)
    mu = abs(c) / s if s > T(0.0) else T(math.inf)
    return lam_unit(kind, mu / smith_width(kind, cphi, sphi, sx, sy, cr, sr))


@helper
def smith_width(kind, cphi, sphi, sx, sy, cr, sr):
    """The slopes' width along a direction of azimuth ``(cphi, sphi)``: ``sx`` for the isotropic
    kinds, the ellipse's radius (rotated by ``(cr, sr)``) for the elliptical ones."""
    if kind == GAUSSIAN or kind == GGX:
        return sx
    cl = cphi * cr + sphi * sr
    sl = sphi * cr - cphi * sr
    return sqrt((sx * cl) ** 2 + (sy * sl) ** 2)


@helper
def smith_h(kind, c, s, cphi, sphi, sx, sy, cr, sr):
    """GGX's ``|c| h = hypot(|c|, alpha s)`` for a direction (arguments as :func:`smith_lambda`'s),
    ``h = sqrt(1 + x^2)``, ``x = alpha tan theta``: its ``Lambda = (h - 1) / 2``, so ``1 + Lambda
    = (1 + h) / 2`` and ``1 + Lambda_i + Lambda_o = (h_i + h_o) / 2``; :func:`smith_g` takes
    ``G`` of both directions over one division, ``|c|`` multiplied out (through ``h`` it took
    three, through ``Lambda`` seven or eight; the divider is the SIMD lanes' narrowest unit).
    Finite at grazing (``c = 0``: ``G = 0``, as ``Lambda``'s infinity gives), ``|c|`` at normal
    incidence (``s = 0``)."""
    alpha = smith_width(kind, cphi, sphi, sx, sy, cr, sr)
    return type(c)(hypot(abs(c), alpha * s))


@helper
def smith_g(shadowing, kind, di, dio, sx, sy, cr, sr):
    """Shadowing-masking ``G`` for directions ``di``, ``dio`` = ``(cos, sin, cos phi, sin phi)``
    (no back-facing test: both see the facet from its front); ``cr``, ``sr`` as
    :func:`smith_lambda`'s."""
    T = type(sx)
    if kind == GGX or kind == ANISO_GGX:
        ci, co = abs(di[0]), abs(dio[0])
        hi = smith_h(kind, di[0], di[1], di[2], di[3], sx, sy, cr, sr)
        ho = smith_h(kind, dio[0], dio[1], dio[2], dio[3], sx, sy, cr, sr)
        if shadowing == SMITH:  # 4 / ((1 + h_i) (1 + h_o)), each h as |c| h / |c|
            return T(4.0) * ci * co / ((ci + hi) * (co + ho))
        den = co * hi + ci * ho  # 2 / (h_i + h_o); zero only where both are grazing, as G
        return T(2.0) * ci * co / (den if den > T(0.0) else T(1.0))
    li = smith_lambda(kind, di[0], di[1], di[2], di[3], sx, sy, cr, sr)
    lo = smith_lambda(kind, dio[0], dio[1], dio[2], dio[3], sx, sy, cr, sr)
    if shadowing == SMITH:
        return (T(1.0) / (T(1.0) + li)) * (T(1.0) / (T(1.0) + lo))
    return T(1.0) / (T(1.0) + (li + lo))


@helper
def mueller16(ssr, ssi, psr, psi, spr, spi, ppr, ppi):
    """The 16 Mueller elements (row-major) of a Jones matrix (Bohren & Huffman, as
    :func:`scatterbench.models.polarization.mueller16_from_jones`)."""
    T = type(ssr)
    half = T(0.5)
    nss = ssr * ssr + ssi * ssi
    npp = ppr * ppr + ppi * ppi
    nps = psr * psr + psi * psi
    nsp = spr * spr + spi * spi
    a = nss + npp
    c = nps + nsp
    b = nss - npp
    d = nsp - nps
    x1r, x1i = ssr * psr + ssi * psi, ssi * psr - ssr * psi
    x2r, x2i = ppr * spr + ppi * spi, ppi * spr - ppr * spi
    x3r, x3i = ssr * spr + ssi * spi, ssi * spr - ssr * spi
    x4r, x4i = ppr * psr + ppi * psi, ppi * psr - ppr * psi
    x5r, x5i = ppr * ssr + ppi * ssi, ppi * ssr - ppr * ssi
    x6r, x6i = psr * spr + psi * spi, psi * spr - psr * spi
    return (
        (a + c) * half, (b + d) * half, x1r + x2r, x1i - x2i,
        (b - d) * half, (a - c) * half, x1r - x2r, x1i + x2i,
        x3r + x4r, x3r - x4r, x5r + x6r, -(x5i + x6i),
        x4i - x3i, -(x3i + x4i), x5i - x6i, x5r - x6r,
    )  # fmt: skip


@helper
def diag16(m00):
    """A depolarizer ``diag(m00, 0, 0, 0)`` (the scalar models)."""
    z = type(m00)(0.0)
    return (m00, z, z, z, z, z, z, z, z, z, z, z, z, z, z, z)


@helper
def scaled16(m, f):
    """The 16 elements ``m`` times ``f``."""
    return (
        m[0] * f, m[1] * f, m[2] * f, m[3] * f, m[4] * f, m[5] * f, m[6] * f, m[7] * f,
        m[8] * f, m[9] * f, m[10] * f, m[11] * f, m[12] * f, m[13] * f, m[14] * f, m[15] * f,
    )  # fmt: skip
