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
