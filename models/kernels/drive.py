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

import numpy as np
from numba import njit, prange

from ..kernel_specs import KERNEL_ROWS
from .common import azimuth
from .cook import cook
from .facet import btdf, facet
from .maxwell import maxwell
from .volume import diffuse, single

FACET, BTDF, SINGLE, DIFFUSE, COOK, MAXWELL = range(6)
CODES = {"facet": FACET, "btdf": BTDF, "single": SINGLE, "diffuse": DIFFUSE, "cook": COOK, "maxwell": MAXWELL}
#: each kernel's parameter rows, in order (``Compiled`` checks a model's spec against them)
ROWS = KERNEL_ROWS


#: rows of ``prm`` and entries of ``iopt`` every kernel is given (``Compiled`` pads to them;
#: :func:`params` and :func:`options` read exactly these)
PARAM_ROWS = max(len(r) for r in ROWS.values())
OPTIONS = 3
assert PARAM_ROWS == 11, "params() reads 11 rows"


@njit(error_model="numpy", inline="always")
def geometry(ti, tr, pr):
    """``(theta_i, theta_r, phi_r, cos phi_r, sin phi_r)`` in the angles' precision."""
    T = type(pr)
    c, s = azimuth(pr)
    return ti, tr, pr, T(c), T(s)


@njit(error_model="numpy")
def params(prm, j):
    """Column ``j`` of the parameter rows as a tuple."""
    return (prm[0, j], prm[1, j], prm[2, j], prm[3, j], prm[4, j], prm[5, j],
            prm[6, j], prm[7, j], prm[8, j], prm[9, j], prm[10, j])  # fmt: skip


@njit(error_model="numpy")
def options(iopt):
    """The options as a tuple."""
    return (iopt[0], iopt[1], iopt[2])


@njit(error_model="numpy")
def store(out, i, m):
    """The elements ``m`` into ``out[:, i]`` (only ``M00`` when ``out`` has one row)."""
    out[0, i] = m[0]
    if out.shape[0] == 1:
        return
    out[1, i], out[2, i], out[3, i], out[4, i] = m[1], m[2], m[3], m[4]
    out[5, i], out[6, i], out[7, i], out[8, i] = m[5], m[6], m[7], m[8]
    out[9, i], out[10, i], out[11, i], out[12, i] = m[9], m[10], m[11], m[12]
    out[13, i], out[14, i], out[15, i] = m[13], m[14], m[15]


#: geometries per task of :func:`run_parallel` (each runs :func:`run_range`'s serial loop)
BLOCK = 1024


@njit(error_model="numpy", forceinline=True)
def _serial(kernel, ti, tr, pr, prm, o, out, start, lo, hi):
    """:func:`run_range`'s loop for one kernel (compiled once per kernel: a loop that
    dispatches on the model per geometry holds every kernel's code and runs slower)."""
    a, b, c, p = ti.shape[0] > 1, tr.shape[0] > 1, pr.shape[0] > 1, prm.shape[1] > 1
    for i in range(lo, hi):
        g = geometry(ti[i * a], tr[i * b], pr[i * c])
        store(out, start + i, kernel(g, params(prm, i * p), o))


@njit(error_model="numpy")
def run_range(code, ti, tr, pr, prm, iopt, out, start, lo, hi):
    """Geometries ``lo .. hi - 1`` of the inputs into ``out[:, start + i]``, serially."""
    o = options(iopt)
    if code == FACET:
        _serial(facet, ti, tr, pr, prm, o, out, start, lo, hi)
    elif code == BTDF:
        _serial(btdf, ti, tr, pr, prm, o, out, start, lo, hi)
    elif code == SINGLE:
        _serial(single, ti, tr, pr, prm, o, out, start, lo, hi)
    elif code == DIFFUSE:
        _serial(diffuse, ti, tr, pr, prm, o, out, start, lo, hi)
    elif code == COOK:
        _serial(cook, ti, tr, pr, prm, o, out, start, lo, hi)
    else:
        _serial(maxwell, ti, tr, pr, prm, o, out, start, lo, hi)


@njit(cache=True, error_model="numpy")
def run(code, ti, tr, pr, prm, iopt, out, start):
    """Serial loop over the geometries ``0 .. len - 1`` of the inputs, into ``out[:, start + i]``."""
    n = max(ti.shape[0], tr.shape[0], pr.shape[0], prm.shape[1])
    # np.int64(0), not 0: numba gives a literal argument a specialization of its own
    # (Literal[int](0)), which compiled every kernel a second time
    run_range(code, ti, tr, pr, prm, iopt, out, start, np.int64(0), n)


@njit(cache=True, error_model="numpy", parallel=True)
def run_parallel(code, ti, tr, pr, prm, iopt, out, start):
    """:func:`run` with blocks of :data:`BLOCK` geometries spread over the cores (``prange``;
    each block the serial loop, which compiles to tighter code than a ``prange`` body)."""
    n = max(ti.shape[0], tr.shape[0], pr.shape[0], prm.shape[1])
    for blk in prange((n + BLOCK - 1) // BLOCK):
        lo = blk * BLOCK
        run_range(code, ti, tr, pr, prm, iopt, out, start, lo, min(lo + BLOCK, n))


@njit(cache=True, error_model="numpy")
def run_checked(code, ti, tr, pr, prm, iopt, out):
    """:func:`run` from column 0 when every angle is valid (:func:`angles_ok`), returning True;
    False, writing nothing, otherwise (one call into numba for a small call)."""
    if not angles_ok(ti, tr, pr):
        return False
    run(code, ti, tr, pr, prm, iopt, out, np.int64(0))  # int64: see run
    return True


@njit(cache=True, error_model="numpy")
def run_one(code, ti, tr, pr, prm, iopt, out):
    """One geometry given as scalars (the small-call path), through :func:`run_range`'s loop:
    the code every other serial call already compiled (a dispatch of its own over the
    kernels compiled them all once more, 14.5 s on a cold cache, to save ~0.1 us a call)."""
    a, b, c = np.full(1, ti), np.full(1, tr), np.full(1, pr)
    run_range(code, a, b, c, prm, iopt, out, np.int64(0), np.int64(0), np.int64(1))


@njit(cache=True, error_model="numpy")
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
