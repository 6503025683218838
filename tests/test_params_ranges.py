"""Issue 13 (models): every in-range parameter gives finite values, every out-of-range one
a ValueError naming it; a bool is never a number.

Each model class in ``models.Model.registry`` is built (as the stability sweep builds it) with
each real or index parameter at its declared bounds and at 1e-300 / 1e300, and with each slope
distribution's widths there, and evaluated on both backends at a few geometries (normal,
in-plane, out-of-plane, near grazing)."""

import dataclasses
import math
import warnings

import numpy as np
import pytest

from scatterbench import models
from scatterbench.models import slopes as S
from scatterbench.models.params import INDEX_MAX, INDEX_MIN, SLOPE_WIDTH_MAX, SLOPE_WIDTH_MIN
from scatterbench.models.stroke_slopes import StrokeSlopes

_TI = np.array([0.0, 0.3, 0.3, 1.2, math.pi / 2 - 1e-9])
_TR = np.array([0.0, 0.3, 0.5, 1.2, 0.3])
_PR = np.array([0.0, 0.0, 1.0, math.pi, 0.0])
_EXTREMES = (1e-300, 1e300, -1e300, 1e-160, 5e-324)
_INDICES = (
    1e300,
    1 + 1e300j,
    1e-300 + 0j,
    1e-300 + 1e300j,
    INDEX_MIN + 0j,
    INDEX_MAX + 0j,
    INDEX_MAX * (1 + 1j) / math.sqrt(2),
    1e-300 + 1j * INDEX_MAX,
    1e-300 + 1j * INDEX_MIN,
)
_SLOPES = [StrokeSlopes] + [
    c
    for c in vars(S).values()
    if isinstance(c, type)
    and issubclass(c, S.SlopeDistribution)
    and not c.__name__.startswith("_")
    and c not in (S.SlopeDistribution, S.TabulatedSlopes, S.UnitSlopes)
]


def _values(info):
    """The values one parameter is tried at: its bounds and the float64 extremes."""
    if info.kind == "index":
        return _INDICES
    vals = list(_EXTREMES)
    if info.low is not None:
        vals.append(info.low * (1 + 1e-15) + (5e-324 if info.low == 0 else 0) if info.low_open else info.low)
    if info.high is not None:
        vals.append(info.high * (1 - 1e-15) if info.high_open else info.high)
    if info.kind == "real_index":
        vals += [INDEX_MAX, math.nextafter(INDEX_MAX, math.inf)]
    return vals


def _variants(base):
    """``(label, owner, info, value, build)`` for each parameter of ``base`` (and of its slopes)
    at each value; ``owner`` is the model's field holding the slope distribution (else None)."""
    for info in type(base).parameters():
        if info.kind in ("real", "index", "real_index"):
            for v in _values(info):
                yield (
                    f"{info.name}={v!r}",
                    None,
                    info,
                    v,
                    lambda n=info.name, v=v: dataclasses.replace(base, **{n: v}),
                )
        if isinstance(getattr(base, info.name), S.SlopeDistribution):
            for sc in _SLOPES:
                for si in sc.parameters():
                    if si.kind != "real":
                        continue
                    for v in _values(si):

                        def build(n=info.name, sc=sc, sn=si.name, v=v):
                            return dataclasses.replace(base, **{n: sc(**{sn: v})})

                        yield f"{info.name}={sc.__name__}({si.name}={v!r})", info.name, si, v, build


def _in_declared_range(info, value) -> bool:
    """Whether ``value`` lies in the range ``info`` declares (its constraint's check)."""
    try:
        info.constraint.check(info.name, value)
    except ValueError:
        return False
    return True


#: In-range values a model refuses with its own reason although its declared range admits
#: them: (class, label) -> the start of that message.  FacetBTDF declares substrate in
#: [1, INDEX_MAX] (kind "real_index" has no open bound) and refuses n = 1 in ``_validate``.
_REFUSED_IN_RANGE = {
    ("FacetBTDF", "substrate=1.0"): "substrate must be a real index > 1",
}


def _base(cls):
    return cls.sweep_base()


def _refusal_problem(cls, label, owner, info, value, exc):
    """What is wrong with a ValueError for one variant, or None: out of the declared range the
    message starts with the parameter's name; in range only a slope family (or coverage) the
    model says it refuses ("slopes must ...") or a listed refusal is allowed."""
    msg = str(exc)
    if not _in_declared_range(info, value):
        return (
            None if msg.startswith(info.name) else f"{label}: ValueError not starting with {info.name}: {msg}"
        )
    if owner is not None and msg.startswith(f"{owner} must"):
        return None
    known = _REFUSED_IN_RANGE.get((cls.__name__, label))
    if known is not None and msg.startswith(known):
        return None
    return f"{label}: in-range value refused: {msg}"


def _problems(cls, backend):
    """What went wrong for ``cls`` on ``backend``: non-finite values, warnings, other
    exceptions, an in-range value refused, or an out-of-range one accepted or refused by a
    ValueError whose message does not start with the parameter's name."""
    out = []
    base = _base(cls)
    with models.backend(backend), warnings.catch_warnings():
        warnings.simplefilter("error")  # an overflow warning is a silent-garbage symptom too
        for label, owner, info, value, build in _variants(base):
            try:
                M = build().mueller(_TI, _TR, _PR)
            except ValueError as exc:
                problem = _refusal_problem(cls, label, owner, info, value, exc)
                if problem is not None:
                    out.append(problem)
                continue
            except Exception as exc:  # noqa: BLE001 - any other exception is the failure looked for
                out.append(f"{label}: {type(exc).__name__}: {exc}")
                continue
            if not _in_declared_range(info, value):
                out.append(f"{label}: out-of-range value accepted")
            elif not np.all(np.isfinite(M)):
                out.append(f"{label}: non-finite Mueller matrix")
    return out


_CLASSES = [c for c in models.Model.registry if c is not models.Sum]


@pytest.mark.parametrize("backend", ["numba", "numpy"])
@pytest.mark.parametrize("cls", _CLASSES, ids=lambda c: c.__name__)
def test_in_range_parameters_give_finite_values(cls, backend):
    assert _problems(cls, backend) == []


@pytest.mark.parametrize(
    "build",
    [
        lambda: models.FacetBRDF(substrate=1e300),
        lambda: models.FacetBRDF(slopes=models.GaussianSlopes(1e-160)),
        lambda: models.FacetBRDF(slopes=models.ExponentialSlopes(1e-300)),
        lambda: models.CookTorranceBRDF(slopes=models.GaussianSlopes(1e-300)),
    ],
)
def test_extreme_indices_and_widths_are_refused_naming_the_bound(build):
    """A substrate index of 1e300 and slope widths of 1e-160 and 1e-300 (issue 13's examples)
    are refused, the message naming the parameter and its bound."""
    with pytest.raises(ValueError, match=r"substrate|sigma") as info:
        build()
    assert "1e-08" in str(info.value) or "1.8e+16" in str(info.value)


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_the_new_bounds_themselves_are_finite(backend):
    with models.backend(backend):
        for sc in (models.GaussianSlopes, models.ExponentialSlopes, models.GGXSlopes):
            for w in (SLOPE_WIDTH_MIN, SLOPE_WIDTH_MAX):
                s = sc(w) if sc is not models.GGXSlopes else sc(alpha=w)
                assert np.all(np.isfinite(models.FacetBRDF(slopes=s).mueller(_TI, _TR, _PR)))
        for w in (SLOPE_WIDTH_MIN, SLOPE_WIDTH_MAX):
            ct = models.CookTorranceBRDF(slopes=models.GaussianSlopes(w))
            assert np.all(np.isfinite(ct.mueller(_TI, _TR, _PR)))


def test_bounds_refuse_just_outside():
    with pytest.raises(ValueError, match="sigma"):
        models.GaussianSlopes(math.nextafter(SLOPE_WIDTH_MIN, 0))
    with pytest.raises(ValueError, match="sigma"):
        models.GaussianSlopes(math.nextafter(SLOPE_WIDTH_MAX, math.inf))
    with pytest.raises(ValueError, match="math.inf for a perfect conductor"):
        models.FacetBRDF(substrate=math.nextafter(INDEX_MAX, math.inf))
    with pytest.raises(ValueError, match="substrate"):
        models.FacetBRDF(substrate=np.array([1.5, 2 * INDEX_MAX]))


def test_perfect_conductor_limit_matches_the_largest_index():
    """At |n| = INDEX_MAX the reflection is the perfect conductor's to double precision: the
    reason for refusing larger indices (use math.inf)."""
    big = models.FacetBRDF(substrate=INDEX_MAX * (1 + 1j) / math.sqrt(2)).mueller(_TI, _TR, _PR)
    pec = models.FacetBRDF(substrate=math.inf).mueller(_TI, _TR, _PR)
    np.testing.assert_allclose(big, pec, rtol=1e-14, atol=1e-14 * np.max(np.abs(pec)))


@pytest.mark.parametrize(
    "build, name",
    [
        (lambda v: models.GaussianSlopes(v), "sigma"),
        (lambda v: models.GaussianSlopes(coverage=v), "coverage"),
        (lambda v: models.FacetBRDF(substrate=v), "substrate"),
        (lambda v: models.SubsurfaceFacetBRDF(coating=v), "coating"),
        (lambda v: models.PointSourceBRDF(model=models.FacetBRDF(), resolution=v), "resolution"),
    ],
)
@pytest.mark.parametrize("flag", [True, False, np.True_, np.array([True, False])], ids=repr)
def test_a_bool_is_not_a_number(build, name, flag):
    with pytest.raises(ValueError, match=name):
        build(flag)


def _declared_classes():
    """Every declared class of scatterbench.models (models, slope distributions, films, ...)."""
    todo, out = [models.params.Declared], []
    while todo:
        for sub in todo.pop().__subclasses__():
            todo.append(sub)
            if sub.__module__.startswith("scatterbench.models") and dataclasses.is_dataclass(sub):
                out.append(sub)
    return out


def test_stability_edges_lie_inside_the_declared_ranges():
    """Every edge value the sweep tries (declared with the parameter, or its constraint's from
    the default) passes the parameter's own check: the sweep never builds a refused instance
    by design (one would be skipped silently)."""
    bad, n = [], 0
    for cls in _declared_classes():
        for info in cls.parameters():
            for v in info.edges(info.default):
                n += 1
                if not _in_declared_range(info, v):
                    bad.append(f"{cls.__name__}.{info.name} = {v!r}")
    assert n > 100 and bad == []


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_computed_limits_equal_the_limit_models(backend):
    """Where the limit is cheap it is computed, and it is the right one: a point source over a
    vanishing disc is the collimated model, a vanishing aperture the model itself, and
    Maxwell-Beard's SO at the smallest Omega the same as at a small one."""
    ct = models.CookTorranceBRDF(convention="corrected")
    sub = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.02))
    with models.backend(backend):
        pairs = [
            (models.PointSourceBRDF(model=ct, distance=100.0, sample_radius=1e-300), ct),
            (models.DetectorAperture(model=sub, aperture=1e-300), sub),
            (models.MaxwellBeardBRDF(omega=5e-324), models.MaxwellBeardBRDF(omega=1e-300)),
        ]
        for limit, reference in pairs:
            got, want = limit.mueller(_TI, _TR, _PR), reference.mueller(_TI, _TR, _PR)
            np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13 * np.max(np.abs(want)))


@pytest.mark.parametrize("dtype", [np.int64, np.float32, np.complex128, bool])
def test_mueller_out_of_the_wrong_dtype_is_refused(dtype):
    """An ``out`` array that would truncate or reinterpret the result (integers, the other
    precision, complex, bools) is refused with its dtype named, and left unwritten."""
    out = np.zeros((16, 3), dtype=dtype)
    with pytest.raises(ValueError, match=f"dtype float64; got \\(16, 3\\) {np.dtype(dtype)}"):
        models.FacetBRDF().mueller(0.5, np.array([0.3, 0.5, 0.7]), 0.0, out=out)
    assert not out.any()


def test_mueller_out_of_the_right_dtype_is_filled():
    out = np.zeros((16, 3))
    M = models.FacetBRDF().mueller(0.5, np.array([0.3, 0.5, 0.7]), 0.0, out=out)
    np.testing.assert_array_equal(M, models.FacetBRDF().mueller(0.5, np.array([0.3, 0.5, 0.7]), 0.0))
    assert np.shares_memory(M, out)
