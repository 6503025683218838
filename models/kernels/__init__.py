"""Compiled kernels: fused float64 (and float32) loops for the closed-form models (numba).

One function per model evaluates one geometry in real arithmetic, with no temporaries
(:mod:`~scatterbench.models.kernels.facet`, :mod:`~scatterbench.models.kernels.volume`, :mod:`~scatterbench.models.kernels.cook`,
:mod:`~scatterbench.models.kernels.maxwell`, sharing :mod:`~scatterbench.models.kernels.common`);
:mod:`~scatterbench.models.kernels.drive` loops it over a range of flat arrays, without the GIL;
:func:`~scatterbench.models.kernels.threads.spread` runs that loop serially for small calls and on ranges over the cores (Python
threads) from :data:`PARALLEL_MIN` geometries on, writing the element-major ``(16, N)``
result directly.  Parameters are per element (a model set) or shared, so a
likelihood evaluates all walkers of an emcee step in one call.  Float64 calls of the models
whose kernels have no C library call left (:func:`~scatterbench.models.kernels.vector.vectorized`: the
facet reflection models and Maxwell-Beard with exponential, Gaussian or GGX slopes and no
shadowing, single scattering, the diffuse subsurface, both Cook-Torrance forms without Smith
shadowing) run
:mod:`~scatterbench.models.kernels.vector`'s loops instead, which
compile to SIMD instructions (:mod:`~scatterbench.models.kernels.vector_math`: polynomial cosines, sines,
exponentials and arctangents) and give the scalar loop's bits.

The numpy implementation of every model stays the reference (``with models.backend("numpy")``);
the tests hold the kernels to it within 1e-12 relative to ``M00``.  A model's
``_kernel_spec`` says which kernel covers it and which options fall back to numpy.

Compilation happens once per machine: numba's on-disk cache (``cache=True``) lives in
``$NUMBA_CACHE_DIR/scatterbench-<hash>`` or, without that variable, in the user's cache
directory (``$XDG_CACHE_HOME`` or ``~/.cache``, then the temporary directory), never next
to an installed, read-only package.  ``<hash>`` covers every kernel source file, so an
edit to a shared helper recompiles the kernels that inline it (numba alone only notices
changes to the file of the function itself).

A first ``scatterbench report`` on worker processes compiles the kernels ahead, a group of
kernels that share helpers per process at once (:func:`warm`,
``validation.report.build.compile_ahead``); elsewhere each entry compiles on its first call.

Only the loops that Python calls are cached: per kernel and precision the scalar
``run_range`` of :data:`~scatterbench.models.kernels.drive.ENTRIES`, and per kernel and option set
the vector ``run_range`` of :func:`~scatterbench.models.kernels.vector.lane_entries` (each with
its kernel of its own, :func:`~scatterbench.models.kernels.drive.own_kernel`, so that a run
compiles only the kernels its models use, and the loop written in the entry: each compiled
level between an entry and its kernel cost another optimization of the inlined kernel), ``angles_ok``
of :mod:`~scatterbench.models.kernels.drive`, :mod:`~scatterbench.models.kernels.montecarlo`'s
``_range`` and ``_exit_range``, :mod:`~scatterbench.models.kernels.rough`'s ``_moments``
and ``write``, :mod:`~scatterbench.models.kernels.aperture`'s
``nodes`` and ``_tiles``, and :mod:`~scatterbench.models.kernels.disc`'s ``points``, each compiled by
:func:`~scatterbench.models.kernels.helper.entry_point`; a cached entry holds the code of
everything it calls.  The functions they call are not cached, because numba loads a cached
function as object code, without the LLVM IR that inlining needs: an entry compiled in a
process that had loaded its kernel from the cache called it instead of inlining it, which
left the loop scalar (CookTorranceBRDF's vector loop ran at 0.118 instead of 0.065 us per
geometry, depending on which process had filled the cache first).  Uncached, every callee
is compiled with its IR in the process that compiles an entry, so the code an entry gets
does not depend on the order in which processes filled the cache.

The kernels' helpers are overloads of themselves
(:func:`~scatterbench.models.kernels.helper.helper`: no Python or C wrapper, one copy for
all literal arguments), inlined by LLVM (``forceinline=True``), not by numba
(``inline="always"``, which types and lowers a callee's body again at every call site): the
report's compile-ahead tasks took 101.9 s of CPU with numba's inlining and 80.9 s with LLVM's
(one process, empty cache, the helper of the same session's other work sharing the 2 cores;
``python benchmarks/scaling.py --compile``), the loops as fast and as vectorized.  A helper may
take an array: numba counts the references a call passes, and prunes them once LLVM has
inlined it (:mod:`~scatterbench.models.kernels.vector`'s scratch accessors, called once or
twice per geometry, leave the lane entries' code as it was with numba's inlining).  Only
loops between an entry and its helpers keep numba's inlining, each called at one place in an
entry (:mod:`~scatterbench.models.kernels.aperture`'s node and tile loops,
:mod:`~scatterbench.models.kernels.montecarlo`'s entry table and blocks,
:func:`~scatterbench.models.kernels.common.azimuths_at`, the azimuths' loop of the lanes'
``gather``: as a helper it cost eight lane entries about 0.2 s more of LLVM, ad hoc): numba compiles a function
that is not inlined into a module of its own, optimizes it and emits its machine code, then
optimizes it again in each caller, while one typed once at its one call site costs nothing
more (the aperture's entries 4.0-4.35 s of CPU instead of 4.9-6.7 s, a fresh cache, ad hoc,
a study sharing the cores).
"""

from __future__ import annotations

import hashlib
import logging
import math
import os
import tempfile

import numpy as np

from .. import evaluation, smooth_interface
from ..float32_domain import ANGLE_ROWS
from .helper import caching_in as _caching_in
from .threads import spread

__all__ = ["Compiled", "PARALLEL_MIN", "cache_dir"]

#: geometries from which the kernels run on every core (below: the serial loop, which has
#: no thread start-up cost).  A fit's half-ensemble step is 16 walkers x ~110 rows: from
#: 8192 down to 1024 its likelihood evaluations rose from 24,786 to 27,867 per second (the
#: ``fit`` command of ``benchmarks/fit_speed.py``, best of three runs each, 2 cores); small
#: calls (<= 100 geometries) stay serial
PARALLEL_MIN = 1024
#: geometries per buffer of :meth:`Compiled.accumulate`: 16 rows of them (512 kB) stay in the cache
ADD_CHUNK = 4096
_HALF_PI = 0.5 * math.pi
_FLOAT64 = np.dtype(np.float64)
_DTYPES = {"float64": _FLOAT64, "float32": np.dtype(np.float32)}
_HERE = os.path.dirname(os.path.abspath(__file__))


def _source_hash() -> str:
    h = hashlib.sha256()
    for name in sorted(os.listdir(_HERE)):
        if name.endswith(".py"):
            with open(os.path.join(_HERE, name), "rb") as fh:
                h.update(name.encode() + fh.read())
    return h.hexdigest()[:16]


def _writable(path) -> bool:
    try:
        os.makedirs(path, exist_ok=True)
    except OSError:
        return False
    return os.access(path, os.W_OK)


def cache_dir() -> str:
    """Where the compiled kernels are cached (see the module docstring)."""
    sub = f"scatterbench-{_source_hash()}"
    env = os.environ.get("NUMBA_CACHE_DIR")
    bases = [env] if env else []
    bases.append(os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "numba"))
    bases.append(
        os.path.join(tempfile.gettempdir(), f"numba-cache-{os.getuid() if hasattr(os, 'getuid') else 0}")
    )
    for base in bases:
        if _writable(os.path.join(base, sub)):
            return os.path.join(base, sub)
    return ""  # nowhere writable: compile in every process


with _caching_in(cache_dir()):
    # every module with a cached entry, those the models import themselves too (montecarlo:
    # RoughDiffuseBRDF's Monte Carlo; aperture, disc: DetectorAperture's and PointSourceBRDF's
    # node algebra): one first imported elsewhere would cache beside the package
    from . import aperture, disc, drive, montecarlo, rough, vector  # noqa: E402, F401  (decorated here, cached there)


def rbar_integrand():
    """R-bar's compiled integrand (:mod:`~scatterbench.models.kernels.rbar`, a ``cfunc``), imported
    on first use: a ``cfunc`` compiles (or loads from the cache) when decorated, and only models
    with a smooth interface need it.  Imported here, so that it caches with the kernels."""
    with _caching_in(cache_dir()):
        from . import rbar
    return rbar.integrand


# R-bar's quadrature (an ingredient, below the kernels) takes its compiled integrand from here
smooth_interface.INTEGRAND_SOURCE = rbar_integrand

#: says when a kernel compiles (the command line shows it: ``scatterbench.validation.cli``)
log = logging.getLogger(__name__)
_READY = set()  # the entries this process has called (loaded from the cache or compiled)
_SAID = set()  # the kernels this process has said it compiles


def uncached(fn, sig=None) -> bool:
    """Whether numba's on-disk cache lacks the cached entry ``fn`` (False for a Python function:
    ``NUMBA_DISABLE_JIT=1``); with ``sig`` (argument types), its compilation for those: an
    entry's index holds each signature compiled (the scalar loops' float64 and float32), so
    that its file alone said a float32 loop was cached once the float64 one was."""
    cache = getattr(fn, "_cache", None)
    if cache is None or not os.path.exists(cache._cache_file._index_path):
        return cache is not None
    if sig is None:
        return False
    # numba's own key of an overload in the index (the index is {} when the source changed)
    return cache._index_key(sig, fn.targetctx.codegen()) not in cache._cache_file._load_index()


def _announced(fn):
    """``fn``, after saying, on the first call in this process of an entry of a kernel that is
    not in the cache yet, that the kernel compiles (once per kernel, not per entry: a first
    report printed 64 lines): the command line shows that the kernels compile once per machine."""
    if fn not in _READY:
        _READY.add(fn)
        if uncached(fn):
            cache = fn._cache
            kernel = getattr(fn.py_func, "kernel", fn.__name__)  # drive.named's
            if kernel not in _SAID:
                # the cache folder once per process
                where = "" if _SAID else f": cached in {cache._cache_path}"
                _SAID.add(kernel)
                log.info("compiling the %s kernel (once per machine%s)", kernel, where)
    return fn


def announce(names, how=""):
    """Say that the kernels ``names`` compile (``how``: e.g. on how many processes), once per
    kernel and process: :func:`_announced` is then silent for their entries."""
    todo = [k for k in dict.fromkeys(names) if k not in _SAID]
    if todo:
        where = f" {how}" if how else ""
        log.info(
            "compiling the %s kernels%s (once per machine: cached in %s)", ", ".join(todo), where, cache_dir()
        )
        _SAID.update(todo)


def _signature(precision):
    """The argument types :class:`Compiled` calls a kernel's loop (``run_range``) with in ``precision``."""
    from numba import types

    f = getattr(types, precision)
    a1, a2, i = types.Array(f, 1, "C"), types.Array(f, 2, "C"), types.int64
    ia = types.Array(types.int64, 1, "C")  # the parameter index (drive.column), then the options
    return (a1, a1, a1, a2, ia, ia, a2, i, i, i)


def within(a, low, high) -> bool:
    """Whether every value of the flat, C-contiguous float64 array ``a`` lies in ``[low, high]``
    (NaN does not): one compiled pass, in ranges on the kernels' threads
    (:func:`~scatterbench.models.kernels.threads.spread`).  numpy's ``min``, ``max`` and
    ``isfinite`` took ~22 ms of one thread for three 10^7-value angle arrays, a quarter of a
    16-thread evaluation of them (benchmarks/scaling.py)."""
    bad = np.zeros(1, dtype=np.int64)
    spread(_announced(drive.outside_range), (a, float(low), float(high), bad), a.shape[0], WITHIN_GRAIN)
    return not bad[0]


#: values per range of :func:`within`: a range costs about a microsecond of calls and waits
WITHIN_GRAIN = 1 << 16
evaluation.register_range_check(within)


def _other_entries(name):
    """``(entry, signature)`` of the cached entries of module ``name`` (``"montecarlo"``,
    ``"aperture"``, ``"disc"``; ``"angles"``: :func:`~scatterbench.models.kernels.drive.angles_ok`),
    for the argument types their models pass."""
    from numba import types

    f, i, b = types.float64, types.int64, types.boolean
    a1, a2, ro = types.Array(f, 1, "C"), types.Array(f, 2, "C"), types.Array(f, 1, "C", readonly=True)
    if name == "montecarlo":  # RoughDiffuseBRDF
        return [(montecarlo._range, (a1,) * 5 + (a2, a2, a1, f, a2, a2, i, i)),
                (montecarlo._exit_range, (a1, a1, a1, a2, a2, f, a1, i, i))]  # fmt: skip
    if name == "aperture":  # DetectorAperture (its node table is read-only)
        return [
            (aperture.nodes, (a1, a1, a1, ro, ro, ro, ro, a2)),
            (aperture._tiles, (a2, a2, i, a2, i, i, i)),
        ]
    if name == "angles":  # the checks of the angles: small calls' (Compiled.fast), large arrays' (within)
        return [
            (drive.angles_ok, (a1, a1, a1)),
            (drive.outside_range, (a1, f, f, types.Array(i, 1, "C"), i, i)),
        ]
    if name == "rough":  # RoughSubsurfaceBRDF
        return rough.signatures()
    if name == "disc":  # PointSourceBRDF's disc quadrature
        return [(disc.points, (f, f, a1, a1, types.Array(b, 1, "C"), a1, a1) + (a2,) * 6)]
    raise KeyError(name)


def _warm_entries(kernel, precision, option_sets=None, scalar=True):
    """``(loop, signature)`` of the loops :class:`Compiled` may call for kernel ``kernel`` in
    ``precision``: the scalar one (unless ``scalar`` is false: a run whose models of this kernel
    all take the vector loop), and in float64 the vector one of each option set in
    ``option_sets`` (default: every one, :func:`~scatterbench.models.kernels.vector.option_sets`);
    for the name of another module with cached entries, those (:func:`_other_entries`)."""
    if kernel not in drive.CODES:
        return _other_entries(kernel)
    code, sig = drive.CODES[kernel], _signature(precision)
    loops = [drive.ENTRIES[code]] if scalar or precision != "float64" else []
    if precision == "float64":  # float32 has no lanes
        sets = vector.option_sets(code) if option_sets is None else option_sets
        loops += [vector.lanes_of(code, o) for o in sets]
    return [(fn, sig) for fn in loops]


def cold(kernel, precision="float64", option_sets=None, scalar=True) -> bool:
    """Whether a loop of :func:`warm`'s is not in the cache yet."""
    return any(uncached(fn, sig) for fn, sig in _warm_entries(kernel, precision, option_sets, scalar))


def warm(kernel, precision="float64", option_sets=None, scalar=True):
    """Compile (or load from the cache) the loops of kernel ``kernel`` (a name of
    :data:`~scatterbench.models.kernels.drive.CODES`, or ``"montecarlo"``, ``"aperture"``,
    ``"disc"``, ``"rough"``: those modules' entries) that :class:`Compiled` may call in
    ``precision`` (the vector ones of ``option_sets`` only, when given; the scalar one unless
    ``scalar`` is false), for the argument types
    it passes, without running them: a first run compiles the kernels on its worker processes
    at once, each a different group of kernels, before it needs them (``scatterbench
    report``).  One process per group: its kernels' loops share helpers, which each process
    compiles for itself.  Returns ``kernel``."""
    for fn, sig in _warm_entries(kernel, precision, option_sets, scalar):
        if hasattr(fn, "compile"):  # not a Python function (NUMBA_DISABLE_JIT=1)
            fn.compile(sig)
    return kernel


def _mutable(x):
    """``x``, or a copy of it when it is read-only (a cached array, a user's frozen one)."""
    return x if x.flags.writeable else x.copy()


def azimuth_as(pr, dtype):
    """Azimuths as ``dtype``: for float32, any beyond [-pi, pi] reduced there in float64 first
    (``atan2(sin, cos)``, whose argument reduction is exact), since a finite float64 azimuth
    such as 1e300 rounds to inf in float32 and its cosine is NaN, and a large one keeps none of
    its phase."""
    if dtype == np.float64:
        return pr.astype(dtype, copy=False)
    far = np.abs(pr) > math.pi
    if far.any():
        pr = np.where(far, np.arctan2(np.sin(pr), np.cos(pr)), pr)
    return pr.astype(dtype)


class Compiled:
    """A model's kernel: its code, parameter rows and options, and the calls into it.

    Parameters
    ----------
    model : Model
        The model (a single model, or a chunk of a model set whose array parameters are
        flat, one element per geometry).
    code : str
        The kernel (:data:`scatterbench.models.kernels.drive.CODES`).
    rows : sequence
        The kernel's parameter rows in order: floats, or flat arrays of one length.
    options : sequence of int
        The kernel's options (slope kind, shadowing, conventions).
    """

    def __init__(self, model, code, rows, options):
        assert len(rows) == len(drive.ROWS[code]), f"{code} kernel rows: {drive.ROWS[code]}"
        self.name = code
        self.code = drive.CODES[code]
        length = max((r.size if type(r) is np.ndarray else np.size(r) for r in rows), default=1)
        prm = np.zeros((drive.PARAM_ROWS, length))  # padded: every kernel takes the same tuple
        for k, r in enumerate(rows):
            prm[k] = r
        self.prm = {"float64": prm}
        self.iopt = np.zeros(drive.OPTIONS, dtype=np.int64)
        self.iopt[: len(options)] = options
        self.vectorized = vector.vectorized(self.code, self.iopt)

    # looked up, not held: a model pickled to a worker process carries its Compiled, and
    # numba's dispatchers do not pickle to the same (cached) functions
    @property
    def scalar(self):
        """The kernel's scalar loop (:data:`scatterbench.models.kernels.drive.ENTRIES`)."""
        return drive.ENTRIES[self.code]

    @property
    def lanes(self):
        """The kernel's loop on SIMD lanes (:func:`scatterbench.models.kernels.vector.lane_entries`)."""
        return vector.lane_entries(self.code, self.iopt)

    @property
    def _loop(self):
        """The float64 loop: on SIMD lanes for a vectorized kernel, whatever the call's size (one
        geometry costs 0.4 us more there than in the scalar loop, whose compilation a run of such
        models then skips: 3-8 s of CPU per kernel on a cold cache), else the scalar one."""
        return self.lanes if self.vectorized else self.scalar

    def params(self, precision):
        """The parameter rows in ``precision``; float32 rows take the angle rows (rotations)
        reduced to (-pi, pi] in float64 first, so that rounding keeps their cosines and sines."""
        p = self.prm.get(precision)
        if p is None:
            p = self.prm["float64"].copy()
            for k, name in enumerate(drive.ROWS[self.name]):
                if name in ANGLE_ROWS:
                    p[k] = np.arctan2(np.sin(p[k]), np.cos(p[k]))
            p = self.prm[precision] = p.astype(precision)
        return p

    def call(self, ti, tr, pr, out, start, precision="float64", index=None):
        """Evaluate flat angles (length 1 or n) into ``out[:, start:start + n]``; with ``index``
        (int64, C-contiguous, each in ``0 .. columns - 1``: :meth:`indexed` checks it), geometry ``k``
        takes parameter column ``index[k]`` and ``n`` is its length."""
        if index is None:
            n = max(ti.shape[0], tr.shape[0], pr.shape[0], self.prm["float64"].shape[1])
            index = drive.NO_INDEX
        else:
            n = index.shape[0]
        loop = self._loop if precision == "float64" else self.scalar
        # contiguous, writable inputs: one compiled specialization per entry and precision
        # (numba types a read-only array apart and compiles every kernel again, ~10 s cold)
        ti, tr, pr = (_mutable(np.ascontiguousarray(x)) for x in (ti, tr, pr))
        args = (ti, tr, pr, self.params(precision), _mutable(index), self.iopt, out, start)
        # below PARALLEL_MIN one range: a thread's start-up costs more than such a call
        grain = n if n < PARALLEL_MIN else drive.BLOCK
        spread(_announced(loop), args, n, grain)

    def indexed(self, index):
        """``index`` as :meth:`call` takes it (int64, C-contiguous, writable); a ``ValueError`` for
        a column outside the parameter rows (the loops do not check their reads)."""
        index = _mutable(np.ascontiguousarray(index, dtype=np.int64))
        if index.shape[0] and (index.min() < 0 or index.max() >= self.prm["float64"].shape[1]):
            raise ValueError(
                f"index: every entry must lie in [0, {self.prm['float64'].shape[1] - 1}] (the model set's elements)"
            )
        return index

    def accumulate(self, ti, tr, pr, out, index):
        """``out += `` the Mueller elements of flat float64 angles (length 1 or ``n``) with parameter
        columns ``index`` (:meth:`indexed`; ``out`` a C-contiguous float64 ``(16, n)`` ndarray):
        the bits of the elements written to an array of their own and added (the same sums),
        range by range over the cores, each range through a buffer of :data:`ADD_CHUNK` geometries
        that stays in the cache, where a whole second result (22 MB for a fit's 24 walkers x 7296
        rows) went through memory twice and was then added on one core."""
        n = index.shape[0]
        ti, tr, pr = (_mutable(np.ascontiguousarray(x)) for x in (ti, tr, pr))
        write = self.range_writer()

        def ranges(lo, hi):
            buf = np.empty((out.shape[0], ADD_CHUNK))
            for a in range(lo, hi, ADD_CHUNK):
                b = min(a + ADD_CHUNK, hi)
                write(ti, tr, pr, index, buf, a, b)
                part = out[:, a:b]
                np.add(part, buf[:, : b - a], out=part)

        spread(ranges, (), n, max(ADD_CHUNK, drive.BLOCK))

    def range_writer(self):
        """``write(ti, tr, pr, index, buf, lo, hi)``: geometries ``lo .. hi - 1`` of flat float64
        angles (C-contiguous, writable, length 1 or ``n``) with parameter columns ``index``
        (:meth:`indexed`) into ``buf[:, :hi - lo]`` (a C-contiguous float64 ``(rows, m)`` ndarray,
        ``m >= hi - lo``), on the calling thread: for callers that spread ranges over the cores
        themselves and use each while it is in the cache.  The loop is looked up once (a few us a
        call otherwise), and given the whole buffer (geometry ``i`` into column ``i - lo``), so
        that it sees one type."""
        loop, prm, iopt = _announced(self._loop), self.params("float64"), self.iopt

        def write(ti, tr, pr, index, buf, lo, hi):
            loop(ti, tr, pr, prm, index, iopt, buf, -lo, lo, hi)

        return write

    def run(self, ti, tr, pr, rows):
        """``(rows, n)`` float64 of flat float64 angles (:func:`scatterbench.models.evaluation.flat`'s kernel route)."""
        n = max(ti.shape[0], tr.shape[0], pr.shape[0], self.prm["float64"].shape[1])
        out = np.empty((rows, n))
        self.call(ti, tr, pr, out, 0)
        return out

    @staticmethod
    def in_place(out, precision) -> bool:
        """Whether :meth:`write` writes into ``out`` itself (a C-contiguous ndarray of
        ``precision``'s dtype) rather than through a buffer of the chunk's size."""
        return type(out) is np.ndarray and out.flags.c_contiguous and out.dtype == np.dtype(precision)

    def write(self, out, sl, ti, tr, pr, precision, index=None):
        """One chunk of flat float64 angles (length 1 or the chunk's) into ``out[:, sl]``,
        computed in ``precision`` (the float32 kernels for ``"float32"``): in place in a
        C-contiguous ndarray of that dtype, otherwise (a memmap; a float32 ``out`` filled by
        the float64 fallback) through a chunk-sized buffer; ``index``: the chunk's parameter
        columns (:meth:`call`)."""
        dtype = np.dtype(precision)
        a, b, c = ti.astype(dtype, copy=False), tr.astype(dtype, copy=False), azimuth_as(pr, dtype)
        if self.in_place(out, precision):
            self.call(a, b, c, out, sl.start, precision, index)
        else:
            buf = np.empty((out.shape[0], sl.stop - sl.start), dtype=dtype)
            self.call(a, b, c, buf, 0, precision, index)
            with np.errstate(over="ignore"):  # rounding to float32: finite32 judges the result
                out[:, sl] = buf

    def fast(self, theta_i, theta_r, phi_r, rows, precision="float64", out=None):
        """The small-call path: up to :data:`scatterbench.models.evaluation.KERNEL_CHUNK` geometries given
        as floats, ints, lists or float64/integer arrays that broadcast
        (:func:`scatterbench.models.evaluation.small_angles`), evaluated in ``precision`` (``"float64"`` or
        ``"float32"``), into ``out`` when given (a C-contiguous ``(rows, N)`` ndarray of that
        dtype); ``None`` for anything else or a bad angle (the general path then raises the
        error naming it)."""
        if precision == "float64" and out is None:
            one = self._one(theta_i, theta_r, phi_r, rows)
            if one is not None:
                return one
        small = evaluation.small_angles(theta_i, theta_r, phi_r, evaluation.KERNEL_CHUNK)
        if small is None:
            return None
        shape, n, angles = small
        ti, tr, pr = (_mutable(x) for x in angles)  # one specialization (see call)
        dtype = _DTYPES[precision]
        if out is None:
            out = np.empty((rows, n), dtype=dtype)
        elif not (type(out) is np.ndarray and out.shape == (rows, n) and out.dtype == dtype):
            return None
        elif not out.flags.c_contiguous:
            return None
        if not drive.angles_ok(ti, tr, pr):
            return None
        if dtype is _FLOAT64 and n < PARALLEL_MIN:
            _announced(self._loop)(ti, tr, pr, self.prm["float64"], drive.NO_INDEX, self.iopt, out, 0, 0, n)
        else:
            self.call(ti.astype(dtype), tr.astype(dtype), azimuth_as(pr, dtype), out, 0, precision)
        return out.reshape(shape) if rows == 1 else evaluation.as_matrices(out, shape)

    def _one(self, theta_i, theta_r, phi_r, rows):
        """One geometry given as three numbers, straight into the float64 loop; ``None`` for
        anything else (arrays, a bad angle)."""
        if type(theta_i) is float and type(theta_r) is float and type(phi_r) is float:
            a, b, c = theta_i, theta_r, phi_r
        else:
            scalars = evaluation.SCALARS
            if not (type(theta_i) in scalars and type(theta_r) in scalars and type(phi_r) in scalars):
                return None
            a, b, c = (evaluation.scalar(x) for x in (theta_i, theta_r, phi_r))
            if a is None or b is None or c is None:
                return None
        if not (0.0 <= a <= _HALF_PI and 0.0 <= b <= _HALF_PI and math.isfinite(c)):
            return None
        out = np.empty((rows, 1))
        _announced(self._loop)(
            np.full(1, a),
            np.full(1, b),
            np.full(1, c),
            self.prm["float64"],
            drive.NO_INDEX,
            self.iopt,
            out,
            0,
            0,
            1,
        )
        return out.reshape(4, 4) if rows == 16 else out.reshape(())
