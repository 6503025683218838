"""Facet (ray-optics) reflection from a rough interface: the shared kernel and
:class:`FacetBRDF`, the exposed rough surface.

The kernel is seed 000 Eq. 2-20 and 47-50 with the coating index ``n`` (``n =
1`` is the exposed surface).  A ray refracts into the coating (Eq. 2-4), reflects
specularly from the facet whose normal bisects the internal directions
(Eq. 5-7), and refracts out.  The BRDF (Eq. 49) is

    M = P3^xy(zeta) / (4 cos ti cos tr cos^4 theta_n) * Mueller(q)

with ``q`` the Jones matrix of Eq. 16-18 (transmission coefficients
``t(theta; 1, n)`` of both passes, Eq. 14-15).

The facet reflection is written without Eq. 18's division by ``a1 =
sin^2(2 alpha)``.  With ``h = k_r' - k_i'`` (``|h|^2 = 4 cos^2 alpha``, Eq. 5),
facet normal ``h/|h|``, the reflection dyadic acting on fields transverse to
``k_i'`` is

    R = r_s (I - 2 nn) + K (n - c k_r)(n + c k_i),   K = (r_s + r_p) / sin^2 alpha,

so ``q_ab = r_s (e_a . e_b) + (K - 2 r_s)(e_a . h)(e_b . h) / |h|^2`` for basis
vectors ``e_a`` of the outgoing and ``e_b`` of the incident ray.  The dot
products reduce to Eq. 19's ``a2 = p_r'.h`` and ``a3 = p_i'.h`` and to
``s_r'.h = sin ti' sin phi``, ``s_i'.h = sin tr' sin phi``.  ``K`` is smooth at
``alpha = 0`` (:func:`models.fresnel.reflection_rs_k`), so exact
retroreflection is finite with no special case, where Eq. 18 is 0/0.  Because
``q = r_s U + K V`` with real ``U``, ``V`` (a non-absorbing coating has real
transmission coefficients), the Mueller matrix needs only the four real numbers
``|r_s|^2, |K|^2, Re(r_s K*), Im(r_s K*)``: the whole evaluation is real
arithmetic on cache-sized chunks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .base import Model
from .fresnel import coating_transmission, reflection_rs_k
from .params import param
from .polarization import mueller_from_products
from .slopes import ExponentialSlopes, SlopeDistribution

__all__ = ["FacetBRDF", "facet_reflection"]


def _geometry(ti, tr, pr, n):
    """Internal directions, facet vector ``h`` and the q-matrix factors."""
    sti, cti = np.sin(ti), np.cos(ti)
    st_r, ct_r = np.sin(tr), np.cos(tr)
    cp, sp = np.cos(pr), np.sin(pr)
    if n == 1.0:
        si, ci, sr, cr = sti, cti, st_r, ct_r
    else:
        si = sti / n  # Eq. 2
        sr = st_r / n  # Eq. 3
        ci = np.sqrt(1.0 - si * si)
        cr = np.sqrt(1.0 - sr * sr)
    hx = sr * cp - si
    hy = sr * sp
    hz = cr + ci
    g = hx * hx + hy * hy + hz * hz  # |h|^2 = 4 cos^2(alpha), Eq. 5
    return sti, cti, st_r, ct_r, cp, sp, si, ci, sr, cr, hx, hy, hz, g


def facet_reflection(ti, tr, pr, n, substrate, slopes):
    """Real decomposition ``q = r_s U + K V`` and the Eq. 49 prefactor.

    Returns ``(S, rs, K, U, V)`` for flat arrays; ``U`` and ``V`` are dicts over
    ``ss, ps, sp, pp`` (``ps`` = p in, s out).  ``S`` is zero where no facet
    connects the two directions or a ray is grazing (``cos = 0``).
    """
    (sti, cti, st_r, ct_r, cp, sp, si, ci, sr, cr, hx, hy, hz, g) = _geometry(ti, tr, pr, n)
    ok = (cti > 0) & (ct_r > 0)
    hz_safe = np.where(ok, hz, 1.0)
    g_safe = np.where(ok, g, 1.0)
    zx = hx / hz_safe
    zy = hy / hz_safe
    p3 = slopes.p3(zx, zy)
    # Eq. 49: P3 / (4 cos ti cos tr cos^4 theta_n), cos theta_n = hz / |h|.
    denom = np.where(ok, 4.0 * cti * ct_r * hz_safe**4, 1.0)
    S = np.where(ok, p3 * g_safe * g_safe / denom, 0.0)
    c = 0.5 * np.sqrt(g_safe)  # cos(alpha), local incidence in the coating
    m = substrate if substrate == math.inf else complex(substrate) / n
    rs, K = reflection_rs_k(np.minimum(c, 1.0), m)
    a2 = cr * cp * si + sr * ci  # p_r'.h  (Eq. 19b)
    a3 = ci * sr * cp + si * cr  # p_i'.h  (Eq. 19c)
    e_r = si * sp  # s_r'.h
    e_i = sr * sp  # s_i'.h
    inv_g = 1.0 / g_safe
    V = {"ss": e_r * e_i * inv_g, "ps": e_r * a3 * inv_g, "sp": a2 * e_i * inv_g, "pp": a2 * a3 * inv_g}
    D = {"ss": cp, "ps": -sp * ci, "sp": -cr * sp, "pp": sr * si - cr * cp * ci}
    if n != 1.0:
        # Eq. 16-18: t(theta_r; 1, n) for the outgoing index, t(theta_i; 1, n) incoming.
        tsi, tpi = coating_transmission(cti, n)
        tsr, tpr = coating_transmission(ct_r, n)
        tt = {"ss": tsr * tsi, "ps": tsr * tpi, "sp": tpr * tsi, "pp": tpr * tpi}
    else:
        tt = None
    U = {}
    for k in ("ss", "ps", "sp", "pp"):
        u = D[k] - 2.0 * V[k]
        v = V[k]
        if tt is not None:
            u = u * tt[k]
            v = v * tt[k]
        U[k] = u
        V[k] = v
    return S, rs, K, U, V


def facet_mueller16(S, rs, K, U, V):
    """Mueller elements ``(16, n)`` of ``S * Mueller(r_s U + K V)`` in real arithmetic."""
    A = S * (rs.real**2 + rs.imag**2)
    B = S * (K.real**2 + K.imag**2)
    x = rs * np.conj(K)
    a = S * x.real
    b = S * x.imag

    def norm(k):
        u, v = U[k], V[k]
        return A * u * u + B * v * v + 2.0 * a * u * v

    def prod(k1, k2):
        u1, v1, u2, v2 = U[k1], V[k1], U[k2], V[k2]
        cross = u1 * v2
        cross2 = v1 * u2
        return A * u1 * u2 + B * v1 * v2 + a * (cross + cross2), b * (cross - cross2)

    return mueller_from_products(
        norm("ss"),
        norm("pp"),
        norm("ps"),
        norm("sp"),
        prod("ss", "ps"),
        prod("pp", "sp"),
        prod("ss", "sp"),
        prod("pp", "ps"),
        prod("pp", "ss"),
        prod("ps", "sp"),
    )


def facet_jones(S, rs, K, U, V):
    root = np.sqrt(S)
    J = np.empty(S.shape + (2, 2), dtype=complex)
    J[:, 0, 0] = root * (rs * U["ss"] + K * V["ss"])
    J[:, 0, 1] = root * (rs * U["ps"] + K * V["ps"])
    J[:, 1, 0] = root * (rs * U["sp"] + K * V["sp"])
    J[:, 1, 1] = root * (rs * U["pp"] + K * V["pp"])
    return J


class _FacetModel(Model):
    """Shared evaluation of the exposed and the coated facet models."""

    def _coating(self) -> float:
        return 1.0

    def _parts(self, ti, tr, pr):
        return facet_reflection(ti, tr, pr, self._coating(), self.substrate, self.slopes)

    def _mueller16(self, ti, tr, pr):
        return facet_mueller16(*self._parts(ti, tr, pr))

    def _jones_flat(self, ti, tr, pr):
        return facet_jones(*self._parts(ti, tr, pr))

    def _brdf_flat(self, ti, tr, pr):
        S, rs, K, U, V = self._parts(ti, tr, pr)
        A = rs.real**2 + rs.imag**2
        B = K.real**2 + K.imag**2
        a = (rs * np.conj(K)).real
        tot = 0.0
        for k in ("ss", "ps", "sp", "pp"):
            u, v = U[k], V[k]
            tot = tot + A * u * u + B * v * v + 2.0 * a * u * v
        return 0.5 * S * tot

    def _validate(self):
        if not isinstance(self.slopes, SlopeDistribution):
            raise ValueError(
                f"slopes must be a slope distribution (e.g. models.ExponentialSlopes); "
                f"got {self.slopes!r}"
            )

    def rotated(self, angle):
        return self.replace(slopes=self.slopes.rotated(angle))

    def lobe(self, theta_i):
        """Specular lobe: centre (theta_i, 0); width in theta_r of ~ 2 n sigma cos(ti')/cos(ti)."""
        n = self._coating()
        si = math.sin(theta_i) / n
        ci = math.sqrt(1 - si * si)
        width = 2.0 * n * self.slopes.scale * ci / max(math.cos(theta_i), 1e-6)
        return (theta_i, 0.0, width)


@dataclass(frozen=True)
class FacetBRDF(_FacetModel):
    """Facet reflection from an exposed rough interface (seed 000 Eq. 48-49 with n = 1).

    Ray-optics (Kirchhoff tangent-plane, stationary-phase) limit with no
    shadowing and no multiple scattering; the Jones matrix is the facet's
    Fresnel reflection in the s/p bases of the two rays.  SCATMECH:
    ``Facet_BRDF_Model`` (``type = 0``).

    Parameters
    ----------
    slopes : SlopeDistribution
        Facet slope distribution ``P3^xy`` (e.g. :class:`ExponentialSlopes`).
    substrate : complex or math.inf
        Index ``n + ik`` of the material below the facets (``k >= 0``), or
        ``math.inf`` for a perfect conductor.
    """

    slopes: SlopeDistribution = param(ExponentialSlopes(0.1), "facet slope distribution", kind="object")
    substrate: complex = param(1.37 + 7.62j, "substrate index n + ik (inf: perfect conductor)", kind="index")
