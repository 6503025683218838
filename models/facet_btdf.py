"""Facet transmission into a rough dielectric: the BTDF of seed 003 Sec. 2.4 (Eq. 29-43).

A ray along ``k_i`` refracts through the facet whose normal satisfies Snell's
law (Eq. 30) into ``k_t``; the normal is ``m = (k_i - n k_t) / D`` (Eq. 31-32,
sign chosen so ``m_z > 0``).  The geometry is reachable only when both local
angles lie in [0, pi/2) (Eq. 33-35): ``cos(iota_i) = (n cos(gamma) - 1)/D > 0``
and ``m_z > 0``, with ``cos(gamma) = k_i . k_t``; otherwise the BTDF is an exact
zero.  The Mueller BTDF is

    f = P3(zeta) n cos(iota_t) / (cos ti cos tt m_z^4) * dOmega_n/dOmega_t * M(J),
    dOmega_n/dOmega_t = n^2 cos(iota_t) / D^2.

Slips of the printed equations, established against SCATMECH (agreement to
1e-12, tests) and by derivation:

* Eq. 43 prints ``n cos t_i``; combining Eq. 37, 38 and 42 as the text says
  gives ``n cos t_t`` (the local transmitted angle, Eq. 34), as SCATMECH has.
* Eq. 39 prints ``theta_t`` in several places where ``theta_i`` belongs
  (SCATMECH's ``Facet_BRDF_Model::jacobian`` has ``cos(ti)(3 + cos 2tt)``,
  ``sin(2 ti) sin(tt)``, ...).  It equals the compact form above (checked
  numerically in the tests), which follows from the half-vector Jacobian of
  refraction.
* Eq. 41's ``a1`` prints ``cos(theta_n)`` where ``sin(theta_n)`` belongs and
  ``theta_t`` for ``theta_i``.  The Jones matrix here is evaluated from the
  dyadic Eq. 40 instead: ``(s_t s' + p_t' p_i')`` is the rotation ``R`` about
  ``s'`` that takes ``k_i`` to ``k_t``, so

      t = t_s R + (t_p - t_s) p_t' p_i'
        = t_s R + [(t_p - t_s) / sin^2(iota)] (k_t x u)(k_i x u),  u = k_i x m,

  with ``R`` from Rodrigues' formula (smooth at ``k_t = k_i``) and
  ``(t_p - t_s)/sin^2 = 2c(m-1)(m^2-1)/((c+w)(m^2 c+w)(w+mc))`` smooth at
  normal local incidence, so no special case is needed where SCATMECH
  switches formula (``iota < 1e-7``).

:func:`facet_transmission_jones` works for any pair of real indices (also from
inside the medium out, which the Monte Carlo model uses).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from . import kernel_specs
from .base import Model
from .constraints import INDEX_MAX, Instance, Interval, Options, ScalarOrArray
from .facts import Correspondence, scatmech_index
from .geometry import sp_basis
from .params import choice_alias, convention_param, param
from .polarization import mueller16_from_jones
from .shadowing import SHADOWING, check_shadowing, smith_g
from .slopes import AnisotropicGGXSlopes, GaussianSlopes, GGXSlopes, SlopeDistribution

__all__ = ["FacetBTDF", "facet_transmission_jones", "ray_basis", "angle_basis", "projected_area"]


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a, b):
    return np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def ray_basis(k):
    """``(s, p)`` of rays ``k`` given as ``(3, ...)`` arrays: :func:`scatterbench.models.geometry.sp_basis`
    (``s = unit(z x k)``, ``p = k x s``, ``s = +y`` along the z axis) in this layout."""
    s, p = sp_basis(np.moveaxis(k, 0, -1))
    return np.moveaxis(s, -1, 0), np.moveaxis(p, -1, 0)


def angle_basis(k, sx, sy):
    """``(s, p)`` with ``s = (sx, sy, 0)`` given from the ray's azimuth and ``p = k x s``."""
    s = np.stack([sx, sy, np.zeros_like(sx)])
    return s, _cross(k, s)


def facet_transmission_jones(k_in, k_out, m, n1, n2, e_in, e_out):
    """Real Jones elements ``(ss, ps, sp, pp)`` of refraction through facets.

    ``k_in``, ``k_out``, ``m``: ``(3, ...)`` unit vectors; ``m`` is the facet
    normal on the incident side (``k_in . m < 0``); ``n1``, ``n2`` real indices
    of the incident and transmitted media (scalars).  ``e_in = (s, p)`` and
    ``e_out = (s, p)`` are the bases of the two rays.  Also returns
    ``cos(iota_in)`` and ``cos(iota_out)`` (clipped at 0).  Beyond the critical
    angle the elements are zero.
    """
    mr = n2 / n1
    c = np.clip(-_dot(k_in, m), 0.0, 1.0)
    arg = mr * mr - 1.0 + c * c
    ok = arg > 0.0
    w = np.sqrt(np.where(ok, arg, 0.0))  # mr cos(iota_out)
    den_s = c + w
    den_p = mr * mr * c + w
    safe = den_s > 0.0
    inv_s = np.where(safe, 1.0 / np.where(safe, den_s, 1.0), 0.0)
    inv_p = np.where(safe, 1.0 / np.where(safe, den_p, 1.0), 0.0)
    ts = 2.0 * c * inv_s * ok
    delta = 2.0 * c * (mr - 1.0) * (mr * mr - 1.0) * inv_s * inv_p * ok
    delta = delta * np.where(safe, 1.0 / np.where(safe, w + mr * c, 1.0), 0.0)
    u = _cross(k_in, m)
    a_out = _cross(k_out, u)
    a_in = _cross(k_in, u)
    v = _cross(k_in, k_out)
    cg = _dot(k_in, k_out)
    # cg > -1 for any transmission (|gamma| < pi/2); unreachable geometries (masked
    # out by the caller) can reach cg = -1, where the rotation term is not needed.
    one_cg = 1.0 + cg
    alive = one_cg > 1e-300
    inv1 = np.where(alive, 1.0 / np.where(alive, one_cg, 1.0), 0.0)
    out = []
    for ea in e_out:
        eav = _dot(ea, v)
        eaa = _dot(ea, a_out)
        for eb in e_in:
            rot = cg * _dot(ea, eb) + _dot(ea, _cross(v, eb)) + eav * _dot(v, eb) * inv1
            out.append(ts * rot + delta * eaa * _dot(a_in, eb))
    ss, ps, sp, pp = out[0], out[1], out[2], out[3]
    # out order above: (s_out,s_in), (s_out,p_in), (p_out,s_in), (p_out,p_in)
    c_out = np.clip(-_dot(k_out, m), 0.0, 1.0)
    return (ss, ps, sp, pp), c, c_out


def projected_area(slopes, cos_theta, quantiles=2048):
    """``N = <(cos theta - k_xy . zeta)_+>`` over ``P3^xy / C`` for rays at ``cos_theta``.

    Isotropic slopes: the azimuthal average of ``(a - b cos phi)_+`` is
    ``a`` for ``b <= a`` and ``(a (pi - phi0) + b sin phi0) / pi``,
    ``phi0 = arccos(a / b)``, otherwise (``a = cos theta``, ``b = sin theta
    |zeta|``); the radial average uses midpoint quantiles of the slope
    magnitude.  Vectorized over ``cos_theta``, computed once per distinct value (it
    depends on the incidence alone, which a scan repeats).
    """
    if not slopes.isotropic:
        raise ValueError(
            f"slopes must be isotropic for the exact projected-area normalization; got {slopes!r}"
        )
    c_all = np.asarray(cos_theta, dtype=float)
    c, inverse = np.unique(c_all, return_inverse=True)
    u = (np.arange(quantiles) + 0.5) / quantiles
    z = slopes._sample_radius_unit(u)
    a = c[..., None]
    b = np.sqrt(np.maximum(1.0 - c * c, 0.0))[..., None] * z
    big = b > a
    ratio = np.where(big, a / np.where(big, b, 1.0), 1.0)
    phi0 = np.arccos(np.clip(ratio, -1.0, 1.0))
    val = np.where(big, (a * (math.pi - phi0) + b * np.sqrt(1.0 - ratio * ratio)) / math.pi, a)
    return val.mean(axis=-1)[inverse].reshape(c_all.shape)


@dataclass(frozen=True)
class FacetBTDF(Model):
    """Facet-model transmission (BTDF, 1/sr) into a rough dielectric (seed 003 Eq. 43).

    Angles: ``mueller(theta_i, theta_t, phi_t)``; the transmitted ray travels
    along ``(sin tt cos pt, sin tt sin pt, -cos tt)``, ``pt = 0`` forward.  No
    shadowing, single interaction.  SCATMECH: ``Facet_BRDF_Model``
    (``type = 1``).

    Parameters
    ----------
    slopes : SlopeDistribution
        Facet slope distribution ``P3^xy``.
    substrate : float
        Real index ``n > 1`` of the substrate.
    convention : "paper" | "corrected"
        ``"paper"``: Eq. 37 as printed, the slope distribution seen by the incident ray
        normalized by ``cos(theta_i)`` (assumes ``<cos i_t> ~ cos theta_i``; SCATMECH's
        choice).  Its integrated transmittance exceeds 1 for wide distributions at
        oblique incidence (``validate`` reports it).  ``"corrected"``: Eq. 36
        normalized exactly, by ``N = <(cos theta_i - k_xy . zeta)_+>``
        (:func:`projected_area`): every incident ray meets one facet, and reflection
        plus transmission integrate to 1.  Either way the printed slips listed in the
        module docstring (Eq. 39, 41, 43) are corrected.  Old name ``normalization``
        (``"paper"``, ``"exact"``).
    shadowing : str
        ``"none"`` (seed 003), ``"smith"`` or ``"smith-correlated"``
        (:mod:`scatterbench.models.shadowing`): the incident direction's shadowing and the
        masking of the transmitted direction from below, ``chi+`` on each (Walter
        et al. 2007 Eq. 21-23); height-correlated, ``B(1 + Lambda_i, 1 + Lambda_t)``
        (:func:`scatterbench.models.shadowing.correlated_g`: a facet lit from above must be
        seen from below), not the reflection form ``1 / (1 + Lambda_i + Lambda_t)``.  Smith's ``G1`` satisfies ``int G1(i) (i.m)+ D dm =
        cos theta_i``, the projected-area identity that ``"paper"`` assumes, so it
        goes with ``convention="paper"`` only (``"corrected"`` corrects the same
        projected area without shadowing).
    """

    slopes: SlopeDistribution = param(
        GaussianSlopes(0.1),
        "facet slope distribution",
        Instance(SlopeDistribution, text="a slope distribution (e.g. models.GaussianSlopes)"),
    )
    # declared (1, INDEX_MAX]: the rule below (n = 1 is a delta) stated where the range is
    substrate: float = param(
        1.5, "substrate index (real, > 1)", ScalarOrArray(Interval(1.0, INDEX_MAX, closed="right"))
    )
    convention: str = convention_param(
        "normalization of the slopes seen by the ray: Eq. 37 (paper, SCATMECH) or exact Eq. 36 (corrected)"
    )
    shadowing: str = param("none", "shadowing-masking", Options(*SHADOWING))

    correspondence = Correspondence("seed 003 Eq. 29-43 (Fig. 1)", "``Facet_BRDF_Model`` (type 1)")
    #: the kit's instance: the slopes of committed SCATMECH reference values
    #: (references/data/scatmech_seed003_btdf.csv), so that its ``scatmech`` check compares with them
    kit_variant = MappingProxyType({"slopes": GaussianSlopes(0.05)})

    aliases = {
        "normalization": choice_alias("convention", "normalization", {"paper": "paper", "exact": "corrected"})
    }
    transmission = True
    _angle_names = ("theta_i", "theta_t", "phi_t")

    @property
    def scatmech(self):
        """SCATMECH's ``Facet_BRDF_Model`` (type 1, transmission) with these parameters, or
        ``None``: it normalizes as Eq. 37 (``convention="paper"``), has no shadowing and the
        exponential and Gaussian families only."""
        sdf, sub = self.slopes.scatmech_parameters(), scatmech_index(self.substrate)
        if sdf is None or sub is None or self.shadowing != "none" or self.convention != "paper":
            return None
        return "Facet_BRDF_Model", {"type": 1, "substrate": sub, **sdf}

    @classmethod
    def sweep_extras(cls):
        """Instances the defaults' edges do not reach: GGX and anisotropic GGX slopes with
        shadowing none and smith, the slopes swept to their edges (its substrate is a real
        index: no film stacks)."""
        ggx = (GGXSlopes(0.1), AnisotropicGGXSlopes(alpha_x=0.05, alpha_y=0.2, rotation=0.3))
        return tuple((cls(slopes=g, shadowing=sh), ("slopes",)) for g in ggx for sh in ("none", "smith"))

    def _validate(self):
        if self.substrate == 1.0:
            raise ValueError(
                "substrate must be a real index > 1 (at n = 1 the interface vanishes and the BTDF is a delta)"
            )
        if self.convention == "corrected" and not self.slopes.isotropic:
            raise ValueError(
                "convention 'corrected' needs isotropic slopes (its exact projected area is the isotropic "
                f"average); got {self.slopes!r}; use convention='paper'"
            )
        check_shadowing(self.shadowing, self.slopes)
        if self.shadowing != "none" and self.convention != "paper":
            raise ValueError(
                f"convention must be 'paper' with shadowing {self.shadowing!r} (Smith's G1 already "
                "normalizes the projected area); got 'corrected'"
            )

    def _parts(self, ti, tt, pt):
        n = self.substrate
        zero = np.zeros_like(ti)
        si, ci = np.sin(ti), np.cos(ti)
        st, ct = np.sin(tt), np.cos(tt)
        cp, sp = np.cos(pt), np.sin(pt)
        k_in = np.stack([si, zero, -ci])
        k_out = np.stack([st * cp, st * sp, -ct])
        h = k_in - n * k_out  # Eq. 31 times D
        D2 = _dot(h, h)
        D = np.sqrt(D2)
        mz = h[2] / D
        cg = _dot(k_in, k_out)
        # Eq. 33-35: reachable iff m_z > 0 and cos(iota_i) = (n cos gamma - 1)/D > 0
        live = (mz > 0.0) & (n * cg - 1.0 > 0.0) & (ti < 0.5 * math.pi) & (tt < 0.5 * math.pi)
        hz = np.where(live, h[2], 1.0)
        m = h / D
        m = np.where(live, m, np.array([0.0, 0.0, 1.0])[:, None])
        # Bases from the angles (the theta -> 0 limit along the ray's azimuth at the
        # pole, as SCATMECH and the other models do): s = (-sin phi, cos phi, 0).
        e_in = angle_basis(k_in, zero, zero + 1.0)
        e_out = angle_basis(k_out, -sp, cp)
        jones, c_in, c_out = facet_transmission_jones(k_in, k_out, m, 1.0, n, e_in, e_out)
        p3 = self.slopes.p3(h[0] / hz, h[1] / hz)
        mz_l = np.where(live, mz, 1.0)
        inv_cc = 1.0 / np.where(live, ci * ct, 1.0)
        # Eq. 43 (with cos t_t) and the Jacobian n^2 cos(iota_t)/D^2 (Eq. 39)
        S = p3 * n * c_out * inv_cc / mz_l**4 * (n * n * c_out / np.where(live, D2, 1.0))
        if self.convention == "corrected":
            S = S * (ci / np.maximum(projected_area(self.slopes, ci), 1e-300))
        if self.shadowing != "none":
            # towards the source (azimuth pi) and along the transmitted ray (below: cos < 0)
            v_i = (ci, si, -1.0, 0.0)
            v_t = (-ct, st, cp, sp)
            S = S * smith_g(self.shadowing, self.slopes, v_i, v_t, c_in, -c_out)
        S = np.where(live, S, 0.0)
        root = np.sqrt(S)
        return tuple((j * root, 0.0) for j in jones)  # real Jones matrix

    def _mueller16(self, ti, tr, pr):
        return mueller16_from_jones(*self._parts(ti, tr, pr))

    def _kernel_spec(self):
        """The facet transmission kernel for ``convention="paper"``; numpy for the corrected
        convention (its projected area is a quantile average) and uncovered slopes."""
        slopes = kernel_specs.slope_rows(self.slopes)
        if slopes is None or self.convention != "paper":
            return None
        shadowing = kernel_specs.shadowing_kind(self.shadowing, slopes[0])
        # the height-correlated transmission form is a Beta function of two Lambdas
        # (shadowing.correlated_g): scipy's, numpy path; the kernel has no Beta function
        if shadowing is None or self.shadowing == "smith-correlated":
            return None
        return "btdf", [self.substrate, *slopes[1]], (slopes[0], shadowing, 0)

    def _jones_flat(self, ti, tr, pr):
        J = np.empty(ti.shape + (4,), dtype=complex)
        for k, (re, _) in enumerate(self._parts(ti, tr, pr)):
            J[:, k] = re
        return J.reshape(ti.shape + (2, 2))

    def rotated(self, angle):
        return self._rotated_slopes(angle)

    @property
    def mirror_symmetric(self) -> bool:
        return self.slopes.isotropic

    @property
    def reciprocal(self):  # type: ignore[override]
        """The BTDF itself is not symmetric in its two angles (the reversed path runs
        from the substrate outward, a different model); ``n^2 f`` is, see tests."""
        return False

    def lobe(self, theta_i):
        """Refracted lobe: centre at Snell's angle; width ~ (n - cos)/n * sigma / cos(tt)."""
        n = self.substrate
        st = math.sin(theta_i) / n
        ct = math.sqrt(1.0 - st * st)
        width = max(self.slopes.scale * (n * ct - math.cos(theta_i)) / (n * ct), 1e-6)
        return (math.asin(st), 0.0, width)
