"""The Cook-Torrance BRDF of seed 001 (Hebert, Emmel & Hersch), Eq. 7-18.

    BRDF = D(alpha, m) G(psi, theta) F(psi', N) / (cos theta cos psi)        (Eq. 7)
    D    = exp(-(tan alpha / m)^2) / (m^2 cos^4 alpha)                       (Eq. 8)
    G    = min(1, 2 cos alpha cos theta / cos psi', 2 cos alpha cos psi / cos psi')   (Eq. 18, Blinn)
    F    = (F_s + F_p) / 2 at the facet's local angle psi'                   (Eq. 11-17)

with ``H`` the bisector of the light and view directions (Eq. 5), ``alpha`` the
angle between ``H`` and the mean normal and ``cos psi' = L . H``.

Normalization (``convention``).  As printed, Eq. 8 has no ``1/pi`` and Eq. 7 no factor 4 in the
denominator.  The normalized microfacet BRDF (Torrance-Sparrow / Walter et al.)
is ``D F G / (4 pi m^2 ...)``-i.e. Eq. 7 divided by ``4 pi``: its ``D/pi`` is
the Beckmann density of facet normals per projected area
(``int D/pi cos alpha dOmega = 1``) and the ``1/4`` is the Jacobian
``dOmega_h / dOmega_r = 1 / (4 cos psi')`` times the ``cos psi'`` projected facet
area.  ``convention="paper"`` keeps the printed form (it is ``4 pi``
times the normalized BRDF and its albedo exceeds 1 -- a property of the paper);
``"corrected"`` is the normalized form, which equals the M00 of
:class:`scatterbench.models.FacetBRDF` with ``GaussianSlopes(sigma=m)`` when there is no
shadowing.

Roughness (``slopes``).  Eq. 8's ``m`` is the ``sigma`` of
:class:`scatterbench.models.GaussianSlopes`: ``D / pi = exp(-tan^2 alpha / m^2) / (pi m^2 cos^4
alpha)`` is Beckmann's density of facet normals, and ``cos^4 alpha D / pi`` is the
Gaussian slope density ``P3(zeta) = exp(-(zeta/m)^2) / (pi m^2)`` at ``zeta = tan
alpha`` (``<zeta^2> = m^2``).  :class:`scatterbench.models.StrokeSlopes` gives Eq. 19's brushed D.

Fresnel.  ``F`` is computed with the real-valued form Eq. 13-16
(:func:`fresnel_real`), tested equal to the complex Born & Wolf form
(:func:`scatterbench.models.fresnel.fresnel_reflectance`, Eq. 11-12) to 1e-12.  Two slips of
the printed Eq. 13-16 are fixed there (see :func:`fresnel_real`), and the labels
of Eq. 11/13 (``parallel``) and 12/14 (``perpendicular``) are swapped in the
paper: Eq. 11 and 13 are the s (perpendicular, TE) reflectance.  The average
Eq. 17 does not depend on the labels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import kernel_specs
from .base import Model
from .constraints import ComplexIndex, Instance, Options, ScalarOrArray
from .facts import Correspondence
from .fresnel import _reflectance
from .params import SLOPE_WIDTH_MAX, SLOPE_WIDTH_MIN, Alias, check_real, choice_alias, convention_param, param
from .shadowing import smith_g
from .slopes import AnisotropicGaussianSlopes, GaussianSlopes
from .stroke_slopes import StrokeSlopes, stroke_d

__all__ = [
    "CookTorranceBRDF",
    "fresnel_real",
    "fresnel_real_printed",
    "fresnel_average",
    "ct_kernel",
    "smith_slopes",
]

_INV_4PI = 1.0 / (4.0 * math.pi)
#: the ``shadowing`` choices of the Cook-Torrance models
SHADOWING_CT = ("blinn", "none", "smith")
#: the Cook-Torrance models' ``slopes``: the families whose D the kernels evaluate (coverage 1,
#: checked by the models)
CT_SLOPES = Instance(
    GaussianSlopes,
    StrokeSlopes,
    text="models.GaussianSlopes(sigma=m) (Eq. 8) or models.StrokeSlopes (Eq. 19)",
)


def fresnel_real(cos_i, n, k=0.0):
    """``(F_s, F_p)`` from the real-valued form, seed 001 Eq. 13-16 (corrected).

    ``cos_i`` is the cosine of the local angle ``psi'``; ``n + ik`` the relative
    index ``N`` (Eq. 10).  With ``A = n^2 - k^2 - sin^2``:

        a^2 = (sqrt(A^2 + 4 n^2 k^2) + A) / 2,   b^2 = (sqrt(A^2 + 4 n^2 k^2) - A) / 2  (Eq. 15-16)
        F_s = (a^2 + b^2 - 2 a cos + cos^2) / (a^2 + b^2 + 2 a cos + cos^2)              (Eq. 13)
        F_p = F_s (a^2 + b^2 - 2 a sin tan + sin^2 tan^2) / (... + ...)                 (Eq. 14)

    Slips of the printed Eq. 15-16 fixed here: the second term is printed
    ``(n0^2 + k0^2 - sin^2)^2``; it is ``(n0^2 - k0^2 - sin^2)``, neither squared
    nor with ``+k0^2`` (``a + ib = N cos(eta)``, so ``a^2 - b^2 = Re(N^2) - sin^2``
    and ``a b = n0 k0``).  The paper labels Eq. 13 ``parallel``; it is ``F_s``.

    Numerics: ``a^2`` and ``b^2`` are formed without cancellation (the smaller
    one from ``a^2 b^2 = n^2 k^2``), and Eq. 14 is multiplied through by
    ``cos^2`` so grazing incidence needs no ``tan``.  Transparent media beyond
    the critical angle (``A < 0``, ``k = 0``) give ``a = 0`` and ``F_s = F_p = 1``.
    """
    c = np.asarray(cos_i, dtype=float)
    s2 = 1.0 - c * c
    A = (n * n - k * k) - s2
    nk2 = (n * k) ** 2
    if nk2 == 0.0 and n >= 1.0:
        # Transparent, optically denser medium: A >= 0 everywhere, b = 0, a^2 = A.
        return _fs_fp(c, s2, A, np.sqrt(A))
    root = np.sqrt(A * A + 4.0 * nk2)  # = a^2 + b^2 = |N^2 - sin^2|
    big = 0.5 * (root + np.abs(A))  # the larger of a^2, b^2: no cancellation
    if nk2 > 0.0:
        small = nk2 / big  # big > 0 whenever n k > 0
    else:
        small = np.zeros_like(big)
    a2 = np.where(A >= 0.0, big, small)
    return _fs_fp(c, s2, root, np.sqrt(a2))


def fresnel_real_printed(cos_i, n, k=0.0, variant="printed"):
    """Eq. 13-16 exactly as printed (``variant="printed"``: second term
    ``(n0^2 + k0^2 - sin^2)^2``) or with only the square removed
    (``variant="unsquared"``: ``n0^2 + k0^2 - sin^2``).  For the report of how
    far the printed form is off; not used by any model."""
    c = np.asarray(cos_i, dtype=float)
    s2 = 1.0 - c * c
    A = (n * n - k * k) - s2
    root = np.sqrt(A * A + 4.0 * (n * k) ** 2)
    B = (n * n + k * k) - s2
    second = B * B if variant == "printed" else B
    # a^2 + b^2 = root in every variant (the second terms cancel); only a changes.
    a = np.sqrt(np.maximum(0.5 * (root + second), 0.0))
    return _fs_fp(c, s2, root, a)


def _fs_fp(c, s2, root, a):
    two_ac = 2.0 * a * c
    base = root + c * c
    # Numerators as sums of squares ((a - cos)^2 + b^2, with b^2 = root - a^2 >= 0) so
    # that rounding can never make a reflectance negative (it did, at -4e-54, for
    # N = 1 near grazing, where a = cos exactly).
    b2 = np.maximum(root - a * a, 0.0)
    num_s = (a - c) ** 2 + b2
    den_s = base + two_ac
    # Eq. 14 times cos^2: (a^2+b^2) cos^2 - 2 a sin^2 cos + sin^4 over the same with +.
    u = root * c * c + s2 * s2
    v = two_ac * s2
    num_p = (a * c - s2) ** 2 + b2 * c * c
    den_p = u + v
    # den = 0 only for N = 1 at exactly grazing incidence (0/0): give 0, the N = 1 value.
    fs = np.divide(num_s, den_s, out=np.zeros_like(num_s), where=den_s > 0)
    ratio = np.divide(num_p, den_p, out=np.zeros_like(num_p), where=den_p > 0)
    return fs, fs * ratio


def fresnel_average(cos_i, index):
    """Natural-light reflectance ``F = (F_s + F_p) / 2`` (Eq. 17) of relative index ``index``:
    the shared complex Fresnel reflectances (:func:`scatterbench.models.fresnel.fresnel_reflectance`),
    which the corrected real form :func:`fresnel_real` equals (checked in validate)."""
    rs, rp = _reflectance(cos_i, 1.0, index)
    return 0.5 * (rs + rp)


def _grazing_safe(ti, tr):
    """``cos ti``, ``cos tr`` with exactly grazing rays (``theta = pi/2``: no
    projected area, as in the facet models) replaced by 1, and the mask of live
    geometries (``None`` when all are live)."""
    ci, cr = np.cos(ti), np.cos(tr)
    if ti.max() < 0.5 * math.pi and tr.max() < 0.5 * math.pi:
        return ci, cr, None
    live = (ti < 0.5 * math.pi) & (tr < 0.5 * math.pi)
    return np.where(live, ci, 1.0), np.where(live, cr, 1.0), live


def ct_kernel(ci, cr, cp, sp, d_fn, index, shadowing, smith=None):
    """``D G F`` of Eq. 7 (published D, Eq. 8) for cosines of the two polar
    angles ``ci``, ``cr`` (both > 0) and the azimuth's ``cp``, ``sp``.

    ``d_fn(hx, hy, hz2)`` returns ``exp(-tan^2 alpha / m^2) / m^2`` for the
    (unnormalized) bisector ``h = L + E``; the ``1/cos^4 alpha`` is applied here.
    ``shadowing``: ``"blinn"`` (Eq. 18), ``"none"`` or ``"smith"``, the separable Smith
    ``G1(L) G1(E)`` of the slope distribution ``smith`` (:func:`smith_slopes`).
    """
    si = np.sqrt(1.0 - ci * ci)
    sr = np.sqrt(1.0 - cr * cr)
    # h = L + E with L = (-sin psi, 0, cos psi) toward the source, E toward the viewer.
    hx = sr * cp - si
    hy = sr * sp
    hz = ci + cr
    hz2 = hz * hz
    g = hx * hx + hy * hy + hz2  # |h|^2 = 4 cos^2 psi'
    q = g / hz2  # 1 / cos^2 alpha
    val = d_fn(hx, hy, hz2) * (q * q)  # Eq. 8
    c_loc = 0.5 * np.sqrt(g)  # cos psi' = L . H
    val *= fresnel_average(c_loc, index)
    if shadowing == "blinn":
        # Eq. 18: 2 cos(alpha) cos(theta) / cos(psi') = 4 hz cos(theta) / |h|^2
        t = (4.0 / g) * hz
        val *= np.minimum(1.0, t * np.minimum(ci, cr))
    elif shadowing == "smith":
        # L points toward the source (azimuth pi), E toward the viewer; both see the
        # bisector facet from its front, so no back-facing test is needed
        val *= smith_g("smith", smith, (ci, si, -1.0, 0.0), (cr, sr, cp, sp))
    return val


def smith_slopes(slopes):
    """The slopes whose Smith ``Lambda`` (:mod:`scatterbench.models.shadowing`) the ``"smith"`` option uses:
    ``GaussianSlopes(sigma=m)`` itself (Beckmann ``alpha = m``, the erf form); for
    :class:`scatterbench.models.StrokeSlopes` the anisotropic Gaussian with the same exponent,
    ``AnisotropicGaussianSlopes(m_par, m_perp, stroke_angle)``, whose ``Lambda`` is the
    Beckmann one at the projected roughness ``m(phi)^2 = (m_par cos phi')^2 + (m_perp
    sin phi')^2`` (``phi'`` from the strokes).  For equal ``m`` values it is exact; for
    brushed roughness it is an approximation, as Eq. 19's prefactor ``1 / m(beta)^2``
    differs from the anisotropic Gaussian's ``1 / (m_par m_perp)`` (see
    :mod:`scatterbench.models.stroke_slopes`)."""
    if isinstance(slopes, StrokeSlopes):
        if slopes.isotropic:
            return GaussianSlopes(sigma=slopes.m_parallel)
        return AnisotropicGaussianSlopes(
            sigma_x=slopes.m_parallel, sigma_y=slopes.m_perpendicular, rotation=slopes.stroke_angle
        )
    return GaussianSlopes(sigma=slopes.sigma)


def _check_m(value) -> float:
    """The old ``m=`` keyword (Eq. 8's rms slope), validated in the range of the slope width
    it sets (``GaussianSlopes.sigma``, ``StrokeSlopes.m_parallel``/``m_perpendicular``:
    :func:`scatterbench.models.params.width_param`) and named ``m``, the keyword the user gave."""
    return check_real("m", value, SLOPE_WIDTH_MIN, SLOPE_WIDTH_MAX)


def _slopes_from_m(given, current):
    """The old ``m=`` keyword: Eq. 8's rms slope, ``GaussianSlopes(sigma=m)``."""
    return GaussianSlopes(sigma=_check_m(given["m"]))


class _CookTorranceBase(Model):
    """Shared parts of the scalar Cook-Torrance models (depolarizing, M00 only): the
    roughness is a declared ``slopes`` (:class:`scatterbench.models.GaussianSlopes`, Eq. 8, or
    :class:`scatterbench.models.StrokeSlopes`, Eq. 19), whose density D is evaluated by
    :func:`scatterbench.models.stroke_slopes.stroke_d`."""

    depolarizing = True

    def _validate(self):
        s = self.slopes
        if not isinstance(s, (GaussianSlopes, StrokeSlopes)) or np.any(np.asarray(s.coverage) != 1.0):
            raise ValueError(
                "slopes must be models.GaussianSlopes(sigma=m) (Eq. 8) or models.StrokeSlopes (Eq. 19), "
                f"with coverage 1; got {s!r}"
            )

    def _m_rows(self):
        """``[m_parallel, m_perpendicular, stroke_angle]`` of the slopes (``[m, m, 0]`` for
        ``GaussianSlopes(sigma=m)``): :func:`scatterbench.models.kernel_specs.slope_rows` without coverage."""
        return kernel_specs.slope_rows(self.slopes)[1][:3]

    def _d_fn(self):
        return stroke_d(*self._m_rows())

    def _cook_spec(self, variant, coating):
        """The Cook-Torrance kernel (every shadowing option: :data:`scatterbench.models.kernel_specs.COOK_SHADOWING`)."""
        m_rows = self._m_rows()
        rows = [
            coating,
            *kernel_specs.index_rows(self.substrate),
            *m_rows,
            np.cos(m_rows[2]),
            np.sin(m_rows[2]),
        ]
        options = (variant, int(self.convention == "corrected"), kernel_specs.COOK_SHADOWING[self.shadowing])
        return "cook", rows, options

    def _smith(self):
        return smith_slopes(self.slopes) if self.shadowing == "smith" else None

    @property
    def mirror_symmetric(self) -> bool:
        s = self.slopes
        return s.isotropic or math.sin(2.0 * s.stroke_angle) == 0.0

    def rotated(self, angle):
        return self._rotated_slopes(angle)

    def _brdf_flat(self, ti, tr, pr):  # pragma: no cover - abstract
        raise NotImplementedError

    def _mueller16(self, ti, tr, pr):
        out = np.zeros((16, ti.size))
        out[0] = self._brdf_flat(ti, tr, pr)
        return out

    def mueller(self, theta_i, theta_r, phi_r=0.0, out=None, precision="float64"):
        """Mueller BRDF ``(..., 4, 4)``: the ideal depolarizer ``diag(f, 0, 0, 0)``
        with ``M00 = f`` the scalar BRDF.  The model is scalar (natural light,
        Eq. 17): it predicts no polarization, so only ``M00`` carries information.
        ``out`` and ``precision`` as for :meth:`scatterbench.models.Model.mueller`.
        (Overridden for this docstring, which ``help(model.mueller)`` shows.)"""
        return super().mueller(theta_i, theta_r, phi_r, out=out, precision=precision)


@dataclass(frozen=True)
class CookTorranceBRDF(_CookTorranceBase):
    """Cook-Torrance BRDF of a rough metal in air, seed 001 Eq. 7-18.

    Scalar model for natural light: :meth:`mueller` returns the depolarizing
    matrix ``diag(BRDF, 0, 0, 0)`` (``M00 = BRDF``).

    Parameters
    ----------
    slopes : GaussianSlopes or StrokeSlopes
        Facet slopes of D: ``GaussianSlopes(sigma=m)`` is Eq. 8 with rms slope ``m``
        (Beckmann's ``alpha``), :class:`scatterbench.models.StrokeSlopes` Eq. 19's brushed
        roughness.  Old keyword ``m=`` (a number: ``GaussianSlopes(sigma=m)``).
    substrate : complex or math.inf
        Metal index ``n + ik`` relative to the ambient (Eq. 10); ``inf``: ``F = 1``.
    convention : "paper" | "corrected"
        ``paper``: Eq. 7-8 as printed (no ``1/pi`` in D, no 4 in the denominator;
        ``4 pi`` times the normalized BRDF, albedo > 1).  ``corrected``: divided by
        ``4 pi``, the normalized microfacet BRDF.  Either way F is the corrected
        Eq. 13-16 (the complex Fresnel reflectance; see :func:`fresnel_real`).
        Old keyword ``normalization`` (``"published"``, ``"energy"``).
    shadowing : "blinn" | "none" | "smith"
        Eq. 18 (Blinn's V-groove ``G``), ``G = 1``, or the separable Smith ``G1(i) G1(o)``
        from the Beckmann ``Lambda`` of the model's ``m`` (:func:`smith_slopes`; not in
        seed 001).  With ``"smith"`` and ``convention="corrected"`` the model is
        :class:`scatterbench.models.FacetBRDF` with ``GaussianSlopes(sigma=m)`` and ``shadowing="smith"``
        (M00).  Options a fused kernel does not cover run on this numpy path.
    """

    slopes: GaussianSlopes | StrokeSlopes = param(
        GaussianSlopes(0.03), "facet slopes of D: GaussianSlopes(sigma=m) (Eq. 8) or StrokeSlopes", CT_SLOPES
    )
    substrate: complex = param(
        2.29 + 3.37j, "metal index n + ik (inf: perfect conductor)", ScalarOrArray(ComplexIndex())
    )
    convention: str = convention_param("Eq. 7-8 as printed (paper) or divided by 4 pi (corrected)")
    shadowing: str = param("blinn", "geometric attenuation G", Options(*SHADOWING_CT))

    aliases = {
        "m": Alias("slopes", _slopes_from_m),
        "normalization": choice_alias(
            "convention", "normalization", {"published": "paper", "energy": "corrected"}
        ),
    }
    correspondence = Correspondence("seed 001 Eq. 7-18")

    def _kernel_spec(self):
        return self._cook_spec(0, 1.0)

    def _brdf_flat(self, ti, tr, pr):
        ci, cr, live = _grazing_safe(ti, tr)
        val = ct_kernel(
            ci, cr, np.cos(pr), np.sin(pr), self._d_fn(), self.substrate, self.shadowing, self._smith()
        )
        scale = _INV_4PI if self.convention == "corrected" else 1.0
        val *= scale / (ci * cr)
        if live is not None:
            val[~live] = 0.0
        return val

    def lobe(self, theta_i):
        """Specular lobe: centre ``(theta_i, 0)``, width ``~ 2 m`` in theta_r."""
        return (theta_i, 0.0, 2.0 * self.slopes.scale)
