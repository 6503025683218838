"""The kernels' loops: every model's one-geometry function driven over flat arrays.

``code`` picks the model (:data:`CODES`); ``ti``, ``tr``, ``pr`` are flat angle arrays of
length 1 (one value for every geometry) or ``n``; ``prm`` holds the model's parameters as
rows of length 1 (a single model) or ``n`` (a model set, one element per geometry), or of
any length ``G`` read through ``index`` (:func:`column`: a fit's walkers x wavelengths, each
shared by many geometries, read in place rather than gathered per geometry);
``iopt`` its options (slope kind, shadowing, conventions); ``out`` the element-major result
``(16, N)`` (or ``(1, N)``: ``M00`` only), written from column ``start``.  No Python runs per
geometry: one compiled loop per kernel (:func:`entry`) takes a range of geometries, and
:class:`scatterbench.models.kernels.Compiled` calls it serially or on ranges over the cores
(:func:`scatterbench.models.kernels.threads.spread`).
"""

from __future__ import annotations

import math
from types import FunctionType

import numpy as np

from ..kernel_specs import KERNEL_ROWS
from .common import azimuth
from .cook import cook
from .facet import btdf, facet
from .helper import entry_point, helper
from .maxwell import maxwell
from .volume import diffuse, single

FACET, BTDF, SINGLE, DIFFUSE, COOK, MAXWELL = range(6)
CODES = {"facet": FACET, "btdf": BTDF, "single": SINGLE, "diffuse": DIFFUSE, "cook": COOK, "maxwell": MAXWELL}
NAMES = {c: name for name, c in CODES.items()}
#: each kernel's parameter rows, in order (``Compiled`` checks a model's spec against them)
ROWS = KERNEL_ROWS


#: rows of ``prm`` and entries of ``iopt`` every kernel is given (``Compiled`` pads to them;
#: :func:`params` and :func:`options` read exactly these)
PARAM_ROWS = max(len(r) for r in ROWS.values())
OPTIONS = 3
assert PARAM_ROWS == 11, "params() reads 11 rows"


@helper
def geometry(ti, tr, pr):
    """``(theta_i, theta_r, phi_r, cos phi_r, sin phi_r)`` in the angles' precision."""
    T = type(pr)
    c, s = azimuth(pr)
    return ti, tr, pr, T(c), T(s)


@helper(forceinline=None)
def params(prm, j):
    """Column ``j`` of the parameter rows as a tuple."""
    return (prm[0, j], prm[1, j], prm[2, j], prm[3, j], prm[4, j], prm[5, j],
            prm[6, j], prm[7, j], prm[8, j], prm[9, j], prm[10, j])  # fmt: skip


@helper(forceinline=None)
def options(iopt):
    """The options as a tuple."""
    return (iopt[0], iopt[1], iopt[2])


@helper(forceinline=None)
def store(out, i, m):
    """The elements ``m`` into ``out[:, i]`` (only ``M00`` when ``out`` has one row)."""
    out[0, i] = m[0]
    if out.shape[0] == 1:
        return
    out[1, i], out[2, i], out[3, i], out[4, i] = m[1], m[2], m[3], m[4]
    out[5, i], out[6, i], out[7, i], out[8, i] = m[5], m[6], m[7], m[8]
    out[9, i], out[10, i], out[11, i], out[12, i] = m[9], m[10], m[11], m[12]
    out[13, i], out[14, i], out[15, i] = m[13], m[14], m[15]


@helper
def column(index, p, i):
    """The parameter column geometry ``i`` reads: ``index[i]`` for an ``index`` longer than 1,
    otherwise ``index[0] + i * p`` (``p``: whether ``prm`` has a column per geometry), so that
    :data:`NO_INDEX` (``[0]``) is the plain rule ``i * p``, and a one-geometry call's index
    ``[j]`` reads column ``j``.  Arithmetic, without a branch (``p > q``: ``p and not q``, whose
    short circuit is one): LLVM may unswitch a loop on a branch that does not change in it,
    copying the loop, inlined kernel and all, once per side (compile time; measured on a cold
    cache, one FacetBRDF vector loop and the FacetBTDF scalar loop compile in the CPU time they
    took before the index, within the machine's noise)."""
    q = index.shape[0] > 1
    return index[i * q] + i * (p > q)


#: the fewest geometries of a range given to a thread (:func:`scatterbench.models.kernels.threads.spread`)
BLOCK = 1024


#: the one-geometry functions by code
KERNELS = (facet, btdf, single, diffuse, cook, maxwell)
assert [KERNELS[c] for c in CODES.values()] == [facet, btdf, single, diffuse, cook, maxwell]


def named(code, tag=""):
    """A decorator that renames a function after kernel ``code``, before numba sees it: numba
    names a function's cache files after its qualified name, so each kernel's entries get
    files of their own (in shared ones, two processes compiling two kernels at once could pair
    one's index with the other's code)."""

    def rename(fn):
        fn.__name__ = fn.__qualname__ = f"{fn.__name__}_{NAMES[code]}{'_' + tag if tag else ''}"
        fn.kernel = NAMES[code]  # the compile notice names the kernel, once (kernels._announced)
        return fn

    return rename


def own_kernel(fn, code, tag="", **own):
    """``fn`` (a loop that calls the global ``_KERNEL``) compiled and cached as an entry of
    kernel ``code`` (:func:`named` after it and ``tag``), with ``_KERNEL`` that kernel: a global
    of ``fn``'s own (a copy of its module's globals).  numba calls a global dispatcher directly,
    and LLVM inlines it into the loop; a dispatcher held in a closure cell is pickled into the
    cache's key, differently in every process (no cache hit, ever), one passed as an argument is
    a Python object, and one picked from a tuple in compiled code is called through a pointer.
    The loop is written in the entry itself, not in a function it calls: numba optimizes and
    emits every compiled function's code, its callees' linked in, so that each level between
    the entry and the kernel cost a cold cache another pass over the inlined kernel (about 2 s a
    Maxwell-Beard option set on SIMD lanes).  ``own``: more globals of ``fn``'s (or another
    ``_KERNEL``), set the same way."""
    fresh = FunctionType(
        fn.__code__, {**fn.__globals__, "_KERNEL": KERNELS[code], **own}, None, None, fn.__closure__
    )
    return entry_point(named(code, tag)(fresh), nogil=True)


def entry(code):
    """The one compiled entry of kernel ``code``'s scalar loop (built once, at import:
    :data:`ENTRIES`): ``run_range(ti, tr, pr, prm, index, iopt, out, start, lo, hi)``, geometries
    ``lo .. hi - 1`` into ``out[:, start + i]``, geometry ``i`` with the parameters of column
    :func:`column` of ``prm`` (``index``: :data:`NO_INDEX` or one column per geometry), without the GIL.  Serial, parallel, checked
    and one-geometry calls are that loop called from Python
    (:func:`scatterbench.models.kernels.threads.spread`): one entry per kernel compiles the kernel once,
    where four (a serial, a ``prange``, a checked and a scalar one) each had LLVM optimize the
    inlined kernel again (10 s of a cold first call for Cook-Torrance, a third of it in the
    three extra copies).  It calls its kernel alone (:func:`own_kernel`): one entry over every
    kernel compiled all six on a first call (23 s of CPU for one geometry of FacetBRDF on a
    cold cache).  The loop compiles once per kernel: a loop that dispatches on the model per
    geometry holds every kernel's code and runs slower."""

    def run_range(ti, tr, pr, prm, index, iopt, out, start, lo, hi):
        o = options(iopt)
        a, b, c, p = ti.shape[0] > 1, tr.shape[0] > 1, pr.shape[0] > 1, prm.shape[1] > 1
        for i in range(lo, hi):
            g = geometry(ti[i * a], tr[i * b], pr[i * c])
            store(out, start + i, _KERNEL(g, params(prm, column(index, p, i)), o))  # noqa: F821

    return own_kernel(run_range, code)


@entry_point
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


@entry_point(nogil=True)
def outside_range(a, low, high, bad, lo, hi):
    """``bad[0] = 1`` when a value of ``a[lo:hi]`` lies outside ``[low, high]`` (NaN does): the
    general path's check of a large angle array, a range of it per thread (:func:`~scatterbench.models.kernels.within`)."""
    n = 0
    for k in range(lo, hi):
        x = a[k]
        if not (low <= x) or not (x <= high):  # no early exit: the loop stays on SIMD lanes
            n += 1
    if n:
        bad[0] = 1


#: the index of a call without one (:func:`column`: geometry ``i`` reads column ``i * p``)
NO_INDEX = np.zeros(1, dtype=np.int64)

#: every kernel's scalar loop (:func:`entry`), by code
ENTRIES = tuple(entry(c) for c in range(len(KERNELS)))
