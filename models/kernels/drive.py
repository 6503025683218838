"""The kernels' loops: every model's one-geometry function driven over flat arrays.

``code`` picks the model (:data:`CODES`); ``ti``, ``tr``, ``pr`` are flat angle arrays of
length 1 (one value for every geometry) or ``n``; ``prm`` holds the model's parameters as
rows of length 1 (a single model) or ``n`` (a model set, one element per geometry);
``iopt`` its options (slope kind, shadowing, conventions); ``out`` the element-major result
``(16, N)`` (or ``(1, N)``: ``M00`` only), written from column ``start``.  No Python runs per
geometry: :func:`run` is serial (small calls), :func:`run_parallel` spreads the geometries
over the cores with ``prange``.
"""

from __future__ import annotations

import math

from numba import njit, prange

from .cook import COOK_ROWS, cook
from .facet import BTDF_ROWS, FACET_ROWS, btdf, facet
from .maxwell import MAXWELL_ROWS, maxwell
from .volume import DIFFUSE_ROWS, SINGLE_ROWS, diffuse, single

FACET, BTDF, SINGLE, DIFFUSE, COOK, MAXWELL = range(6)
CODES = {"facet": FACET, "btdf": BTDF, "single": SINGLE, "diffuse": DIFFUSE, "cook": COOK, "maxwell": MAXWELL}
#: each kernel's parameter rows, in order (``Compiled`` checks a model's spec against them)
ROWS = {
    "facet": FACET_ROWS,
    "btdf": BTDF_ROWS,
    "single": SINGLE_ROWS,
    "diffuse": DIFFUSE_ROWS,
    "cook": COOK_ROWS,
    "maxwell": MAXWELL_ROWS,
}


@njit(cache=True, inline="always")
def element(code, a, b, c, prm, j, iopt, out, i):
    """One geometry of model ``code`` into ``out[:, i]``."""
    if code == FACET:
        facet(a, b, c, prm, j, iopt, out, i)
    elif code == BTDF:
        btdf(a, b, c, prm, j, iopt, out, i)
    elif code == SINGLE:
        single(a, b, c, prm, j, iopt, out, i)
    elif code == DIFFUSE:
        diffuse(a, b, c, prm, j, iopt, out, i)
    elif code == COOK:
        cook(a, b, c, prm, j, iopt, out, i)
    else:
        maxwell(a, b, c, prm, j, iopt, out, i)


@njit(cache=True)
def run(code, ti, tr, pr, prm, iopt, out, start):
    """Serial loop over the geometries ``0 .. len - 1`` of the inputs, into ``out[:, start + i]``."""
    n = max(ti.shape[0], tr.shape[0], pr.shape[0], prm.shape[1])
    a, b, c, p = ti.shape[0] > 1, tr.shape[0] > 1, pr.shape[0] > 1, prm.shape[1] > 1
    for i in range(n):
        element(code, ti[i * a], tr[i * b], pr[i * c], prm, i * p, iopt, out, start + i)


@njit(cache=True, parallel=True)
def run_parallel(code, ti, tr, pr, prm, iopt, out, start):
    """:func:`run` with the geometries spread over the cores (``prange``)."""
    n = max(ti.shape[0], tr.shape[0], pr.shape[0], prm.shape[1])
    a, b, c, p = ti.shape[0] > 1, tr.shape[0] > 1, pr.shape[0] > 1, prm.shape[1] > 1
    for i in prange(n):
        element(code, ti[i * a], tr[i * b], pr[i * c], prm, i * p, iopt, out, start + i)


@njit(cache=True)
def run_checked(code, ti, tr, pr, prm, iopt, out):
    """:func:`run` from column 0 when every angle is valid (:func:`angles_ok`), returning True;
    False, writing nothing, otherwise (one call into numba for a small call)."""
    if not angles_ok(ti, tr, pr):
        return False
    run(code, ti, tr, pr, prm, iopt, out, 0)
    return True


@njit(cache=True)
def run_one(code, ti, tr, pr, prm, iopt, out):
    """One geometry given as scalars (the small-call path)."""
    element(code, ti, tr, pr, prm, 0, iopt, out, 0)


@njit(cache=True)
def angles_ok(ti, tr, pr):
    """True when every polar angle lies in [0, pi/2] and every azimuth is finite (the small-call
    path's validation; the general path raises the error that names the angle)."""
    top = 0.5 * math.pi
    for k in range(ti.shape[0]):
        if not (0.0 <= ti[k] <= top):
            return False
    for k in range(tr.shape[0]):
        if not (0.0 <= tr[k] <= top):
            return False
    for k in range(pr.shape[0]):
        if not math.isfinite(pr[k]):
            return False
    return True
