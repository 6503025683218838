"""The Maxwell-Beard BRDF (Maxwell, Beard, Weiner, Ladd & Ladd, ERIM 1973), the model
seed 003 compares its combination with (Sec. 4).

Published form: a specular facet term with the Fresnel ratio and the empirical
shadowing/obscuration function, a Lambertian term and a volumetric term,

    f = [R(beta)/R(0)] f_facet^(0)(theta_N) SO(theta_N, beta) + rho_D + 2 rho_V / (cos ti + cos tr),
    SO = (1 + (theta_N / Omega) exp(-2 beta / tau)) / (1 + theta_N / Omega),

with ``beta`` half the angle between the directions to the source and to the
detector (the facet's local angle of incidence) and ``theta_N`` the polar
angle of their bisector (the facet normal).  Maxwell-Beard's measured
``f_facet^(0)`` (the facet distribution at the Fresnel reference) is here the
facet model's, so ``R(0) f_facet^(0) [R(beta)/R(0)]`` is the unpolarized
:class:`scatterbench.models.FacetBRDF` and the specular term is ``FacetBRDF x SO``: the same
as SCATMECH's ``Shadowed_Facet_BRDF_Model`` with
``Maxwell_Beard_Shadow_Function`` (tests compare with it).  ``rho_D`` and
``rho_V`` are BRDF values (1/sr).

``polarized=False`` (the published, scalar form): every term is depolarizing and
only ``M00`` is non-zero.  ``polarized=True`` (the extension seed 003 discusses):
the specular term carries the facet's Mueller matrix (Jones x sqrt(SO)); the
Lambertian and volumetric terms stay depolarizing.  As seed 003 notes, the model
has no refraction into the material and no interface on the diffuse terms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from . import kernel_specs
from .base import Model
from .constraints import FACTOR_MAX, ComplexIndex, Interval, Options, ScalarOrArray
from .facet import FacetBRDF
from .facts import Correspondence, scatmech_index
from .params import param
from .slopes import SLOPES, GaussianSlopes, SlopeDistribution

__all__ = ["MaxwellBeardBRDF", "maxwell_beard_shadow"]


def maxwell_beard_shadow(ti, tr, pr, tau, omega):
    """Shadowing/obscuration ``SO(theta_N, beta)`` of Maxwell-Beard (flat arrays).

    With ``a = (-sin ti, 0, cos ti)`` the direction to the source and ``b`` that to the
    detector, the facet normal is along ``a + b`` and ``beta`` is half the angle between
    ``a`` and ``b``: ``theta_N = atan2(|(a + b)_xy|, (a + b)_z)`` and
    ``beta = atan2(|a - b|, |a + b|)``.  Both are well conditioned everywhere; ``beta`` as
    ``arccos(sqrt((1 + a.b) / 2))`` is not near retroreflection (``beta -> 0``), where it
    turned an ulp of the cosines into 1e-10 of ``SO``."""
    si, ci, sr, cr = np.sin(ti), np.cos(ti), np.sin(tr), np.cos(tr)
    cp, sp = np.cos(pr), np.sin(pr)
    hx, hy = sr * cp - si, sr * sp  # (a + b)_xy
    t = hx * hx + hy * hy
    den = ci + cr  # (a + b)_z
    theta_n = np.arctan2(np.sqrt(t), np.where(den > 0, den, 1.0))
    dx, dz = sr * cp + si, cr - ci  # b - a
    beta = np.arctan2(np.sqrt(dx * dx + hy * hy + dz * dz), np.sqrt(t + den * den))
    with np.errstate(over="ignore", invalid="ignore"):
        e = np.exp(-2.0 * beta / tau)  # a tiny tau: -inf, e = 0, the limit
        x = theta_n / omega
        so = (1.0 + x * e) / (1.0 + x)
    # theta_N / Omega overflows for a tiny Omega: SO is then its limit exp(-2 beta / tau)
    return np.where(np.isinf(x), e, so)


@dataclass(frozen=True)
class MaxwellBeardBRDF(Model):
    """Maxwell-Beard BRDF: shadowed specular facet term + Lambertian + volumetric.

    Parameters
    ----------
    slopes : SlopeDistribution
        Facet slope distribution of the specular term.
    substrate : complex
        Index of the material (Fresnel reflectance of the facets).
    rho_d : float
        Lambertian BRDF (1/sr).
    rho_v : float
        Volumetric BRDF coefficient (1/sr); the term is ``2 rho_v / (cos ti + cos tr)``.
    tau, omega : float
        Shadowing/obscuration parameters (radians).
    polarized : bool
        False: the published scalar form; True: facet Mueller matrix on the specular term.
    """

    slopes: SlopeDistribution = param(GaussianSlopes(0.1), "facet slope distribution", SLOPES)
    substrate: complex = param(1.5 + 0j, "material index n + ik", ScalarOrArray(ComplexIndex()))
    # the amplitudes are BRDFs (1/sr): swept at 0 and 1/pi, a white Lambertian
    # bounded by FACTOR_MAX: an amplitude scales the model, and an unbounded one overflows it
    rho_d: float = param(
        0.0, "Lambertian BRDF (1/sr)", ScalarOrArray(Interval(0.0, FACTOR_MAX)), edges=(0.0, 1.0 / math.pi)
    )
    rho_v: float = param(
        0.0,
        "volumetric BRDF coefficient (1/sr)",
        ScalarOrArray(Interval(0.0, FACTOR_MAX)),
        edges=(0.0, 1.0 / math.pi),
    )
    tau: float = param(
        0.25, "shadowing parameter tau (rad)", ScalarOrArray(Interval(0.0, closed="right")), edges=(1e-4, 2.0)
    )
    omega: float = param(
        0.7,
        "obscuration parameter Omega (rad)",
        ScalarOrArray(Interval(0.0, closed="right")),
        edges=(1e-4, 2.0),
    )
    polarized: bool = param(False, "facet Mueller matrix on the specular term", Options(True, False))

    depolarizing = True
    correspondence = Correspondence(
        "Maxwell-Beard, compared with the combination in seed 003 Sec. 3",
        "``Shadowed_Facet_BRDF_Model`` for its specular term",
    )

    @property
    def scatmech(self):
        """SCATMECH's ``Shadowed_Facet_BRDF_Model`` with its ``Maxwell_Beard_Shadow_Function``,
        or ``None``: it is the specular term alone (``rho_d = rho_v = 0``), polarized (the
        facet Mueller matrix), of an exponential or Gaussian family."""
        sdf, sub = self.slopes.scatmech_parameters(), scatmech_index(self.substrate)
        scalars = all(isinstance(v, float) for v in (self.rho_d, self.rho_v, self.tau, self.omega))
        if sdf is None or sub is None or not scalars or not self.polarized or self.rho_d or self.rho_v:
            return None
        shadow = {
            "shadow": "Maxwell_Beard_Shadow_Function",
            "shadow.tau": self.tau,
            "shadow.Omega": self.omega,
        }
        return "Shadowed_Facet_BRDF_Model", {"substrate": sub, **sdf, **shadow}

    @cached_property
    def _facet(self):
        return FacetBRDF(slopes=self.slopes, substrate=self.substrate)

    def _kernel_spec(self):
        slopes = kernel_specs.slope_rows(self.slopes)
        if slopes is None:
            return None
        rows = [
            1.0,
            *kernel_specs.index_rows(self.substrate),
            *slopes[1],
            self.rho_d,
            self.rho_v,
            self.tau,
            self.omega,
        ]
        return "maxwell", rows, (slopes[0], 0, int(self.polarized))

    def _mueller16(self, ti, tr, pr):
        so = maxwell_beard_shadow(ti, tr, pr, self.tau, self.omega)
        if self.polarized:
            out = self._facet.flat_mueller16(ti, tr, pr) * so
        else:
            out = np.zeros((16, ti.size))
            out[0] = self._facet.flat_brdf(ti, tr, pr) * so
        ci, cr = np.cos(ti), np.cos(tr)
        den = ci + cr
        vol = 2.0 * self.rho_v / np.where(den > 0, den, 1.0)
        grazing = (ti >= 0.5 * math.pi) | (tr >= 0.5 * math.pi)
        out[0] += np.where(grazing, 0.0, self.rho_d + vol)
        return out

    def rotated(self, angle):
        return self._rotated_slopes(angle)

    @property
    def mirror_symmetric(self):  # type: ignore[override]
        return self.slopes.isotropic

    def lobe(self, theta_i):
        return self._facet.lobe(theta_i)
