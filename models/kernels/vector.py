"""The float64 loops that run on SIMD lanes: the kernels of :mod:`~scatterbench.models.kernels.drive`
over a block of geometries at a time, compiled so that the compiler vectorizes them.

The scalar loops of :mod:`~scatterbench.models.kernels.drive` call a model's one-geometry function in a loop the
compiler keeps scalar: the function branches on the model and its options, calls the C
library, and reads and writes several arrays the compiler must assume overlap.  Here, per
block of :data:`VBLOCK` geometries:

1. :func:`gather` copies the block's angles and parameters into one scratch
   array (``memcpy``, :func:`copy_into`, or :func:`pick_rows` for a model set's columns; what
   every block shares, :func:`shared` wrote once per call with :func:`fill`) and takes the
   azimuths' cosines and sines there with the polynomial
   :func:`~scatterbench.models.kernels.vector_math.sincos` (the C library beyond its range);
2. :func:`entry`'s loop runs the kernel over the scratch: one loop per model and option set (:func:`lane_options`), with
   the code and options constants, so that the branches left are selects; no call remains
   (the kernels use :mod:`~scatterbench.models.kernels.vector_math`, and ``error_model="numpy"`` lets a
   division by zero give inf, as numpy's, instead of raising); all reads and writes are in
   the one scratch at fixed offsets, so no overlap test is needed;
3. the block's result rows are copied to ``out`` (:func:`put`, a ``memcpy`` a row, or streamed
   to memory for a result larger than the caches: :mod:`~scatterbench.models.kernels.memory`).

Steps 1 and 3 are the same code in every entry, and LLVM optimizes and emits each entry's
callees again inside it: written as loops, vectorized, versioned for overlap and unrolled,
they were most of each entry's code (gather and put about 8,000 of the 9,500 lines of a
Cook-Torrance entry's optimized IR) and about a third of its compile time (Cook-Torrance's six
entries 7.0 s of CPU with both emptied, against 10.4-11.4 s; ad hoc, a fresh cache), and slower
than ``memcpy`` at run time.

The facet kernel's block first takes its polar angles' cosines and sines and its coating in a
pass of its own (:func:`facet_prepass`), which skips the coating's refraction where the
block has none; its loop (:func:`~scatterbench.models.kernels.facet.facet_lanes`) reads them.

The kernels are the same functions as the scalar loop's, so both give the same bits
(``tests/test_vector_kernels.py``).  :func:`vectorized` says which models and options take this
path.  The others keep C library calls that leave any loop scalar (FacetBTDF, anisotropic
slopes, unit slopes); :class:`scatterbench.models.kernels.Compiled` runs them through
:mod:`~scatterbench.models.kernels.drive`.  Smith shadowing takes the lanes (its ``erfc``,
``exp(-mu^2)`` and ``hypot`` are :mod:`~scatterbench.models.kernels.vector_math`'s): the facet
kernel's of isotropic Gaussian and GGX slopes, and Cook-Torrance's, isotropic or elliptical by
its parameters, the ellipse's rotation given as the strokes' azimuth's cosine and sine
(parameter rows) rather than through the C library.
"""

from __future__ import annotations

import numpy as np
from numba.core import config

from ..kernel_specs import COOK_SHADOWING, EXPONENTIAL, GAUSSIAN, GGX, RUNTIME, SHADOWING_KINDS
from .common import NO_SHADOWING, azimuths_at, polar
from .drive import COOK, DIFFUSE, FACET, MAXWELL, NAMES, PARAM_ROWS, ROWS, SINGLE, own_kernel
from .facet import coating, facet_lanes
from .helper import caching_in, helper
from .memory import STREAM_MIN, copy_into, copy_rows, fill, line_aligned, pick_rows

#: geometries per block: the scratch, :data:`_ROWS` rows of them in float64 (90 kB), stays
#: in the L2 cache
VBLOCK = 256
#: scratch rows: angles, azimuth cosine and sine, the 16 result rows, the parameters, and the
#: facet kernel's polar cosines and sines and coating (:func:`facet_prepass`)
_TI, _TR, _PR, _CP, _SP, _OUT, _PRM = 0, 1, 2, 3, 4, 5, 21
_PRE = _PRM + PARAM_ROWS
_ROWS = _PRE + 13
#: the facet kernel's slope kinds that vectorize (the anisotropic ones rotate by a parameter
#: through the C library's cosine; the unit one is left to the scalar loop: each kind costs
#: about 2 s of compilation)
FACET_KINDS = (EXPONENTIAL, GAUSSIAN, GGX)
#: the facet kernel's shadowing on the lanes: Smith's separable and height-correlated ``G`` of the
#: isotropic slope kinds whose ``Lambda`` is in closed form (the exponential's is numpy's table)
SMITH_KINDS, SMITH_FORMS = (GAUSSIAN, GGX), (SHADOWING_KINDS["smith"], SHADOWING_KINDS["smith-correlated"])
BLINN, NO_COOK_SHADOWING, COOK_SMITH = (
    COOK_SHADOWING["blinn"],
    COOK_SHADOWING["none"],
    COOK_SHADOWING["smith"],
)


def vectorized(code, iopt) -> bool:
    """Whether kernel ``code`` with options ``iopt`` takes the vector path (float64)."""
    if code == FACET:
        return iopt[0] in FACET_KINDS and (
            iopt[1] == NO_SHADOWING or (iopt[0] in SMITH_KINDS and iopt[1] in SMITH_FORMS)
        )
    if code == COOK:
        return True
    if code == MAXWELL:
        return iopt[0] in FACET_KINDS
    return code in (SINGLE, DIFFUSE)


# The scratch accessors index it directly (a helper per element, 19 per facet geometry, made
# compiling the facet task's loops inline 175 functions), and are helpers (kernels.helper), typed
# and lowered once per process, not numba's inline="always", which did that again in each of a
# report's 17 lane entries: the two largest compile-ahead groups took 1.0-1.7 s less CPU each
# (a fresh process and cache per group, two rounds alternating with 9c66b1a, ad hoc); LLVM
# inlines them, and the entries' code is the same (the array's reference counts pruned: 13
# increments and 32 decrements in each entry either way, the facet entry's 4522 lines of
# assembly both).


@helper
def _geometry(sc, k):
    """Geometry ``k`` of the scratch, as :func:`scatterbench.models.kernels.drive.geometry` gives it."""
    B = VBLOCK
    return sc[_TI * B + k], sc[_TR * B + k], sc[_PR * B + k], sc[_CP * B + k], sc[_SP * B + k]


@helper
def _facet_geometry(sc, k):
    """:func:`_geometry` followed by the rows :func:`facet_prepass` filled (:func:`~scatterbench.models.kernels.facet.facet_lanes`' ``ge``)."""
    B, o = VBLOCK, _PRE * VBLOCK + k
    return _geometry(sc, k) + (
        sc[o], sc[o + B], sc[o + 2 * B], sc[o + 3 * B], sc[o + 4 * B], sc[o + 5 * B], sc[o + 6 * B],
        sc[o + 7 * B], sc[o + 8 * B], sc[o + 9 * B], sc[o + 10 * B], sc[o + 11 * B], sc[o + 12 * B],
    )  # fmt: skip


@helper(forceinline=None)
def facet_prepass(sc, m):
    """The facet kernel's polar cosines and sines, and its :func:`~scatterbench.models.kernels.facet.coating`
    for the block's ``m`` geometries, into the scratch rows from :data:`_PRE`: the coating's own
    loop only where a column of the block has one (``n != 1``), otherwise its values for
    ``n = 1``, the outer angles and ones.  A loop on SIMD lanes computes both sides of a branch,
    so that the coating inside the kernel's loop (two square roots and three divisions a geometry)
    cost an uncoated FacetBRDF about 7% of its time; a loop per case (its kernel compiled twice)
    cost 1.1 s of a cold cache per option set (5.6 s for a report's five), this pass about 0.2 s
    (both ad hoc: ``kernels.warm`` of the five in a fresh process, an empty cache)."""
    coated = 0
    for k in range(m):
        coated += sc[_PRM * VBLOCK + k] != 1.0
    if coated:
        for k in range(m):
            _coating_at(sc, k, sc[_PRM * VBLOCK + k])
    else:
        for k in range(m):
            _coating_at(sc, k, 1.0)


@helper
def _coating_at(sc, k, n):
    """Geometry ``k``'s polar cosines and sines and their
    :func:`~scatterbench.models.kernels.facet.coating` into its 13 scratch rows (written out, as
    :func:`_store`)."""
    pol_i, pol_r = polar(sc[_TI * VBLOCK + k]), polar(sc[_TR * VBLOCK + k])
    v = coating(pol_i, pol_r, n)
    B, o = VBLOCK, _PRE * VBLOCK + k
    sc[o], sc[o + B], sc[o + 2 * B], sc[o + 3 * B] = pol_i[0], pol_i[1], pol_r[0], pol_r[1]
    o += 4 * B
    sc[o], sc[o + B], sc[o + 2 * B], sc[o + 3 * B], sc[o + 4 * B] = v[0], v[1], v[2], v[3], v[4]
    sc[o + 5 * B], sc[o + 6 * B], sc[o + 7 * B], sc[o + 8 * B] = v[5], v[6], v[7], v[8]


@helper
def _no_prepass(sc, m):
    """The other kernels' (their loop computes all it needs)."""


@helper
def _scratch_params(sc, k):
    """Geometry ``k``'s parameters (:func:`gather` copied them)."""
    B, o = VBLOCK, _PRM * VBLOCK + k
    return (sc[o], sc[o + B], sc[o + 2 * B], sc[o + 3 * B], sc[o + 4 * B], sc[o + 5 * B],
            sc[o + 6 * B], sc[o + 7 * B], sc[o + 8 * B], sc[o + 9 * B], sc[o + 10 * B])  # fmt: skip


@helper
def _store(sc, k, m):
    """The 16 elements ``m`` into the result rows, column ``k`` (written out: a loop over a
    tuple's index compiles to a switch, which keeps the loop around it scalar)."""
    B, o = VBLOCK, _OUT * VBLOCK + k
    sc[o], sc[o + B], sc[o + 2 * B], sc[o + 3 * B] = m[0], m[1], m[2], m[3]
    sc[o + 4 * B], sc[o + 5 * B], sc[o + 6 * B], sc[o + 7 * B] = m[4], m[5], m[6], m[7]
    sc[o + 8 * B], sc[o + 9 * B], sc[o + 10 * B], sc[o + 11 * B] = m[8], m[9], m[10], m[11]
    sc[o + 12 * B], sc[o + 13 * B], sc[o + 14 * B], sc[o + 15 * B] = m[12], m[13], m[14], m[15]


@helper(forceinline=None)
def shared(sc, ti, tr, pr, prm, index, m, rows):
    """Once per call, the scratch rows that every block shares, in its first ``m`` columns: the
    angles as if each were one value (:func:`gather` then copies over those that are not) and,
    for parameters shared by every geometry (one column), the first ``rows`` parameter rows.
    A single model's parameters are then not copied again per block."""
    fill(sc, _TI * VBLOCK, m, ti[0])
    fill(sc, _TR * VBLOCK, m, tr[0])
    fill(sc, _PR * VBLOCK, m, pr[0])
    if index.shape[0] == 1 and prm.shape[1] == 1:
        for r in range(rows):
            fill(sc, (_PRM + r) * VBLOCK, m, prm[r, index[0]])


@helper(forceinline=None)
def gather(sc, ti, tr, pr, prm, index, lo, m, turns, rows):
    """Geometries ``lo .. lo + m - 1`` of the inputs into the scratch (over what :func:`shared`
    wrote): angles given per geometry, the azimuth's cosine and sine
    (:func:`~scatterbench.models.kernels.common.azimuths_at`), and
    the first ``rows`` parameter rows, those the kernel reads, when the parameters are per
    geometry (the columns :func:`~scatterbench.models.kernels.drive.column` reads), the copies
    ``memcpy`` (:func:`copy_into`, :func:`copy_rows`) or, a column per geometry picked,
    :func:`pick_rows`.  Branches, not the arithmetic of ``column``: LLVM
    unswitched the loop of that on its selects, a copy per case."""
    if ti.shape[0] > 1:
        copy_into(sc, _TI * VBLOCK, ti, lo, m)
    if tr.shape[0] > 1:
        copy_into(sc, _TR * VBLOCK, tr, lo, m)
    if pr.shape[0] > 1:
        copy_into(sc, _PR * VBLOCK, pr, lo, m)
    if turns:  # a constant of the kernel: only the diffuse one reads no azimuth
        azimuths_at(sc, _PR * VBLOCK, sc, _CP * VBLOCK, sc, _SP * VBLOCK, m)
    if index.shape[0] > 1:  # a column per geometry, picked
        pick_rows(sc, _PRM * VBLOCK, VBLOCK, prm, index, lo, rows, m)
    elif prm.shape[1] > 1:  # a column per geometry, in order from index[0]
        copy_rows(sc, _PRM * VBLOCK, VBLOCK, prm, index[0] + lo, prm.shape[1], rows, m, False)


@helper(forceinline=None)
def put(out, sc, at, m):
    """The block's ``m`` result columns of every row of ``out`` (C-contiguous) from the scratch
    into ``out[:, at:at + m]``, a ``memcpy`` a row, streamed to memory for a result of more than
    :data:`~scatterbench.models.kernels.memory.STREAM_MIN` elements (a result the caches do not
    hold, written to memory without reading it first)."""
    n = out.shape[1]
    copy_rows(out, at, n, sc, _OUT * VBLOCK, VBLOCK, out.shape[0], m, out.size > STREAM_MIN)


def lane_options(code, iopt) -> tuple:
    """The options kernel ``code``'s lanes are compiled for: those its kernel reads, as
    constants (a loop per slope kind, phase, varnish, shadowing), so that the branches left in
    the loop are selects and each variant compiles only when a model uses it; :data:`RUNTIME`
    where the loop reads the option from ``iopt`` instead (Cook-Torrance's convention, a choice
    of scale: a loop per convention cost ~3 s more of a cold cache each, for nothing at run time)."""
    o0, o1, o2 = (int(x) for x in iopt[:3])
    kind = o0 if o0 in (EXPONENTIAL, GAUSSIAN) else GGX
    if code == FACET:
        return (kind, o1, 0)
    if code == SINGLE:
        return (int(o0 != 0), 0, 0)
    if code == DIFFUSE:
        return (0, 0, 0)
    if code == COOK:  # the convention is one scale or another: read at run time
        return (int(o0 == 1), RUNTIME, o2)
    return (kind, NO_SHADOWING, o2)  # MAXWELL


def entry(code, opts):
    """The one compiled entry of kernel ``code``'s loop on SIMD lanes with options ``opts``
    (:func:`lane_options`), a closure over those ints: ``run_range(ti, tr, pr, prm, index, iopt,
    out, start, lo, hi)``, the arguments of the scalar loop's
    (:func:`scatterbench.models.kernels.drive.entry`; ``iopt`` read only for the options
    :data:`RUNTIME`), without the GIL: geometries ``lo .. hi - 1`` into ``out[:, start + i]``, a
    block at a time.  Serial, parallel and checked calls are this loop called from Python
    (:func:`scatterbench.models.kernels.threads.spread`): a compiled caller links the loop's code
    into its own and LLVM optimizes it again (a ``prange`` entry and a checked one took 7.8 s
    and 3.0 s per option set beside the loop's own 6.2 s, Cook-Torrance on a cold cache).

    The kernel is the loop's own (:func:`~scatterbench.models.kernels.drive.own_kernel`), and so
    are the options, closure cells (ints: numba folds them, and they key the cache), those
    :data:`RUNTIME` read from ``iopt``; they reach the kernel typed int64, not as literals, so
    that numba types the kernel once per kernel, not once per option set (17 sets in a report:
    35 s of a cold run), and LLVM, inlining it, still folds them."""
    k0, k1, k2 = opts
    r0, r1, r2 = (k == RUNTIME for k in opts)
    # the diffuse kernel reads no azimuth: its blocks skip the cosines and sines (a tenth of its time)
    turns = code != DIFFUSE
    rows = len(ROWS[NAMES[code]])

    def run_range(ti, tr, pr, prm, index, iopt, out, start, lo, hi):
        o = (
            iopt[0] if r0 else np.int64(k0),
            iopt[1] if r1 else np.int64(k1),
            iopt[2] if r2 else np.int64(k2),
        )
        sc = line_aligned(_ROWS * VBLOCK)
        unread = (_PRM + rows) * VBLOCK  # the parameter rows the kernel does not read: never gathered
        fill(sc, unread, sc.size - unread, 0.0)
        # the parameter rows to copy, a count LLVM cannot fold: with the constant, it unrolled
        # shared's and gather's row loops in full, a vectorized inner loop per row, in every entry
        copied = min(rows, prm.shape[0])
        shared(sc, ti, tr, pr, prm, index, min(VBLOCK, hi - lo), copied)
        for blo in range(lo, hi, VBLOCK):
            m = min(VBLOCK, hi - blo)
            gather(sc, ti, tr, pr, prm, index, blo, m, turns, copied)
            _PREPASS(sc, m)  # noqa: F821
            for k in range(m):
                _store(sc, k, _KERNEL(_GEOMETRY(sc, k), _scratch_params(sc, k), o))  # noqa: F821
            put(out, sc, start + blo, m)

    tag = "_".join("r" if k == RUNTIME else str(k) for k in opts)
    if code == FACET:  # its coating computed apart (facet_prepass), per block
        return own_kernel(
            run_range, code, tag, _KERNEL=facet_lanes, _GEOMETRY=_facet_geometry, _PREPASS=facet_prepass
        )
    return own_kernel(run_range, code, tag, _GEOMETRY=_geometry, _PREPASS=_no_prepass)


#: numba's cache directory when this module was imported (:mod:`scatterbench.models.kernels`
#: sets it then): the entries made later cache there too
_CACHE_DIR = config.CACHE_DIR
_ENTRIES = {}


def option_sets(code) -> list:
    """Every option set :func:`lane_options` gives kernel ``code`` (20 in all): what
    :func:`scatterbench.models.kernels.warm` compiles."""
    if code == FACET:
        return [(k, NO_SHADOWING, 0) for k in FACET_KINDS] + [
            (k, f, 0) for k in SMITH_KINDS for f in SMITH_FORMS
        ]
    if code == SINGLE:
        return [(0, 0, 0), (1, 0, 0)]
    if code == DIFFUSE:
        return [(0, 0, 0)]
    if code == COOK:
        return [(a, RUNTIME, c) for a in (0, 1) for c in (NO_COOK_SHADOWING, BLINN, COOK_SMITH)]
    if code == MAXWELL:
        return [(k, NO_SHADOWING, c) for k in FACET_KINDS for c in (0, 1)]
    return []  # no lanes (FacetBTDF)


def lane_entries(code, iopt):
    """The vector loop of kernel ``code`` with options ``iopt`` (:func:`entry`): made on first
    use, once per process (there are 20 variants; a run uses a few)."""
    return lanes_of(code, lane_options(code, iopt))


def lanes_of(code, opts):
    """The vector loop (:func:`entry`) of kernel ``code`` with the option set ``opts`` (:func:`lane_options`)."""
    key = (int(code), tuple(int(x) for x in opts))  # ints: the closures' cells key the cache
    got = _ENTRIES.get(key)
    if got is None:
        with caching_in(_CACHE_DIR):  # numba reads it when decorating; one thread at a time
            got = _ENTRIES.get(key)  # another thread's, made while this one waited
            if got is None:
                got = _ENTRIES[key] = entry(*key)
    return got
