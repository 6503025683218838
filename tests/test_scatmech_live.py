"""Fresh random cases against a live pySCATMECH (skipped where it is not installed, as in CI)."""

import math

import numpy as np
import pytest

from scatterbench import models

scm = pytest.importorskip("pySCATMECH.brdf")


@pytest.mark.parametrize("seed", range(5))
def test_random_cases_agree(seed):
    """400 random cases per seed, seeded so that a failure can be reproduced.  The error is
    relative to SCATMECH's M00, floored at 1e-250 as the committed-reference checks do: far
    in a Gaussian tail both sides underflow (SCATMECH's 1.5e-302 against our 0.0 at seed 58
    of a search over 300), which says nothing about either model."""
    rng = np.random.default_rng(seed)
    worst, where = 0.0, None
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
            err = float(np.max(np.abs(M - R)) / max(R[0, 0], 1e-250))
            if err > worst:
                worst, where = err, (coat, sub, sigma, str(dist), ti, tr, pr)
    assert worst <= 1e-6, where


@pytest.mark.parametrize(
    "scene_name, generator",
    [("red_paint_fit.toml", "paint_mueller"), ("maxwell_beard_fit.toml", "mb_mueller")],
)
def test_comparison_scenes_at_the_truth_reproduce_their_scatmech_generators(scene_name, generator):
    """The scenes of seed 003's comparison, set to the truth of the data files, against the
    SCATMECH generators that made those files (references/scripts/make_scatmech_paint_data.py),
    at the files' 200 geometries.  The paint's tolerance is set by SCATMECH's own diffuse R-bar
    (off by up to 2.3e-4 of itself, see checks_seed003)."""
    import os
    import sys

    from scatterbench import references
    from scatterbench.models import scene

    sys.path.insert(0, os.path.join(os.path.dirname(references.__file__), "scripts"))
    import make_scatmech_paint_data as mk
    from make_scatmech_flake_data import geometries

    truth = mk.MB_TRUTH if generator == "mb_mueller" else mk.PAINT_TRUTH
    sc = scene.load(references.scene_path(scene_name))
    sc = sc.with_values({k: v for k, v in truth.items() if not k.endswith("index")})  # the index is fixed
    g = np.radians(geometries()[:, :3])
    M = sc.build().mueller(g[:, 0], g[:, 1], g[:, 2])
    ref = getattr(mk, generator)()
    R = np.array([ref(*row) for row in g])
    err = np.max(np.abs(M - R), axis=(1, 2)) / R[:, 0, 0]
    assert err.max() <= (1e-6 if generator == "paint_mueller" else 1e-12)
