"""Cook-Torrance kernels (seed 001 Eq. 7-24): :class:`scatterbench.models.CookTorranceBRDF` and
:class:`scatterbench.models.VarnishedCookTorranceBRDF`, one geometry per call, as
:mod:`scatterbench.models.cook_torrance` and :mod:`scatterbench.models.varnished` compute them."""

from __future__ import annotations

import math

from ..kernel_specs import ANISO_GAUSSIAN, GAUSSIAN
from .common import (
    SMITH,
    cdiv,
    coating_cos,
    diag16,
    dielectric_transmittance,
    internal_sine,
    polar,
    refraction_w,
    smith_g,
    stroke_d,
)
from .helper import helper
from .vector_math import sqrt


@helper(forceinline=None)
def fresnel_average(c, mr, mi, pec):
    """Natural-light reflectance ``(|r_s|^2 + |r_p|^2) / 2`` at cosine ``c`` for relative index
    ``mr + i mi`` (:func:`scatterbench.models.cook_torrance.fresnel_average`)."""
    T = type(c)
    if T(1e-300) > T(0.0):
        # float64: the perfect conductor and m = 1 (whose denominators vanish at grazing) are
        # selects after the arithmetic, not early returns, and |r|^2 is |numerator|^2 /
        # |denominator|^2 (squares of index-sized values, < 1e66, fit): two real divisions
        # instead of two complex ones whose branches a vector loop computes both of.  With
        # the returns or those divisions LLVM 22's cost model (numba 0.68) kept the
        # Cook-Torrance loops scalar: 1.9-2.5x slower per geometry (benchmarks/kernel_ab.py
        # --what geometry against the branching form).
        m2r, m2i, wr, wi = refraction_w(c, mr, mi)
        ar, ai = m2r * c, m2i * c
        rs2 = ((c - wr) * (c - wr) + wi * wi) / ((c + wr) * (c + wr) + wi * wi)
        rp2 = ((ar - wr) * (ar - wr) + (ai - wi) * (ai - wi)) / (
            (ar + wr) * (ar + wr) + (ai + wi) * (ai + wi)
        )
        unit = mr == T(1.0) and mi == T(0.0)
        return T(1.0) if pec else (T(0.0) if unit else T(0.5) * (rs2 + rp2))
    if pec:
        return T(1.0)
    if mr == T(1.0) and mi == T(0.0):
        return T(0.0)
    # float32: those squares overflow from 1.8e19; Smith's division scales them
    m2r, m2i, wr, wi = refraction_w(c, mr, mi)
    ar, ai = m2r * c, m2i * c
    rsr, rsi = cdiv(c - wr, -wi, c + wr, wi)
    rpr, rpi = cdiv(ar - wr, ai - wi, ar + wr, ai + wi)
    return T(0.5) * ((rsr * rsr + rsi * rsi) + (rpr * rpr + rpi * rpi))


@helper
def ct_value(ci, si, cr, sr, cp, sp, p, mr, mi, shadowing):
    """``D G F`` of Eq. 7 (:func:`scatterbench.models.cook_torrance.ct_kernel`) for polar cosines ``ci``, ``cr``
    and sines ``si``, ``sr``;
    ``shadowing``: a code of :data:`scatterbench.models.kernel_specs.COOK_SHADOWING`.  Smith's ``G`` is that of
    :func:`scatterbench.models.cook_torrance.smith_slopes`: the Gaussian of width ``m`` (equal ``m``
    values), else the anisotropic Gaussian ``(m_par, m_perp)`` rotated by the strokes' azimuth."""
    T = type(ci)
    hx = sr * cp - si
    hy = sr * sp
    hz = ci + cr
    hz2 = hz * hz
    g = hx * hx + hy * hy + hz2
    q = g / hz2
    # the strokes' azimuth matters only for unequal m (stroke_d, as the numpy path's)
    ca, sa = (T(1.0), T(0.0)) if p[3] == p[4] else (p[6], p[7])
    val = stroke_d(hx, hy, hz2, p[3], p[4], ca, sa) * (q * q)
    val *= fresnel_average(T(0.5) * sqrt(g), mr, mi, mr == T(math.inf))
    if shadowing == 1:
        t = (T(4.0) / g) * hz
        val *= min(T(1.0), t * min(ci, cr))
    elif shadowing == 2:
        kind = GAUSSIAN if p[3] == p[4] else ANISO_GAUSSIAN
        # the strokes' azimuth's cosine and sine (ca, sa) are its rotation's: no call on the lanes
        val *= smith_g(SMITH, kind, (ci, si, -T(1.0), T(0.0)), (cr, sr, cp, sp), p[3], p[4], ca, sa)
    return val


@helper
def cook(geo, p, o):
    """Cook-Torrance (``o[0] = 0``) or its varnished form (1); ``o[1]``: corrected
    convention, ``o[2]``: the shadowing (:data:`scatterbench.models.kernel_specs.COOK_SHADOWING`)."""
    ti, tr, _, cp, sp = geo
    T = type(ti)
    half_pi = T(0.5 * math.pi)
    if ti >= half_pi or tr >= half_pi:
        return diag16(T(0.0))
    ci, si = polar(ti)
    cr, sr = polar(tr)
    nv, sub_r, sub_i = p[0], p[1], p[2]
    if o[0] == 0:
        val = ct_value(ci, si, cr, sr, cp, sp, p, sub_r, sub_i, o[2])
        scale = T(1.0 / (4.0 * math.pi)) if o[1] == 1 else T(1.0)
        return diag16(val * (scale / (ci * cr)))
    cii, cri = coating_cos(ci, nv), coating_cos(cr, nv)
    sii, sri = internal_sine(cii, si, nv), internal_sine(cri, sr, nv)
    val = ct_value(cii, sii, cri, sri, cp, sp, p, sub_r / nv, sub_i / nv, o[2])
    # both factors computed, then selected (no branch: the loop stays on SIMD lanes)
    film = dielectric_transmittance(ci, nv) * dielectric_transmittance(cr, nv)
    val *= film if nv != T(1.0) else T(1.0)
    paper, corrected = T(1.0) / (ci * cr), T(1.0 / (4.0 * math.pi)) / (nv * nv * cii * cri)
    return diag16(val * (paper if o[1] == 0 else corrected))
