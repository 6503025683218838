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

Since ``integral P3 zeta_x d^2 zeta = 0``, ``H = C (1 + Lambda(cot theta_i'))`` with
``Lambda`` Smith's function of the slopes along the beam's azimuth
(:mod:`scatterbench.models.shadowing`): the separable Smith ``G1 = 1 / (1 + Lambda)`` is exactly the
factor that brings ``H`` back to ``C``.  The tests hold the quadrature here to that
identity; nothing here uses it.

Truncation of the slope plane.  The radial integrals stop at ``60 scale`` for the
light-tailed families (exponential, Gaussian, angle distributions: their mass beyond
is below ``exp(-60 sqrt 6)``).  GGX slopes have no rms slope and a power-law tail,
``P3 <= C b^2 / (pi zeta^4)`` with ``b^2 = max(ax, ay)^4 / (ax ay)`` (``b = alpha``
isotropic), so the hit-fraction integrand beyond a radius ``R`` holds at most
``C b^2 (1 / R^2 + 4 tan / (pi R))`` (the ``1`` and the ``tan |zeta_x|`` parts of
``(1 - tan zeta_x)_+``).  The radius is derived from that bound, not typed: the
smallest geometric panel edge where it is below :data:`TAIL_TOL`.

For an exposed surface (coating 1) and unpolarized light the integrated
reflectance has a closed slope-space form, since unpolarized light stays
unpolarized in the facet's own s/p frame:

    R(theta_i) = integral P3 (1 - tan(ti) zeta_x)_+ [k_r up] (R_s + R_p)(alpha) / 2 d^2 zeta.
"""

from __future__ import annotations

import math

import numpy as np

from scatterbench.models.fresnel import fresnel_reflectance
from scatterbench.models.shadowing import azimuthal_width, is_elliptical
from scatterbench.models.slopes import AnisotropicGGXSlopes, GGXSlopes

__all__ = ["hit_fraction", "exposed_reflectance", "tail_radius", "TAIL_TOL"]

#: bound on the part of a power-law (GGX) slope density's integrals left beyond the
#: truncation radius (module docstring)
TAIL_TOL = 1e-12


def tail_radius(slopes, tan=0.0):
    """The radius beyond which the hit-fraction integrand of power-law (GGX) slopes holds
    at most :data:`TAIL_TOL` (module docstring), for a beam at ``tan(theta_i')``; None for
    the light-tailed families (their integrals stop at ``60 scale``)."""
    if isinstance(slopes, GGXSlopes):
        b2 = slopes.alpha**2
    elif isinstance(slopes, AnisotropicGGXSlopes):
        b2 = max(slopes.alpha_x, slopes.alpha_y) ** 4 / (slopes.alpha_x * slopes.alpha_y)
    else:
        return None
    c = slopes.coverage * b2
    # C b^2 / R^2 <= TAIL_TOL / 2 and 4 C b^2 tan / (pi R) <= TAIL_TOL / 2
    return max(math.sqrt(2.0 * c / TAIL_TOL), 8.0 * c * tan / (math.pi * TAIL_TOL))


def _radial_nodes(scale, rho_max, n=64, outer=None):
    """Gauss-Legendre nodes on [0, rho_max] split at geometric breakpoints of ``scale``
    (continued by factors of 2.5 up to ``outer`` when given: :func:`tail_radius`)."""
    edges = [0.0] + [scale * f for f in (0.1, 0.5, 1.5, 4.0, 10.0, 25.0, 60.0)]
    while outer is not None and edges[-1] < outer:
        edges.append(edges[-1] * 2.5)
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
    """``H(theta_i)``: mean illuminated facet area per unit beam footprint (see module doc).

    Elliptical slopes (an isotropic density stretched by ``sigma_x``, ``sigma_y`` along
    axes rotated by ``rotation``) are integrated in the unstretched coordinates, where
    ``zeta_x`` is ``alpha_b`` times one coordinate, ``alpha_b^2 = (sigma_x cos rotation)^2 +
    (sigma_y sin rotation)^2``: ``H`` is ``C`` times the isotropic unit density's at
    ``tan(theta_i') alpha_b`` (an exact change of variables, so a 1e5:1 anisotropy needs no
    finer azimuthal grid).
    """
    ti = math.asin(math.sin(theta_i) / coating)
    tan = math.tan(ti)
    if is_elliptical(slopes):
        unit, alpha_b = azimuthal_width(slopes, 1.0, 0.0)  # the beam's azimuth, phi = 0
        return slopes.coverage * _hit_fraction(unit, tan * float(alpha_b))
    return _hit_fraction(slopes, tan)


def _hit_fraction(slopes, tan):
    psi, wp = _azimuths()
    c = np.cos(psi)
    with np.errstate(divide="ignore"):
        rho_hit = np.where(c * tan > 0, 1.0 / np.where(c * tan > 0, c * tan, 1.0), np.inf)
    rho, wr = _radial_nodes(slopes.scale, rho_hit, outer=tail_radius(slopes, tan))
    zx = rho * c[:, None]
    zy = rho * np.sin(psi)[:, None]
    f = slopes.p3(zx, zy) * np.maximum(1.0 - tan * zx, 0.0) * rho
    return float(np.sum(f * wr * wp[:, None]))


def exposed_reflectance(slopes, theta_i, substrate):
    """Integrated reflectance of :class:`scatterbench.models.FacetBRDF` for unpolarized light, in slope space."""
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
    rho, wr = _radial_nodes(slopes.scale, np.minimum(rho_hit, rho_up), outer=tail_radius(slopes, tan))
    zx = rho * c[:, None]
    zy = rho * np.sin(psi)[:, None]
    norm = np.sqrt(1.0 + zx * zx + zy * zy)
    cos_alpha = np.clip((ci - si * zx) / norm, 0.0, 1.0)
    rs2, rp2 = fresnel_reflectance(cos_alpha, 1.0, substrate)
    f = slopes.p3(zx, zy) * np.maximum(1.0 - tan * zx, 0.0) * 0.5 * (rs2 + rp2) * rho
    return float(np.sum(f * wr * wp[:, None]))
