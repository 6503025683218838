"""Brushed-metal roughness of seed 001 Eq. 19 as a facet slope distribution.

Eq. 19 interpolates the roughness ``m`` of Eq. 8 between ``m_parallel`` (along
the strokes) and ``m_perpendicular`` (across them) on an ellipse in polar form,

    m(beta) = m_par m_perp / sqrt(m_perp^2 cos^2 beta + m_par^2 sin^2 beta),

and the Cook-Torrance D (Eq. 8) is evaluated with ``m = m(beta)``.  Choice made
here (the paper does not say which azimuth ``beta`` is): ``beta`` is the
azimuth of the facet normal -- the bisector ``H`` -- measured from the stroke
direction, i.e. the direction of the facet slope.  It is the only choice that
keeps D a distribution of facet normals (and so keeps the BRDF reciprocal).

In slope space (``zeta = tan(alpha) (cos beta, sin beta)`` in stroke axes,
``u`` along and ``v`` across the strokes), ``D / pi`` cos^4 is

    P3(zeta) = exp(-(u/m_par)^2 - (v/m_perp)^2) / (pi m(beta)^2),

the anisotropic Gaussian's exponent with the prefactor ``1 / m(beta)^2`` in
place of ``1 / (m_par m_perp)``.  It is normalized (for each ``beta`` the
radial integral is ``m(beta)^2 / 2``), and it is *not* the anisotropic Gaussian
of :class:`scatterbench.models.AnisotropicGaussianSlopes`: their ratio is
``(m_perp/m_par) cos^2 beta + (m_par/m_perp) sin^2 beta``, and at zero slope the
density depends on the direction of approach (``1/(pi m(beta)^2)``); the value
at exactly ``zeta = 0`` is taken as its azimuthal mean
``(1/m_par^2 + 1/m_perp^2) / (2 pi)``.  Sampling is exact: ``beta`` is uniform
and ``|zeta|`` Rayleigh with scale ``m(beta)/sqrt(2)``.

``m_parallel`` and ``m_perpendicular`` are the paper's ``m`` values, not the rms
slopes along and across the strokes: with ``a = m_par``, ``b = m_perp`` the second
moments of this density are

    <u^2> = a^2 b / (a + b),   <v^2> = b^2 a / (a + b),   <u v> = 0,

and ``<|zeta|^2> = a b`` (``beta`` is uniform and ``<|zeta|^2>`` at fixed ``beta`` is
``m(beta)^2``; the mean over ``beta`` of ``cos^2 beta / (b^2 cos^2 beta + a^2 sin^2
beta)`` is ``1 / (b (a + b))``).  Only for ``a = b = m`` are both ``m^2 / 2``, the
per-axis moments of ``GaussianSlopes(sigma=m)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import kernel_specs
from .params import width_param
from .slopes import SlopeDistribution, _exp_neg, coverage_param, rotation_param

__all__ = ["StrokeSlopes", "stroke_d"]


def stroke_d(m_par, m_perp, stroke_angle):
    """``d_fn(hx, hy, hz2) = exp(-tan^2 alpha / m(beta)^2) / m(beta)^2`` (Eq. 8 with Eq. 19)
    for an unnormalized bisector ``h``, as used by the Cook-Torrance kernels."""
    a2, b2 = 1.0 / (m_par * m_par), 1.0 / (m_perp * m_perp)
    c, s = math.cos(stroke_angle), math.sin(stroke_angle)
    at_zero = 0.5 * (a2 + b2)
    if m_par == m_perp:

        def d_iso(hx, hy, hz2):
            return _exp_neg((hx * hx + hy * hy) * a2 / hz2) * a2

        return d_iso

    def d_fn(hx, hy, hz2):
        u = c * hx + s * hy
        v = c * hy - s * hx
        u2, v2 = u * u, v * v
        q = u2 * a2 + v2 * b2  # tan^2(alpha) / m(beta)^2 times hz^2
        r2 = u2 + v2
        inv_m2 = np.divide(q, r2, out=np.full_like(q, at_zero), where=r2 > 0.0)  # 1/m(beta)^2
        return _exp_neg(q / hz2) * inv_m2

    return d_fn


@dataclass(frozen=True)
class StrokeSlopes(SlopeDistribution):
    """Seed 001 Eq. 19 roughness as a slope density (see module docstring).

    ``P3 = exp(-(u/m_par)^2 - (v/m_perp)^2) / (pi m(beta)^2)`` with ``(u, v)``
    the slope along / across the strokes, which lie at ``stroke_angle`` from x.
    ``m_par = m_perp = m`` is :class:`scatterbench.models.GaussianSlopes` with ``sigma = m``.
    """

    # swept from a near-mirror to seed 001's roughest m = 2, and a 100:1 (and 2e4:1) anisotropy
    m_parallel: float = width_param(
        0.03,
        "the paper's m along the strokes (Eq. 19); slope moment <u^2> = m_par^2 m_perp / (m_par + m_perp)",
        edges=(1e-4, 0.3, 2.0),
    )
    m_perpendicular: float = width_param(
        0.03,
        "the paper's m across the strokes (Eq. 19); slope moment <v^2> = m_perp^2 m_par / (m_par + m_perp)",
        edges=(1e-4, 0.3, 2.0),
    )
    stroke_angle: float = rotation_param("azimuth of the strokes from the sample x axis (rad)")
    coverage: float = coverage_param()

    kernel_code = kernel_specs.STROKE

    def kernel_row(self):
        return [self.m_parallel, self.m_perpendicular, self.stroke_angle, self.coverage]

    @property
    def isotropic(self):  # type: ignore[override]
        return self.m_parallel == self.m_perpendicular

    @property
    def scale(self):
        return max(self.m_parallel, self.m_perpendicular)

    @property
    def _zeta_max(self):
        return 12.0 * self.scale

    def _p3_unit(self, zx, zy):
        zx = np.asarray(zx, dtype=float)
        zy = np.asarray(zy, dtype=float)
        d = stroke_d(self.m_parallel, self.m_perpendicular, self.stroke_angle)
        return d(zx, zy, np.ones_like(zx + zy)) / math.pi

    def m_of_beta(self, beta):
        """Eq. 19: ``m(beta)``, ``beta`` measured from the strokes."""
        a, b = self.m_parallel, self.m_perpendicular
        beta = np.asarray(beta, dtype=float)
        return a * b / np.sqrt((b * np.cos(beta)) ** 2 + (a * np.sin(beta)) ** 2)

    def sample(self, size, seed=None):
        rng = np.random.default_rng(seed)
        beta = rng.random(size) * 2.0 * math.pi
        r = self.m_of_beta(beta) * np.sqrt(-np.log1p(-rng.random(size)))
        phi = beta + self.stroke_angle
        return r * np.cos(phi), r * np.sin(phi)

    def rotated(self, angle):
        if self.isotropic:
            return self
        return self.replace(stroke_angle=(self.stroke_angle + angle) % (2 * math.pi))
