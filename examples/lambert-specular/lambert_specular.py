"""A Lambertian base under a Beckmann-Smith specular lobe: an example of a BRDF written
outside scatterbench (it imports numpy and scipy only) and validated with its kit.

    f = (1 - w) albedo / pi + w D(h) F(i.h) G1(i) G1(o) / (4 cos(theta_i) cos(theta_r))

with the Beckmann slope density ``D`` (rms slope ``roughness``), the unpolarized Fresnel
reflectance ``F`` of a dielectric of index ``n``, and Smith's exact shadowing ``G1`` for
Beckmann slopes.  Each term's albedo is at most 1 and the weights sum to 1, so energy is
conserved; every factor is symmetric in the two directions, so it is reciprocal.  It is a
scalar model: its Mueller matrix is that of an ideal depolarizer, ``f diag(1, 0, 0, 0)``.

Geometry as scatterbench's (SCATMECH's): angles in radians, the source at azimuth pi,
specular at ``theta_r = theta_i, phi_r = 0``.
"""

import math

import numpy as np
from scipy.special import erfc

__all__ = ["LambertSpecular"]


def _smith_g1(cos_t, alpha):
    """Smith's shadowing of Beckmann slopes for a direction at polar cosine ``cos_t``."""
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    with np.errstate(divide="ignore"):
        a = np.where(sin_t > 0, cos_t / (alpha * np.where(sin_t > 0, sin_t, 1.0)), np.inf)
    finite = np.isfinite(a)
    af = np.where(finite, a, 1.0)
    lam = np.where(finite, 0.5 * (np.exp(-af * af) / (af * math.sqrt(math.pi)) - erfc(af)), 0.0)
    return 1.0 / (1.0 + lam)


def _fresnel(cos_d, n):
    """Unpolarized Fresnel reflectance of a dielectric of index ``n`` at local cosine ``cos_d``."""
    c = np.clip(cos_d, 0.0, 1.0)
    w = np.sqrt(n * n - 1.0 + c * c)
    rs = ((c - w) / (c + w)) ** 2
    rp = ((n * n * c - w) / (n * n * c + w)) ** 2
    return 0.5 * (rs + rp)


class LambertSpecular:
    """A Lambertian base under a Beckmann-Smith specular lobe (scalar, depolarizing).

    Parameters
    ----------
    albedo : float
        Reflectance of the Lambertian base, in [0, 1].
    weight : float
        Weight ``w`` of the specular lobe, in [0, 1] (the base has ``1 - w``).
    roughness : float
        Beckmann rms slope, in (0, 10].
    n : float
        Refractive index of the specular interface, in [1, 10].
    """

    reciprocal = True  # the kit checks M00 and the Mueller relation
    mirror_symmetric = True  # even in phi_r: the integrator may halve its domain

    def __init__(self, albedo=0.6, weight=0.2, roughness=0.3, n=1.5):
        for name, value, lo, hi in (("albedo", albedo, 0, 1), ("weight", weight, 0, 1), ("n", n, 1, 10)):
            if not lo <= value <= hi:
                raise ValueError(f"{name} must lie in [{lo}, {hi}]; got {value!r}")
        if not 0 < roughness <= 10:
            raise ValueError(f"roughness must lie in (0, 10]; got {roughness!r}")
        self.albedo, self.weight, self.roughness, self.n = (
            float(albedo),
            float(weight),
            float(roughness),
            float(n),
        )

    def __repr__(self):
        return f"LambertSpecular(albedo={self.albedo}, weight={self.weight}, roughness={self.roughness}, n={self.n})"

    def brdf(self, theta_i, theta_r, phi_r):
        """The BRDF ``f`` (1/sr)."""
        ti, tr, pr = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (theta_i, theta_r, phi_r)))
        ci, cr = np.cos(ti), np.cos(tr)
        # half vector of the direction to the source (-sin ti, 0, cos ti) and the detector's
        hx, hy, hz = np.sin(tr) * np.cos(pr) - np.sin(ti), np.sin(tr) * np.sin(pr), ci + cr
        norm = np.sqrt(hx * hx + hy * hy + hz * hz)
        cos_h = hz / norm
        # i . h = o . h; their mean is the same expression for the reversed path, so the
        # rounding near grazing incidence cannot break reciprocity
        i_h = ci * hz - np.sin(ti) * hx
        o_h = cr * hz + np.sin(tr) * (np.cos(pr) * hx + np.sin(pr) * hy)
        cos_d = 0.5 * (i_h + o_h) / norm
        a2 = self.roughness**2
        with np.errstate(over="ignore", under="ignore"):
            tan2 = (1.0 - cos_h * cos_h) / (cos_h * cos_h)
            d = np.exp(-tan2 / a2) / (math.pi * a2 * cos_h**4)
        d = np.where(np.isfinite(d), d, 0.0)
        g = _smith_g1(ci, self.roughness) * _smith_g1(cr, self.roughness)
        # G1 vanishes like cos at grazing incidence, so G / (cos cos) stays finite
        spec = d * _fresnel(cos_d, self.n) * g / (4.0 * np.maximum(ci * cr, 1e-300))
        return (1.0 - self.weight) * self.albedo / math.pi + self.weight * spec

    def mueller(self, theta_i, theta_r, phi_r):
        """Mueller BRDF ``(..., 4, 4)``: an ideal depolarizer, ``f diag(1, 0, 0, 0)``."""
        f = self.brdf(theta_i, theta_r, phi_r)
        out = np.zeros(f.shape + (4, 4))
        out[..., 0, 0] = f
        return out
