"""Model sets: models whose declared real or index parameters are numpy arrays.

A declared parameter whose constraint accepts arrays (``ScalarOrArray`` of a real or index
constraint, :mod:`scatterbench.models.constraints`) may be an array of any shape; the model then stands for one model per element (astropy's
"model sets").  Its *parameter shape* is the broadcast of the shapes of all its array
parameters, those of nested declared objects included (``FacetBRDF(slopes=
GaussianSlopes(sigma=array))``), and evaluation broadcasts it against the angles:
``sigma`` of shape ``(W, 1)`` with angles of shape ``(N,)`` gives ``(W, N, 4, 4)``.

The helpers here walk a model's tree of declared parameters.  A *path* names one
parameter: a tuple of field names and tuple indices, e.g. ``("slopes", "sigma")`` or
``("terms", 1, 1, "coating")`` (the second term of a :class:`scatterbench.models.Sum`).
:func:`with_leaves` builds a model with some parameters replaced *without* validating
them again: for callers that checked the values once, vectorized (a fit checks its
walkers' values against the prior bounds, which were checked against the models).
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from .params import Declared, declared_constraints

__all__ = [
    "array_leaves",
    "scalar_leaves",
    "with_leaves",
    "rebuilt",
    "element",
]


def _walk(obj, path, visit):
    """Call ``visit(path, value, kind)`` for every declared value under ``obj`` that may be an
    array (its constraint's ``arrays``), and walk into every other declared value.

    A declared object where a value goes (a :class:`scatterbench.models.FilmStack` as a substrate
    index) is walked into, like an object parameter."""
    if isinstance(obj, Declared) and dataclasses.is_dataclass(obj):
        for name, constraint in declared_constraints(type(obj)).items():
            value = getattr(obj, name)
            if constraint.arrays and not isinstance(value, Declared):
                visit(path + (name,), value, constraint.kind)
            else:
                _walk(value, path + (name,), visit)
    elif isinstance(obj, tuple):
        for i, item in enumerate(obj):
            _walk(item, path + (i,), visit)


def array_leaves(obj) -> dict:
    """``{path: array}`` of the parameters under ``obj`` that are numpy arrays."""
    out = {}
    _walk(obj, (), lambda p, v, k: out.__setitem__(p, v) if isinstance(v, np.ndarray) else None)
    return out


def scalar_leaves(obj) -> dict:
    """``{path: (value, kind)}`` of every declared real or index parameter under ``obj``."""
    out = {}
    _walk(obj, (), lambda p, v, k: out.__setitem__(p, (v, k)))
    return out


def path_text(path) -> str:
    """A path as the dotted text :meth:`scatterbench.models.Model.with_values` takes."""
    return ".".join(str(k) for k in path)


def check_broadcast(leaves: dict) -> tuple:
    """The broadcast shape of array parameters ``{path: array}``, or a ``ValueError`` naming them."""
    try:
        return np.broadcast_shapes(*(a.shape for a in leaves.values()))
    except ValueError:
        shapes = ", ".join(f"{path_text(p)} {a.shape}" for p, a in leaves.items())
        raise ValueError(f"array parameters must broadcast to one parameter shape; got {shapes}") from None


@functools.cache
def _cached_names(cls) -> frozenset:
    """Attributes an instance caches from its parameters (dropped when they change)."""
    return frozenset(
        name for k in cls.__mro__ for name, v in vars(k).items() if isinstance(v, functools.cached_property)
    )


def _copy_with(obj, changes: dict):
    """``obj`` with fields changed, trusted (no ``__post_init__``): cached values are dropped."""
    if isinstance(obj, tuple):
        items = list(obj)
        for k, v in changes.items():
            items[k] = v
        return tuple(items)
    new = object.__new__(type(obj))
    drop = _cached_names(type(obj))
    new.__dict__.update({k: v for k, v in obj.__dict__.items() if k not in drop})
    new.__dict__.update(changes)
    return new


def _changed(obj, leaves, rebuild):
    groups = {}
    for path, value in leaves.items():
        groups.setdefault(path[0], {})[path[1:]] = value
    changes = {}
    for head, sub in groups.items():
        if () in sub:
            changes[head] = sub[()]
        else:
            child = obj[head] if isinstance(obj, tuple) else getattr(obj, head)
            changes[head] = rebuild(child, sub)
    return changes


def with_leaves(obj, leaves: dict):
    """``obj`` with the parameters at the given paths replaced, *trusted*: no validation.

    The caller guarantees every value is in its parameter's range (see the module
    docstring); :func:`rebuilt` validates.
    """
    if not leaves:
        return obj
    return _copy_with(obj, _changed(obj, leaves, with_leaves))


def rebuilt(obj, leaves: dict):
    """``obj`` with the parameters at the given paths replaced and everything validated again
    (:meth:`scatterbench.models.params.Declared.replace`, vectorized for arrays)."""
    if not leaves:
        return obj
    changes = _changed(obj, leaves, rebuilt)
    if isinstance(obj, tuple):
        return _copy_with(obj, changes)
    return obj.replace(**changes)


def scalar_value(value):
    """One element of an array parameter as the scalar the model would hold: a float, or for
    an index (complex arrays) a complex or ``math.inf``."""
    if isinstance(value, (complex, np.complexfloating)):
        z = complex(value)
        return math.inf if (z.real == math.inf and z.imag == 0) else z
    return float(value)


def element(obj, leaves: dict, index):
    """The single model at flat ``index`` of the flat array parameters ``leaves``."""
    return with_leaves(obj, {p: scalar_value(a[index]) for p, a in leaves.items()})
