"""Polarized Henyey-Greenstein phase function (seed 003 Sec. 2.1, Eq. 2-7).

The scalar Henyey-Greenstein density per steradian is

    p(theta) = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos theta)^(3/2)).

Seed 003 Eq. 2 (and Eq. 7) print ``1 + 2 g cos(theta) + g^2``; with that sign
``<cos theta> = -g``, contradicting the text ("g is the average of the cosine
of the scattering angle").  The Henyey-Greenstein form above is used (DESIGN.md
slip list); tests check ``<cos theta> = g``.

Polarized form (Eq. 3-7).  The scattered amplitude is taken proportional to the
projection dyadic ``I - k2 k2`` (Eq. 4, Rayleigh-Gans), so in *any* pair of
transverse bases ``e_b`` of the incident and ``e_a`` of the scattered ray the
Jones matrix is simply ``J_ab = e_a . e_b``; in the scattering-plane bases of
Eq. 3 it is ``diag(1, cos theta)`` (Eq. 5).  Since ``sum |J_ab|^2 = 1 +
cos^2 theta`` in every basis, Eq. 6-7 make the unpolarized probability the
scalar HG density:

    P = p(theta) * 2 M(J) / (1 + cos^2 theta).

``polarized=False`` gives the depolarizing variant ``P = p(theta) D``, ``D =
diag(1, 0, 0, 0)`` (SCATMECH ``Unpolarized_Phase_Function`` around
``Henyey_Greenstein_Phase_Function``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .constraints import Interval, Options, ScalarOrArray
from .params import Declared, param

__all__ = ["HenyeyGreenstein"]


@dataclass(frozen=True)
class HenyeyGreenstein(Declared):
    """Henyey-Greenstein phase function, polarized (Rayleigh-Gans, Eq. 7) or depolarizing.

    Parameters
    ----------
    g : float
        Asymmetry parameter ``<cos theta>``, in (-1, 1).
    polarized : bool
        True: Eq. 7 (Rayleigh-Gans polarization); False: totally depolarizing.
    """

    # swept at strong back scattering, isotropic and strong forward scattering
    g: float = param(
        0.3,
        "asymmetry parameter <cos theta>",
        ScalarOrArray(Interval(-1.0, 1.0, closed="neither")),
        edges=(-0.99, 0.0, 0.99),
    )
    polarized: bool = param(True, "Rayleigh-Gans polarization (Eq. 7) or depolarizing", Options(True, False))

    def density(self, cos_theta):
        """Scalar HG density per steradian ``p(theta)`` (Eq. 2 with the HG sign)."""
        c = np.asarray(cos_theta, dtype=float)
        g = self.g
        # 1 + g^2 - 2 g c as u^2 + 2 |g| v, u = 1 - |g|, v = 1 -+ c by the sign of g: two
        # non-negative terms (the printed form cancels to 0, and the density to inf, at
        # g -> -1 and backscatter, c = -1, where it is finite: (1 - g) / (4 pi (1 + g)^2))
        u = 1.0 - np.abs(g)
        v = np.maximum(np.where(np.asarray(g) < 0.0, 1.0 + c, 1.0 - c), 0.0)
        base = u * u + 2.0 * np.abs(g) * v
        return u * (2.0 - u) / (4.0 * math.pi * base * np.sqrt(base))

    def mean_cos(self) -> float:
        """``<cos theta>`` (= g for Henyey-Greenstein)."""
        return self.g

    def scattering_plane_mueller(self, cos_theta):
        """Mueller phase matrix ``(..., 4, 4)`` per sr in the scattering-plane bases of Eq. 3."""
        c = np.asarray(cos_theta, dtype=float)
        p = self.density(c)
        M = np.zeros(c.shape + (4, 4))
        M[..., 0, 0] = p
        if self.polarized:
            k = 2.0 * p / (1.0 + c * c)
            M[..., 0, 1] = M[..., 1, 0] = 0.5 * k * (1.0 - c * c)
            M[..., 1, 1] = 0.5 * k * (1.0 + c * c)
            M[..., 2, 2] = M[..., 3, 3] = k * c
        return M
