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
the strokes (:mod:`models.stroke_slopes`).

Normalizations as for :class:`models.CookTorranceBRDF`: ``published`` is Eq. 24
as printed, ``energy`` divides by ``4 pi``.

What Eq. 24 leaves out (measured against :class:`models.SubsurfaceFacetBRDF`,
see ``validation.checks.seed001``):

* the solid-angle Jacobian of refraction.  Radiance crossing into a medium of
  index ``n_v`` is multiplied by ``n_v^2`` (``L / n^2`` is invariant), and the
  internal microfacet BRDF has the *internal* cosines in its denominator, so the
  radiometrically consistent form is ``T_in T_out f_int(Psi, Theta) / n_v^2``
  with ``f_int = D G F / (4 pi cos Psi cos Theta)``.  Eq. 24 instead divides by
  the external ``cos theta cos psi`` and has no ``1 / n_v^2``: it exceeds the
  consistent form by ``n_v^2 cos Psi cos Theta / (cos psi cos theta)`` (2.25 at
  normal incidence for ``n_v = 1.5``, -> infinity at grazing).
  ``solid_angle="refracted"`` applies the consistent denominator
  ``n_v^2 cos Psi cos Theta``; the default ``"published"`` keeps Eq. 24.
* polarization: F' multiplies natural-light averages, whereas the transmission
  in, the metal reflection and the transmission out act on s and p in three
  different frames (a Jones product, as in seed 000).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .cook_torrance import _INV_4PI, _CookTorranceBase, _grazing_safe, ct_kernel, fresnel_average
from .params import param
from .stroke_slopes import stroke_d

__all__ = ["VarnishedCookTorranceBRDF"]


@dataclass(frozen=True)
class VarnishedCookTorranceBRDF(_CookTorranceBase):
    """Varnished, brushed metal: Cook-Torrance under a flat varnish, seed 001 Eq. 19-24.

    Scalar model for natural light: :meth:`mueller` returns the depolarizing
    matrix ``diag(BRDF, 0, 0, 0)`` (``M00 = BRDF``).

    Parameters
    ----------
    m_parallel, m_perpendicular : float
        rms slopes along and across the strokes (Eq. 19); equal values give
        isotropic Cook-Torrance roughness ``m``.
    varnish : float
        Real varnish index ``n_v >= 1`` (``1``: :class:`CookTorranceBRDF`).
    substrate : complex or math.inf
        Metal index ``n + ik`` (relative to air; Eq. 22 divides it by ``n_v``).
    stroke_angle : float
        Azimuth of the strokes from the sample x axis (rad).
    normalization : "published" | "energy"
    shadowing : "blinn" | "none"
        Eq. 18 with the internal angles (Eq. 24's ``G(Psi, Theta)``) or ``G = 1``.
    solid_angle : "published" | "refracted"
        Denominator ``cos theta cos psi`` (Eq. 24) or the radiometrically
        consistent ``n_v^2 cos Theta cos Psi`` (see module docstring).
    """

    m_parallel: float = param(0.03, "rms slope along the strokes (Eq. 19)", low=0.0, low_open=True)
    m_perpendicular: float = param(0.03, "rms slope across the strokes (Eq. 19)", low=0.0, low_open=True)
    varnish: float = param(1.5, "varnish index n_v (real)", kind="real_index", low=1.0)
    substrate: complex = param(2.29 + 3.37j, "metal index n + ik (inf: perfect conductor)", kind="index")
    stroke_angle: float = param(0.0, "azimuth of the strokes from the x axis (rad)")
    normalization: str = param(
        "published", "Eq. 24 as printed or energy-normalized", kind="choice", choices=("published", "energy")
    )
    shadowing: str = param("blinn", "geometric attenuation G", kind="choice", choices=("blinn", "none"))
    solid_angle: str = param(
        "published",
        "denominator of Eq. 24 or the refraction-consistent one",
        kind="choice",
        choices=("published", "refracted"),
    )

    @property
    def mirror_symmetric(self) -> bool:
        return self.m_parallel == self.m_perpendicular or math.sin(2.0 * self.stroke_angle) == 0.0

    @property
    def slopes(self):
        """The brushed facet slope density of Eq. 19 (:class:`models.StrokeSlopes`)."""
        from .stroke_slopes import StrokeSlopes

        return StrokeSlopes(
            m_parallel=self.m_parallel, m_perpendicular=self.m_perpendicular, stroke_angle=self.stroke_angle
        )

    @property
    def coating(self):
        """The varnish is the coating the light crosses (for coating-generic analyses)."""
        return self.varnish

    def rotated(self, angle):
        if self.m_parallel == self.m_perpendicular:
            return self
        return self.replace(stroke_angle=(self.stroke_angle + angle) % (2 * math.pi))

    def _brdf_flat(self, ti, tr, pr):
        ci, cr, live = _grazing_safe(ti, tr)
        nv = self.varnish
        ext = np.stack([ci, cr])
        # Eq. 20-21: internal cosines (no TIR entering from air).
        # cos' = sqrt(n_v^2 - 1 + cos^2) / n_v: exact for n_v = 1 and free of the
        # cancellation of sqrt(1 - sin^2/n_v^2) at grazing incidence.
        c_int = np.sqrt(nv * nv - 1.0 + ext * ext) * (1.0 / nv)
        index = self.substrate if self.substrate == math.inf else complex(self.substrate) / nv  # Eq. 22
        d_fn = stroke_d(self.m_parallel, self.m_perpendicular, self.stroke_angle)
        val = ct_kernel(c_int[0], c_int[1], np.cos(pr), np.sin(pr), d_fn, index, self.shadowing)
        if nv != 1.0:
            t = 1.0 - fresnel_average(ext, nv)  # 1 - F_in(psi), 1 - F_out(Theta) = 1 - F(theta)
            val *= t[0] * t[1]  # Eq. 23
        scale = _INV_4PI if self.normalization == "energy" else 1.0
        if self.solid_angle == "published":
            val *= scale / (ci * cr)  # Eq. 24
        else:
            val *= scale / (nv * nv * c_int[0] * c_int[1])
        if live is not None:
            val[~live] = 0.0
        return val

    def lobe(self, theta_i):
        """Specular lobe at ``(theta_i, 0)``; width ``2 n_v m cos(Psi) / cos(psi)`` in theta_r."""
        nv = self.varnish
        s = math.sin(theta_i) / nv
        width = 2.0 * nv * max(self.m_parallel, self.m_perpendicular) * math.sqrt(1 - s * s)
        return (theta_i, 0.0, width / max(math.cos(theta_i), 1e-6))
