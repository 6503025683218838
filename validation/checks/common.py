"""Helpers shared by the check modules of every seed (and by the tests that reuse them):
the extreme-geometry counter, the facet model suite and the slope
distributions' numerical normalization and conversion errors."""

from __future__ import annotations

import math

import numpy as np
from scipy import integrate

from scatterbench import models
from scatterbench.validation.numerics.probes import fp_warnings

__all__ = [
    "count_extremes",
    "facet_suite",
    "slope_normalization_errors",
    "slope_conversion_errors",
]


def count_extremes(models_, ti, tr, pr, jones=False):
    """``(bad, warned, M)`` over models at the given geometries: non-finite Mueller (and
    Jones) elements and negative M00 counted in ``bad``, floating-point warnings other than
    gradual underflow in ``warned`` (a far tail underflowing to zero is the correct IEEE
    result); ``M`` the models' Mueller matrices."""
    bad = warned = 0
    Ms = []
    for m in models_:
        with fp_warnings() as w:
            M = m.mueller(ti, tr, pr)
            J = m.jones(ti, tr, pr) if jones else None
        warned += len(w)
        bad += int(np.sum(~np.isfinite(M))) + int(np.sum(M[..., 0, 0] < 0))
        if J is not None:
            bad += int(np.sum(~np.isfinite(J)))
        Ms.append(M)
    return bad, warned, Ms


def facet_suite():
    """Seed 000 facet models spanning the slope families, coatings and substrates."""
    return [
        models.FacetBRDF(slopes=models.ExponentialSlopes(0.2), substrate=1.37 + 7.62j),
        models.FacetBRDF(slopes=models.GaussianSlopes(0.5), substrate=1.5),
        models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.3), coating=1.5, substrate=1.37 + 7.62j),
        models.SubsurfaceFacetBRDF(slopes=models.GaussianSlopes(1.0), coating=2.2, substrate=1.5),
        models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.1), coating=1.5, substrate=math.inf),
        models.SubsurfaceFacetBRDF(
            slopes=models.AnisotropicExponentialSlopes(0.1, 0.5, 0.7), coating=1.5, substrate=3.88 + 0.02j
        ),
        models.SubsurfaceFacetBRDF(
            slopes=models.GaussianAngles(0.2, 0.7), coating=1.6, substrate=1.37 + 7.62j
        ),
    ]


def _polar_sums(dist, tb):
    """Numerical P1^A over the hemisphere and P3^xy over the slope plane, in polar
    coordinates, split at the angles ``tb`` where the densities change scale."""
    rr, wr = np.polynomial.legendre.leggauss(200)
    pp = np.linspace(0, 2 * math.pi, 256, endpoint=False)
    t_edges = np.concatenate([[0.0], tb, [math.pi / 2]])
    tot3 = tot1 = 0.0
    for a, b in zip(t_edges[:-1], t_edges[1:], strict=True):
        t = 0.5 * (b - a) * rr + 0.5 * (a + b)
        w = 0.5 * (b - a) * wr
        T, P = np.meshgrid(t, pp, indexing="ij")
        # P1^A dOmega
        tot1 += np.sum(dist.p1(T, P, "A") * np.sin(T) * w[:, None]) * (2 * math.pi / len(pp))
        # P3^xy d^2 zeta with zeta = tan(t): d zeta = sec^2 dt
        Z = np.tan(T)
        tot3 += np.sum(dist.p3(Z * np.cos(P), Z * np.sin(P)) * Z / np.cos(T) ** 2 * w[:, None]) * (
            2 * math.pi / len(pp)
        )
    return tot1, tot3


def slope_normalization_errors(dist):
    """Numerical Eq. 31-34 (xy, = C) and Eq. 37-40 (A, = 1) integrals minus their targets."""
    C = dist.coverage
    out = {}
    opts = dict(limit=400, epsabs=1e-13, epsrel=1e-11)
    sc = dist.scale
    brk = [sc * k for k in (0.5, 2, 8, 30)]
    out["P4_xy"] = integrate.quad(lambda z: float(dist.p4(np.array(z))), 0, np.inf, **opts)[0] - C
    out["P4_A"] = integrate.quad(lambda z: float(dist.p4(np.array(z), "A")), 0, np.inf, **opts)[0] - 1
    tb = [math.atan(b) for b in brk]
    out["P2_xy"] = (
        integrate.quad(lambda t: float(dist.p2(np.array(t))), 0, math.pi / 2, points=tb, **opts)[0] - C
    )
    out["P2_A"] = (
        integrate.quad(lambda t: float(dist.p2(np.array(t), "A")), 0, math.pi / 2, points=tb, **opts)[0] - 1
    )
    tot1, tot3 = _polar_sums(dist, tb)
    out["P1_A"] = tot1 - 1
    out["P3_xy"] = tot3 - C
    return out


def slope_conversion_errors(dist):
    """Eq. 29, 30, 35/41 evaluated both ways at random normals (relative errors)."""
    rng = np.random.default_rng(1)
    t = rng.uniform(0, 1.2, 200)
    p = rng.uniform(-math.pi, math.pi, 200)
    z = np.tan(t)
    p3 = dist.p3(z * np.cos(p), z * np.sin(p))
    p1 = dist.p1(t, p)
    e29 = np.abs(p3 - np.cos(t) ** 3 * p1) / np.maximum(p3, 1e-300)
    p1a = dist.p1(t, p, "A")
    e41 = np.abs(p1a - p3 / np.cos(t) ** 4 / (dist.coverage * dist.mean_sec())) / np.maximum(p1a, 1e-300)
    e35 = np.abs(p1a - p1 / np.cos(t) / (dist.coverage * dist.mean_sec())) / np.maximum(p1a, 1e-300)
    e30 = 0.0
    if dist.isotropic:
        e30 = np.abs(dist.p4(z) - np.cos(t) ** 2 * dist.p2(t)) / np.maximum(dist.p4(z), 1e-300)
    return {
        "Eq29": float(e29.max()),
        "Eq30": float(np.max(e30)),
        "Eq35": float(e35.max()),
        "Eq41": float(e41.max()),
    }
