"""How a model is evaluated: backend, precision, broadcasting and chunks, model sets.

:class:`models.Model` validates the angles, broadcasts them against its parameter shape
(:mod:`models.modelset`) and evaluates them in chunks through one dispatcher per
quantity (``_m16`` for the Mueller matrix, ``_m00`` for its first element):

* the compiled kernels (:mod:`models.kernels`, numba) for the closed-form models and
  the options they cover, the default backend;
* otherwise the numpy implementation (``_mueller16``, ``_brdf_flat``), the reference
  path the kernels are tested against (``with models.backend("numpy"): ...`` selects
  it for everything).  A model set whose numpy implementation takes scalar parameters
  only is evaluated one distinct parameter element at a time (:func:`each`).

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

__all__ = ["backend", "current_backend", "BACKENDS", "PRECISIONS", "CHUNK", "KERNEL_CHUNK", "Plan"]

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


def check_precision(precision):
    if precision not in PRECISIONS:
        raise ValueError(f"precision must be one of {', '.join(map(repr, PRECISIONS))}; got {precision!r}")
    return precision


def checked_angles(model, theta_i, theta_r, phi_r):
    """The three angle inputs as float64 arrays, each validated under ``model``'s names for
    them (two polar angles in [0, pi/2], a finite azimuth)."""
    n1, n2, n3 = model._angle_names
    return [check_polar_angle(n1, theta_i), check_polar_angle(n2, theta_r), check_finite_array(n3, phi_r)]


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


def each(model, ti, tr, pr, method, axis):
    """``method`` (e.g. ``"_m16"``) of a model whose parameters are flat arrays (one per
    geometry) and whose numpy implementation takes scalar parameters: evaluated once per
    distinct parameter element, on the geometries that have it.  ``axis`` is the geometry
    axis of the method's result (1 for ``(16, n)``, 0 for ``(n,)`` or ``(n, 2, 2)``)."""
    leaves = model._sets
    cols = []
    for a in leaves.values():
        cols += [a.real, a.imag] if np.iscomplexobj(a) else [a]
    _, first, inverse = np.unique(np.stack(cols, axis=1), axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    out = None
    for r, i0 in enumerate(first):
        sel = np.flatnonzero(inverse == r)
        val = getattr(model._element(leaves, int(i0)), method)(ti[sel], tr[sel], pr[sel])
        if out is None:
            shape = list(val.shape)
            shape[axis] = ti.size
            out = np.empty(shape, dtype=val.dtype)
        out[(slice(None),) * axis + (sel,)] = val
    return out
