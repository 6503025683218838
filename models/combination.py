"""Monte Carlo standard errors through incoherent sums (seed 003 Sec. 4 combinations).

``m1 + m2`` and ``w * m`` (:class:`scatterbench.models.base.Sum`) already combine any models;
:func:`mueller_with_error` adds the standard error of a sum whose terms include
Monte Carlo models (those with ``mueller_with_error``): errors of independent
terms add in quadrature, weighted; deterministic terms contribute none.
"""

from __future__ import annotations

import numpy as np

from .base import Model, Sum

__all__ = ["mueller_with_error"]


def mueller_with_error(model: Model, theta_i, theta_r, phi_r=0.0):
    """``(M, standard_error)`` of any model; zero error for deterministic ones.

    Terms are assumed statistically independent (different seeds); two terms
    that share a seed are correlated and the quadrature sum then understates
    the error.
    """
    if isinstance(model, Sum):
        total = err2 = None
        for w, m in model.terms:
            M, E = mueller_with_error(m, theta_i, theta_r, phi_r)
            total = w * M if total is None else total + w * M
            err2 = (w * E) ** 2 if err2 is None else err2 + (w * E) ** 2
        return total, np.sqrt(err2)
    if hasattr(model, "mueller_with_error"):
        return model.mueller_with_error(theta_i, theta_r, phi_r)
    M = model.mueller(theta_i, theta_r, phi_r)
    return M, np.zeros_like(M)
