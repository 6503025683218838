"""pytest-benchmark: seed 001 models over 10^6 geometries, and the point-source grid.

Run:  python -m pytest benchmarks/test_bench_seed001.py --benchmark-only
Issue 4 target: CookTorranceBRDF and VarnishedCookTorranceBRDF <= 0.2 us per
geometry over 10^6 geometries (extra_info holds us per geometry).  The
point-source trade-off against the resolution knob is printed by
``python benchmarks/point_source_tradeoff.py``.
"""

import math

import numpy as np
from conftest import per_geometry

from scatterbench import models


def test_cook_torrance_brdf_1e6(benchmark, geometries_1e6):
    m = models.CookTorranceBRDF(slopes=models.GaussianSlopes(0.03), substrate=2.29 + 3.37j)
    benchmark.pedantic(m.brdf, args=geometries_1e6, rounds=5, warmup_rounds=1)
    per_geometry(benchmark, geometries_1e6[0].size)


def test_varnished_brdf_1e6(benchmark, geometries_1e6):
    m = models.VarnishedCookTorranceBRDF(slopes=models.StrokeSlopes(0.03, 0.1, 0.3))
    benchmark.pedantic(m.brdf, args=geometries_1e6, rounds=5, warmup_rounds=1)
    per_geometry(benchmark, geometries_1e6[0].size)


def test_varnished_isotropic_brdf_1e6(benchmark, geometries_1e6):
    m = models.VarnishedCookTorranceBRDF()
    benchmark.pedantic(m.brdf, args=geometries_1e6, rounds=5, warmup_rounds=1)
    per_geometry(benchmark, geometries_1e6[0].size)


def test_cook_torrance_mueller_1e6(benchmark, geometries_1e6):
    m = models.CookTorranceBRDF(slopes=models.GaussianSlopes(0.03), substrate=2.29 + 3.37j)
    benchmark.pedantic(m.mueller, args=geometries_1e6, rounds=3, warmup_rounds=1)
    per_geometry(benchmark, geometries_1e6[0].size)


def _grid():
    return np.radians(np.linspace(0, 40, 161)), np.radians(np.linspace(-10, 10, 41))


def test_point_source_exact_grid(benchmark):
    tr, pr = _grid()
    ps = models.PointSourceBRDF(model=models.VarnishedCookTorranceBRDF(), distance=10.0, resolution=8)
    benchmark.pedantic(ps.brdf_grid, args=(math.radians(17), tr, pr), rounds=3, warmup_rounds=1)


def test_point_source_shift_grid(benchmark):
    tr, pr = _grid()
    ps = models.PointSourceBRDF(
        model=models.VarnishedCookTorranceBRDF(), distance=10.0, resolution=8, method="shift"
    )
    benchmark.pedantic(ps.brdf_grid, args=(math.radians(17), tr, pr), rounds=5, warmup_rounds=1)
