"""Energy bookkeeping of the facet models, computed in slope space.

These predictions share nothing with the BRDF code or the hemispherical
integrator: they integrate the slope density directly.

The ray model of seed 000 has no shadowing (Sec. 2.A).  A facet of slope
``zeta`` is hit with probability proportional to its area projected on the
beam, ``cos(alpha) / cos(theta_n)``, divided by the beam's footprint
``cos(theta_i')`` (Eq. 43), i.e. ``(1 - tan(theta_i') zeta_x)`` where positive.
Its mean over ``P3``, the *hit fraction*

    H(theta_i) = integral P3(zeta) (1 - tan(theta_i') zeta_x)_+ d^2 zeta
               = C + integral P3 (tan(theta_i') zeta_x - 1)_+ d^2 zeta  >=  C,

exceeds the coverage once ``tan(theta_i') sigma`` is not small: facets tilted
toward a grazing beam are counted although their neighbours would shadow them.
The model's integrated reflectance is bounded by ``H``, not by 1, and can exceed
1 near grazing incidence on rough exposed surfaces.  This is a property of the
model (SCATMECH's ``Facet_BRDF_Model`` behaves identically), reported as such.

For an exposed surface (coating 1) and unpolarized light the integrated
reflectance has a closed slope-space form, since unpolarized light stays
unpolarized in the facet's own s/p frame:

    R(theta_i) = integral P3 (1 - tan(ti) zeta_x)_+ [k_r up] (R_s + R_p)(alpha) / 2 d^2 zeta.
"""

from __future__ import annotations

import math

import numpy as np

from models.fresnel import fresnel_reflectance

__all__ = ["hit_fraction", "exposed_reflectance"]


def _radial_nodes(scale, rho_max, n=64):
    """Gauss-Legendre nodes on [0, rho_max] split at geometric breakpoints of ``scale``."""
    edges = [0.0] + [scale * f for f in (0.1, 0.5, 1.5, 4.0, 10.0, 25.0, 60.0)]
    x, w = np.polynomial.legendre.leggauss(n)
    nodes, weights = [], []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        nodes.append(0.5 * (b - a) * x + 0.5 * (a + b))
        weights.append(0.5 * (b - a) * w)
    rho = np.concatenate(nodes)  # (K,)
    wr = np.concatenate(weights)
    # Map onto [0, rho_max(psi)] per azimuth: rho_max is an array (P,)
    rm = np.minimum(rho_max, edges[-1])[:, None]
    return rho[None, :] * rm / edges[-1], wr[None, :] * rm / edges[-1]


def _azimuths(n=256):
    x, w = np.polynomial.legendre.leggauss(n)
    return math.pi * (x + 1.0), math.pi * w  # psi in [0, 2 pi]


def hit_fraction(slopes, theta_i, coating=1.0):
    """``H(theta_i)``: mean illuminated facet area per unit beam footprint (see module doc)."""
    ti = math.asin(math.sin(theta_i) / coating)
    tan = math.tan(ti)
    psi, wp = _azimuths()
    c = np.cos(psi)
    with np.errstate(divide="ignore"):
        rho_hit = np.where(c * tan > 0, 1.0 / np.where(c * tan > 0, c * tan, 1.0), np.inf)
    rho, wr = _radial_nodes(slopes.scale, rho_hit)
    zx = rho * c[:, None]
    zy = rho * np.sin(psi)[:, None]
    f = slopes.p3(zx, zy) * np.maximum(1.0 - tan * zx, 0.0) * rho
    return float(np.sum(f * wr * wp[:, None]))


def exposed_reflectance(slopes, theta_i, substrate):
    """Integrated reflectance of :class:`models.FacetBRDF` for unpolarized light, in slope space."""
    ti = float(theta_i)
    si, ci = math.sin(ti), math.cos(ti)
    tan = si / ci
    psi, wp = _azimuths()
    c = np.cos(psi)
    with np.errstate(divide="ignore"):
        rho_hit = np.where(c * tan > 0, 1.0 / np.where(c * tan > 0, c * tan, 1.0), np.inf)
    # reflected ray upward: cos(ti) rho^2 + 2 sin(ti) cos(psi) rho - cos(ti) < 0
    b = si * c
    rho_up = (-b + np.sqrt(b * b + ci * ci)) / ci
    rho, wr = _radial_nodes(slopes.scale, np.minimum(rho_hit, rho_up))
    zx = rho * c[:, None]
    zy = rho * np.sin(psi)[:, None]
    norm = np.sqrt(1.0 + zx * zx + zy * zy)
    cos_alpha = np.clip((ci - si * zx) / norm, 0.0, 1.0)
    rs2, rp2 = fresnel_reflectance(cos_alpha, 1.0, substrate)
    f = slopes.p3(zx, zy) * np.maximum(1.0 - tan * zx, 0.0) * 0.5 * (rs2 + rp2) * rho
    return float(np.sum(f * wr * wp[:, None]))
