"""Facet kernels: reflection by facets under a smooth coating (seed 000; :class:`scatterbench.models.FacetBRDF`,
:class:`scatterbench.models.SubsurfaceFacetBRDF`) and transmission into a rough dielectric (seed 003
Sec. 2.4; :class:`scatterbench.models.FacetBTDF`), one geometry per call, as :mod:`scatterbench.models.facet` and
:mod:`scatterbench.models.facet_btdf` compute them."""

from __future__ import annotations

import math

from .common import NO_SHADOWING, coating_t, coating_w, mueller16, p3, polar, rotation, rs_k, smith_g
from .helper import helper
from .vector_math import sqrt


@helper
def facet_jones(g, p, o):
    """Jones elements ``(ss, ps, sp, pp)`` (re, im) of facet reflection, scaled so that their
    Mueller matrix is the BRDF (:func:`scatterbench.models.facet.facet_jones`); ``g``: the geometry
    (:func:`scatterbench.models.kernels.drive.geometry`)."""
    return facet_jones_at(g, polar(g[0]), polar(g[1]), p, o)


@helper
def facet_jones_at(g, pol_i, pol_r, p, o):
    """:func:`facet_jones` given the polar angles' ``(cos, sin)`` (:func:`~scatterbench.models.kernels.common.polar`)."""
    return facet_jones_through(g, pol_i, pol_r, coating(pol_i, pol_r, p[0]), p, o)


@helper
def coating(pol_i, pol_r, n):
    """The directions of polar ``(cos, sin)`` ``pol_i``, ``pol_r`` inside a smooth non-absorbing
    coating ``n``: their sines and cosines ``(si, sr, ci, cr)``, the transmission coefficients
    ``(tsi, tpi, tsr, tpr)`` into it and ``1 / n``; for ``n = 1`` the outer ones and ones.  Apart
    from :func:`facet_jones_through`, so that the facet loop on SIMD lanes computes it only for
    a block with a coating (:func:`scatterbench.models.kernels.vector.facet_prepass`: a vector
    loop computes both sides of a branch)."""
    ci_e, si_e = pol_i
    cr_e, sr_e = pol_r
    T = type(ci_e)
    one = T(1.0)
    if n == one:
        return si_e, sr_e, ci_e, cr_e, one, one, one, one, one
    inv_n = one / n
    wi, wr = coating_w(ci_e, n), coating_w(cr_e, n)  # one root a direction: cosine and t's
    tsi, tpi = coating_t(ci_e, n, wi)
    tsr, tpr = coating_t(cr_e, n, wr)
    return si_e * inv_n, sr_e * inv_n, wi * inv_n, wr * inv_n, tsi, tpi, tsr, tpr, inv_n


@helper
def facet_jones_through(g, pol_i, pol_r, coat, p, o):
    """:func:`facet_jones_at` given the :func:`coating`'s values ``coat`` (its transmission
    coefficients applied as they are: ones leave the bits alone)."""
    ti, tr, _, cp, sp = g
    T = type(ti)
    sub_r, sub_i = p[1], p[2]
    ci_e, cr_e = pol_i[0], pol_r[0]
    si, sr, ci, cr, tsi, tpi, tsr, tpr, inv_n = coat
    hx = sr * cp - si
    hy = sr * sp
    hz = cr + ci
    g = hx * hx + hy * hy + hz * hz
    # 1 / hz and 1 / g by one division (hz >= cos of the larger polar angle, g >= hz^2: in range)
    inv_hzg = T(1.0) / (hz * g)
    inv_hz, inv_g = g * inv_hzg, hz * inv_hzg
    dens = p3(o[0], hx * inv_hz, hy * inv_hz, p[3], p[4], p[5], p[6])
    q = g * inv_hz * inv_hz
    S = dens * q * q / (T(4.0) * ci_e * cr_e)
    half_pi = T(0.5 * math.pi)
    if ti >= half_pi or tr >= half_pi:
        S = T(0.0)
    if o[1] != NO_SHADOWING:
        rc, rs = rotation(o[0], p[5])
        S = S * smith_g(o[1], o[0], (ci, si, -T(1.0), T(0.0)), (cr, sr, cp, sp), p[3], p[4], rc, rs)
    c = T(0.5) * sqrt(g)
    rsr, rsi, kr, ki = rs_k(c, sub_r * inv_n, sub_i * inv_n, sub_r == T(math.inf))
    ho_s, ho_p = si * sp, cr * cp * si + sr * ci
    hi_s, hi_p = sr * sp * inv_g, (ci * sr * cp + si * cr) * inv_g
    d_ss, d_ps, d_sp, d_pp = cp, -sp * ci, -cr * sp, sr * si - cr * cp * ci
    ho_s, ho_p, hi_s, hi_p = ho_s * tsr, ho_p * tpr, hi_s * tsi, hi_p * tpi
    d_ss, d_ps = d_ss * (tsr * tsi), d_ps * (tsr * tpi)
    d_sp, d_pp = d_sp * (tpr * tsi), d_pp * (tpr * tpi)
    root = sqrt(S)
    r_re, r_im = rsr * root, rsi * root
    k_re = kr * root - T(2.0) * r_re
    k_im = ki * root - T(2.0) * r_im
    b_ss, b_ps, b_sp, b_pp = ho_s * hi_s, ho_s * hi_p, ho_p * hi_s, ho_p * hi_p
    return (
        r_re * d_ss + k_re * b_ss,
        r_im * d_ss + k_im * b_ss,
        r_re * d_ps + k_re * b_ps,
        r_im * d_ps + k_im * b_ps,
        r_re * d_sp + k_re * b_sp,
        r_im * d_sp + k_im * b_sp,
        r_re * d_pp + k_re * b_pp,
        r_im * d_pp + k_im * b_pp,
    )


@helper
def facet(geo, p, o):
    """:class:`scatterbench.models.FacetBRDF` and :class:`scatterbench.models.SubsurfaceFacetBRDF` at one geometry."""
    a, b, c, d, e, f, g, h = facet_jones(geo, p, o)
    return mueller16(a, b, c, d, e, f, g, h)


@helper
def facet_lanes(ge, p, o):
    """:func:`facet` on SIMD lanes: ``ge`` the geometry followed by its polar angles' cosines and
    sines and its :func:`coating`'s values, which
    :func:`scatterbench.models.kernels.vector.facet_prepass` computed for the block."""
    pol_i, pol_r = (ge[5], ge[6]), (ge[7], ge[8])
    coat = (ge[9], ge[10], ge[11], ge[12], ge[13], ge[14], ge[15], ge[16], ge[17])
    a, b, c, d, e, f, g, h = facet_jones_through(
        (ge[0], ge[1], ge[2], ge[3], ge[4]), pol_i, pol_r, coat, p, o
    )
    return mueller16(a, b, c, d, e, f, g, h)


@helper(forceinline=None)
def dot3(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@helper(forceinline=None)
def cross3(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@helper(forceinline=None)
def transmission_factors(c, mr):
    """``t_s`` and ``(t_p - t_s) / sin^2`` of refraction at local cosine ``c`` into relative
    index ``mr`` (zero beyond the critical angle), as :func:`scatterbench.models.facet_btdf.facet_transmission_jones`."""
    T = type(c)
    arg = mr * mr - T(1.0) + c * c
    if not arg > T(0.0):
        return T(0.0), T(0.0)
    w = sqrt(arg)
    den_s = c + w
    if not den_s > T(0.0):
        return T(0.0), T(0.0)
    inv_s = T(1.0) / den_s
    inv_p = T(1.0) / (mr * mr * c + w)
    ts = T(2.0) * c * inv_s
    # each factor paired with its denominator: (mr - 1)(mr^2 - 1) ~ mr^3 alone overflows
    # float32 from mr ~ 7e12 (float32's largest: 3.4e38)
    delta = T(2.0) * c * ((mr - T(1.0)) * inv_s) * ((mr * mr - T(1.0)) * inv_p)
    return ts, delta * (T(1.0) / (w + mr * c))


@helper
def btdf_jones(k_in, k_out, m, mr, e_in, e_out):
    """Real Jones elements ``(ss, ps, sp, pp)`` of refraction through facet ``m`` and the local
    cosines ``(cos iota_in, cos iota_out)`` (the dyadic of seed 003 Eq. 40, Rodrigues' rotation)."""
    T = type(mr)
    c = min(max(-dot3(k_in, m), T(0.0)), T(1.0))
    ts, delta = transmission_factors(c, mr)
    u = cross3(k_in, m)
    a_out = cross3(k_out, u)
    a_in = cross3(k_in, u)
    v = cross3(k_in, k_out)
    cg = dot3(k_in, k_out)
    one_cg = T(1.0) + cg
    inv1 = T(1.0) / one_cg if one_cg > T(1e-300) else T(0.0)
    ss = _btdf_element(e_out[0], e_in[0], v, a_in, a_out, cg, inv1, ts, delta)
    ps = _btdf_element(e_out[0], e_in[1], v, a_in, a_out, cg, inv1, ts, delta)
    sp = _btdf_element(e_out[1], e_in[0], v, a_in, a_out, cg, inv1, ts, delta)
    pp = _btdf_element(e_out[1], e_in[1], v, a_in, a_out, cg, inv1, ts, delta)
    c_out = min(max(-dot3(k_out, m), T(0.0)), T(1.0))
    return ss, ps, sp, pp, c, c_out


@helper
def _btdf_element(ea, eb, v, a_in, a_out, cg, inv1, ts, delta):
    """One element of :func:`btdf_jones`: out-basis vector ``ea``, in-basis vector ``eb``."""
    rot = cg * dot3(ea, eb) + dot3(ea, cross3(v, eb)) + dot3(ea, v) * dot3(v, eb) * inv1
    return ts * rot + delta * dot3(ea, a_out) * dot3(a_in, eb)


@helper
def btdf(g, p, o):
    """:class:`scatterbench.models.FacetBTDF` (``convention="paper"``) at one geometry."""
    ti, tt, pt, _, _ = g
    T = type(ti)
    n = p[0]
    si, ci = math.sin(ti), math.cos(ti)
    st, ct = math.sin(tt), math.cos(tt)
    cp, sp = math.cos(pt), math.sin(pt)
    k_in = (si, T(0.0), -ci)
    k_out = (st * cp, st * sp, -ct)
    h = (k_in[0] - n * k_out[0], k_in[1] - n * k_out[1], k_in[2] - n * k_out[2])
    D2 = dot3(h, h)
    D = sqrt(D2)
    mz = h[2] / D
    half_pi = T(0.5 * math.pi)
    if not (mz > T(0.0) and n * dot3(k_in, k_out) - T(1.0) > T(0.0) and ti < half_pi and tt < half_pi):
        z = T(0.0)
        return mueller16(z, z, z, z, z, z, z, z)
    m = (h[0] / D, h[1] / D, mz)
    z = (T(0.0), T(0.0), T(0.0))
    s_in = (T(0.0), T(1.0), T(0.0))
    s_out = (-sp, cp, T(0.0))
    e_in = (s_in, cross3(k_in, s_in))
    e_out = (s_out, cross3(k_out, s_out))
    ss, ps, sp_, pp, c_in, c_out = btdf_jones(k_in, k_out, m, n, e_in, e_out)
    dens = p3(o[0], h[0] / h[2], h[1] / h[2], p[1], p[2], p[3], p[4])
    mz2 = mz * mz
    S = dens * n * c_out * (T(1.0) / (ci * ct)) / (mz2 * mz2) * (n * n * c_out / D2)
    if o[1] != NO_SHADOWING:
        rc, rs = rotation(o[0], p[3])
        g = smith_g(o[1], o[0], (ci, si, -T(1.0), T(0.0)), (-ct, st, cp, sp), p[1], p[2], rc, rs)
        # back-facing (chi+) tests of Walter et al. Eq. 21-23: both local cosines positive here
        S = S * (g if (c_in * ci > T(0.0) and c_out * ct > T(0.0)) else T(0.0))
    root = sqrt(S)
    zr = z[0]
    return mueller16(ss * root, zr, ps * root, zr, sp_ * root, zr, pp * root, zr)
