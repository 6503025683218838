"""Fresh random cases against a live pySCATMECH (skipped where it is not installed, as in CI)."""

import math

import numpy as np
import pytest

import models

scm = pytest.importorskip("pySCATMECH.brdf")


def test_fresh_random_cases_agree():
    rng = np.random.default_rng()  # fresh cases every run
    worst = 0.0
    for _ in range(40):
        coat = float(rng.uniform(1.0, 2.2))
        sub = complex(rng.uniform(0.3, 4.0), rng.choice([0.0, rng.uniform(0.01, 8)]))
        sigma = float(np.exp(rng.uniform(math.log(0.05), 0.0)))
        dist = rng.choice(["Exponential", "Gaussian"])
        slopes = (models.ExponentialSlopes if dist == "Exponential" else models.GaussianSlopes)(sigma)
        ours = models.SubsurfaceFacetBRDF(slopes=slopes, coating=coat, substrate=sub)
        ref = scm.BRDF_Model(
            "Subsurface_Facet_BRDF_Model",
            substrate=f"({sub.real!r},{sub.imag!r})",
            overcoat=f"({coat!r},0)",
            sdf=f"{dist}_Slope_Distribution_Function",
            **{"sdf.s": sigma},
        )
        for _ in range(10):
            ti, tr = rng.uniform(0, math.radians(80), 2)
            pr = rng.uniform(-math.pi, math.pi)
            R = np.array(ref.MuellerBRDF(ti, tr, pr))
            M = ours.mueller(ti, tr, pr)
            worst = max(worst, float(np.max(np.abs(M - R)) / max(R[0, 0], 1e-300)))
    assert worst <= 1e-6
