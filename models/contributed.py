"""Models from outside scatterbench: the ones other packages contribute, and any object with a
``mueller`` method seen as a :class:`Model`.

scatterbench's own model classes are listed by :attr:`Model.registry`; other packages
contribute models in the entry-point group :data:`ENTRY_POINT_GROUP` (each entry names a model
instance, or a class or callable returning one: ``examples/lambert-specular``), listed by
:func:`contributed_models`.  :class:`Conformant` gives any such object the :class:`Model`
interface (validated, broadcast and chunked angles, ``brdf``, the optional attributes with the
kit's documented defaults), so that the stability sweep, the conformance kit and the report
treat a contributed model as they treat their own.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
from dataclasses import dataclass

import numpy as np

from .base import Model
from .constraints import HasMethods
from .params import param

__all__ = ["ENTRY_POINT_GROUP", "Contributed", "contributed_models", "resolve", "Conformant", "as_model"]

#: the entry-point group other packages register their models in
ENTRY_POINT_GROUP = "scatterbench.models"


def resolve(obj, what):
    """A model from an instance, a class or a callable returning one."""
    if not isinstance(obj, type) and callable(getattr(obj, "mueller", None)):
        return obj
    if callable(obj):
        try:
            made = obj()
        except Exception as exc:  # noqa: BLE001 - reported as a bad argument, not a traceback
            raise ValueError(
                f"{what}: calling it with no arguments raised {type(exc).__name__}: {exc}"
            ) from exc
        if callable(getattr(made, "mueller", None)):
            return made
        raise ValueError(
            f"{what}: calling it returned {type(made).__name__}, not a model (no mueller method)"
        )
    raise ValueError(
        f"{what}: {type(obj).__name__} is not a model (no mueller method) nor a callable returning one"
    )


@dataclass(frozen=True)
class Contributed:
    """A model another package registers in the ``scatterbench.models`` entry-point group:
    the entry's name, its ``module:attr``, the distribution that ships it, and the model
    (``None``, with ``error``, when it cannot be loaded)."""

    name: str
    value: str
    dist: str
    model: object = None
    error: str | None = None


def contributed_models() -> list[Contributed]:
    """Every model registered in the ``scatterbench.models`` entry-point group, sorted by name;
    an entry that fails to load is listed with its error, not raised."""
    out = []
    for ep in sorted(importlib.metadata.entry_points(group=ENTRY_POINT_GROUP), key=lambda e: e.name):
        dist = f"{ep.dist.name} {ep.dist.version}" if ep.dist is not None else "?"
        try:
            model = resolve(ep.load(), f"entry point {ep.name!r}")
        except Exception as exc:  # noqa: BLE001 - a broken plug-in is reported, not fatal
            out.append(Contributed(ep.name, ep.value, dist, None, f"{type(exc).__name__}: {exc}"))
            continue
        except SystemExit as exc:  # its module called sys.exit: broken too, not the end of the listing
            why = f"its module called sys.exit({exc.code!r}) while loading"
            out.append(Contributed(ep.name, ep.value, dist, None, why))
            continue
        out.append(Contributed(ep.name, ep.value, dist, model))
    return out


class _NotYetAModel(HasMethods):
    """An object with a ``mueller`` method that is not a :class:`scatterbench.models.Model`
    (:func:`as_model` takes those as they are)."""

    def __init__(self):
        super().__init__("mueller", text="an object with a mueller(theta_i, theta_r, phi_r) method")

    def check(self, name, value):
        if isinstance(value, Model):
            self.fail(name, value)
        return super().check(name, value)


@dataclass(frozen=True)
class Conformant(Model, registry=False):
    """Any object with ``mueller(theta_i, theta_r, phi_r)``, seen as a :class:`scatterbench.models.Model`:
    validated, broadcast and chunked angles, ``brdf``, and the optional attributes
    (:data:`ATTRIBUTES`) with the defaults the kit documents."""

    model: object = param(dataclasses.MISSING, "the wrapped model", _NotYetAModel())

    @property
    def depolarizing(self):  # type: ignore[override]
        return not callable(getattr(self.model, "jones", None))

    @property
    def reciprocal(self):  # type: ignore[override]
        return bool(getattr(self.model, "reciprocal", True))

    @property
    def transmission(self):  # type: ignore[override]
        return bool(getattr(self.model, "transmission", False))

    @property
    def mirror_symmetric(self):  # type: ignore[override]
        return bool(getattr(self.model, "mirror_symmetric", False))

    def _mueller16(self, ti, tr, pr):
        M = np.asarray(self.model.mueller(*_readonly(ti, tr, pr)), dtype=float)
        return M.reshape(len(ti), 16).T

    def _jones_flat(self, ti, tr, pr):
        return np.asarray(self.model.jones(*_readonly(ti, tr, pr)), dtype=complex).reshape(len(ti), 2, 2)

    def rotated(self, angle):
        rot = getattr(self.model, "rotated", None)
        return self if rot is None else Conformant(model=rot(angle))

    def lobe(self, theta_i):
        lobe = getattr(self.model, "lobe", None)
        return None if lobe is None else lobe(theta_i)

    def __repr__(self):
        return repr(self.model)


def _readonly(*arrays):
    """Read-only copies of the angles handed to a wrapped model: one that writes into its
    inputs raises there, and cannot change the caller's arrays (the kit's grids, a chunk)."""
    out = []
    for a in arrays:
        a = np.array(a, copy=True)
        a.flags.writeable = False
        out.append(a)
    return out


def as_model(obj):
    """``obj`` itself if it is a :class:`Model`, else its :class:`Conformant` view."""
    return obj if isinstance(obj, Model) else Conformant(model=obj)
