"""How a model is evaluated: one route chooser for backend, precision, broadcasting,
chunks and model sets.

Every evaluation of a model goes through this module, and the choice between the routes is
made in one place each:

* :func:`compiled` chooses the implementation: the model's compiled kernel
  (:mod:`scatterbench.models.kernels`, numba) where one covers the model and its options and
  the numba backend is selected (the default), otherwise the numpy implementation
  (``_mueller16``, ``_brdf_flat``), the reference path the kernels are tested against
  (``with models.backend("numpy"): ...`` selects it for everything);
* :func:`flat` is the named internal entry for angles that were validated already (flat
  float64 arrays, a single model or a chunk of a model set): wrappers (point source,
  aperture), sums and the Monte Carlo's surface term evaluate their inner models through it.
  A model set whose numpy implementation takes scalar parameters only is evaluated one
  distinct parameter element at a time (:func:`each`);
* :func:`evaluate` is the route of a user's call (``mueller``, ``mueller16``, ``brdf``):
  a small call of a single compiled model straight into its kernel (:func:`small`), or the
  angles validated and broadcast once (:class:`Plan`) and evaluated chunk by chunk
  (:func:`fill`); :func:`blocks` streams the same chunks (``iter_mueller``), and
  :class:`FixedAngles` keeps one set of validated angles for many models (a fit's rows)
  (:meth:`scatterbench.models.base.Model.flat_mueller16_indexed` evaluates a small model set
  gathered per geometry: a fit's walkers x wavelengths over its rows);
* :func:`kernel_precision` decides, once per model, whether a float32 request runs the
  float32 kernel or the float64 one (:mod:`scatterbench.models.float32_domain`).

Chunks bound memory however many geometries there are: the numpy path's temporaries
stay in cache (:data:`CHUNK`), a kernel keeps none and takes longer chunks
(:data:`KERNEL_CHUNK`).
"""

from __future__ import annotations

import contextlib
import contextvars
import math

import numpy as np

from .modelset import with_leaves
from .params import check_finite_array, check_polar_angle

__all__ = [
    "backend",
    "current_backend",
    "BACKENDS",
    "PRECISIONS",
    "CHUNK",
    "KERNEL_CHUNK",
    "compiled",
    "flat",
    "evaluate",
    "small",
    "blocks",
    "Plan",
    "FixedAngles",
    "small_angles",
    "as_matrices",
    "float32_guarded",
    "finite32",
    "check_out",
    "raw_float32",
    "kernel_precision",
]

#: Geometries per chunk on the numpy path, chosen so a model's float64 temporaries stay in
#: L2 cache: the smallest size of the flat optimum (``python benchmarks/chunk_size.py``:
#: 4096-32768 within 4% of each other for the facet models here, 1024 32-38% slower).
CHUNK = 4096
#: Geometries per chunk on the kernel path (no temporaries; bounds the gathered inputs and,
#: when streaming, the blocks handed out: 16 x 8 bytes x 65536 = 8 MB).
KERNEL_CHUNK = 1 << 16
BACKENDS = ("numba", "numpy")
PRECISIONS = ("float64", "float32")

_BACKEND = contextvars.ContextVar("scatterbench_backend", default="numba")


def current_backend() -> str:
    """The backend models evaluate with here: ``"numba"`` (kernels where they exist) or ``"numpy"``."""
    return _BACKEND.get()


@contextlib.contextmanager
def backend(name: str):
    """Evaluate every model with ``name``'s implementation inside the ``with`` block.

    ``"numba"`` (the default): the compiled kernels for the closed-form models (numpy
    for the options and models they do not cover); ``"numpy"``: the numpy reference
    implementation everywhere.
    """
    if name not in BACKENDS:
        raise ValueError(f"backend must be one of {', '.join(map(repr, BACKENDS))}; got {name!r}")
    token = _BACKEND.set(name)
    try:
        yield
    finally:
        _BACKEND.reset(token)


_FLOAT32_GUARD = contextvars.ContextVar("scatterbench_float32_guard", default=True)


def float32_guarded() -> bool:
    """True (the default) when float32 requests outside a model's float32-safe domain are
    evaluated in float64 (:mod:`scatterbench.models.float32_domain`)."""
    return _FLOAT32_GUARD.get()


@contextlib.contextmanager
def raw_float32():
    """Run the float32 kernels inside the ``with`` block even outside their float32-safe
    domain (:mod:`scatterbench.models.float32_domain`): for tests of the kernels themselves (finite at
    the ends of the declared ranges), never for results."""
    token = _FLOAT32_GUARD.set(False)
    try:
        yield
    finally:
        _FLOAT32_GUARD.reset(token)


def check_precision(precision):
    if precision not in PRECISIONS:
        raise ValueError(f"precision must be one of {', '.join(map(repr, PRECISIONS))}; got {precision!r}")
    return precision


def checked_angles(model, theta_i, theta_r, phi_r):
    """The three angle inputs as float64 arrays, each validated under ``model``'s names for
    them (two polar angles in [0, pi/2], a finite azimuth)."""
    n1, n2, n3 = model._angle_names
    return [
        _checked(check_polar_angle, n1, theta_i, 0.0, _HALF_PI),
        _checked(check_polar_angle, n2, theta_r, 0.0, _HALF_PI),
        _checked(check_finite_array, n3, phi_r, -_LARGEST, _LARGEST),
    ]


_HALF_PI, _LARGEST = 0.5 * math.pi, float(np.finfo(np.float64).max)
#: from this many values a C-contiguous float64 angle array is checked by one compiled pass on
#: the kernels' threads (:func:`scatterbench.models.kernels.within`) instead of numpy's
#: reductions, which run on one thread
PARALLEL_CHECK = 1 << 18
#: the compiled check ``within(a, low, high) -> bool``: registered by
#: :mod:`scatterbench.models.kernels` when it loads (it sits above this module: the layers)
_WITHIN = []


def register_range_check(fn):
    """Check large angle arrays with ``fn(a, low, high) -> bool`` (whether every value of the
    flat float64 ``a`` lies in ``[low, high]``) from now on (:func:`_checked`)."""
    _WITHIN[:] = [fn]


def _checked(check, name, a, low, high):
    """``check(name, a)``, or ``a`` itself when it is a large C-contiguous float64 array
    (:data:`PARALLEL_CHECK`) whose values all lie in ``[low, high]``, which the kernels' threads
    check in one pass once the kernels have loaded; anything else (a value out of range
    included) takes ``check``, which raises the error that names the angle."""
    large = type(a) is np.ndarray and a.dtype == np.float64 and a.size >= PARALLEL_CHECK
    if large and _WITHIN and a.flags.c_contiguous and _BACKEND.get() == "numba":
        if _WITHIN[0](a.reshape(-1), low, high):
            return a
    return check(name, a)


#: one angle value a small call takes without numpy's conversion (a ``bool`` is not one:
#: the general path refuses it, naming the angle)
SCALARS = (float, int, np.float64, np.int64, np.int32)


def scalar(x):
    """``x`` (one of :data:`SCALARS`) as a float, or ``None`` (an integer no float holds: the
    general path refuses it, naming the angle)."""
    try:
        return float(x)
    except OverflowError:
        return None


def small_angles(theta_i, theta_r, phi_r, limit):
    """``(shape, n, [ti, tr, pr])`` for a small call: the broadcast ``shape`` of the three
    angle inputs (numbers, lists, float64 or integer arrays), its size ``n``, and each input
    as a flat float64 array of length 1 (a single value) or ``n``; ``None`` for what the
    general path (:class:`Plan`) takes instead: other types (float32, whose polar angles are
    judged in float32; bools and objects, which it refuses), more than ``limit`` geometries
    (the general path's chunks bound the memory), none at all, or shapes that do not
    broadcast (it raises the error).  The values are not validated here.
    """
    arrays, shapes = [], []
    for x in (theta_i, theta_r, phi_r):
        if type(x) is float:
            x = np.array((x,))
            shapes.append(())
        else:
            if not (type(x) is np.ndarray and x.dtype is _FLOAT64):
                x = _converted(x)
                if x is None:
                    return None
            shapes.append(x.shape)
        arrays.append(x)
    shape = _broadcast(*shapes)
    if shape is None:
        return None
    n = math.prod(shape)
    if n == 0 or n > limit:
        return None
    for k, x in enumerate(arrays):
        if x.size == 1:
            arrays[k] = x.reshape(1)
        elif x.shape != shape or not x.flags.c_contiguous:
            full = np.empty(shape)
            full[...] = x  # numpy.broadcast_to costs more than this copy at a small call's sizes
            arrays[k] = full.reshape(-1)
        elif x.ndim != 1:
            arrays[k] = x.reshape(-1)
    return shape, n, arrays


_FLOAT64 = np.dtype(np.float64)


def _broadcast(s1, s2, s3):
    """``numpy.broadcast_shapes`` (``None`` where they do not broadcast), without its cost
    where the shapes other than ``()`` are equal."""
    full = s1 or s2 or s3
    if (not s1 or s1 == full) and (not s2 or s2 == full) and (not s3 or s3 == full):
        return full
    try:
        return np.broadcast_shapes(s1, s2, s3)
    except ValueError:
        return None


def _converted(x):
    """A small call's angle input other than a float or a float64 array, as a float64 array,
    or ``None`` (see :func:`small_angles`)."""
    if type(x) in SCALARS:
        v = scalar(x)
        return None if v is None else np.array(v)
    if type(x) in (list, tuple):
        try:
            x = np.asarray(x)
        except ValueError:  # ragged: the general path names the angle
            return None
    if (
        type(x) is not np.ndarray
        or x.dtype.kind not in "fiu"
        or (x.dtype.kind == "f" and x.dtype.itemsize != 8)
    ):
        return None
    return x.astype(np.float64)


_AXES = {}


def as_matrices(m16, shape):
    """The ``shape + (4, 4)`` view of element-major Mueller storage ``m16`` ``(16, N)``
    (``numpy.moveaxis`` without its argument checking, which costs more than a small call)."""
    nd = len(shape)
    axes = _AXES.get(nd)
    if axes is None:
        axes = _AXES[nd] = tuple(range(2, nd + 2)) + (0, 1)
    return m16.reshape((4, 4) + shape).transpose(axes)


class Plan:
    """The validated, broadcast evaluation of ``model`` at three angle inputs.

    ``shape`` is the broadcast of the angles and the model's parameter shape, ``n`` its
    size; :meth:`blocks` yields ``(slice, ti, tr, pr, model)`` per chunk, flat float64
    angles and the model with its array parameters flattened to the chunk (trusted: they
    were validated when the model was built).  Broadcast inputs are never materialized
    beyond a chunk: inputs of the full shape are sliced, single values are passed as
    length-1 arrays (kernels) or filled (numpy), others are gathered per chunk.
    """

    def __init__(self, model, theta_i, theta_r, phi_r, chunk):
        self.model = model
        self.inputs = checked_angles(model, theta_i, theta_r, phi_r)
        self.leaves = model._sets
        shapes = [a.shape for a in self.inputs] + [a.shape for a in self.leaves.values()]
        self.shape = np.broadcast_shapes(*shapes)
        self.n = math.prod(self.shape)
        self.chunk = chunk

    def whole(self):
        """The flat angles ``[ti, tr, pr]`` of the whole evaluation (a single value as a
        length-1 array) when nothing need be gathered chunk by chunk: no model set, and each
        angle input of the full shape or a single value; otherwise ``None``."""
        if self.leaves or any(a.shape != self.shape and a.size != 1 for a in self.inputs):
            return None
        return [a.reshape(-1) for a in self.inputs]

    def blocks(self, fill=True):
        """Chunks ``(slice, ti, tr, pr, model)``; ``fill=False`` keeps single angle values as
        length-1 arrays (the kernels broadcast them)."""
        arrays = self.inputs + list(self.leaves.values())
        flat = [a.reshape(-1) if a.shape == self.shape else None for a in arrays]
        if self.n <= self.chunk:  # one chunk: gather each broadcast input whole
            flat = [
                f if f is not None or a.size == 1 else _whole(a, self.shape)
                for a, f in zip(arrays, flat, strict=True)
            ]
        for start in range(0, self.n, self.chunk):
            stop = min(start + self.chunk, self.n)
            parts = _gather(arrays, flat, self.shape, start, stop, fill)
            model = self.model
            if self.leaves:
                model = with_leaves(model, dict(zip(self.leaves, parts[3:], strict=True)))
            yield slice(start, stop), parts[0], parts[1], parts[2], model


class FixedAngles:
    """Angles at which many models are evaluated, one after another (a fit's rows, each
    likelihood evaluation a new model set of the walkers): :meth:`mueller16` is
    :func:`evaluate` at them.  For a model whose geometries fit in one chunk of its route
    (:data:`KERNEL_CHUNK` compiled, :data:`CHUNK` numpy, as for a sum of compiled models),
    the angles are validated and broadcast once per broadcast shape and handed to
    :func:`flat` as :class:`Plan`'s single chunk hands them: the same flat inputs and the same
    implementation, so the same bits, without the validation, broadcasting and gathering a
    :class:`Plan` repeats per call (for a fit's sum of three compiled models, with the other
    changes of 8990f21: docs/guide/nightly.md, ``benchmarks/likelihood_batch.py``)."""

    def __init__(self, theta_i, theta_r, phi_r):
        self.angles = (theta_i, theta_r, phi_r)
        self._flat = {}  # broadcast shape: the three angles, flat

    def mueller16(self, model):
        """``(shape, M)``: ``model.mueller16`` at the angles."""
        leaves = model._sets
        shape = np.broadcast_shapes(*(np.shape(a) for a in self.angles), *(v.shape for v in leaves.values()))
        n = math.prod(shape)
        # up to CHUNK geometries either route takes one chunk: no need to ask for the kernel,
        # whose spec flat() builds on the flattened model anyway
        if n > CHUNK and n > (KERNEL_CHUNK if kernel_path(model) else CHUNK):
            return evaluate(model, *self.angles, 16)
        angles = self._flat.get(shape)
        if angles is None:
            angles = self._flat[shape] = [_whole(a, shape) for a in checked_angles(model, *self.angles)]
        if leaves:
            model = with_leaves(model, {k: _whole(v, shape) for k, v in leaves.items()})
        with np.errstate(over="ignore"):  # as fill() computes a numpy route's chunk
            return shape, flat(model, *angles, 16)


def _whole(a, shape):
    return np.ascontiguousarray(np.broadcast_to(a, shape)).reshape(-1)


def _gather(arrays, flat, shape, start, stop, fill):
    idx = None
    parts = []
    for i, (a, f) in enumerate(zip(arrays, flat, strict=True)):
        if f is not None:
            parts.append(f[start:stop])
        elif a.size == 1:
            v = a.reshape(-1)
            # parameters are always filled: a model's flat parameters have the chunk's length
            parts.append(np.full(stop - start, v[0]) if (fill or i >= 3) else v)
        else:
            if idx is None:
                idx = np.unravel_index(np.arange(start, stop), shape)
            parts.append(np.broadcast_to(a, shape)[idx])
    return parts


def each(model, ti, tr, pr, fn, axis):
    """``fn(element, ti, tr, pr)`` of a model whose parameters are flat arrays (one per
    geometry) and whose numpy implementation takes scalar parameters: evaluated once per
    distinct parameter element, on the geometries that have it.  ``axis`` is the geometry
    axis of the result (1 for ``(16, n)``, 0 for ``(n,)`` or ``(n, 2, 2)``)."""
    leaves = model._sets
    cols = []
    for a in leaves.values():
        cols += [a.real, a.imag] if np.iscomplexobj(a) else [a]
    _, first, inverse = np.unique(np.stack(cols, axis=1), axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    out = None
    for r, i0 in enumerate(first):
        sel = np.flatnonzero(inverse == r)
        val = fn(model._element(leaves, int(i0)), ti[sel], tr[sel], pr[sel])
        if out is None:
            shape = list(val.shape)
            shape[axis] = ti.size
            out = np.empty(shape, dtype=val.dtype)
        out[(slice(None),) * axis + (sel,)] = val
    return out


# --------------------------------------------------------------------------- the routes
def compiled(model):
    """``model``'s compiled kernel where it evaluates here, else ``None`` (numpy): the numba
    backend is selected and a kernel covers the model and its options.  For a single model or
    a chunk of a model set (flat parameters): a whole model set's chunks build their own."""
    if _BACKEND.get() != "numba":
        return None
    return model._kernel  # None where no kernel covers it (asking _has_kernel too built the spec twice)


def flat(model, ti, tr, pr, rows=16):
    """The named internal entry: Mueller elements ``(16, n)`` (``rows=16``) or ``M00``
    ``(n,)`` (``rows=1``) of flat float64 angles validated already, for a single model or a
    chunk of a model set (its array parameters flat, one element per geometry), by
    :func:`compiled`'s choice of implementation."""
    kernel = compiled(model)
    if kernel is not None:
        out = kernel.run(ti, tr, pr, rows)
        return out if rows == 16 else out[0]
    if not model._numpy_sets and model._sets:  # a class's flag first: a sum walks no tree
        return each(model, ti, tr, pr, lambda m, a, b, c: flat(m, a, b, c, rows), 1 if rows == 16 else 0)
    return model._mueller16(ti, tr, pr) if rows == 16 else model._brdf_flat(ti, tr, pr)


def flat_jones(model, ti, tr, pr):
    """:func:`flat` for the Jones matrix ``(n, 2, 2)`` of a non-depolarizing model (numpy:
    no kernel computes Jones matrices)."""
    if model._sets and not model._numpy_sets:
        return each(model, ti, tr, pr, flat_jones, 0)
    return model._jones_flat(ti, tr, pr)


def kernel_precision(model, precision):
    """The precision a kernel of ``model`` runs a ``precision`` request in: float32 only
    inside the model's float32-safe domain (:mod:`scatterbench.models.float32_domain`,
    decided once per model), unless :func:`raw_float32` is in effect; then the float64
    result is rounded."""
    if precision == "float32" and model._float32_unsafe is not None and float32_guarded():
        return "float64"
    return precision


def kernel_path(model) -> bool:
    """True when ``model``'s chunks go through the kernels here (a model set's chunks each
    build their own, so the whole set's kernel is never built)."""
    return model._has_kernel and _BACKEND.get() == "numba"


def plan(model, theta_i, theta_r, phi_r):
    """The validated, broadcast evaluation of ``model`` at a user's angles, in the chunk size
    of its route (:class:`Plan`)."""
    return Plan(model, theta_i, theta_r, phi_r, KERNEL_CHUNK if kernel_path(model) else CHUNK)


def small(model, theta_i, theta_r, phi_r, rows, precision, out=None):
    """The small-call route (:meth:`scatterbench.models.kernels.Compiled.fast`): a single
    compiled model's call straight into its kernel, formatted (``(..., 4, 4)`` matrices, or
    ``M00`` of the angles' shape); ``None`` for the general route (which also raises the
    errors).  :func:`compiled`'s choice, written out: this route's overhead is the call's."""
    check_out(out)
    if model._sets or _BACKEND.get() != "numba":
        return None
    kernel = model._kernel  # None where no kernel covers the model
    if kernel is None:
        return None
    if precision == "float64":
        return kernel.fast(theta_i, theta_r, phi_r, rows, precision, out)
    if precision != "float32":
        return None
    if kernel_precision(model, precision) == precision:
        return kernel.fast(theta_i, theta_r, phi_r, rows, precision, out)
    if out is not None:
        return None
    fast = kernel.fast(theta_i, theta_r, phi_r, rows, "float64")  # the float32 fallback
    with np.errstate(over="ignore"):  # beyond float32: finite32 refuses it, naming precision
        return None if fast is None else fast.astype(np.float32)


#: the largest float32
FLOAT32_MAX = float(np.finfo(np.float32).max)


def finite32(model, values, angles, rows, precision):
    """A float32 result made finite or refused, the one rule for every float32 route: where
    ``values`` (the result, a view of its storage) holds inf or NaN, the call is evaluated
    again in float64; if that fits float32's range (3.4e38) it is rounded into ``values``
    (the float32 kernel overflowed where float64 did not), else a ``ValueError`` naming
    ``precision`` says the result is beyond float32 (a lobe of width 1e-8 at grazing reaches
    1e47) rather than returning inf."""
    if precision != "float32" or np.isfinite(values).all():
        return values
    shape, m64 = evaluate(model, *angles, rows, "float64")
    peak = float(np.max(np.abs(m64))) if m64.size else 0.0
    if not np.isfinite(m64).all() or peak > FLOAT32_MAX:
        raise ValueError(
            f"precision must be 'float64' for this call: the result reaches {peak:.3g}, beyond "
            f"float32's range (<= {FLOAT32_MAX:.3g}); precision='float32' would give inf"
        )
    values[...] = (as_matrices(m64, shape) if rows == 16 else m64.reshape(shape)).reshape(values.shape)
    return values


def check_out(out):
    """``out`` as a user may give it: ``None`` or a writeable numpy array (a ``numpy.memmap``
    is one), else the ``TypeError`` or ``ValueError`` naming ``out`` (a list raised an
    AttributeError and a read-only array numba's TypingError from inside the kernels)."""
    if out is None:
        return None
    if not isinstance(out, np.ndarray):
        raise TypeError(
            f"out must be a numpy array (or numpy.memmap) of shape (rows, N); got {type(out).__name__}"
        )
    if not out.flags.writeable:
        raise ValueError("out must be a writeable array; got a read-only one")
    return out


def evaluate(model, theta_i, theta_r, phi_r, rows, precision="float64", out=None):
    """``(shape, M)``: ``model`` at a user's angles, validated and broadcast once, as
    element-major storage ``M`` ``(rows, N)`` (rows 16: row ``4 a + b`` is element ``ab``;
    rows 1: ``M00``), ``shape`` the broadcast shape (``N`` its size); into ``out`` when given
    (a ``(rows, N)`` array of the precision's dtype, e.g. a ``numpy.memmap``)."""
    check_out(out)
    p = plan(model, theta_i, theta_r, phi_r)
    dtype = np.dtype(check_precision(precision))
    if out is None:
        out = np.empty((rows, p.n), dtype=dtype)
    elif out.shape != (rows, p.n) or out.dtype != dtype:
        raise ValueError(
            f"out must have shape ({rows}, {p.n}) and dtype {dtype}; got {out.shape} {out.dtype}"
        )
    fill(p, out, rows, precision)
    return p.shape, out


def fill(p, out, rows, precision):
    """Evaluate plan ``p`` into ``out``: the kernel where one covers the model, in
    :func:`kernel_precision`, in one call where nothing is gathered and ``out`` takes the
    kernel's writes (:meth:`Plan.whole`), otherwise chunk by chunk (a model set's chunk is a
    model with flat parameters, with its own kernel rows); without a kernel, :func:`flat`'s
    numpy implementation chunk by chunk, rounded to ``out``'s dtype."""
    kernel = kernel_path(p.model)
    runs = kernel_precision(p.model, precision) if kernel else precision
    angles = p.whole() if kernel else None  # None for a model set: its kernel is its chunks'
    if angles is not None and p.model._kernel.in_place(out, runs):
        # one call: the kernel's threads share the whole range.  A call per chunk made every
        # thread wait for the others every 65536 geometries: FacetBRDF on 10^7 geometries ran
        # 3.2x faster on 16 threads than on one (benchmarks/scaling_16core.sh at 4235c56)
        p.model._kernel.write(out, slice(0, p.n), *angles, runs)
        return
    for sl, ti, tr, pr, m in p.blocks(fill=not kernel):
        if kernel:
            m._kernel.write(out, sl, ti, tr, pr, runs)
        else:
            with np.errstate(over="ignore"):  # rounding to float32: finite32 judges the result
                out[:, sl] = flat(m, ti, tr, pr, rows)


def blocks(model, theta_i, theta_r, phi_r):
    """Stream ``model`` at a user's angles: ``(flat_slice, (k, 4, 4) block)`` per chunk."""
    for sl, ti, tr, pr, m in plan(model, theta_i, theta_r, phi_r).blocks():
        yield sl, flat(m, ti, tr, pr).T.reshape(-1, 4, 4)


def jones(model, theta_i, theta_r, phi_r):
    """The Jones matrices ``(..., 2, 2)`` of a non-depolarizing model at a user's angles."""
    p = Plan(model, theta_i, theta_r, phi_r, CHUNK)
    out = np.empty((p.n, 2, 2), dtype=complex)
    for sl, ti, tr, pr, m in p.blocks():
        out[sl] = flat_jones(m, ti, tr, pr)
    return out.reshape(p.shape + (2, 2))
