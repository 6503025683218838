"""Constraint objects (models.constraints): each one's check, normalization, message and edges,
and the declarations built on them (models.params.param, ParamInfo)."""

import dataclasses
import math
import numbers
import re

import numpy as np
import pytest

from scatterbench import models
from scatterbench.models.constraints import (
    INDEX_EDGES,
    INDEX_MAX,
    INDEX_MIN,
    ComplexIndex,
    Constraint,
    HasMethods,
    Instance,
    Integer,
    Interval,
    OneOf,
    Options,
    ParameterError,
    RealIndex,
    Samples,
    ScalarOrArray,
    interval_notation,
)
from scatterbench.models.params import Declared, ParamInfo, param


def _message(constraint, value, name="x"):
    with pytest.raises(ParameterError) as exc:
        constraint.check(name, value)
    return str(exc.value)


# ----------------------------------------------------------------------------- the interval text
@pytest.mark.parametrize(
    "args, text",
    [
        ((0, 1), "[0, 1]"),
        ((0, 1, True, False), "(0, 1]"),
        ((0, 1, False, True), "[0, 1)"),
        ((None, None), "(-inf, inf)"),
        ((1e-8, 1e8), "[1e-08, 1e+08]"),
        ((0, math.inf), "[0, inf]"),
    ],
)
def test_interval_notation(args, text):
    assert interval_notation(*args) == text


# ----------------------------------------------------------------------------- Interval
def test_interval_checks_normalizes_and_names_the_offender():
    c = Interval(0.0, 1.0, closed="right")
    assert c.check("x", 1) == 1.0 and type(c.check("x", 1)) is float
    assert c.check("x", 0.5 + 0j) == 0.5  # a complex number with no imaginary part is real
    assert c.describe() == "a finite real number in (0, 1]"
    assert _message(c, 0.0) == "x must be a finite real number in (0, 1]; got 0.0"
    assert _message(c, float("nan")).endswith("got nan")
    assert _message(c, 0.5 + 1j).endswith("got (0.5+1j)")
    assert _message(c, True) == "x must be a finite real number in (0, 1]; got True (a bool is not a number)"
    assert "not an array parameter" in _message(c, np.array([0.5]))


def test_interval_admits_only_a_closed_infinite_bound():
    finite = Interval(0.0)
    with pytest.raises(ParameterError, match=r"^d must be a finite real number in \[0, inf\); got inf$"):
        finite.check("d", math.inf)
    with_inf = Interval(0.0, math.inf, closed="right")
    assert with_inf.check("d", math.inf) == math.inf and with_inf.check("d", 10**400) == math.inf
    assert with_inf.describe() == "a real number in (0, inf]"
    with pytest.raises(ParameterError, match=r"got -inf"):
        with_inf.check("d", -math.inf)


@pytest.mark.parametrize("low", [None, -math.inf, -1.0, 0.0])
@pytest.mark.parametrize("high", [None, 1.0, math.inf])
@pytest.mark.parametrize("closed", ["both", "left", "right", "neither"])
def test_interval_outside_follows_its_rule_element_by_element(low, high, closed):
    """``outside`` (two comparisons an array) against the rule written out per value: NaN is
    outside; an infinity only inside at a closed bound of that infinity (never at an unbounded
    end); a finite value by the bounds' closedness."""
    c = Interval(low, high, closed=closed)
    a = np.array([-math.inf, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0, math.inf, math.nan])

    def rule(x):
        if math.isnan(x):
            return True
        if math.isinf(x):
            bound, closed_there = (high, not c.high_open) if x > 0 else (low, not c.low_open)
            return not (bound == x and closed_there)
        below = low is not None and (x <= low if c.low_open else x < low)
        above = high is not None and (x >= high if c.high_open else x > high)
        return below or above

    assert c.outside(a).tolist() == [rule(x) for x in a]
    assert [bool(c.outside(np.float64(x))) for x in a] == [rule(x) for x in a]


def test_interval_refuses_a_bad_declaration():
    with pytest.raises(ValueError, match="closed must be one of"):
        Interval(0, 1, closed="open")
    with pytest.raises(ValueError, match="low must be <= high"):
        Interval(2, 1)


@pytest.mark.parametrize(
    "constraint, current, edges",
    [
        (Interval(0.0, 1.0), 0.5, [0.0, 1.0]),
        (Interval(0.0, 1.0), 1.0, [0.0]),
        (Interval(0.0, closed="right"), 2.0, [1e-12, 200.0]),  # open zero: just inside; x100 above
        (Interval(2.0, 4.0, closed="neither"), 3.0, [2.0 * (1 + 1e-9), 4.0 * (1 - 1e-9)]),
        (Interval(-1.0, 1.0, closed="neither"), 0.0, [-1.0 * (1 - 1e-9), 1.0 * (1 - 1e-9)]),
        (Interval(), 0.0, []),
    ],
)
def test_interval_edges(constraint, current, edges):
    got = constraint.edges(current)
    assert got == edges
    for v in got:  # every edge is inside the interval
        constraint.check("x", v)


def test_scalar_or_array_checks_each_element_once_and_freezes():
    c = ScalarOrArray(Interval(0.0, 1.0))
    a = c.check("rho", np.array([[0.1], [1]]))
    assert a.dtype == np.float64 and not a.flags.writeable and a.shape == (2, 1)
    assert c.check("rho", 0.3) == 0.3 and c.arrays and c.kind == "real"
    msg = _message(c, np.array([[0.5, 0.2], [2.0, 0.1]]), "rho")
    assert msg == "rho must be a finite real number in [0, 1]; got 2.0 at index (1, 0)"
    assert _message(c, np.array([0.5, 0.5 + 1j]), "rho").endswith("got (0.5+1j) at index (1,)")
    assert "array of <U1" in _message(c, np.array(["a"]), "rho")
    with pytest.raises(TypeError, match="check_array"):
        ScalarOrArray(Options("a", "b"))


# ----------------------------------------------------------------------------- Integer
def test_integer():
    c = Integer(1, 256)
    assert c.check("n", np.int64(7)) == 7 and type(c.check("n", np.int64(7))) is int
    assert c.describe() == "an integer in [1, 256]"
    assert _message(c, 2.0, "n") == "n must be an integer in [1, 256]; got 2.0"
    assert _message(c, 0, "n").endswith("got 0")
    assert _message(c, True, "n").endswith("got True (a bool is not a number)")
    assert Integer(0).check("seed", 10**30) == 10**30  # no float rounding of large integers
    assert c.edges(4) == [1, 256] and Integer(2).edges(3) == [2, 300]


# ----------------------------------------------------------------------------- indices
def test_complex_index():
    c = ComplexIndex()
    z = c.check("substrate", complex(1.5, -0.0))
    assert z == 1.5 and math.copysign(1.0, z.imag) == 1.0  # -0.0 made +0.0 (decaying branch)
    assert c.check("substrate", math.inf) == math.inf
    for bad in (1 - 1j, 0.0, -1.5, complex("nan"), 2 * INDEX_MAX, INDEX_MIN / 2, "1.5", True):
        msg = _message(c, bad, "substrate")
        assert msg.startswith("substrate must be n + ik with n > 0, k >= 0") and msg.endswith(f"got {bad!r}")
        assert "math.inf for a perfect conductor" in msg and "1.8e+16" in msg
    assert c.edges(1.5 + 0j) == [e for e in INDEX_EDGES if e != 1.5]
    a = ScalarOrArray(c).check("substrate", np.array([1.5, math.inf]))
    assert a.dtype == np.complex128 and a[1] == complex(math.inf, 0)
    assert _message(ScalarOrArray(c), np.array([1.5, 1 - 1j]), "substrate").endswith(
        "got (1-1j) at index (1,)"
    )


def test_real_index():
    c = RealIndex(1.0)
    assert c.check("coating", 1.5 + 0j) == 1.5 and c.kind == "real_index"
    msg = _message(c, 1.5 + 0.1j, "coating")
    assert msg.startswith("coating must be a real (non-absorbing) index, a finite real number in [1, ")
    assert _message(c, 0.9, "coating").endswith("got 0.9")
    assert _message(c, math.inf, "coating").endswith("got inf")
    assert c.edges(1.5) == [1.0, 150.0]  # INDEX_MAX bounds the arithmetic, it is no edge


# ----------------------------------------------------------------------------- options, objects
def test_options():
    c = Options("paper", "corrected")
    assert c.check("convention", "paper") == "paper" and c.kind == "choice"
    assert (
        _message(c, "energy", "convention") == "convention must be one of 'paper', 'corrected'; got 'energy'"
    )
    assert _message(c, np.array(["paper"]), "convention").startswith("convention must be one of")
    assert c.edges("paper") == ["corrected"]
    flags = Options(True, False)
    assert flags.check("polarized", np.True_) is True
    assert _message(flags, 1, "polarized") == "polarized must be one of True, False; got 1"
    assert Options("auto").describe() == "'auto'"
    with pytest.raises(ValueError, match="at least one"):
        Options()


def test_instance_and_has_methods():
    c = Instance(tuple, list, text="a tuple of pairs")
    assert c.check("terms", [1]) == [1]
    assert _message(c, 3, "terms") == "terms must be a tuple of pairs; got 3"
    maybe = Instance(models.Films, none=True)
    assert maybe.check("f", None) is None and maybe.describe() == "None or a Films"
    assert c.edges(()) == [] and c.kind == "object"
    duck = HasMethods("mueller", text="an object with a mueller method")
    assert duck.check("model", models.FacetBRDF()) == models.FacetBRDF()
    assert _message(duck, 3, "model") == "model must be an object with a mueller method; got 3"


def test_samples():
    c = Samples(Interval(0.0), increasing=True)
    assert c.check("zeta", [0, 0.5, 2]) == (0.0, 0.5, 2.0)
    assert c.describe() == (
        "a sequence of at least 2 values, strictly increasing, each a finite real number in [0, inf)"
    )
    assert _message(c, (0.0, 0.2, 0.1), "zeta").endswith("(not strictly increasing)")
    assert _message(c, (0.0, -1.0), "zeta").endswith("got -1.0 at index (1,)")
    assert _message(c, (1.0,), "zeta").endswith("got (1.0,)")
    assert _message(c, ((0.0, 1.0), (2.0,)), "zeta").startswith("zeta must be a sequence")  # ragged
    assert "a bool is not a number" in _message(c, (True, False), "zeta")


def test_one_of_names_every_alternative_and_keeps_the_first_s_detail():
    c = OneOf(Options("auto"), Integer(1, 4096))
    assert c.check("resolution", "auto") == "auto" and c.check("resolution", 12) == 12
    assert _message(c, 0, "resolution") == "resolution must be 'auto' or an integer in [1, 4096]; got 0"
    index = OneOf(ScalarOrArray(ComplexIndex()), Instance(models.FilmStack, text="a models.FilmStack"))
    msg = _message(index, np.array([1.5, 1 - 1j]), "substrate")
    assert msg.endswith("or a models.FilmStack; got (1-1j) at index (1,)")
    assert index.kind == "index" and index.arrays and index.edges(math.inf) == list(INDEX_EDGES[:-1])
    stack = models.FilmStack()
    assert index.check("substrate", stack) is stack
    with pytest.raises(ValueError, match="at least two"):
        OneOf(Integer())


# ----------------------------------------------------------------------------- declarations
@dataclasses.dataclass(frozen=True)
class _Knob(Declared):
    k: float = param(1.0, "a knob", ScalarOrArray(Interval(0.0, 2.0)), edges=(0.0, 0.5))
    mode: str = param("a", "a mode", Options("a", "b"))


def test_param_takes_a_constraint_and_param_info_reads_it():
    with pytest.raises(TypeError, match="constraint must be"):
        param(1.0, "a knob", "real")
    k, mode = _Knob.parameters()
    assert isinstance(k, ParamInfo) and k.range_text() == "a finite real number in [0, 2]"
    assert (k.kind, k.low, k.high, k.low_open, k.high_open, k.choices) == (
        "real",
        0.0,
        2.0,
        False,
        False,
        None,
    )
    assert k.edges(1.0) == [0.0, 0.5] and k.edges(0.5) == [0.0]  # the declaration's own edges
    assert mode.kind == "choice" and mode.choices == ("a", "b") and mode.edges("a") == ["b"]
    assert _Knob(k=np.int64(2)).k == 2.0
    with pytest.raises(ValueError, match=re.escape("k must be a finite real number in [0, 2]; got 3")):
        _Knob(k=3)
    assert _Knob.check_parameter("mode", "b") == "b"


def _declared_classes():
    todo, out = [Declared], []
    while todo:
        for sub in todo.pop().__subclasses__():
            todo.append(sub)
            if sub.__module__.startswith("scatterbench.models") and dataclasses.is_dataclass(sub):
                out.append(sub)
    return out


_NUMERIC = ("real", "int", "index", "real_index", "sequence")


def test_no_numeric_parameter_is_declared_a_bare_object():
    """A parameter whose default is a number (or a tuple of numbers) is declared with a numeric
    constraint; every constraint is one of the library's (no catch-all)."""
    seen = 0
    for cls in _declared_classes():
        for info in cls.parameters():
            assert isinstance(info.constraint, Constraint) and type(info.constraint) is not Constraint
            d = info.default
            numeric = isinstance(d, numbers.Number) and not isinstance(d, bool)
            numeric |= isinstance(d, tuple) and len(d) > 0 and all(isinstance(v, numbers.Number) for v in d)
            if numeric:
                seen += 1
                assert info.kind in _NUMERIC, (cls.__name__, info.name, info.kind)
    assert seen > 50


def test_every_numeric_parameter_names_itself_its_range_and_the_value():
    """NaN given to any numeric parameter: a ValueError that starts with the parameter's name
    and holds its allowed range and the value (the message of its constraint)."""
    checked = 0
    for cls in _declared_classes():
        for info in cls.parameters():
            if info.kind not in ("real", "index", "real_index"):
                continue
            with pytest.raises(ValueError) as exc:
                cls.check_parameter(info.name, float("nan"))
            msg = str(exc.value)
            assert msg.startswith(f"{info.name} must be ") and "nan" in msg, msg
            assert info.constraint.base.describe() in msg, msg
            checked += 1
    assert checked > 40
