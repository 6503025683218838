"""pytest-benchmark: facet models over 10^6 geometries and the Table I integrals.

Run:  python -m pytest benchmarks --benchmark-only
Issue 2 targets: SubsurfaceFacetBRDF.mueller <= 0.3 us per geometry (one core);
Table I's 27 integrals at <= 1e-4 absolute error in <= 1 s.
"""

import math

from conftest import per_geometry

from scatterbench import models
from scatterbench.validation.checks.table1 import compute_table1


def test_subsurface_facet_mueller_1e6(benchmark, geometries_1e6):
    m = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.2), coating=1.5, substrate=1.37 + 7.62j)
    benchmark.pedantic(m.mueller, args=geometries_1e6, rounds=5, warmup_rounds=1)
    per_geometry(benchmark, geometries_1e6[0].size)


def test_facet_mueller_1e6(benchmark, geometries_1e6):
    m = models.FacetBRDF(slopes=models.GaussianSlopes(0.2), substrate=1.37 + 7.62j)
    benchmark.pedantic(m.mueller, args=geometries_1e6, rounds=5, warmup_rounds=1)
    per_geometry(benchmark, geometries_1e6[0].size)


def test_subsurface_facet_brdf_1e6(benchmark, geometries_1e6):
    m = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.2), coating=1.5, substrate=math.inf)
    benchmark.pedantic(m.brdf, args=geometries_1e6, rounds=5, warmup_rounds=1)
    per_geometry(benchmark, geometries_1e6[0].size)


def test_table1_27_integrals(benchmark):
    rows, _ = benchmark.pedantic(compute_table1, kwargs={"tol": 1e-4}, rounds=3, warmup_rounds=1)
    assert all(r.error <= 1e-4 for r in rows)
    benchmark.extra_info["evaluations"] = sum(r.evaluations for r in rows)
