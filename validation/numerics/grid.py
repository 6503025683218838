"""Hemispherical reflectance of the Monte Carlo model on a fixed product grid.

The adaptive integrator would call the Monte Carlo model tens of thousands of
times; here a Gauss-Legendre grid in ``t = sin^2(theta_r)`` (``cos dOmega =
dt dphi / 2``) and a uniform grid in ``phi_r`` is evaluated in one vectorized
call.  Common random numbers make the integrand smooth in angle, so the grid
error is small next to the Monte Carlo error.  Because every geometry uses the
same facet pairs, the per-geometry errors are correlated, not independent: the
returned error is ``sum W_g SE_g``, the bound that holds for any correlation
(exact when the errors are perfectly correlated).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["grid_reflectance"]


def grid_reflectance(model, theta_i, n_t=48, n_phi=64):
    """``(value, standard_error)`` of ``integral M00 cos dOmega`` on a product grid."""
    x, w = np.polynomial.legendre.leggauss(n_t)
    t = 0.5 * (x + 1.0)
    wt = 0.5 * w
    tr = np.arcsin(np.sqrt(t))
    phi = (np.arange(n_phi) + 0.5) * (2.0 * math.pi / n_phi)
    TR, PH = np.meshgrid(tr, phi, indexing="ij")
    W = (wt[:, None] * (2.0 * math.pi / n_phi) * 0.5) * np.ones_like(PH)
    if hasattr(model, "mueller_with_error"):
        M, E = model.mueller_with_error(theta_i, TR, PH)
        return float(np.sum(W * M[..., 0, 0])), float(np.sum(W * E[..., 0, 0]))
    M = model.mueller(theta_i, TR, PH)
    return float(np.sum(W * M[..., 0, 0])), 0.0
