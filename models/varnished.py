"""Cook-Torrance under a varnish layer, with brushed roughness: seed 001 Eq. 19-24.

    BRDF = D(alpha, m(beta)) G(Psi, Theta) F' / (cos theta cos psi)           (Eq. 24)
    F'   = (1 - F_in)(1 - F_out) F(psi', n / n_v)                            (Eq. 22-23)

The incident and viewing rays refract into the varnish (Eq. 20-21,
``sin psi = n_v sin Psi``; the azimuth is unchanged); D, G and the metal's F
use the internal angles: ``alpha`` and the facet's local angle ``psi'`` come
from the bisector of the *internal* directions ("alpha must be recomputed"),
and F uses the relative index ``n / n_v`` (Eq. 22).  ``F_in`` and ``F_out`` are
the natural-light air-varnish reflectances at ``psi`` and ``Theta`` (Eq. 11-12
with ``n_v`` and ``1/n_v``; ``F_out(Theta) = F_in(theta)`` by Stokes' relations).
``m(beta)`` is Eq. 19 with ``beta`` the azimuth of the (internal) bisector from
the strokes (:mod:`scatterbench.models.stroke_slopes`).

``convention="paper"`` is Eq. 24 as printed; ``"corrected"`` divides by ``4 pi``
(the normalization of :class:`scatterbench.models.CookTorranceBRDF`) and applies the refraction
Jacobian below.  The old keywords ``normalization`` (``published``/``energy``) and
``solid_angle`` (``published``/``refracted``) map onto it when they agree; their
mixed pairs are no model of their own: scale one of the two conventions by the
exact ``4 pi`` (``(1 / (4 pi)) * VarnishedCookTorranceBRDF()`` is the energy
normalization with the printed solid angle).

What Eq. 24 leaves out (measured against :class:`scatterbench.models.SubsurfaceFacetBRDF`,
see ``validation.checks.seed001``):

* the solid-angle Jacobian of refraction.  Radiance crossing into a medium of
  index ``n_v`` is multiplied by ``n_v^2`` (``L / n^2`` is invariant), and the
  internal microfacet BRDF has the *internal* cosines in its denominator, so the
  radiometrically consistent form is ``T_in T_out f_int(Psi, Theta) / n_v^2``
  with ``f_int = D G F / (4 pi cos Psi cos Theta)``.  Eq. 24 instead divides by
  the external ``cos theta cos psi`` and has no ``1 / n_v^2``: it exceeds the
  consistent form by ``n_v^2 cos Psi cos Theta / (cos psi cos theta)`` (2.25 at
  normal incidence for ``n_v = 1.5``, -> infinity at grazing).
  ``convention="corrected"`` applies the consistent denominator
  ``n_v^2 cos Psi cos Theta``; the default ``"paper"`` keeps Eq. 24.
* polarization: F' multiplies natural-light averages, whereas the transmission
  in, the metal reflection and the transmission out act on s and p in three
  different frames (a Jones product, as in seed 000).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .constraints import ComplexIndex, Options, ScalarOrArray
from .cook_torrance import (
    _INV_4PI,
    CT_SLOPES,
    SHADOWING_CT,
    _check_m,
    _CookTorranceBase,
    _grazing_safe,
    ct_kernel,
    fresnel_average,
)
from .facts import Correspondence
from .fresnel import coating_cos
from .params import Alias, coating_param, convention_param, param
from .slopes import GaussianSlopes
from .stroke_slopes import StrokeSlopes

__all__ = ["VarnishedCookTorranceBRDF"]


#: (normalization, solid_angle) of the old keywords -> convention
_OLD_PAIRS = {("published", "published"): "paper", ("energy", "refracted"): "corrected"}


def _convention_from_old(given, current):
    """The old ``normalization`` / ``solid_angle`` keywords, completed from the current
    convention, as one convention; their mixed pairs are refused (see the module docstring)."""
    now = {v: k for k, v in _OLD_PAIRS.items()}[current]
    pair = (given.get("normalization", now[0]), given.get("solid_angle", now[1]))
    for key, value, allowed in zip(
        ("normalization", "solid_angle"),
        pair,
        (("published", "energy"), ("published", "refracted")),
        strict=True,
    ):
        if value not in allowed:
            raise ValueError(f"{key} (old name of convention) must be one of {allowed}; got {value!r}")
    if pair in _OLD_PAIRS:
        return _OLD_PAIRS[pair]
    raise ValueError(
        f"normalization={pair[0]!r} with solid_angle={pair[1]!r}: this pair is no longer a model of its own. "
        "convention='paper' is Eq. 24 as printed (published, published); convention='corrected' divides by 4 pi "
        "and applies the refraction Jacobian (energy, refracted).  For a mixed pair scale one of them by the "
        "exact 4 pi: (1 / (4 pi)) * VarnishedCookTorranceBRDF(convention='paper') is energy with the printed "
        "solid angle, 4 pi * VarnishedCookTorranceBRDF(convention='corrected') published with the refracted one"
    )


def _slopes_from_strokes(given, current):
    """The old ``m_parallel`` / ``m_perpendicular`` / ``stroke_angle`` keywords (or ``m`` for
    both ``m`` values, as :class:`CookTorranceBRDF`'s), completed from the current slopes, as a
    :class:`scatterbench.models.StrokeSlopes`."""
    given = dict(given)
    if "m" in given:
        if "m_parallel" in given or "m_perpendicular" in given:
            raise ValueError("m: give either m or m_parallel and m_perpendicular, not both")
        m = _check_m(given.pop("m"))
        given.update(m_parallel=m, m_perpendicular=m)
    if isinstance(current, GaussianSlopes):
        current = StrokeSlopes(m_parallel=current.sigma, m_perpendicular=current.sigma)
    return current.replace(**given)


@dataclass(frozen=True)
class VarnishedCookTorranceBRDF(_CookTorranceBase):
    """Varnished, brushed metal: Cook-Torrance under a flat varnish, seed 001 Eq. 19-24.

    Scalar model for natural light: :meth:`mueller` returns the depolarizing
    matrix ``diag(BRDF, 0, 0, 0)`` (``M00 = BRDF``).

    Parameters
    ----------
    slopes : StrokeSlopes or GaussianSlopes
        Brushed roughness of Eq. 19 (:class:`scatterbench.models.StrokeSlopes`: the paper's
        ``m_parallel``, ``m_perpendicular`` and the strokes' azimuth); equal ``m``
        values, or ``GaussianSlopes(sigma=m)``, give isotropic Cook-Torrance roughness
        ``m``.  Old keywords ``m_parallel``, ``m_perpendicular``, ``stroke_angle`` (and ``m``
        for both ``m`` values, as :class:`CookTorranceBRDF`'s).
    coating : float
        Real varnish index ``n_v >= 1`` (``1``: :class:`CookTorranceBRDF`).  Old name
        ``varnish``.
    substrate : complex or math.inf
        Metal index ``n + ik`` (relative to air; Eq. 22 divides it by ``n_v``).
    convention : "paper" | "corrected"
        ``paper``: Eq. 24 as printed, denominator ``cos theta cos psi`` and no ``1/pi``
        in D, no 4 in the denominator (the normalization of Eq. 7-8).  ``corrected``:
        divided by ``4 pi`` and with the radiometrically consistent denominator
        ``n_v^2 cos Theta cos Psi`` (see module docstring).  Either way F is the
        corrected Eq. 13-16.  Old keywords ``normalization`` and ``solid_angle``.
    shadowing : "blinn" | "none" | "smith"
        Eq. 18 with the internal angles (Eq. 24's ``G(Psi, Theta)``), ``G = 1``, or the
        separable Smith ``G1 G1`` of the internal directions from the Beckmann ``Lambda``
        of the model's roughness (:func:`scatterbench.models.cook_torrance.smith_slopes`; not in seed
        001).  Options a fused kernel does not cover run on this numpy path.
    """

    slopes: StrokeSlopes | GaussianSlopes = param(
        StrokeSlopes(), "brushed facet slopes of D: StrokeSlopes (Eq. 19) or GaussianSlopes", CT_SLOPES
    )
    coating: float = coating_param(1.5, "varnish index n_v (real)")
    substrate: complex = param(
        2.29 + 3.37j, "metal index n + ik (inf: perfect conductor)", ScalarOrArray(ComplexIndex())
    )
    convention: str = convention_param(
        "Eq. 24 as printed (paper) or divided by 4 pi with the refraction Jacobian (corrected)"
    )
    shadowing: str = param("blinn", "geometric attenuation G", Options(*SHADOWING_CT))

    aliases = {
        "varnish": "coating",
        "m": Alias("slopes", _slopes_from_strokes),
        "m_parallel": Alias("slopes", _slopes_from_strokes),
        "m_perpendicular": Alias("slopes", _slopes_from_strokes),
        "stroke_angle": Alias("slopes", _slopes_from_strokes),
        "normalization": Alias("convention", _convention_from_old),
        "solid_angle": Alias("convention", _convention_from_old),
    }
    correspondence = Correspondence("seed 001 Eq. 19-24")

    def _kernel_spec(self):
        return self._cook_spec(1, self.coating)

    def _brdf_flat(self, ti, tr, pr):
        ci, cr, live = _grazing_safe(ti, tr)
        nv = self.coating
        ext = np.stack([ci, cr])
        c_int = coating_cos(ext, nv)  # Eq. 20-21: internal cosines (no TIR entering from air)
        index = self.substrate if self.substrate == math.inf else complex(self.substrate) / nv  # Eq. 22
        val = ct_kernel(
            c_int[0], c_int[1], np.cos(pr), np.sin(pr), self._d_fn(), index, self.shadowing, self._smith()
        )
        if nv != 1.0:
            t = 1.0 - fresnel_average(ext, nv)  # 1 - F_in(psi), 1 - F_out(Theta) = 1 - F(theta)
            val *= t[0] * t[1]  # Eq. 23
        if self.convention == "paper":
            val *= 1.0 / (ci * cr)  # Eq. 24
        else:
            val *= _INV_4PI / (nv * nv * c_int[0] * c_int[1])
        if live is not None:
            val[~live] = 0.0
        return val

    def lobe(self, theta_i):
        """Specular lobe at ``(theta_i, 0)``; width ``2 n_v m cos(Psi) / cos(psi)`` in theta_r."""
        nv = self.coating
        s = math.sin(theta_i) / nv
        width = 2.0 * nv * self.slopes.scale * math.sqrt(1 - s * s)
        return (theta_i, 0.0, width / max(math.cos(theta_i), 1e-6))
