"""Scattering geometry shared by every model (DESIGN.md conventions, SCATMECH's).

Mean surface normal +z.  The incident ray travels along
``k_i = (sin ti, 0, -cos ti)`` (incident azimuth pi); the reflected ray along
``k_r = (sin tr cos pr, sin tr sin pr, cos tr)``; specular is ``tr = ti, pr = 0``
and retroreflection ``tr = ti, pr = pi``.  A transmitted ray travels along
``(sin tt cos pt, sin tt sin pt, -cos tt)``.

Polarization basis per ray (seed 000 Sec. 2.B, SCATMECH ``GetBasisVectorsSP``):
``s = unit(z x k)``, ``p = k x s`` so that ``{s, p, k}`` is right-handed; for a
ray along the z axis ``s = y``.  This fixes two printed slips of seed 000 Eq. 8:
Eq. 8a has ``cos(phi_r)`` where ``sin(phi_r)`` belongs (``s_r = -x sin(phi_r) +
y cos(phi_r)``), and with Eq. 8b as printed ``{s, p, k}`` would be left-handed;
the right-handed ``p_r`` is ``-x cos(tr)cos(pr) - y cos(tr)sin(pr) + z sin(tr)``.
"""

from __future__ import annotations

import functools

import numpy as np

__all__ = [
    "incident_direction",
    "scattered_direction",
    "transmitted_direction",
    "sp_basis",
    "sp_basis_angles",
    "signed_inplane",
    "refracted_cos",
    "broadcast_angles",
    "disc_quadrature",
]


def incident_direction(theta_i):
    """Unit propagation vector of the incident ray, shape ``(..., 3)``."""
    t = np.asarray(theta_i, dtype=float)
    return np.stack([np.sin(t), np.zeros_like(t), -np.cos(t)], axis=-1)


def scattered_direction(theta_r, phi_r):
    """Unit propagation vector of a ray leaving the surface upward, ``(..., 3)``."""
    t, p = np.broadcast_arrays(np.asarray(theta_r, float), np.asarray(phi_r, float))
    st = np.sin(t)
    return np.stack([st * np.cos(p), st * np.sin(p), np.cos(t)], axis=-1)


def transmitted_direction(theta_t, phi_t):
    """Unit propagation vector of a ray transmitted downward, ``(..., 3)``."""
    t, p = np.broadcast_arrays(np.asarray(theta_t, float), np.asarray(phi_t, float))
    st = np.sin(t)
    return np.stack([st * np.cos(p), st * np.sin(p), -np.cos(t)], axis=-1)


def sp_basis(k):
    """The ``(s, p)`` polarization basis of propagation vectors ``k`` (``(..., 3)``).

    ``s = unit(z x k)`` and ``p = k x s``; along the z axis (where ``z x k`` is
    zero) ``s`` is taken as ``+y`` as SCATMECH does.
    """
    k = np.asarray(k, dtype=float)
    s = np.stack([-k[..., 1], k[..., 0], np.zeros_like(k[..., 0])], axis=-1)
    norm = np.sqrt(s[..., 0] ** 2 + s[..., 1] ** 2)
    along_z = norm <= 1e-15
    safe = np.where(along_z, 1.0, norm)
    s = s / safe[..., None]
    s = np.where(along_z[..., None], np.array([0.0, 1.0, 0.0]), s)
    p = np.cross(k, s)
    return s, p


def sp_basis_angles(theta, phi):
    """The ``(s, p)`` basis of the upward ray ``(theta, phi)``, ``(..., 3)`` each, with
    ``s = (-sin phi, cos phi, 0)``: :func:`sp_basis` away from the normal, and along it
    the limit from the ray's own azimuth, the basis every model uses at ``theta = 0``
    (SCATMECH's angle convention), so that a scan through the normal is continuous."""
    t, p = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float))
    k = scattered_direction(t, p)
    s = np.stack([-np.sin(p), np.cos(p), np.zeros_like(p)], axis=-1)
    return s, np.cross(k, s)


def signed_inplane(x):
    """A signed in-plane scattering angle ``x`` (radians) as ``(theta_r, phi_r)``: positive
    forward (``phi_r = 0``, the specular side), negative on the incidence side (``phi_r = pi``)."""
    x = np.asarray(x, dtype=float)
    return np.abs(x), np.where(x >= 0, 0.0, np.pi)


def refracted_cos(sin_theta, n1, n2):
    """``cos`` of the refracted angle in medium ``n2`` for a ray at ``sin_theta`` in ``n1``.

    Complex in general: ``sqrt(1 - (n1 sin / n2)^2)`` on the principal branch,
    which for real indices beyond the critical angle gives ``+i|...|`` (the
    evanescent, decaying wave) and for ``n2 = n + ik`` with ``k >= 0`` a
    non-negative imaginary part.  Same branch as SCATMECH's
    ``cos_internal_angle``.
    """
    ratio = np.asarray(n1, dtype=complex) / np.asarray(n2, dtype=complex)
    arg = 1.0 - (ratio * np.asarray(sin_theta)) ** 2
    # Force a +0 imaginary part where it vanished so TIR takes the +i branch.
    arg = np.where(arg.imag == 0, arg.real + 0j, arg)
    return np.sqrt(arg)


def broadcast_angles(*arrays):
    """Broadcast angle arrays to one shape; returns ``(shape, flat arrays)``."""
    b = np.broadcast_arrays(*[np.asarray(a, dtype=float) for a in arrays])
    shape = b[0].shape
    return shape, [np.ascontiguousarray(x).reshape(-1) for x in b]


@functools.lru_cache(maxsize=64)
def gauss_legendre(n):
    """``numpy.polynomial.legendre.leggauss(n)``, computed once per ``n`` (read-only arrays):
    it takes 140 us even for ``n = 4`` (an eigenvalue problem), which a wrapper built afresh
    for every evaluation, as in a fit, paid on every call."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.flags.writeable = w.flags.writeable = False
    return x, w


def polar_rule(n):
    """``(t, chi, w)``, flat: Gauss-Legendre in ``t`` on [0, 1] (``n`` nodes) times the periodic
    trapezoid rule in ``chi`` (``2 n`` nodes), ``w`` the product of their weights (no area
    element: ``sum w f ~ int_0^1 int_0^2pi f dchi dt``).  :func:`disc_quadrature` and the point
    source's polar cells build on it."""
    x, wx = gauss_legendre(n)
    chi = (np.arange(2 * n) + 0.5) * (np.pi / n)
    return np.repeat(0.5 * (x + 1.0), 2 * n), np.tile(chi, n), np.repeat(0.5 * wx, 2 * n) * (np.pi / n)


def disc_quadrature(n, radius, unit_weights=False):
    """Nodes ``(x, y)`` and weights ``w`` integrating over a disc of ``radius``
    (``sum w f(x, y) ~ integral f dA``): Gauss-Legendre in the radius (``n`` nodes,
    weight ``r dr``) times the periodic trapezoid rule in the azimuth (``2 n``
    nodes), exact for polynomials of degree ``2n - 1`` in ``r`` times trigonometric
    polynomials of degree ``2n - 1``.  Shared by the point source (a disc sample)
    and the detector aperture (a cone of directions in equal-area coordinates).

    ``unit_weights=True``: the weights of the unit disc (``radius^2`` times them are the
    disc's), for callers that use only their ratios: they never leave the float64 range,
    however large or small ``radius`` is."""
    t, chi, w = polar_rule(n)
    r = radius * t
    return r * np.cos(chi), r * np.sin(chi), w * t if unit_weights else w * (radius * r)  # r dr
