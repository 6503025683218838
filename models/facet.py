"""Facet (ray-optics) reflection from a rough interface: the shared kernel and
:class:`FacetBRDF`, the exposed rough surface.

The kernel is seed 000 Eq. 2-20 and 47-50 with the coating index ``n`` (``n =
1`` is the exposed surface).  A ray refracts into the coating (Eq. 2-4), reflects
specularly from the facet whose normal bisects the internal directions
(Eq. 5-7), and refracts out.  The BRDF (Eq. 49) is

    M = P3^xy(zeta) / (4 cos ti cos tr cos^4 theta_n) * Mueller(q)

with ``q`` the Jones matrix of Eq. 16-18 (transmission coefficients
``t(theta; 1, n)`` of both passes, Eq. 14-15).

The facet reflection is written without Eq. 18's division by ``a1 =
sin^2(2 alpha)``.  With ``h = k_r' - k_i'`` (``|h|^2 = 4 cos^2 alpha``, Eq. 5),
facet normal ``h/|h|``, the reflection dyadic acting on fields transverse to
``k_i'`` is

    R = r_s (I - 2 nn) + K (n - c k_r)(n + c k_i),   K = (r_s + r_p) / sin^2 alpha,

so ``q_ab = r_s (e_a . e_b) + (K - 2 r_s)(e_a . h)(e_b . h) / |h|^2`` for basis
vectors ``e_a`` of the outgoing and ``e_b`` of the incident ray.  The dot
products reduce to Eq. 19's ``a2 = p_r'.h`` and ``a3 = p_i'.h`` and to
``s_r'.h = sin ti' sin phi``, ``s_i'.h = sin tr' sin phi``.  ``K`` is smooth at
``alpha = 0`` (:func:`scatterbench.models.fresnel.reflection_rs_k`), so exact
retroreflection is finite with no special case, where Eq. 18 is 0/0.  Because
``q = r_s U + K V`` with real ``U``, ``V`` (a non-absorbing coating has real
transmission coefficients), the Jones elements are formed directly as real and
imaginary parts and the Mueller matrix follows in real arithmetic on cache-sized
chunks (:func:`scatterbench.models.polarization.mueller16_from_jones`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from . import kernel_specs
from .base import Model
from .constraints import Options
from .facts import Correspondence, scatmech_index
from .fresnel import coating_cos, coating_transmission, reflection_rs_k
from .params import param
from .polarization import mueller16_from_jones
from .shadowing import SHADOWING, check_shadowing, smith_g
from .slopes import SLOPES, AnisotropicGGXSlopes, ExponentialSlopes, GGXSlopes, SlopeDistribution
from .smooth_interface import film_transmission
from .thin_film import INDEX_OR_STACK, FilmStack

__all__ = ["FacetBRDF", "facet_jones", "local_cosine", "substrate_rs_k"]


def substrate_rs_k(cos_i, n, substrate):
    """``r_s`` and ``K = (r_s + r_p) / sin^2`` (:func:`scatterbench.models.fresnel.reflection_rs_k`) for
    light in the coating ``n`` meeting ``substrate``: an index (``n + ik`` or ``math.inf``)
    or a layer stack (:class:`scatterbench.models.FilmStack`, whose ``reflection_rs_k(cos_i, n)`` it
    calls).  The one place the facet models take their reflection coefficients from."""
    if isinstance(substrate, FilmStack):
        return substrate.reflection_rs_k(cos_i, n)
    m = substrate if substrate == math.inf else complex(substrate) / n
    return reflection_rs_k(cos_i, m)


def _polar(ti, tr, n):
    """``(cos_ext, sin_int, cos_int)``: cosines of the external polar angles and sines and
    cosines of the internal (refracted) ones, each a ``(2, k)`` stack (incident, scattered)."""
    # Incident and scattered polar angles are handled as one (2, k) stack: the
    # same trigonometry, Snell refraction and coating transmission for both.
    cos_ext = np.cos(np.stack([ti, tr]))
    # sin = sqrt(1 - cos^2): exact to ~1e-16 absolute (it loses relative precision
    # only below ~1e-8 rad, where sin enters additively); cos, which divides the
    # BRDF, stays exact.
    sin_ext = np.sqrt(1.0 - cos_ext * cos_ext)  # |cos| <= 1 from np.cos
    if n == 1.0:
        return cos_ext, sin_ext, cos_ext
    sin_int = sin_ext * (1.0 / n)  # Eq. 2-3
    return cos_ext, sin_int, coating_cos(cos_ext, n)


def _bisector(sin_int, cos_int, cp, sp):
    """``(hx, hy, hz)`` of ``h = k_r' - k_i'``, which bisects the internal directions: the
    facet normal is ``h / |h|`` and ``|h| = 2 cos(alpha)`` (Eq. 5-7)."""
    si, sr = sin_int
    ci, cr = cos_int
    return sr * cp - si, sr * sp, cr + ci


def local_cosine(ti, tr, pr, n):
    """``cos(alpha)``: the local incidence, in a coating of index ``n``, on the facet that
    reflects ``ti`` into ``(tr, pr)`` (``|h| / 2``, Eq. 5), as :func:`facet_jones` takes it."""
    _, sin_int, cos_int = _polar(ti, tr, n)
    hx, hy, hz = _bisector(sin_int, cos_int, np.cos(pr), np.sin(pr))
    return 0.5 * np.sqrt(hx * hx + hy * hy + hz * hz)


def facet_slopes(ti, tr, pr, n):
    """``(zeta_x, zeta_y)``: the slopes of the facet that reflects ``ti`` into ``(tr, pr)``
    in a coating of index ``n`` (``h_xy / h_z``, Eq. 2-7), where :func:`facet_jones` reads
    the slope density."""
    _, sin_int, cos_int = _polar(ti, tr, n)
    hx, hy, hz = _bisector(sin_int, cos_int, np.cos(pr), np.sin(pr))
    return hx / hz, hy / hz


def facet_jones(ti, tr, pr, n, substrate, slopes, shadowing="none", top=None):
    """Jones elements ``(ss, ps, sp, pp)`` as ``(re, im)`` pairs of flat arrays
    (``ps`` = p in, s out), scaled so that their Mueller matrix is the BRDF.

    Flat float64 arrays in.  Zero where a ray is grazing (``theta = pi/2``: no
    projected area, as in SCATMECH) or where the slope density vanishes.
    ``substrate`` is an index or a :class:`scatterbench.models.FilmStack`
    (:func:`substrate_rs_k`); ``shadowing`` one of
    :data:`scatterbench.models.shadowing.SHADOWING` (``"none"``: seed 000's model, untouched),
    applied with the internal directions (in the coating).  ``top``: ``None`` (the bare
    coating, Eq. 14-15) or a :class:`scatterbench.models.FilmStack` of films on the coating's top
    surface (substrate ``n``), whose complex crossing amplitudes replace ``t(theta; 1, n)``
    (:func:`scatterbench.models.smooth_interface.film_transmission`).
    """
    cos_ext, sin_int, cos_int = _polar(ti, tr, n)
    sp, cp = np.sin(pr), np.cos(pr)
    si, sr = sin_int
    ci, cr = cos_int
    hx, hy, hz = _bisector(sin_int, cos_int, cp, sp)
    g = hx * hx + hy * hy + hz * hz  # |h|^2 = 4 cos^2(alpha), Eq. 5
    inv_hz = 1.0 / hz
    p3 = slopes.p3(hx * inv_hz, hy * inv_hz)
    # Eq. 49: P3 / (4 cos ti cos tr cos^4 theta_n), with cos theta_n = hz / |h|.
    q = g * inv_hz * inv_hz
    S = p3 * q * q / (4.0 * cos_ext[0] * cos_ext[1])
    if ti.max() >= 0.5 * math.pi or tr.max() >= 0.5 * math.pi:
        S[(ti >= 0.5 * math.pi) | (tr >= 0.5 * math.pi)] = 0.0
    if shadowing != "none":
        # both directions see the facet from its front (v.m = cos(alpha) > 0): no chi+ test;
        # the incident direction (towards the source) has azimuth pi
        S = S * smith_g(shadowing, slopes, (ci, si, -1.0, 0.0), (cr, sr, cp, sp))
    c = 0.5 * np.sqrt(g)  # cos(alpha), local incidence in the coating (|h| <= 2)
    rs, K = substrate_rs_k(c, n, substrate)
    # s_r'.h, p_r'.h (a2, Eq. 19b), s_i'.h / |h|^2, p_i'.h / |h|^2 (a3, Eq. 19c)
    inv_g = 1.0 / g
    h_dots = (si * sp, cr * cp * si + sr * ci, sr * sp * inv_g, (ci * sr * cp + si * cr) * inv_g)
    d = (cp, -sp * ci, -cr * sp, sr * si - cr * cp * ci)  # e_a . e_b for ss, ps, sp, pp
    if top is not None:  # the films' complex crossing amplitudes replace Eq. 14-15's
        return _through_films(_jones_elements(rs, K, np.sqrt(S), h_dots, d, None), cos_ext, top)
    # Eq. 14-18: t(theta; 1, n) of both passes; an exposed surface (n = 1) has none (t = 1,
    # and coating_transmission would give 0/0 at grazing)
    crossing = None if n == 1.0 else coating_transmission(cos_ext, n)
    return _jones_elements(rs, K, np.sqrt(S), h_dots, d, crossing)


def _through_films(parts, cos_ext, top):
    """The facet's Jones elements ``(re, im)`` times the complex crossing amplitudes of the
    films on the coating, ``t_out,a(theta_r) t_in,b(theta_i)`` for element ``ab``
    (:func:`scatterbench.models.smooth_interface.film_transmission`, F1-F2): complex products, so the
    relative s/p phase of the films' transmission reaches the Mueller matrix."""
    (tsi, tpi), (tsr, tpr) = film_transmission(cos_ext[0], cos_ext[1], top)
    out = []
    for (re, im), f in zip(parts, (tsr * tsi, tsr * tpi, tpr * tsi, tpr * tpi), strict=True):
        z = (re + 1j * im) * f
        out.append((z.real, z.imag))
    return tuple(out)


def _jones_elements(rs, K, root, h_dots, d, crossing):
    """``q_ab = r_s D_ab + (K - 2 r_s) (e_a.h)(e_b.h)/|h|^2`` (module docstring) as
    ``(re, im)`` pairs scaled by ``root``, times the coating's real transmission factors
    ``crossing = ((t_s,in, t_s,out), (t_p,in, t_p,out))``
    (:func:`scatterbench.models.fresnel.coating_transmission`), or without any for ``crossing=None``."""
    r_re = rs.real * root
    r_im = rs.imag * root
    k_re = K.real * root
    k_re -= 2.0 * r_re
    k_im = K.imag * root
    k_im -= 2.0 * r_im
    ho_s, ho_p, hi_s, hi_p = h_dots
    d_ss, d_ps, d_sp, d_pp = d
    if crossing is not None:
        # t(theta_r; 1, n) on the way out, t(theta_i; 1, n) on the way in
        (tsi, tsr), (tpi, tpr) = crossing
        ho_s *= tsr
        ho_p *= tpr
        hi_s *= tsi
        hi_p *= tpi
        d_ss = d_ss * (tsr * tsi)
        d_ps = d_ps * (tsr * tpi)
        d_sp = d_sp * (tpr * tsi)
        d_pp = d_pp * (tpr * tpi)

    def elem(d, b):
        re = r_re * d
        re += k_re * b
        im = r_im * d
        im += k_im * b
        return re, im

    return (
        elem(d_ss, ho_s * hi_s),
        elem(d_ps, ho_s * hi_p),
        elem(d_sp, ho_p * hi_s),
        elem(d_pp, ho_p * hi_p),
    )


class _FacetModel(Model):
    """Shared evaluation of the exposed and the coated facet models."""

    def _coating(self) -> float:
        return 1.0

    def _top(self):
        """The films on the coating's top surface as a :class:`scatterbench.models.FilmStack`, or ``None``."""
        return None

    def _parts(self, ti, tr, pr):
        return facet_jones(
            ti, tr, pr, self._coating(), self.substrate, self.slopes, self.shadowing, self._top()
        )

    def _mueller16(self, ti, tr, pr):
        return mueller16_from_jones(*self._parts(ti, tr, pr))

    def _kernel_spec(self):
        """The facet kernel; numpy for films (on the facets or the coating) and slopes or
        shadowing it does not cover (:mod:`scatterbench.models.kernel_specs`)."""
        slopes = kernel_specs.slope_rows(self.slopes)
        if slopes is None or isinstance(self.substrate, FilmStack) or self._top() is not None:
            return None
        shadowing = kernel_specs.shadowing_kind(self.shadowing, slopes[0])
        if shadowing is None:
            return None
        rows = [self._coating(), *kernel_specs.index_rows(self.substrate), *slopes[1]]
        return "facet", rows, (slopes[0], shadowing, 0)

    def _jones_flat(self, ti, tr, pr):
        J = np.empty(ti.shape + (4,), dtype=complex)
        for k, (re, im) in enumerate(self._parts(ti, tr, pr)):
            J[:, k] = re + 1j * im
        return J.reshape(ti.shape + (2, 2))

    def _brdf_flat(self, ti, tr, pr):
        tot = 0.0
        for re, im in self._parts(ti, tr, pr):
            tot = tot + re * re + im * im
        return 0.5 * tot

    def _validate(self):
        check_shadowing(self.shadowing, self.slopes)

    @classmethod
    def sweep_extras(cls):
        """Instances the defaults' edges do not reach: GGX and anisotropic GGX slopes with
        shadowing none and smith (the slopes swept to their edges), and film-stack substrates
        (zero thickness, thick, an absorbing film on aluminium) with both, as they are."""
        ggx = (GGXSlopes(0.1), AnisotropicGGXSlopes(alpha_x=0.05, alpha_y=0.2, rotation=0.3))
        out = [(cls(slopes=g, shadowing=sh), ("slopes",)) for g in ggx for sh in ("none", "smith")]
        films = (
            FilmStack(layers=((2.6, 0.0),), substrate=1.58, wavelength_nm=550.0),
            FilmStack(layers=((2.6, 1e5),), substrate=1.58, wavelength_nm=550.0),
            FilmStack(
                layers=((3.1 + 3.3j, 10.0), (1.46, 200.0)), substrate=1.37 + 7.62j, wavelength_nm=550.0
            ),
        )
        return (*out, *((cls(substrate=f, shadowing=sh), ()) for f in films for sh in ("none", "smith")))

    def rotated(self, angle):
        return self._rotated_slopes(angle)

    @property
    def mirror_symmetric(self) -> bool:
        """True when the sample has a mirror plane at phi = 0 (isotropic slopes)."""
        return self.slopes.isotropic

    def lobe(self, theta_i):
        """Specular lobe: centre (theta_i, 0); width in theta_r ~ 2 n sigma cos(ti')/cos(ti)."""
        n = self._coating()
        si = math.sin(theta_i) / n
        ci = math.sqrt(1 - si * si)
        width = 2.0 * n * self.slopes.scale * ci / max(math.cos(theta_i), 1e-6)
        return (theta_i, 0.0, width)


@dataclass(frozen=True)
class FacetBRDF(_FacetModel):
    """Facet reflection from an exposed rough interface (seed 000 Eq. 48-49 with n = 1).

    Ray-optics (Kirchhoff tangent-plane, stationary-phase) limit with no
    multiple scattering and, by default, no shadowing; the Jones matrix is the
    facet's Fresnel reflection in the s/p bases of the two rays.  SCATMECH:
    ``Facet_BRDF_Model`` (``type = 0``).  With ``shadowing="smith"`` and GGX or
    Gaussian slopes it is Mitsuba 3's ``roughconductor`` (divided by
    ``cos theta_i``), polarized.

    Parameters
    ----------
    slopes : SlopeDistribution
        Facet slope distribution ``P3^xy`` (e.g. :class:`ExponentialSlopes`).
    substrate : complex, math.inf or FilmStack
        Index ``n + ik`` of the material below the facets (``k >= 0``),
        ``math.inf`` for a perfect conductor, or a :class:`scatterbench.models.FilmStack`
        (films on the facets, e.g. an interference pigment).
    shadowing : str
        ``"none"`` (seed 000), ``"smith"`` (separable Smith ``G1(i) G1(o)``) or
        ``"smith-correlated"`` (height-correlated), :mod:`scatterbench.models.shadowing`.

    Examples
    --------
    One geometry gives one 4 x 4 Mueller matrix (1/sr, psps basis); arrays of angles
    broadcast, and so do array parameters (a model set):

    >>> import math, numpy as np
    >>> from scatterbench import models
    >>> m = models.FacetBRDF(slopes=models.GaussianSlopes(0.2), substrate=math.inf, shadowing="smith")
    >>> M = m.mueller(math.radians(30), math.radians(30), 0.0)  # specular, phi_r = 0
    >>> M.shape, round(float(M[0, 0]), 6)
    ((4, 4), 2.652582)
    >>> m.mueller(np.radians([10.0, 20.0, 30.0]), 0.5, 0.0).shape
    (3, 4, 4)
    >>> sigmas = models.GaussianSlopes(np.array([[0.1], [0.2]]))
    >>> models.FacetBRDF(slopes=sigmas).brdf(0.5, np.array([0.4, 0.5, 0.6]), 0.0).shape
    (2, 3)
    """

    slopes: SlopeDistribution = param(ExponentialSlopes(0.1), "facet slope distribution", SLOPES)
    substrate: complex = param(
        1.37 + 7.62j, "substrate index n + ik (inf: perfect conductor) or a models.FilmStack", INDEX_OR_STACK
    )
    shadowing: str = param("none", "shadowing-masking", Options(*SHADOWING))

    correspondence = Correspondence(
        "seed 000 Eq. 48-49 with coating n = 1",
        "``Facet_BRDF_Model`` (type 0)",
        "``roughconductor`` (``beckmann``/``ggx``) with ``shadowing='smith'``, divided by cos(theta_i)",
    )
    #: the kit's instance: the slopes of committed SCATMECH reference values
    #: (references/data/scatmech_facet.csv), so that its ``scatmech`` check compares with them
    kit_variant = MappingProxyType({"slopes": ExponentialSlopes(0.05)})

    @property
    def scatmech(self):
        """SCATMECH's ``Facet_BRDF_Model`` (type 0) with these parameters, or ``None``: it has no
        shadowing, no film stacks and the exponential and Gaussian families only."""
        sdf, sub = self.slopes.scatmech_parameters(), scatmech_index(self.substrate)
        if sdf is None or sub is None or self.shadowing != "none":
            return None
        return "Facet_BRDF_Model", {"type": 0, "substrate": sub, **sdf}
