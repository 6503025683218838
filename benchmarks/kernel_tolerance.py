"""The compiled float64 kernels against the numpy reference, measured beside the tolerance
derived from each model's conditioning (:mod:`scatterbench.models.kernel_tolerance`).

    python benchmarks/kernel_tolerance.py

Per model: the worst geometry's ``max |M_kernel - M_numpy| / |M00_numpy|`` over 400 random
geometries, the extremes and 2000 near-specular ones, in EPS (2.2e-16), the derived bound and
their ratio.
The command exits 1 when a measured difference exceeds its bound.
"""

from __future__ import annotations

import math
import sys

import numpy as np

from scatterbench import models
from scatterbench.models.evaluation import backend
from scatterbench.models.kernel_tolerance import EPS, kernel_tolerance
from scatterbench.validation.checks.conformance_checks import _relative
from scatterbench.validation.numerics.probes import extreme_geometries, random_geometries


def geometries(n=2000, seed=5):
    """Random, extreme and near-specular geometries (the last within 1e-9..1e-1 rad)."""
    rng = np.random.default_rng(seed)
    t0 = rng.uniform(0.0, 1.4, n)
    d = 10 ** rng.uniform(-9, -1, n) * rng.choice([-1.0, 1.0], n)
    near = (t0, np.clip(t0 + d, 0.0, math.pi / 2), rng.choice([0.0, math.pi], n) + d * rng.uniform(-1, 1, n))
    parts = (random_geometries(400, seed=12, max_deg=90.0), extreme_geometries(), near)
    return tuple(np.concatenate(p) for p in zip(*parts, strict=True))


def cases():
    S = models
    out = [S.FacetBRDF(slopes=S.GaussianSlopes(w), substrate=1.5) for w in (0.3, 1e-2, 1e-4, 1e-6, 1e-8)]
    out += [S.FacetBRDF(slopes=S.ExponentialSlopes(w), substrate=1.5) for w in (0.3, 1e-4, 1e-6)]
    out += [S.FacetBRDF(slopes=S.GGXSlopes(w), substrate=1.5) for w in (0.3, 1e-4, 1e-6)]
    out += [S.CookTorranceBRDF(slopes=S.GaussianSlopes(w), substrate=math.inf) for w in (0.3, 0.03, 1e-3)]
    out += [
        S.SingleScatterBRDF(coating=1.5, phase=S.HenyeyGreenstein(g, True)) for g in (0.9, -0.99, -0.9999)
    ]
    out += [
        S.MaxwellBeardBRDF(rho_d=0.02, rho_v=0.01, tau=t, omega=o) for t, o in ((0.01, 2.0), (1e-4, 1e-4))
    ]
    out += [S.DiffuseSubsurfaceBRDF(coating=1.5, rho=0.93), S.FacetBTDF(substrate=1.5)]
    return out


def main():
    ti, tr, pr = geometries()
    bad = 0
    print(f"{'model':<72} {'measured':>12} {'bound':>12} {'ratio':>6}")
    for m in cases():
        mk = m.mueller(ti, tr, pr)
        with backend("numpy"):
            mn = m.mueller(ti, tr, pr)
        err = float(np.max(_relative(mk, mn)))
        bound = kernel_tolerance(m)
        bad += err > bound
        print(f"{repr(m)[:72]:<72} {err / EPS:10.0f} E {bound / EPS:10.0f} E {err / bound:6.2f}")
    print(f"{bad} measured differences above their bound")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
