import numpy as np
import pytest


@pytest.fixture(scope="session")
def geometries_1e6():
    rng = np.random.default_rng(2026)
    n = 10**6
    return (
        rng.uniform(0, np.radians(85), n),
        rng.uniform(0, np.radians(85), n),
        rng.uniform(-np.pi, np.pi, n),
    )


def per_geometry(benchmark, n):
    """Record the per-geometry cost of a benchmark over ``n`` geometries (min and median);
    nothing under ``--benchmark-disable``, where the function ran once, untimed."""
    benchmark.extra_info["geometries"] = n
    if benchmark.stats is None:
        return
    benchmark.extra_info["us_per_geometry_min"] = benchmark.stats.stats.min / n * 1e6
    benchmark.extra_info["us_per_geometry_median"] = benchmark.stats.stats.median / n * 1e6
