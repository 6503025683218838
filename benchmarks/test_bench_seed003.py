"""pytest-benchmark: seed 003 models.

Run:  python -m pytest benchmarks/test_bench_seed003.py --benchmark-only
Issue 3 targets: DiffuseSubsurfaceBRDF and SingleScatterBRDF <= 0.3 us per
geometry over 10^6 geometries; RoughDiffuseBRDF, an in-plane curve of 181
angles at 5000 facet pairs in <= 2 s.  ``python benchmarks/speed_seed003.py``
prints the same numbers with ratios and the Monte Carlo error/cost vs pairs.
"""

import math

import numpy as np
from conftest import per_geometry

from scatterbench import models


def test_diffuse_subsurface_mueller_1e6(benchmark, geometries_1e6):
    m = models.DiffuseSubsurfaceBRDF(coating=1.5, rho=0.93)
    benchmark.pedantic(m.mueller, args=geometries_1e6, rounds=3, warmup_rounds=1)
    per_geometry(benchmark, geometries_1e6[0].size)


def test_single_scatter_depolarizing_mueller_1e6(benchmark, geometries_1e6):
    m = models.SingleScatterBRDF(coating=1.5, phase=models.HenyeyGreenstein(0.3, polarized=False))
    benchmark.pedantic(m.mueller, args=geometries_1e6, rounds=3, warmup_rounds=1)
    per_geometry(benchmark, geometries_1e6[0].size)


def test_single_scatter_polarized_mueller_1e6(benchmark, geometries_1e6):
    m = models.SingleScatterBRDF(coating=1.5, phase=models.HenyeyGreenstein(0.3, polarized=True))
    benchmark.pedantic(m.mueller, args=geometries_1e6, rounds=3, warmup_rounds=1)
    per_geometry(benchmark, geometries_1e6[0].size)


def in_plane_curve():
    t = np.radians(np.linspace(-90.0, 90.0, 181))
    tr = np.minimum(np.abs(t), math.radians(89.9))
    pr = np.where(t < 0, math.pi, 0.0)
    return math.radians(60.0), tr, pr


def test_rough_diffuse_curve_181x5000(benchmark):
    m = models.RoughDiffuseBRDF(
        slopes=models.ExponentialSlopes(2.0),
        coating=1.5,
        phase=models.HenyeyGreenstein(0.3),
        rho=0.05,
        pairs=5000,
        seed=0,
    )
    ti, tr, pr = in_plane_curve()
    M, E = benchmark.pedantic(m.mueller_with_error, args=(ti, tr, pr), rounds=3, warmup_rounds=1)
    assert M.shape == (181, 4, 4)
    benchmark.extra_info["median_relative_se_M00"] = float(np.median(E[:, 0, 0] / M[:, 0, 0]))
