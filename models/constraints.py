"""Constraints: what a declared model parameter may hold.

A constraint object is one declaration of an allowed set of values, after the pattern of
scikit-learn's ``utils/_param_validation.py`` (``Interval``, ``Options``, ...), and it owns
the three things the harness needs of it:

* ``check(name, value)``: the value normalized (a float, an int, a complex index, a
  read-only array for a model set) or a :class:`ParameterError`, a ``ValueError`` naming the
  parameter, the allowed set (:meth:`Constraint.describe`) and the offending value;
* ``describe()``: the allowed set in words, the one text that error messages,
  :meth:`scatterbench.models.ParamInfo.range_text`, ``scatterbench models`` and the docs'
  parameter tables show (intervals are written by :func:`interval_notation` alone);
* ``edges(current)``: the values the stability sweep tries a parameter at, when its
  declaration names none of its own (:func:`scatterbench.models.params.param`'s ``edges``).

Scalars and arrays: :class:`Interval`, :class:`ComplexIndex` and :class:`RealIndex` hold one
value; wrapped in :class:`ScalarOrArray` they also accept a numpy array of them (a model set,
:mod:`scatterbench.models.modelset`), checked element by element and frozen.

This module is a leaf: it imports numpy and the standard library only.
"""

from __future__ import annotations

import math
import numbers
import sys

import numpy as np

__all__ = [
    "INDEX_MAX",
    "INDEX_MIN",
    "SLOPE_WIDTH_MIN",
    "SLOPE_WIDTH_MAX",
    "INDEX_EDGES",
    "FACTOR_MAX",
    "ParameterError",
    "Constraint",
    "Interval",
    "Integer",
    "ComplexIndex",
    "RealIndex",
    "Options",
    "Instance",
    "HasMethods",
    "Samples",
    "ScalarOrArray",
    "OneOf",
    "interval_notation",
]

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

#: Largest multiplicative factor a model takes: a weight of an incoherent sum, a BRDF amplitude
#: in 1/sr (a Lambertian's, Maxwell-Beard's volumetric one), a Monte Carlo term's weight.  Such a
#: factor scales every value of the model, so without an upper bound a finite, in-range value
#: (1e306) overflows the result.  Two nested factors (a weight of a sum of an amplitude's model)
#: give at most FACTOR_MAX^2 = 1e200, which leaves a factor 1e108 of float64's range
#: (1.8e308) above them for the model itself: the largest value an in-range model reaches
#: (a lobe of width SLOPE_WIDTH_MIN, ~1e15, seen at float64's grazing cosine, ~6e-17, on both
#: sides) is below 1e50.  (float32's range is the float32 route's: see float32_domain.)
FACTOR_MAX = 1e100

#: The stability sweep's complex indices: index-matched to the ambient, a hair above it, a
#: dielectric, silicon, aluminium, a near-perfect conductor and the perfect conductor.
INDEX_EDGES = (1.0 + 0j, 1.0 + 1e-9 + 0j, 1.5 + 0j, 3.88 + 0.02j, 1.37 + 7.62j, 1e6 + 1e6j, math.inf)

_CLOSED = ("both", "left", "right", "neither")


class ParameterError(ValueError):
    """A parameter outside its constraint: ``"{name} must be {allowed}; got {got}{note}"``.

    ``got`` is the offending value's repr (with its place in an array), ``note`` an optional
    reason; :class:`OneOf` rebuilds the message with its own ``allowed`` from them."""

    def __init__(self, name, allowed, got, note=""):
        self.name, self.allowed, self.got, self.note = name, allowed, got, note
        super().__init__(f"{name} must be {allowed}; got {got}{note}")

    def restated(self, allowed) -> ParameterError:
        """The same refusal with a wider constraint's description of what is allowed."""
        return ParameterError(self.name, allowed, self.got, self.note)


def interval_notation(low=None, high=None, low_open=False, high_open=False) -> str:
    """``[low, high]`` with ``(``/``)`` for open or missing bounds (``-inf``, ``inf``): the one
    place an interval is written, for every constraint and the data-file loaders."""
    lo = "-inf" if low is None else f"{low:g}"
    hi = "inf" if high is None else f"{high:g}"
    lb = "(" if (low_open or low is None) else "["
    hb = ")" if (high_open or high is None) else "]"
    return f"{lb}{lo}, {hi}{hb}"


def _is_array(value) -> bool:
    """A numpy array of at least one dimension: a model set's parameter (0-d arrays are scalars)."""
    return isinstance(value, np.ndarray) and value.ndim > 0


def _frozen(a: np.ndarray) -> np.ndarray:
    """A read-only copy: a model set's parameters cannot change under the model."""
    a = np.array(a, copy=True)
    a.flags.writeable = False
    return a


def _scalar_of(value):
    """A 0-d numpy array as the scalar it holds (0-d arrays are scalars, not model sets:
    ``np.array(0.2)``); anything else unchanged."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        return value[()]
    return value


def _is_bool(value) -> bool:
    # bool is a numbers.Integral subclass: True would silently become 1 (or 1.0)
    return isinstance(value, (bool, np.bool_))


class Constraint:
    """Base class: one declared set of allowed values (module docstring).

    ``kind`` names the family for listings and older readers of
    :class:`scatterbench.models.ParamInfo` (``real``, ``int``, ``index``, ``real_index``,
    ``choice``, ``sequence``, ``object``); ``arrays`` is True where a numpy array of values
    (a model set) is accepted."""

    kind = "object"
    arrays = False

    def check(self, name, value):  # pragma: no cover - abstract
        raise NotImplementedError

    def describe(self) -> str:  # pragma: no cover - abstract
        raise NotImplementedError

    def edges(self, current) -> list:
        """Values other than ``current`` at the edges of the allowed set (none by default:
        objects are swept through their own parameters)."""
        return []

    @property
    def base(self) -> Constraint:
        """The constraint that fixes the kind (itself; a wrapper's inner one)."""
        return self

    def fail(self, name, value, note=""):
        """Raise the :class:`ParameterError` of ``value``."""
        raise ParameterError(name, self.describe(), repr(value), note)

    def __repr__(self):
        return f"{type(self).__name__}({self.describe()!r})"


def _nudged_in(bound, up):
    """A value just inside an open ``bound`` (1e-9 relative; 1e-12 beside zero)."""
    if bound == 0:
        return 1e-12 if up else -1e-12
    grow = (bound > 0) == up
    return bound * (1 + 1e-9) if grow else bound * (1 - 1e-9)


class Interval(Constraint):
    """Real numbers between ``low`` and ``high`` (``None``: unbounded), closed at the ends
    ``closed`` names (``"both"``, ``"left"``, ``"right"``, ``"neither"``).  Finite values only,
    except an infinite bound that is closed (``Interval(0, math.inf, closed="right")``: > 0 or
    ``math.inf``).  One value; :class:`ScalarOrArray` for arrays.

    >>> Interval(0.0, 1.0, closed="right").check("rho", 1)
    1.0
    >>> Interval(0.0, 1.0, closed="right").check("rho", 0.0)
    Traceback (most recent call last):
    ...
    scatterbench.models.constraints.ParameterError: rho must be a finite real number in (0, 1]; got 0.0
    >>> Interval(0.0, 1.0, closed="right").edges(0.5)
    [1e-12, 1.0]
    """

    kind = "real"

    def __init__(self, low=None, high=None, *, closed="both"):
        if closed not in _CLOSED:
            raise ValueError(f"closed must be one of {', '.join(map(repr, _CLOSED))}; got {closed!r}")
        if low is not None and high is not None and low > high:
            raise ValueError(f"low must be <= high; got {low!r} > {high!r}")
        self.low, self.high, self.closed = low, high, closed

    @property
    def low_open(self) -> bool:
        return self.closed in ("right", "neither")

    @property
    def high_open(self) -> bool:
        return self.closed in ("left", "neither")

    def _infinite_ok(self) -> bool:
        return (self.high == math.inf and not self.high_open) or (self.low == -math.inf and not self.low_open)

    def describe(self) -> str:
        what = "a real number" if self._infinite_ok() else "a finite real number"
        return f"{what} in {interval_notation(self.low, self.high, self.low_open, self.high_open)}"

    def outside(self, a) -> np.ndarray:
        """Boolean array: where the float64 array ``a`` lies outside the interval (NaN always).

        Two comparisons, each false for NaN: an unbounded end (``None``) compares as an open
        bound at infinity, which refuses that infinity, and a closed infinite bound admits its
        own; so infinities need no test of their own (a fit checks its walkers' parameters at
        every step: four numpy calls an array, where the tests of NaN and infinities took eight
        to twelve)."""
        low = -math.inf if self.low is None else self.low
        high = math.inf if self.high is None else self.high
        above = (a > low) if (self.low is None or self.low_open) else (a >= low)
        below = (a < high) if (self.high is None or self.high_open) else (a <= high)
        return ~(above & below)

    def _scalar(self, name, value) -> float:
        """``value`` as a float (a complex number with no imaginary part counts), unchecked range."""
        value = _scalar_of(value)
        if _is_array(value):
            self.fail(name, value, " (one value: this parameter is not an array parameter)")
        if _is_bool(value):
            self.fail(name, value, " (a bool is not a number)")
        if not isinstance(value, numbers.Real):
            if isinstance(value, numbers.Complex) and complex(value).imag == 0:
                value = complex(value).real
            else:
                self.fail(name, value)
        try:
            return float(value)
        except OverflowError:  # an integer no float can hold
            return math.inf if value > 0 else -math.inf

    def check(self, name, value) -> float:
        v = self._scalar(name, value)
        if self.outside(np.float64(v)):
            self.fail(name, value)
        return v

    def check_array(self, name, value) -> np.ndarray:
        """A numpy array of values as a read-only float64 array, every element checked once."""
        if value.dtype.kind == "c":
            if np.any(value.imag != 0):
                _first_bad(self, name, value, value.imag != 0)
            value = value.real
        if value.dtype.kind not in "iuf":
            self.fail(name, value, f" (an array of {value.dtype}; an array of numbers was expected)")
        a = value.astype(np.float64, copy=False)
        bad = self.outside(a)
        if bad.any():
            _first_bad(self, name, a, bad)
        return _frozen(a)

    def edges(self, current) -> list:
        """The bounds (just inside an open one), and 100 times ``current`` when unbounded above."""
        vals = []
        if self.low is not None and math.isfinite(self.low):
            vals.append(_nudged_in(self.low, up=True) if self.low_open else self.low)
        if self.high is not None and math.isfinite(self.high):
            vals.append(_nudged_in(self.high, up=False) if self.high_open else self.high)
        if self.high is None and isinstance(current, (int, float)) and current:
            vals.append(current * 100)
        return [v for v in vals if v != current]


def _first_bad(constraint, name, a, bad):
    """Raise the :class:`ParameterError` naming the first element of array ``a`` where ``bad``."""
    k = int(np.argmax(bad.reshape(-1)))
    where = tuple(int(i) for i in np.unravel_index(k, a.shape))
    got = f"{a.reshape(-1)[k].item()!r} at index {where}"
    raise ParameterError(name, constraint.describe(), got)


class Integer(Constraint):
    """Integers between ``low`` and ``high`` (``None``: unbounded), both ends included."""

    kind = "int"
    low_open = high_open = False  # both ends are included

    def __init__(self, low=None, high=None):
        self.low, self.high = low, high

    def describe(self) -> str:
        return f"an integer in {interval_notation(self.low, self.high)}"

    def check(self, name, value) -> int:
        value = _scalar_of(value)
        if _is_bool(value):
            self.fail(name, value, " (a bool is not a number)")
        if not isinstance(value, numbers.Integral):
            self.fail(name, value)
        v = int(value)
        if (self.low is not None and v < self.low) or (self.high is not None and v > self.high):
            self.fail(name, value)
        return v

    def edges(self, current) -> list:
        """The bounds, and 100 times ``current`` when unbounded above."""
        vals = [b for b in (self.low, self.high) if b is not None]
        if self.high is None and current:
            vals.append(current * 100)
        return [int(v) for v in vals if v != current]


class ComplexIndex(Constraint):
    """A refractive index ``n + ik`` with ``n > 0``, ``k >= 0`` and ``INDEX_MIN <= |n + ik| <=
    INDEX_MAX``, or ``math.inf`` (a perfect conductor).

    A finite index comes back as a ``complex`` whose imaginary part is a non-negative float
    (``-0.0`` becomes ``+0.0``, so that the principal square roots used for total internal
    reflection pick the evanescent, decaying branch); ``math.inf`` as ``math.inf``."""

    kind = "index"

    def describe(self) -> str:
        return (
            f"n + ik with n > 0, k >= 0 and {INDEX_MIN:.3g} <= abs(n + ik) <= {INDEX_MAX:.3g} (above "
            "the upper bound the reflectance is a perfect conductor's to double precision), or "
            "math.inf for a perfect conductor"
        )

    def check(self, name, value):
        value = _scalar_of(value)
        if _is_array(value) or _is_bool(value) or not isinstance(value, numbers.Complex):
            self.fail(name, value)
        z = complex(value)
        if z.real == math.inf and z.imag == 0:
            return math.inf
        if not (math.isfinite(z.real) and math.isfinite(z.imag)):
            self.fail(name, value)
        if z.real <= 0 or z.imag < 0 or not INDEX_MIN <= abs(z) <= INDEX_MAX:
            self.fail(name, value)
        return complex(z.real, abs(z.imag))

    def check_array(self, name, value) -> np.ndarray:
        """A numpy array of indices as a read-only complex128 array (``inf + 0j``: a perfect
        conductor), every element checked once."""
        if value.dtype.kind not in "iufc":
            self.fail(name, value, f" (an array of {value.dtype}; an array of numbers was expected)")
        z = value.astype(np.complex128, copy=False)
        pec = (z.real == math.inf) & (z.imag == 0)
        with np.errstate(invalid="ignore"):
            ok = np.isfinite(z.real) & np.isfinite(z.imag) & (z.real > 0) & (z.imag >= 0)
            ok &= (np.abs(z) >= INDEX_MIN) & (np.abs(z) <= INDEX_MAX)
        if not np.all(ok | pec):
            _first_bad(self, name, z, ~(ok | pec))
        return _frozen(z.real + 1j * np.abs(z.imag))

    def edges(self, current) -> list:
        return [v for v in INDEX_EDGES if v != current]


class RealIndex(Interval):
    """A real (non-absorbing) index in ``[low, INDEX_MAX]``; a complex number with no
    imaginary part counts."""

    kind = "real_index"

    def __init__(self, low=1.0):
        super().__init__(low, INDEX_MAX)

    def describe(self) -> str:
        return (
            f"a real (non-absorbing) index, a finite real number in {interval_notation(self.low, self.high)}"
        )

    def edges(self, current) -> list:
        """``low`` and 100 times ``current`` (``INDEX_MAX`` is an overflow bound, not an edge)."""
        vals = [self.low] + ([current * 100] if isinstance(current, (int, float)) and current else [])
        return [v for v in vals if v != current]


def _member(value, options) -> bool:
    """``value in options`` without numpy's elementwise ``==`` (an array is never an option)."""
    if isinstance(value, np.ndarray):
        return False
    return any(value == o for o in options)


class Options(Constraint):
    """One of a set of values (strings, or the flags ``True``/``False``, which then must be
    bools: 1 is no flag)."""

    kind = "choice"

    def __init__(self, *options):
        if not options:
            raise ValueError("options: give at least one")
        self.options = tuple(options)
        self._flags = all(isinstance(o, bool) for o in self.options)

    def describe(self) -> str:
        if len(self.options) == 1:
            return repr(self.options[0])
        return "one of " + ", ".join(repr(o) for o in self.options)

    def check(self, name, value):
        if not _member(value, self.options) or (self._flags and not _is_bool(value)):
            self.fail(name, value)
        return bool(value) if self._flags else value

    def edges(self, current) -> list:
        return [o for o in self.options if o != current]


class Instance(Constraint):
    """An instance of one of ``types`` (or ``None`` with ``none=True``); ``text`` overrides the
    description (default ``"a T1 or a T2"``)."""

    def __init__(self, *types, none=False, text=None):
        self.types, self.none, self.text = types, none, text

    def describe(self) -> str:
        if self.text is not None:
            return self.text
        names = " or ".join(f"a {t.__name__}" for t in self.types)
        return f"None or {names}" if self.none else names

    def check(self, name, value):
        if (self.none and value is None) or isinstance(value, self.types):
            return value
        self.fail(name, value)


class HasMethods(Constraint):
    """An object with the methods ``names`` (duck typing); ``text`` overrides the description."""

    def __init__(self, *names, text=None):
        self.names, self.text = names, text

    def describe(self) -> str:
        return self.text or "an object with method(s) " + ", ".join(self.names)

    def check(self, name, value):
        if all(callable(getattr(value, m, None)) for m in self.names):
            return value
        self.fail(name, value)


class Samples(Constraint):
    """A sequence of at least ``min_size`` numbers, each in ``element`` (an :class:`Interval`),
    strictly increasing with ``increasing=True``; returned as a tuple of floats."""

    kind = "sequence"

    def __init__(self, element, *, min_size=2, increasing=False):
        self.element, self.min_size, self.increasing = element, min_size, increasing

    def describe(self) -> str:
        order = ", strictly increasing," if self.increasing else ","
        return f"a sequence of at least {self.min_size} values{order} each {self.element.describe()}"

    def check(self, name, value) -> tuple:
        if not isinstance(value, np.ndarray) and any(_is_bool(v) for v in _items(value)):
            # numpy turns (True, 1.6) into floats: a bool is no sample
            self.fail(name, value, " (a bool is not a number)")
        try:
            a = np.asarray(value)
        except (TypeError, ValueError):  # ragged nesting
            self.fail(name, value)
        if a.ndim != 1 or a.size < self.min_size:
            self.fail(name, value)
        try:
            a = self.element.check_array(name, a)
        except ParameterError as exc:
            raise exc.restated(self.describe()) from None
        if self.increasing and np.any(np.diff(a) <= 0):
            self.fail(name, value, " (not strictly increasing)")
        return tuple(a.tolist())


def _items(value):
    """The items of a sequence (none for anything that is not iterable)."""
    try:
        return list(value)
    except TypeError:
        return []


class ScalarOrArray(Constraint):
    """``inner``'s values, or a numpy array of them (a model set: one model per element,
    :mod:`scatterbench.models.modelset`), returned read-only."""

    arrays = True

    def __init__(self, inner):
        if not callable(getattr(inner, "check_array", None)):
            raise TypeError(f"inner must be a constraint with check_array; got {inner!r}")
        self.inner = inner

    @property
    def kind(self):
        return self.inner.kind

    @property
    def base(self):
        return self.inner.base

    def describe(self) -> str:
        return self.inner.describe()

    def check(self, name, value):
        return self.inner.check_array(name, value) if _is_array(value) else self.inner.check(name, value)

    def edges(self, current) -> list:
        return self.inner.edges(current)


class OneOf(Constraint):
    """Any of ``alternatives``, tried in order; the first fixes the kind and the edges.  A
    value none accepts gets one message naming all of them (and the first's detail, e.g. the
    index of the first bad element of an array)."""

    def __init__(self, *alternatives):
        if len(alternatives) < 2:
            raise ValueError("alternatives: give at least two constraints")
        self.alternatives = alternatives

    @property
    def kind(self):
        return self.alternatives[0].kind

    @property
    def arrays(self):
        return any(a.arrays for a in self.alternatives)

    @property
    def base(self):
        return self.alternatives[0].base

    def describe(self) -> str:
        return " or ".join(a.describe() for a in self.alternatives)

    def check(self, name, value):
        errors = []
        for alt in self.alternatives:
            try:
                return alt.check(name, value)
            except ParameterError as exc:
                errors.append(exc)
        raise errors[0].restated(self.describe())

    def edges(self, current) -> list:
        return self.alternatives[0].edges(current)
