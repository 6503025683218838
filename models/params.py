"""Declared, validated model parameters.

Every model and distribution in :mod:`scatterbench.models` is a frozen dataclass whose fields
are declared with :func:`param`: a default, a one-line description and a constraint object
(:mod:`scatterbench.models.constraints`: :class:`~.constraints.Interval`,
:class:`~.constraints.Options`, :class:`~.constraints.ComplexIndex`, ...) that fixes the
allowed values, checks and normalizes them, describes them and names their edges for the
stability sweep.  ``Declared.__post_init__`` validates every field and raises a
``ValueError`` that names the parameter, its allowed range and the offending value, so a bad
value never reaches the physics.  ``Cls.parameters()`` lists the declared parameters the way
SCATMECH's ``AskUser``/``ListParameters`` does.

Old keyword names keep working through :class:`Alias` entries in a class's
``aliases`` table (``aliases = {"n": "coating"}``): they are translated when the
model is built or replaced (:meth:`Declared.replace`), listed by ``parameters()`` and
``info()``, and, for plain renames, readable as attributes.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .constraints import (
    INDEX_MAX,
    INDEX_MIN,
    SLOPE_WIDTH_MAX,
    SLOPE_WIDTH_MIN,
    ComplexIndex,
    Constraint,
    Interval,
    Options,
    RealIndex,
    ScalarOrArray,
)

__all__ = [
    "INDEX_MAX",
    "INDEX_MIN",
    "SLOPE_WIDTH_MIN",
    "SLOPE_WIDTH_MAX",
    "COATING_EDGES",
    "width_param",
    "coating_param",
    "Alias",
    "choice_alias",
    "convention_param",
    "Declared",
    "ParamInfo",
    "param",
    "check_real",
    "check_index",
    "check_polar_angle",
    "check_finite_array",
]

#: The stability sweep's coating indices: index-matched to the ambient (no interface), a
#: hair above it (an interface that almost vanishes: 0/0-prone), a varnish and a high index.
COATING_EDGES = (1.0, 1.0 + 1e-9, 1.5, 3.0)


@dataclass(frozen=True)
class _Declaration:
    """What :func:`param` stores in a field's metadata: the description, the constraint and
    the declaration's own edge values for the stability sweep (``None``: the constraint's)."""

    doc: str
    constraint: Constraint
    edges: tuple | None = None


@dataclass(frozen=True)
class ParamInfo:
    """What a declared parameter is: name, default, description, constraint (the allowed
    values) and the edge values the stability sweep tries it at."""

    name: str
    default: Any
    doc: str
    constraint: Constraint
    aliases: tuple = ()  # old keyword names that still set this parameter
    required: bool = False  # no default: must be given
    declared_edges: tuple | None = None  # the declaration's own sweep values (None: the constraint's)

    def range_text(self) -> str:
        """The allowed values in words (the constraint's description)."""
        return self.constraint.describe()

    def edges(self, current) -> list:
        """The stability sweep's values of this parameter other than ``current``: the
        declaration's own (:func:`param`'s ``edges``), else its constraint's."""
        if self.declared_edges is not None:
            return [v for v in self.declared_edges if v != current]
        return self.constraint.edges(current)

    # -- the constraint's family and bounds, for readers of the declaration ---------------
    @property
    def kind(self) -> str:
        """``real``, ``int``, ``index``, ``real_index``, ``choice``, ``sequence`` or ``object``."""
        return self.constraint.kind

    @property
    def low(self):
        return getattr(self.constraint.base, "low", None)

    @property
    def high(self):
        return getattr(self.constraint.base, "high", None)

    @property
    def low_open(self) -> bool:
        return bool(getattr(self.constraint.base, "low_open", False))

    @property
    def high_open(self) -> bool:
        return bool(getattr(self.constraint.base, "high_open", False))

    @property
    def choices(self) -> tuple | None:
        """The options of an :class:`~.constraints.Options` parameter, else ``None``."""
        c = self.constraint
        return c.options if isinstance(c, Options) else None


def param(default: Any, doc: str, constraint: Constraint, *, edges: tuple | None = None):
    """Declare a model parameter (a dataclass field with its validation).

    ``default`` may be ``dataclasses.MISSING``: the parameter is then required.
    ``constraint`` (:mod:`scatterbench.models.constraints`) fixes the allowed values: it
    checks and normalizes each value given and describes the range in error messages and
    listings.  ``edges``: the values the stability sweep tries this parameter at (default:
    the constraint's, e.g. an interval's bounds).
    """
    if not isinstance(constraint, Constraint):
        raise TypeError(f"constraint must be a models.constraints.Constraint; got {constraint!r}")
    info = _Declaration(doc, constraint, None if edges is None else tuple(edges))
    if isinstance(default, (list, dict, np.ndarray)):
        return field(default_factory=lambda: default, metadata={"scatterbench": info})
    return field(default=default, metadata={"scatterbench": info})


#: a slope-distribution width: narrower or wider lobes are not resolved in float64
WIDTH = ScalarOrArray(Interval(SLOPE_WIDTH_MIN, SLOPE_WIDTH_MAX))


def width_param(default: float, doc: str, *, high: float = SLOPE_WIDTH_MAX, edges: tuple | None = None):
    """Declare a slope-distribution width (rms slope, GGX alpha, angular width) in
    [:data:`SLOPE_WIDTH_MIN`, ``high``]: narrower or wider lobes are not resolved in float64."""
    why = f"; >= {SLOPE_WIDTH_MIN:g} (a narrower lobe is below float64's resolution of directions)"
    if high == SLOPE_WIDTH_MAX:
        why += f", <= {SLOPE_WIDTH_MAX:g} (facets within 1/{SLOPE_WIDTH_MAX:g} rad of vertical)"
    constraint = WIDTH if high == SLOPE_WIDTH_MAX else ScalarOrArray(Interval(SLOPE_WIDTH_MIN, high))
    return param(default, doc + why, constraint, edges=edges)


def coating_param(default: float, doc: str):
    """Declare a coating (binder, varnish) index: real, non-absorbing, ``>= 1`` (the ambient's),
    swept at :data:`COATING_EDGES`."""
    return param(default, doc, ScalarOrArray(RealIndex(1.0)), edges=COATING_EDGES)


def _closed(low_open, high_open) -> str:
    return {(False, False): "both", (True, False): "right", (False, True): "left"}.get(
        (bool(low_open), bool(high_open)), "neither"
    )


def check_real(name, value, low=None, high=None, low_open=False, high_open=False):
    """Return ``value`` as a float, or a numpy array as a read-only float64 array (a model set,
    every element checked once), or raise ``ValueError`` naming ``name``, the range and the
    (first) offending value (:class:`scatterbench.models.constraints.Interval`)."""
    return ScalarOrArray(Interval(low, high, closed=_closed(low_open, high_open))).check(name, value)


_INDEX = ScalarOrArray(ComplexIndex())


def check_index(name, value):
    """Validate a refractive index ``n + ik`` (``k >= 0``) or ``math.inf``
    (:class:`scatterbench.models.constraints.ComplexIndex`).

    Returns ``math.inf`` for a perfect conductor, otherwise a ``complex`` whose
    imaginary part is a non-negative float (``-0.0`` is normalised to ``+0.0`` so
    that the principal square roots used for total internal reflection pick the
    evanescent, decaying branch).  A numpy array (a model set) is checked element by
    element and returned as a read-only complex128 array (``inf + 0j``: a perfect
    conductor).
    """
    return _INDEX.check(name, value)


def check_polar_angle(name, value) -> np.ndarray:
    """Polar angles in radians: finite, in [0, pi/2]. Returns a float64 array.

    Lower-precision inputs are judged in their own precision: float32(pi/2) is
    slightly above the float64 pi/2 and means grazing, so it is accepted and
    clipped to pi/2.
    """
    raw = _real_array(name, value)
    a = raw.astype(np.float64, copy=False)
    # one pass for the common case: NaN fails both comparisons, +-inf one of them
    if a.size and not (0.0 <= a.min() and a.max() <= _HALF_PI):
        a = _checked_polar(name, raw, a)
    return a


_HALF_PI = 0.5 * math.pi


def _checked_polar(name, raw, a):
    """:func:`check_polar_angle` of values that are not all in [0, pi/2] in float64: the
    error naming ``name``, or float32 grazing angles clipped to pi/2."""
    if not np.isfinite(a).all():
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    if raw.dtype.kind == "f" and raw.dtype.itemsize < 8:
        top = float(np.asarray(_HALF_PI, dtype=raw.dtype))
        if top > _HALF_PI:
            a = np.where((a > _HALF_PI) & (a <= top), _HALF_PI, a)
    if a.min() < 0.0 or a.max() > _HALF_PI:
        raise ValueError(
            f"{name} must lie in [0, pi/2] radians (a polar angle above the surface); "
            f"got values in [{a.min():.6g}, {a.max():.6g}]"
        )
    return a


def _real_array(name, value) -> np.ndarray:
    """``value`` as a numpy array of integers or reals, or the ``ValueError`` naming ``name``."""
    try:
        a = np.asarray(value)
    except Exception as exc:  # pragma: no cover - numpy raises many types
        raise ValueError(f"{name} must be a real number or array of real numbers") from exc
    if a.dtype.kind not in "iuf":
        raise ValueError(f"{name} must be a real number or array of real numbers; got {a.dtype}")
    return a


def check_finite_array(name, value) -> np.ndarray:
    """A real array with only finite values (float32 is promoted to float64)."""
    a = _real_array(name, value).astype(np.float64, copy=False)
    if not np.isfinite(a).all():
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    return a


@dataclass(frozen=True)
class Alias:
    """An old keyword name that still sets the declared parameter ``target``.

    ``convert`` is None for a plain rename.  Otherwise it receives the old keywords
    given (a dict; several old names may share one target and one ``convert``) and
    the target's current value (its default at construction), and returns the
    target's value, raising ``ValueError`` when the old values have no equivalent.
    """

    target: str
    convert: Callable[[dict, Any], Any] | None = None


def choice_alias(target: str, old: str, mapping: dict) -> Alias:
    """An :class:`Alias` for an old ``choice`` keyword whose values map one to one onto
    ``target``'s (e.g. ``normalization="exact"`` -> ``convention="corrected"``)."""

    def convert(given, current):
        value = given[old]
        if not isinstance(value, str) or value not in mapping:
            allowed = ", ".join(repr(k) for k in mapping)
            raise ValueError(f"{old} (old name of {target}) must be one of {allowed}; got {value!r}")
        return mapping[value]

    return Alias(target, convert)


def convention_param(doc: str):
    """The ``convention`` parameter of a model whose paper prints a form that is corrected here:
    ``"paper"`` keeps the printed equations, ``"corrected"`` applies the corrections (the
    model's docstring says exactly which)."""
    return param("paper", doc, Options("paper", "corrected"))


class _DeclaredMeta(type):
    """Translates old keyword names (``cls.aliases``) before the dataclass ``__init__``."""

    def __call__(cls, *args, **kwargs):
        renamed = {}
        if cls.aliases:
            kwargs, renamed = cls._resolve_aliases(kwargs, current=None)
        if dataclasses.is_dataclass(cls):
            for f in dataclasses.fields(cls)[len(args) :]:
                if f.name not in kwargs and f.default is f.default_factory is dataclasses.MISSING:
                    decl = f.metadata.get("scatterbench")
                    doc = decl.doc if decl is not None else ""
                    raise ValueError(f"{f.name} is required ({doc}); it has no default")
        with _naming_old(renamed):
            return super().__call__(*args, **kwargs)


@functools.cache
def declared_constraints(cls) -> dict:
    """``{name: constraint}`` of the declared fields of dataclass ``cls``, in field order, read
    once per class: building a model, checking a parameter by name and walking a model set's
    tree each read it, a fit's walkers at every step.  Treat it as read-only."""
    return {
        f.name: f.metadata["scatterbench"].constraint
        for f in dataclasses.fields(cls)
        if "scatterbench" in f.metadata
    }


@contextlib.contextmanager
def _naming_old(renamed):
    """A ValueError about a parameter that was given by an old name also names the old name."""
    try:
        yield
    except ValueError as exc:
        for target, old in renamed.items():
            if str(exc).startswith(f"{target} "):
                raise ValueError(f"{old} (old name of {target}): {exc}") from exc
        raise


class Declared(metaclass=_DeclaredMeta):
    """Mixin for frozen dataclasses whose fields were declared with :func:`param`."""

    #: old keyword name -> :class:`Alias` (or the new name, for a plain rename)
    aliases: dict = {}

    def __post_init__(self):
        for name, constraint in declared_constraints(type(self)).items():
            object.__setattr__(self, name, constraint.check(name, getattr(self, name)))
        self._validate()

    def _validate(self):
        """Hook for cross-parameter checks in subclasses."""

    @classmethod
    def check_parameter(cls, name: str, value):
        """``value`` validated as the declared parameter ``name`` (a ``ValueError`` naming it
        and its allowed range otherwise), without building an instance: for callers, such
        as scene files, that hold a value for a model they build later."""
        constraint = declared_constraints(cls).get(name)
        if constraint is None:
            raise ValueError(f"{name}: not a declared parameter of {cls.__name__}")
        return constraint.check(name, value)

    @classmethod
    def _alias(cls, old) -> Alias:
        a = cls.aliases[old]
        return Alias(a) if isinstance(a, str) else a

    @classmethod
    def _resolve_aliases(cls, kwargs, current):
        """``(kwargs, renamed)``: ``kwargs`` with old names replaced by the declared ones, and
        ``{target: old names}`` of those given; ``current`` is the instance being replaced
        (None at construction: the defaults)."""
        groups = {}
        for k, v in kwargs.items():
            if k in cls.aliases:
                groups.setdefault(cls._alias(k).target, {})[k] = v
        if not groups:
            return kwargs, {}
        out = {k: v for k, v in kwargs.items() if k not in cls.aliases}
        for target, given in groups.items():
            if target in out:
                raise ValueError(f"{', '.join(given)}: old name of {target}; give {target} alone")
            convert = cls._alias(next(iter(given))).convert
            if convert is None:
                (value,) = given.values()
            else:
                value = convert(given, cls._current(target, current))
            out[target] = value
        return out, {target: ", ".join(given) for target, given in groups.items()}

    @classmethod
    def _current(cls, name, instance):
        if instance is not None:
            return getattr(instance, name)
        f = {f.name: f for f in dataclasses.fields(cls)}[name]
        return f.default if f.default is not dataclasses.MISSING else f.default_factory()

    def __getattr__(self, name):
        # Only reached when normal lookup fails: old names of plain renames read the new one.
        a = type(self).aliases.get(name)
        if isinstance(a, str) or (isinstance(a, Alias) and a.convert is None):
            return getattr(self, a if isinstance(a, str) else a.target)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    @classmethod
    def parameters(cls) -> list[ParamInfo]:
        """The declared parameters: name, default, description, allowed range and old names."""
        old = {}
        for k in cls.aliases:
            old.setdefault(cls._alias(k).target, []).append(k)
        out = []
        for f in dataclasses.fields(cls):
            decl = f.metadata.get("scatterbench")
            if decl is None:
                continue
            required = f.default is dataclasses.MISSING
            out.append(
                ParamInfo(
                    name=f.name,
                    default=None if required else f.default,
                    doc=decl.doc,
                    constraint=decl.constraint,
                    aliases=tuple(old.get(f.name, ())),
                    required=required,
                    declared_edges=decl.edges,
                )
            )
        return out

    def replace(self, **changes):
        """A copy with some parameters changed (validated again; old names accepted)."""
        renamed = {}
        if type(self).aliases:
            changes, renamed = self._resolve_aliases(changes, current=self)
        with _naming_old(renamed):
            return dataclasses.replace(self, **changes)

    def describe(self) -> str:
        lines = [type(self).__name__]
        for p in self.parameters():
            lines.append(f"  {p.name} = {getattr(self, p.name)!r}  # {p.doc}; {p.range_text()}")
        return "\n".join(lines)
