"""From a scene's dotted keys to its model's parameters, found once: model sets for fits.

A fit varies a few keys of a scene file (``substrate.sigma``, ``coating.index``,
``substrate.index[1]``, ``substrate.tau_deg``, ...).  Rebuilding and re-validating the scene
for every walker costs far more than evaluating its model, so :func:`bind` finds, once,
which parameters of the built model each key sets and how (the value itself, in radians for
a ``*_deg`` key, or the real or imaginary part of an index), by building the scene at two
probe values per key and comparing the models' parameters.  :meth:`Binding.model` then sets
those parameters directly, as arrays: one model set for all walkers of an emcee step
(:mod:`scatterbench.models.modelset`), trusted, because the caller checked the values against bounds that
were themselves checked to give valid scenes.

Where the keys do more than set parameters (a structural change, a value the binding cannot
express, a Monte Carlo model that draws from its parameters), :func:`bind` returns ``None`` and
the caller rebuilds the scene per walker, as before.  The binding is verified, not assumed:
the model it builds at the probe values must give the same Mueller matrices, bit for bit, as
the scene rebuilt there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import modelset
from ..evaluation import backend

__all__ = ["Binding", "bind"]

#: how a key's value becomes a parameter: (name, function of the value, part of an index)
_TRANSFORMS = (("value", lambda v: v), ("radians", math.radians))


@dataclass(frozen=True)
class _Target:
    path: tuple  # the parameter's path in the model (models.modelset)
    transform: str  # "value" or "radians"
    part: str  # "real" (a real parameter, or an index's real part) or "imag"


@dataclass(frozen=True)
class Binding:
    """The model of a scene at its own values, and where each free key goes in it."""

    model: object
    targets: dict  # key -> tuple of _Target
    reference: dict  # path -> (value, kind) of every real and index parameter of ``model``

    def values_model(self, values: dict, shape=()):
        """The model with each key's value(s) set (arrays of ``shape``; trusted, see module)."""
        leaves = {}
        for key, v in values.items():
            for t in self.targets[key]:
                x = np.radians(v) if t.transform == "radians" else np.asarray(v, dtype=float)
                ref, kind = self.reference[t.path]
                if kind == "index":
                    cur = np.asarray(leaves.get(t.path, ref), dtype=complex)
                    x = x + 1j * cur.imag if t.part == "real" else cur.real + 1j * x
                leaves[t.path] = x
        if shape == ():
            leaves = {p: modelset.scalar_value(np.asarray(a).reshape(())[()]) for p, a in leaves.items()}
        else:
            leaves = {p: np.broadcast_to(a, shape) if a.shape != shape else a for p, a in leaves.items()}
        return modelset.with_leaves(self.model, leaves)

    def check(self, model):
        """Vectorized validation of the bound parameters of ``model`` (a ``ValueError`` names
        the first bad value)."""
        for path in {t.path for ts in self.targets.values() for t in ts}:
            parent = _at(model, path[:-1])
            type(parent).check_parameter(path[-1], getattr(parent, path[-1]))


def _at(obj, path):
    for k in path:
        obj = obj[k] if isinstance(obj, tuple) else getattr(obj, k)
    return obj


def _match(v0, va, vb, a, b, kind):
    """The transform and part taking values ``a``, ``b`` to parameters ``va``, ``vb``."""
    for name, f in _TRANSFORMS:
        fa, fb = f(a), f(b)
        if kind != "index":
            if va == fa and vb == fb:
                return name, "real"
            continue
        if va == math.inf or vb == math.inf or v0 == math.inf:
            return None
        za, zb, z0 = complex(va), complex(vb), complex(v0)
        if za.real == fa and zb.real == fb and za.imag == zb.imag == z0.imag:
            return name, "real"
        if za.imag == fa and zb.imag == fb and za.real == zb.real == z0.real:
            return name, "imag"
    return None


def _targets(m0, ma, mb, a, b):
    """The parameters a key sets, from the models at its reference and probe values."""
    l0, la, lb = (modelset.scalar_leaves(m) for m in (m0, ma, mb))
    if not (l0.keys() == la.keys() == lb.keys()):
        return None
    out = []
    for path, (v0, kind) in l0.items():
        va, vb = la[path][0], lb[path][0]
        if va == v0 and vb == v0:
            continue
        if isinstance(v0, np.ndarray):
            return None
        found = _match(v0, va, vb, a, b, kind)
        if found is None:
            return None
        out.append(_Target(path, *found))
    return tuple(out) if out else None


def bind(scene, bounds: dict, decisions=None, probe=None):
    """The :class:`Binding` of ``scene``'s keys (``{key: (low, high)}``, each range's values
    valid), or ``None`` when the keys cannot be bound (see the module docstring).

    ``probe``: ``(theta_i, theta_r, phi_r)`` geometries on which the binding is verified
    against the scene rebuilt at the probe values.
    """
    m0 = scene.build(decisions=decisions)
    targets = {}
    for key, (lo, hi) in bounds.items():
        a, b = lo + 0.375 * (hi - lo), lo + 0.6875 * (hi - lo)
        ma = scene.with_values({key: a}).build(decisions=decisions)
        mb = scene.with_values({key: b}).build(decisions=decisions)
        found = _targets(m0, ma, mb, a, b)
        if found is None:
            return None
        targets[key] = found
    binding = Binding(m0, targets, modelset.scalar_leaves(m0))
    if probe is not None and not _verified(scene, binding, bounds, decisions, probe):
        return None
    return binding


def _verified(scene, binding, bounds, decisions, probe):
    """The bound model equals the rebuilt scene at the probe values (all keys at once)."""
    values = {key: lo + 0.53125 * (hi - lo) for key, (lo, hi) in bounds.items()}
    direct = binding.values_model(values)
    rebuilt = scene.with_values(values).build(decisions=decisions)
    with backend("numpy"):
        return bool(np.array_equal(direct.mueller(*probe), rebuilt.mueller(*probe), equal_nan=True))
