"""Declared, validated model parameters.

Every model and distribution in :mod:`scatterbench.models` is a frozen dataclass whose fields
are declared with :func:`param`: a default, a one-line description and a kind
that fixes the allowed range.  ``Declared.__post_init__`` validates every field
and raises a ``ValueError`` that names the parameter and its allowed range, so a
bad value never reaches the physics.  ``Cls.parameters()`` lists the declared
parameters the way SCATMECH's ``AskUser``/``ListParameters`` does.

Old keyword names keep working through :class:`Alias` entries in a class's
``aliases`` table (``aliases = {"n": "coating"}``): they are translated when the
model is built or replaced (:meth:`Declared.replace`), listed by ``parameters()`` and
``info()``, and, for plain renames, readable as attributes.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import numbers
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

#: Largest finite index magnitude |n + ik|.  A mirror's reflection coefficient differs from
#: the perfect conductor's r = -1 by about 2 cos(theta) / (n + ik), so 1 - |r|^2 <= 4 / |n + ik|:
#: above 4 / eps (eps the float64 machine epsilon; ~1.8e16) that difference is below double
#: precision and the only exact answer is the perfect conductor, math.inf.  (The Fresnel
#: algebra itself overflows near |n + ik| ~ 1e77, where |n|^4 leaves the float64 range.)
INDEX_MAX = 4.0 / sys.float_info.epsilon

#: Smallest index magnitude: r differs from its |n + ik| -> 0 limit by about 2 |n + ik|, below
#: double precision under eps / 4 (the same argument; the algebra divides by n^2 there).
INDEX_MIN = 1.0 / INDEX_MAX

#: Narrowest declared slope width (rms slope, GGX alpha, angular width).  A slope computed
#: from two directions (the half vector's x/z, y/z) carries a rounding error dz of a few eps
#: (~1e-15).  Inside a lobe of width w (|z| <= 3 w) a Gaussian's logarithm moves by
#: 6 dz / w, so w >= 1e-8 keeps that relative error of the lobe's value below ~1e-6; a
#: narrower lobe is narrower than double precision resolves directions (and below ~1e-154
#: its 1 / w^2 normalisation overflows).
SLOPE_WIDTH_MIN = 1e-8

#: Widest declared slope width: at w = 1e8 the typical facet is tilted within 1 / w = 1e-8 rad
#: of vertical, the same resolution limit as :data:`SLOPE_WIDTH_MIN` from the other side
#: (and above ~1e154 the w^2 of the lobe's normalisation overflows).
SLOPE_WIDTH_MAX = 1e8

__all__ = [
    "INDEX_MAX",
    "INDEX_MIN",
    "SLOPE_WIDTH_MIN",
    "SLOPE_WIDTH_MAX",
    "width_param",
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


@dataclass(frozen=True)
class ParamInfo:
    """What a declared parameter is: name, default, description and range."""

    name: str
    default: Any
    doc: str
    kind: str
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    aliases: tuple = ()  # old keyword names that still set this parameter
    required: bool = False  # no default: must be given
    check: Any = field(
        default=None, repr=False, compare=False
    )  # validator replacing the kind's check (see param)

    def range_text(self) -> str:
        if self.kind == "index":
            return (
                f"n + ik with n > 0, k >= 0 and {INDEX_MIN:.3g} <= abs(n + ik) <= {INDEX_MAX:.3g}, "
                "or math.inf (perfect conductor)"
            )
        if self.kind == "real_index":
            return f"real, finite, in [{self.low:g}, {INDEX_MAX:.3g}]"
        if self.kind in ("real", "int"):
            lo = "-inf" if self.low is None else f"{self.low:g}"
            hi = "inf" if self.high is None else f"{self.high:g}"
            lb = "(" if (self.low_open or self.low is None) else "["
            hb = ")" if (self.high_open or self.high is None) else "]"
            what = "integer" if self.kind == "int" else "finite real"
            return f"{what} in {lb}{lo}, {hi}{hb}"
        if self.kind == "choice":
            return "one of " + ", ".join(repr(c) for c in self.low)
        return self.kind


def param(
    default: Any,
    doc: str,
    *,
    kind: str = "real",
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    choices: tuple | None = None,
    check: Callable | None = None,
):
    """Declare a model parameter (a dataclass field with validation metadata).

    ``default`` may be ``dataclasses.MISSING``: the parameter is then required.
    ``kind`` is one of ``real``, ``int``, ``index`` (complex refractive index,
    ``k >= 0``, ``math.inf`` allowed), ``real_index`` (non-absorbing index
    ``>= low``), ``choice`` (``choices``), ``object`` (checked by the model's ``_validate``).
    ``check(name, value)``, when given, replaces the kind's check: it returns the value or
    raises ``ValueError`` (e.g. an ``index`` that may also be a layer stack).
    """
    info = dict(
        doc=doc,
        kind=kind,
        low=tuple(choices) if kind == "choice" else low,
        high=high,
        low_open=low_open,
        high_open=high_open,
        check=check,
    )
    if isinstance(default, (list, dict, np.ndarray)):
        return field(default_factory=lambda: default, metadata={"scatterbench": info})
    return field(default=default, metadata={"scatterbench": info})


def width_param(default: float, doc: str, *, high: float = SLOPE_WIDTH_MAX):
    """Declare a slope-distribution width (rms slope, GGX alpha, angular width) in
    [:data:`SLOPE_WIDTH_MIN`, ``high``]: narrower or wider lobes are not resolved in float64."""
    why = f"; >= {SLOPE_WIDTH_MIN:g} (a narrower lobe is below float64's resolution of directions)"
    if high == SLOPE_WIDTH_MAX:
        why += f", <= {SLOPE_WIDTH_MAX:g} (facets within 1/{SLOPE_WIDTH_MAX:g} rad of vertical)"
    return param(default, doc + why, low=SLOPE_WIDTH_MIN, high=high)


def _range_text(low, high, low_open, high_open) -> str:
    lo = "-inf" if low is None else f"{low:g}"
    hi = "inf" if high is None else f"{high:g}"
    lb = "(" if (low_open or low is None) else "["
    hb = ")" if (high_open or high is None) else "]"
    return f"a finite real number in {lb}{lo}, {hi}{hb}"


def _is_array(value) -> bool:
    """A numpy array of at least one dimension: a model set's parameter (0-d arrays are scalars)."""
    return isinstance(value, np.ndarray) and value.ndim > 0


def _first_bad(name, rng, a, bad):
    """Raise the ``ValueError`` naming ``name``, the range and the first element where ``bad``."""
    k = int(np.argmax(bad.reshape(-1)))
    where = tuple(int(i) for i in np.unravel_index(k, a.shape))
    raise ValueError(f"{name} must be {rng}; got {a.reshape(-1)[k].item()!r} at index {where}")


def _frozen(a: np.ndarray) -> np.ndarray:
    """A read-only copy: a model set's parameters cannot change under the model."""
    a = np.array(a, copy=True)
    a.flags.writeable = False
    return a


def check_real(name, value, low=None, high=None, low_open=False, high_open=False):
    """Return ``value`` as a float, or a numpy array as a read-only float64 array (a model set,
    every element checked once), or raise ``ValueError`` naming ``name``, the range and the
    (first) offending value."""
    rng = _range_text(low, high, low_open, high_open)
    if _is_array(value):
        return _check_real_array(name, value, rng, low, high, low_open, high_open)
    if isinstance(value, (bool, np.bool_)):
        # bool is a numbers.Real subclass: True would silently become 1.0
        raise ValueError(f"{name} must be {rng}; got {value!r} (a bool is not a number)")
    if not isinstance(value, numbers.Real):
        if isinstance(value, numbers.Complex) and complex(value).imag == 0:
            value = complex(value).real
        else:
            raise ValueError(f"{name} must be {rng}; got {value!r}")
    try:
        v = float(value)
    except OverflowError:  # an integer no float can hold
        v = math.inf
    if not math.isfinite(v):
        raise ValueError(f"{name} must be {rng}; got {value!r}")
    bad = (low is not None and (v < low or (low_open and v == low))) or (
        high is not None and (v > high or (high_open and v == high))
    )
    if bad:
        raise ValueError(f"{name} must be {rng}; got {value!r}")
    return v


def _check_real_array(name, value, rng, low, high, low_open, high_open) -> np.ndarray:
    if value.dtype.kind == "c":
        if np.any(value.imag != 0):
            _first_bad(name, rng, value, value.imag != 0)
        value = value.real
    if value.dtype.kind not in "iuf":
        raise ValueError(f"{name} must be {rng} (an array of them); got an array of {value.dtype}")
    a = value.astype(np.float64, copy=False)
    bad = ~np.isfinite(a)
    with np.errstate(invalid="ignore"):
        if low is not None:
            bad |= (a <= low) if low_open else (a < low)
        if high is not None:
            bad |= (a >= high) if high_open else (a > high)
    if bad.any():
        _first_bad(name, rng, a, bad)
    return _frozen(a)


def check_index(name, value):
    """Validate a refractive index ``n + ik`` (``k >= 0``) or ``math.inf``.

    Returns ``math.inf`` for a perfect conductor, otherwise a ``complex`` whose
    imaginary part is a non-negative float (``-0.0`` is normalised to ``+0.0`` so
    that the principal square roots used for total internal reflection pick the
    evanescent, decaying branch).  A numpy array (a model set) is checked element by
    element and returned as a read-only complex128 array (``inf + 0j``: a perfect
    conductor).
    """
    rng = (
        f"n + ik with n > 0, k >= 0 and {INDEX_MIN:.3g} <= abs(n + ik) <= {INDEX_MAX:.3g} (above the upper bound the reflectance is "
        "a perfect conductor's to double precision), or math.inf for a perfect conductor"
    )
    if _is_array(value):
        if value.dtype.kind not in "iufc":
            raise ValueError(f"{name} must be {rng} (an array of them); got an array of {value.dtype}")
        z = value.astype(np.complex128, copy=False)
        pec = (z.real == math.inf) & (z.imag == 0)
        with np.errstate(invalid="ignore"):
            ok = np.isfinite(z.real) & np.isfinite(z.imag) & (z.real > 0) & (z.imag >= 0)
            ok &= (np.abs(z) >= INDEX_MIN) & (np.abs(z) <= INDEX_MAX)
        if not np.all(ok | pec):
            _first_bad(name, rng, z, ~(ok | pec))
        return _frozen(z.real + 1j * np.abs(z.imag))
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Complex):
        raise ValueError(f"{name} must be {rng}; got {value!r}")
    z = complex(value)
    if z.real == math.inf and z.imag == 0:
        return math.inf
    if not (math.isfinite(z.real) and math.isfinite(z.imag)):
        raise ValueError(f"{name} must be {rng}; got {value!r}")
    if z.real <= 0 or z.imag < 0 or not INDEX_MIN <= abs(z) <= INDEX_MAX:
        raise ValueError(f"{name} must be {rng}; got {value!r}")
    return complex(z.real, abs(z.imag))


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
    return param("paper", doc, kind="choice", choices=("paper", "corrected"))


class _DeclaredMeta(type):
    """Translates old keyword names (``cls.aliases``) before the dataclass ``__init__``."""

    def __call__(cls, *args, **kwargs):
        renamed = {}
        if cls.aliases:
            kwargs, renamed = cls._resolve_aliases(kwargs, current=None)
        if dataclasses.is_dataclass(cls):
            for f in dataclasses.fields(cls)[len(args) :]:
                if f.name not in kwargs and f.default is f.default_factory is dataclasses.MISSING:
                    doc = f.metadata.get("scatterbench", {}).get("doc", "")
                    raise ValueError(f"{f.name} is required ({doc}); it has no default")
        with _naming_old(renamed):
            return super().__call__(*args, **kwargs)


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
        for f in dataclasses.fields(self):
            info = f.metadata.get("scatterbench")
            if info is not None:
                object.__setattr__(self, f.name, _checked(f.name, getattr(self, f.name), info))
        self._validate()

    def _validate(self):
        """Hook for cross-parameter checks in subclasses."""

    @classmethod
    def check_parameter(cls, name: str, value):
        """``value`` validated as the declared parameter ``name`` (a ``ValueError`` naming it
        and its allowed range otherwise), without building an instance: for callers, such
        as scene files, that hold a value for a model they build later."""
        for f in dataclasses.fields(cls):
            if f.name == name and "scatterbench" in f.metadata:
                return _checked(name, value, f.metadata["scatterbench"])
        raise ValueError(f"{name}: not a declared parameter of {cls.__name__}")

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
            info = f.metadata.get("scatterbench")
            if info is None:
                continue
            required = f.default is dataclasses.MISSING
            out.append(
                ParamInfo(
                    name=f.name,
                    default=None if required else f.default,
                    aliases=tuple(old.get(f.name, ())),
                    required=required,
                    **info,
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


def _checked(name, value, info):
    """``value`` validated against a declared parameter's kind and range: by its ``check``
    when it has one (which may accept more than the kind, e.g. a layer stack where an index
    goes, and calls the kind's check itself), else by the kind."""
    if info.get("check") is not None:
        return info["check"](name, value)
    kind = info["kind"]
    if kind == "real":
        return check_real(name, value, info["low"], info["high"], info["low_open"], info["high_open"])
    if kind == "int":
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
            raise ValueError(f"{name} must be an integer; got {value!r}")
        check_real(name, value, info["low"], info["high"], info["low_open"], info["high_open"])
        return int(value)
    if kind == "index":
        return check_index(name, value)
    if kind == "real_index":
        z = value
        if _is_array(z):
            return check_real(name, z, info["low"], INDEX_MAX)
        if isinstance(z, numbers.Complex) and not isinstance(z, numbers.Real):
            if complex(z).imag != 0:
                raise ValueError(
                    f"{name} must be a real (non-absorbing) index >= {info['low']:g}; got {value!r}"
                )
            z = complex(z).real
        return check_real(name, z, info["low"], INDEX_MAX)
    if kind == "choice":
        choices = info["low"]
        flags = all(isinstance(c, bool) for c in choices)
        if value not in choices or (flags and not isinstance(value, (bool, np.bool_))):
            allowed = ", ".join(repr(c) for c in choices)
            raise ValueError(f"{name} must be one of {allowed}; got {value!r}")
        return bool(value) if flags else value
    return value
