"""Write ``rough_diffuse_a0b9da6.npz``: RoughDiffuseBRDF's estimates (mean and standard
error, 16 elements) and its rough R-bar as computed at commit a0b9da6, before the Monte
Carlo was compiled, so the tests hold today's paths to the same numbers.

    mkdir /tmp/a0b9da6 && git archive a0b9da6 | tar -x -C /tmp/a0b9da6
    PYTHONPATH=/tmp/a0b9da6 python tests/data/rough_diffuse_reference.py
"""

from __future__ import annotations

import math
import os

import numpy as np

try:
    from scatterbench import models
except ImportError:  # a checkout from before the one namespace (a0b9da6), on PYTHONPATH
    import models

HERE = os.path.dirname(os.path.abspath(__file__))
PATH = os.path.join(HERE, "rough_diffuse_a0b9da6.npz")

_KW = dict(slopes=models.ExponentialSlopes(0.5), coating=1.5, phase=models.HenyeyGreenstein(0.3), rho=0.3)
#: name -> model keywords: every branch of the estimate (polarized or not, single or not,
#: rough or flat R-bar, huge weights rescaled, wide slopes with many dead pairs)
CASES = {
    "polarized": dict(_KW, pairs=300, seed=4),
    "depolarizing": dict(
        _KW, pairs=300, seed=5, single=0.7, phase=models.HenyeyGreenstein(-0.4, polarized=False)
    ),
    "no_single": dict(_KW, pairs=257, seed=6, single=0.0),
    "rho0": dict(_KW, pairs=300, seed=7, rho=0.0),
    "flat_corrected": dict(_KW, pairs=300, seed=8, feedback="flat", convention="corrected", rho=1.0),
    "wide": dict(_KW, pairs=400, seed=9, slopes=models.GaussianSlopes(2.0), coating=2.4, rho=0.9),
    "huge": dict(_KW, pairs=200, seed=10, single=1e300, surface=False),
    "carc": dict(pairs=5000, seed=0),
}


def geometries():
    """Scattered geometries with the edges (normal, grazing, the pole along either azimuth)
    and the benchmark's in-plane curve of 181 angles at theta_i = 0.5."""
    rng = np.random.default_rng(2024)
    ti = np.concatenate([rng.uniform(0, 1.5, 40), [0.0, 0.0, math.pi / 2, 0.3, 1.2, 1.5707]])
    tr = np.concatenate([rng.uniform(0, 1.5, 40), [0.0, 0.7, 0.4, math.pi / 2, 0.0, 1.5707]])
    pr = np.concatenate([rng.uniform(-math.pi, math.pi, 40), [0.0, 2.0, 0.0, 1.0, 3.0, math.pi]])
    t = np.radians(np.linspace(-90.0, 90.0, 181))
    return (ti, tr, pr), (np.full(181, 0.5), np.abs(t), np.where(t < 0, math.pi, 0.0))


def main():
    scattered, curve = geometries()
    out = {}
    for name, kw in CASES.items():
        m = models.RoughDiffuseBRDF(**kw)
        g = curve if name == "carc" else scattered
        M, E = m.mueller_with_error(*g)
        out[f"{name}_mean"], out[f"{name}_err"] = M, E
        out[f"{name}_rbar"] = np.float64(m._rbar)
    np.savez_compressed(PATH, **out)


if __name__ == "__main__":
    main()
