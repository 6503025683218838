"""Volume-scattering kernels under a smooth interface (seed 003 Sec. 2.2-2.3):
:class:`scatterbench.models.SingleScatterBRDF` and :class:`scatterbench.models.DiffuseSubsurfaceBRDF`, one geometry per
call, as :mod:`scatterbench.models.single_scatter` and :mod:`scatterbench.models.diffuse_subsurface` compute them."""

from __future__ import annotations

from .common import coating_cos, hg_density, mueller16, polar
from .helper import helper
from .vector_math import sqrt

#: parameter rows: the binder's index, then the phase's g (single) or the diffuse scale


@helper
def amplitudes(c, s, n):
    """``(sin_int, cos_int, a_s, a_p)`` of :func:`scatterbench.models.smooth_interface.interface_amplitudes`
    for the external cosine and sine ``c``, ``s`` (:func:`scatterbench.models.kernels.common.polar`)."""
    T = type(c)
    # a few ulps of pi/2 from grazing is grazing (as the numpy path); float32's pi/2 is 1.2e-7
    # wide and rounds above pi/2 (a negative cosine).  T(1e-300) is 0 in float32.
    if c < (T(1e-15) if T(1e-300) > T(0.0) else T(2.4e-7)):
        c, s = T(0.0), T(1.0)
    s_int = s * (T(1.0) / n)
    c_int = coating_cos(c, n)
    root = T(2.0) * sqrt(c * c_int)
    # n = 1 at grazing: both denominators vanish with the numerator (no projected flux): 0;
    # otherwise root / den <= 1 (den >= c + c_int >= root for n >= 1), so no guard is needed
    den_s, den_p = c + n * c_int, n * c + c_int
    a_s = root / den_s if den_s > T(0.0) else T(0.0)
    a_p = root / den_p if den_p > T(0.0) else T(0.0)
    return s_int, c_int, a_s, a_p


@helper
def depolarized16(asi, api, asr, apr, scale):
    """:func:`scatterbench.models.smooth_interface.depolarized_between`'s 16 elements."""
    T = type(asi)
    half = T(0.5)
    a, b = asr * asr, apr * apr
    c, d = asi * asi, api * api
    s_out, d_out = half * (a + b) * scale, half * (a - b) * scale
    s_in, d_in = half * (c + d), half * (c - d)
    z = T(0.0)
    return (s_out * s_in, s_out * d_in, z, z, d_out * s_in, d_out * d_in, z, z, z, z, z, z, z, z, z, z)


@helper
def single(geo, p, o):
    """Single scattering under a smooth interface (seed 003 Eq. 20); ``o[0]``: polarized phase."""
    ti, tr, _, cp, sp = geo
    T = type(ti)
    n, g = p[0], p[1]
    ci_e, si_e = polar(ti)
    cr_e, sr_e = polar(tr)
    si, ci, asi, api = amplitudes(ci_e, si_e, n)
    sr, cr, asr, apr = amplitudes(cr_e, sr_e, n)
    cos_scat = si * sr * cp - ci * cr
    dens = hg_density(g, cos_scat)
    # both internal cosines zero (grazing under n = 1): no projected flux and zero amplitudes;
    # dens / tiny would overflow float32 and give inf * 0
    K = dens / (ci + cr) if ci + cr > T(0.0) else T(0.0)
    if o[0] == 0:
        return depolarized16(asi, api, asr, apr, K)
    root = sqrt(T(2.0) * K / (T(1.0) + cos_scat * cos_scat))
    ss = asr * asi * root * cp
    ps = -(asr * api * root) * sp * ci
    sp_ = -(apr * asi * root) * sp * cr
    pp = apr * api * root * (si * sr - ci * cr * cp)
    z = T(0.0)
    return mueller16(ss, z, ps, z, sp_, z, pp, z)


@helper
def diffuse(geo, p, o):
    """Lambertian diffuser under a smooth interface (seed 003 Eq. 27); ``p[1]``: its scale."""
    ti, tr = geo[0], geo[1]
    n = p[0]
    ci_e, si_e = polar(ti)
    cr_e, sr_e = polar(tr)
    _, _, asi, api = amplitudes(ci_e, si_e, n)
    _, _, asr, apr = amplitudes(cr_e, sr_e, n)
    return depolarized16(asi, api, asr, apr, p[1])
