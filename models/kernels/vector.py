"""The float64 loops that run on SIMD lanes: the kernels of :mod:`~scatterbench.models.kernels.drive`
over a block of geometries at a time, compiled so that the compiler vectorizes them.

:func:`scatterbench.models.kernels.drive.run` calls a model's one-geometry function in a loop the
compiler keeps scalar: the function branches on the model and its options, calls the C
library, and reads and writes several arrays the compiler must assume overlap.  Here, per
block of :data:`VBLOCK` geometries:

1. :func:`gather` copies the block's angles and parameters into one scratch
   array and takes the azimuths' cosines and sines there with the polynomial
   :func:`~scatterbench.models.kernels.vector_math.sincos` (the C library beyond its range:
   :func:`~scatterbench.models.kernels.common.azimuths`);
2. :func:`lanes` runs the kernel over the scratch: one loop per model and slope kind, with
   the code and options constants, so that the branches left are selects; no call remains
   (the kernels use :mod:`~scatterbench.models.kernels.vector_math`, and ``error_model="numpy"`` lets a
   division by zero give inf, as numpy's, instead of raising); all reads and writes are in
   the one scratch at fixed offsets, so no overlap test is needed;
3. the block's result rows are copied to ``out``.

The kernels are the same functions as the scalar loop's, so both give the same bits
(``tests/test_vector_kernels.py``).  :func:`vectorized` says which models and options take this
path.  The others keep C library calls that leave any loop scalar (FacetBTDF, Smith
shadowing, anisotropic slopes, unit slopes); :class:`scatterbench.models.kernels.Compiled` runs them through
:mod:`~scatterbench.models.kernels.drive`.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ..kernel_specs import COOK_SHADOWING, EXPONENTIAL, GAUSSIAN, GGX
from .common import NO_SHADOWING, azimuths
from .cook import cook
from .drive import BLOCK, COOK, DIFFUSE, FACET, MAXWELL, PARAM_ROWS, SINGLE, angles_ok, options
from .facet import facet
from .maxwell import maxwell
from .volume import diffuse, single

#: geometries per block: the scratch, :data:`_ROWS` rows of them in float64 (55 kB), stays
#: in the L2 cache
VBLOCK = 256
#: scratch rows: angles, azimuth cosine and sine, the 16 result rows, the parameters
_TI, _TR, _PR, _CP, _SP, _OUT, _PRM = 0, 1, 2, 3, 4, 5, 21
_ROWS = _PRM + PARAM_ROWS
#: the facet kernel's slope kinds that vectorize (the anisotropic ones rotate by a parameter
#: through the C library's cosine; the unit one is left to the scalar loop: each kind costs
#: about 2 s of compilation)
FACET_KINDS = (EXPONENTIAL, GAUSSIAN, GGX)
BLINN, NO_COOK_SHADOWING = COOK_SHADOWING["blinn"], COOK_SHADOWING["none"]


def vectorized(code, iopt) -> bool:
    """Whether kernel ``code`` with options ``iopt`` takes the vector path (float64)."""
    if code == FACET:
        return iopt[1] == NO_SHADOWING and iopt[0] in FACET_KINDS
    if code == COOK:
        return iopt[2] != COOK_SHADOWING["smith"]
    if code == MAXWELL:
        return iopt[0] in FACET_KINDS
    return code in (SINGLE, DIFFUSE)


@njit(error_model="numpy", inline="always")
def _at(sc, row, k):
    return sc[row * VBLOCK + k]


@njit(error_model="numpy", inline="always")
def _row(sc, row, m):
    """The first ``m`` columns of scratch row ``row`` (a view)."""
    return sc[row * VBLOCK : row * VBLOCK + m]


@njit(error_model="numpy", inline="always")
def _geometry(sc, k):
    """Geometry ``k`` of the scratch, as :func:`scatterbench.models.kernels.drive.geometry` gives it."""
    return _at(sc, _TI, k), _at(sc, _TR, k), _at(sc, _PR, k), _at(sc, _CP, k), _at(sc, _SP, k)


@njit(error_model="numpy", inline="always")
def _scratch_params(sc, k):
    """Geometry ``k``'s parameters (:func:`gather` copied them)."""
    return (_at(sc, _PRM, k), _at(sc, _PRM + 1, k), _at(sc, _PRM + 2, k), _at(sc, _PRM + 3, k),
            _at(sc, _PRM + 4, k), _at(sc, _PRM + 5, k), _at(sc, _PRM + 6, k), _at(sc, _PRM + 7, k),
            _at(sc, _PRM + 8, k), _at(sc, _PRM + 9, k), _at(sc, _PRM + 10, k))  # fmt: skip


@njit(error_model="numpy", inline="always")
def _store(sc, k, m):
    """The 16 elements ``m`` into the result rows, column ``k`` (written out: a loop over a
    tuple's index compiles to a switch, which keeps the loop around it scalar)."""
    B, o = VBLOCK, _OUT * VBLOCK + k
    sc[o], sc[o + B], sc[o + 2 * B], sc[o + 3 * B] = m[0], m[1], m[2], m[3]
    sc[o + 4 * B], sc[o + 5 * B], sc[o + 6 * B], sc[o + 7 * B] = m[4], m[5], m[6], m[7]
    sc[o + 8 * B], sc[o + 9 * B], sc[o + 10 * B], sc[o + 11 * B] = m[8], m[9], m[10], m[11]
    sc[o + 12 * B], sc[o + 13 * B], sc[o + 14 * B], sc[o + 15 * B] = m[12], m[13], m[14], m[15]


@njit(error_model="numpy", forceinline=True)
def _loop(kernel, sc, m, o):
    """The loop of :func:`lanes` for one kernel and its options: compiled once per kernel,
    inlined by LLVM into :func:`lanes`, where the options are constants and fold (numba's
    own inlining would type the kernel once per call: minutes of compilation)."""
    for k in range(m):
        _store(sc, k, kernel(_geometry(sc, k), _scratch_params(sc, k), o))


@njit(error_model="numpy")
def lanes(code, sc, m, o):
    """Geometries ``0 .. m - 1`` of the scratch through kernel ``code`` (:func:`vectorized`
    models only): one loop per kernel, slope kind and option set, each with them constant."""
    if code == FACET:
        kind = o[0]
        if kind == EXPONENTIAL:
            _loop(facet, sc, m, (EXPONENTIAL, NO_SHADOWING, 0))
        elif kind == GAUSSIAN:
            _loop(facet, sc, m, (GAUSSIAN, NO_SHADOWING, 0))
        else:
            _loop(facet, sc, m, (GGX, NO_SHADOWING, 0))
    elif code == SINGLE:
        if o[0] == 0:
            _loop(single, sc, m, (0, 0, 0))
        else:
            _loop(single, sc, m, (1, 0, 0))
    elif code == DIFFUSE:
        _loop(diffuse, sc, m, (0, 0, 0))
    elif code == MAXWELL:
        _maxwell_lanes(sc, m, o)
    elif o[0] == 1:
        if o[2] == BLINN:
            _loop(cook, sc, m, (1, o[1], BLINN))
        else:
            _loop(cook, sc, m, (1, o[1], NO_COOK_SHADOWING))
    elif o[2] == BLINN:
        _loop(cook, sc, m, (0, o[1], BLINN))
    else:
        _loop(cook, sc, m, (0, o[1], NO_COOK_SHADOWING))


@njit(error_model="numpy", forceinline=True)
def _maxwell_lanes(sc, m, o):
    """:func:`lanes` for Maxwell-Beard: one loop per facet slope kind."""
    kind, pol = o[0], o[2]
    if kind == EXPONENTIAL:
        _loop(maxwell, sc, m, (EXPONENTIAL, NO_SHADOWING, pol))
    elif kind == GAUSSIAN:
        _loop(maxwell, sc, m, (GAUSSIAN, NO_SHADOWING, pol))
    else:
        _loop(maxwell, sc, m, (GGX, NO_SHADOWING, pol))


@njit(error_model="numpy")
def gather(sc, ti, tr, pr, prm, lo, m):
    """Geometries ``lo .. lo + m - 1`` of the inputs into the scratch: angles, the azimuth's
    cosine and sine (:func:`~scatterbench.models.kernels.common.azimuths` over the block), and the
    parameters (a single model's repeated)."""
    a, b, c, p = ti.shape[0] > 1, tr.shape[0] > 1, pr.shape[0] > 1, prm.shape[1] > 1
    for k in range(m):
        i = lo + k
        sc[_TI * VBLOCK + k], sc[_TR * VBLOCK + k], sc[_PR * VBLOCK + k] = ti[i * a], tr[i * b], pr[i * c]
    azimuths(_row(sc, _PR, m), _row(sc, _CP, m), _row(sc, _SP, m))
    for r in range(PARAM_ROWS):  # a single model's too: the loop then reads them as a set's
        for k in range(m):
            sc[(_PRM + r) * VBLOCK + k] = prm[r, (lo + k) * p]


@njit(error_model="numpy")
def run_range(code, ti, tr, pr, prm, iopt, out, start, lo, hi):
    """Geometries ``lo .. hi - 1`` into ``out[:, start + i]``, a block at a time."""
    o = options(iopt)
    sc = np.empty(_ROWS * VBLOCK)
    for blo in range(lo, hi, VBLOCK):
        m = min(VBLOCK, hi - blo)
        gather(sc, ti, tr, pr, prm, blo, m)
        lanes(code, sc, m, o)
        for r in range(out.shape[0]):
            for k in range(m):
                out[r, start + blo + k] = sc[(_OUT + r) * VBLOCK + k]


@njit(cache=True, error_model="numpy")
def run(code, ti, tr, pr, prm, iopt, out, start):
    """:func:`scatterbench.models.kernels.drive.run` (same arguments, float64) on SIMD lanes."""
    n = max(ti.shape[0], tr.shape[0], pr.shape[0], prm.shape[1])
    # np.int64(0), not 0: numba gives a literal argument a specialization of its own
    # (Literal[int](0)), which compiled every kernel a second time
    run_range(code, ti, tr, pr, prm, iopt, out, start, np.int64(0), n)


@njit(cache=True, error_model="numpy")
def run_checked(code, ti, tr, pr, prm, iopt, out):
    """:func:`scatterbench.models.kernels.drive.run_checked` (same arguments, float64) on SIMD lanes."""
    if not angles_ok(ti, tr, pr):
        return False
    run(code, ti, tr, pr, prm, iopt, out, np.int64(0))  # int64: see run
    return True


@njit(cache=True, error_model="numpy", parallel=True)
def run_parallel(code, ti, tr, pr, prm, iopt, out, start):
    """:func:`run` with blocks of :data:`scatterbench.models.kernels.drive.BLOCK` geometries over the cores."""
    n = max(ti.shape[0], tr.shape[0], pr.shape[0], prm.shape[1])
    for blk in prange((n + BLOCK - 1) // BLOCK):
        lo = blk * BLOCK
        run_range(code, ti, tr, pr, prm, iopt, out, start, lo, min(lo + BLOCK, n))
