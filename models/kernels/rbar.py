"""R-bar's integrand compiled (numba ``cfunc``), for scipy's QUADPACK to call without Python.

:func:`scatterbench.models.smooth_interface.internal_hemispherical_reflectance` integrates
``(Rs + Rp) c`` over the external cosine ``c`` once per index; a fit meets a new index per
walker and wavelength at every step (96 per batch of the PTFE joint fit), where the quadrature
with a Python integrand took ~150 us (42 calls of the integrand through the interpreter, and
``quad``'s own argument handling).  The same QUADPACK routine (``qagpe``, the same breakpoints
and tolerances) called with this integrand as a :class:`scipy.LowLevelCallable` evaluates the
same float operations in the same order (no fast-math, no fused multiply-add: numba emits
separate IEEE multiplies and adds, and LLVM does not contract them unless told), so it samples
the same values and returns the same bits (``tests/test_seed003_smooth.py``, over a dense grid
of indices), in ~8 us.
"""

from __future__ import annotations

import math

from numba import cfunc, types

__all__ = ["integrand"]


@cfunc(types.float64(types.intc, types.CPointer(types.float64)), cache=True, error_model="numpy")
def integrand(n_args, x):  # pragma: no cover - compiled
    """``0.5 (Rs + Rp) 2c`` at external cosine ``x[0]`` for ``x[1] = n^2``: the float form of
    :func:`scatterbench.models.smooth_interface._rbar`'s Python integrand, operation for operation."""
    c = x[0]
    nn = x[1]
    w = math.sqrt((nn - 1.0) + c * c)
    rs = (c - w) * (1.0 / (c + w))
    rp = (nn * c - w) * (1.0 / (nn * c + w))
    return (rs * rs + rp * rp) * c
