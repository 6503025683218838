"""Geometries to probe a model at, and the floating-point warnings a probe raises: shared by
the checks, the studies (stability sweep, trade-off), the tests and the benchmarks."""

from __future__ import annotations

import contextlib
import math
import warnings

import numpy as np

__all__ = ["random_geometries", "extreme_geometries", "fp_warnings"]


def random_geometries(n, seed=0, max_deg=89.0):
    """``n`` seeded random geometries, polar angles up to ``max_deg``, every azimuth."""
    rng = np.random.default_rng(seed)
    tmax = math.radians(max_deg)
    return rng.uniform(0, tmax, n), rng.uniform(0, tmax, n), rng.uniform(-math.pi, math.pi, n)


def extreme_geometries():
    """Polar angles 0, 1e-9, 30, 60, 89.99 and exactly 90 deg in every pair, at azimuths
    0, +-pi, pi/2 and 1e-12 (specular, retro, out of plane, almost in plane)."""
    d = math.radians
    t = np.array([0.0, 1e-9, d(30), d(60), d(89.99), math.pi / 2])
    ti, tr = np.meshgrid(t, t, indexing="ij")
    ti, tr = ti.ravel(), tr.ravel()
    phis = np.array([0.0, math.pi, -math.pi, math.pi / 2, 1e-12])
    ti = np.repeat(ti, len(phis))
    tr = np.repeat(tr, len(phis))
    pr = np.tile(phis, len(t) ** 2)
    return ti, tr, pr


@contextlib.contextmanager
def fp_warnings():
    """Record the warnings raised in the block, floating-point ones included (division by
    zero, overflow, invalid operation; not gradual underflow, the correct IEEE result for
    far tails): yields the list they go into."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with np.errstate(divide="warn", over="warn", invalid="warn", under="ignore"):
            yield caught
