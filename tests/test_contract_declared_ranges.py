"""The contract, generated from the declarations (issue 31): for every registered model class,
every slope distribution, film and shadowing option, parameters drawn by hypothesis inside the
declared ranges (from each class's declared constraints, not a hand list; hypothesis's floats
include the bounds and the float extremes), at geometries over the hemisphere, grazing
included, on both backends and both precisions, give finite values, M00 >= 0 and realizable
Mueller matrices; a value outside a declared range is refused with a ValueError naming it.

Tolerances.  Realizability as the kit's (``REALIZABLE_TOL``): the smallest coherency
eigenvalue >= -1e-9 M00, a million roundings of the matrix's scale (the elements of a
realizable matrix are bounded by M00), so only a physically wrong matrix fails it.  float32 is
held to finiteness (or the ValueError naming ``precision`` where the value is beyond float32's
range) and to M00 >= -1e-2 of the float64 M00: the float32-safe domain's tolerance
(``float32_domain.TOLERANCE``), outside which it evaluates in float64 and rounds.

Cost knobs (``pairs``, ``resolution``, ``tol``, ``seed``) and wrapped models keep the kit's
cheap instance (``kit_variant``): their ranges are tested by the refusals below, their
upper ends cost minutes per evaluation, not accuracy.
"""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from scatterbench import models
from scatterbench.models import constraints as C
from scatterbench.models import thin_film
from scatterbench.models.polarization import coherency_eigenvalues
from scatterbench.models.slopes import SlopeDistribution

REALIZABLE_TOL = 1e-9
FLOAT32_TOL = 1e-2
OBJECTS = {"slopes", "phase", "coating_films"}
COST = {"pairs", "resolution", "tol", "seed", "model", "coefficients"}
CLASSES = [c for c in models.Model.registry if c.sweep_base() is not None]
SLOPE_CLASSES = [
    getattr(models, n)
    for n in sorted(dir(models))
    if isinstance(getattr(models, n), type) and issubclass(getattr(models, n), SlopeDistribution)
    and getattr(models, n) is not SlopeDistribution
]  # fmt: skip
SETTINGS = settings(
    max_examples=8,
    deadline=None,
    derandomize=True,
    suppress_health_check=list(HealthCheck),
    database=None,
    phases=[Phase.explicit, Phase.reuse, Phase.generate],  # no shrinking: CI reports the example as found
)


def _base(c):
    while isinstance(c, (C.ScalarOrArray, C.OneOf)):
        c = c.inner if isinstance(c, C.ScalarOrArray) else c.alternatives[0]
    return c


def _index():
    finite = (
        st.tuples(st.floats(C.INDEX_MIN, C.INDEX_MAX), st.floats(0.0, C.INDEX_MAX))
        .map(lambda nk: complex(*nk))
        .filter(lambda z: C.INDEX_MIN <= abs(z) <= C.INDEX_MAX)
    )
    return st.one_of(finite, st.just(math.inf), st.sampled_from(C.INDEX_EDGES))


def _interval(c):
    inf_ok = c.high == math.inf and not c.high_open
    return st.floats(
        min_value=c.low, max_value=None if c.high in (None, math.inf) else c.high,
        exclude_min=c.low_open and c.low is not None, exclude_max=c.high_open and c.high not in (None, math.inf),
        allow_nan=False, allow_infinity=inf_ok,
    )  # fmt: skip


def value_strategy(info):
    """In-range values of a declared parameter, from its constraint; ``None``: keep the kit's."""
    if info.name in COST:
        return None
    if info.name == "slopes":
        return st.sampled_from(SLOPE_CLASSES).flatmap(instance_strategy)
    if info.name == "phase":
        return instance_strategy(models.HenyeyGreenstein)
    if info.name == "coating_films":
        return st.one_of(st.none(), instance_strategy(models.Films))
    if info.name == "layers":
        return st.lists(st.tuples(_index().filter(lambda z: z != math.inf), _interval(thin_film.Layers.THICKNESS)),
                        max_size=2).map(tuple)  # fmt: skip
    c = _base(info.constraint)
    if isinstance(c, C.Options):
        return st.sampled_from(c.options)
    if isinstance(c, C.ComplexIndex):
        return _index()
    if isinstance(c, C.Interval):
        return _interval(c)
    return None


def instance_strategy(cls, base=None):
    """Instances of ``cls`` with every declared parameter drawn (those it accepts together)."""
    base = cls() if base is None else base
    drawn = {p.name: s for p in cls.parameters() if (s := value_strategy(p)) is not None}

    def build(values):
        try:
            return base.replace(**values)
        except ValueError:  # a combination the class refuses as a whole (cross-parameter rule)
            return None

    return st.fixed_dictionaries(drawn).map(build).filter(lambda m: m is not None)


def _accepts(cls, slopes):
    try:
        cls.sweep_base().replace(**{**cls.kit_variant, "slopes": slopes})
        return True
    except ValueError:
        return False


ANGLE = st.floats(0.0, 0.5 * math.pi)
GEOMETRY = st.tuples(st.lists(ANGLE, min_size=3, max_size=3), st.lists(ANGLE, min_size=3, max_size=3),
                     st.lists(st.floats(-1e6, 1e6), min_size=3, max_size=3))  # fmt: skip


def _angles(g):
    ti, tr, pr = (np.array(a, dtype=float) for a in g)
    h = 0.5 * math.pi  # normal and grazing always
    return np.r_[ti, 0.0, h, h], np.r_[tr, 0.0, h, 0.3], np.r_[pr, 0.0, math.pi, 0.0]


def _judge(m, ti, tr, pr):
    # floating-point warnings are the stability sweep's findings; the contract is the values
    with np.errstate(all="ignore"):
        _judge_values(m, ti, tr, pr)


def _judge_values(m, ti, tr, pr):
    for backend in models.evaluation.BACKENDS:
        with models.backend(backend):
            M = m.mueller(ti, tr, pr)
            assert np.isfinite(M).all(), (backend, repr(m))
            m00 = M[..., 0, 0]
            assert (m00 >= 0).all(), (backend, repr(m), m00.min())
            live = m00 > 1e-250
            if live.any():
                ev = coherency_eigenvalues(M[live])[:, 0] / m00[live]
                assert ev.min() >= -REALIZABLE_TOL, (backend, repr(m), ev.min())
            try:
                M32 = m.mueller(ti, tr, pr, precision="float32")
            except ValueError as exc:
                assert "precision" in str(exc)
                assert np.abs(M).max() > np.finfo(np.float32).max
                continue
            assert np.isfinite(M32).all(), (backend, "float32", repr(m))
            assert (M32[..., 0, 0] >= -FLOAT32_TOL * m00).all(), (backend, "float32", repr(m))


#: in-range combinations this test found non-finite, not yet fixed.  Not strict: which example
#: hypothesis reaches first varies with the run's selection, so a class may pass one run; the
#: deterministic reproductions are the strict xfails at the end of this file.
OPEN: dict = {}  # none now (SingleScatterBRDF and SubsurfaceFacetBRDF were: see the end of this file)
PARAMS = [
    pytest.param(c, marks=pytest.mark.xfail(strict=False, reason=OPEN[c.__name__]))
    if c.__name__ in OPEN
    else c
    for c in CLASSES
]


@pytest.mark.parametrize("cls", PARAMS, ids=[c.__name__ for c in CLASSES])
def test_in_range_parameters_give_finite_realizable_values(cls):
    base = cls.sweep_base().replace(**cls.kit_variant)
    drawn = {}
    for p in cls.parameters():
        s = value_strategy(p)
        if p.name == "slopes" and s is not None:
            ok = [k for k in SLOPE_CLASSES if _accepts(cls, k())]
            s = st.sampled_from(ok).flatmap(instance_strategy)
        if s is not None:
            drawn[p.name] = s

    @SETTINGS
    @given(values=st.fixed_dictionaries(drawn), geometry=GEOMETRY)
    def run(values, geometry):
        try:
            m = base.replace(**values)
        except ValueError as exc:
            # only a cross-parameter rule, or a model's rule on an object it holds (Cook-Torrance
            # takes Gaussian slopes of coverage 1 only), may refuse in-range values
            named = [k for k in values if str(exc).startswith(f"{k} must") and k not in OBJECTS]
            for k in named:  # alone, the value must be accepted: the rule is between parameters
                base.replace(**{k: values[k]})
            return
        _judge(m, *_angles(geometry))

    run()


def _outside(info):
    """Values just outside a declared interval (and a bool, a string), or none."""
    c = _base(info.constraint)
    if not isinstance(c, C.Interval) or info.name in ("tol",):
        return []
    out = ["1.0", True]
    if c.low is not None and math.isfinite(c.low):
        out.append(c.low if c.low_open else np.nextafter(c.low, -math.inf))
    if c.high is not None and math.isfinite(c.high):
        out.append(c.high if c.high_open else np.nextafter(c.high, math.inf))
    return out + [math.nan]


CASES = [(cls, p.name, v) for cls in CLASSES + SLOPE_CLASSES + [models.HenyeyGreenstein, models.Films]
         for p in cls.parameters() for v in _outside(p)]  # fmt: skip


@pytest.mark.parametrize("cls, name, value", CASES, ids=[f"{c.__name__}-{n}-{v!r}" for c, n, v in CASES])
def test_values_outside_a_declared_range_are_refused_naming_it(cls, name, value):
    base = cls.sweep_base().replace(**cls.kit_variant) if cls in CLASSES else cls()
    with pytest.raises(ValueError, match=rf"^{name} must"):
        base.replace(**{name: value})


def test_found_single_scatter_extreme():
    """Found by the contract: HG at g -> -1 and backscatter (the coating's normal incidence and
    exit) was inf, its base 1 + g^2 - 2 g cos cancelling to 0."""
    m = models.SingleScatterBRDF(
        coating=1.2013246493907676e16,
        phase=models.HenyeyGreenstein(g=-0.9999999999999998, polarized=False),
        coating_films=models.Films(layers=(), wavelength_nm=1.7354283102454746e308),
    )
    ti = np.array([1.5290365231618364e-142, 0.9893972492714842, 0.8189557691873255])
    tr = np.array([0.0, 2.2250738585072014e-308, 0.6433892242285975])
    pr = np.array([217027.70780761563, 6.639576452190328e-50, -27601.039663074538])
    _judge(m, *_angles((ti, tr, pr)))


def test_found_subsurface_extreme():
    """Found by the contract: Smith shadowing of UnitSlopes (P3 = 1, not a density): its Lambda
    integral diverges, the table held inf and its interpolation gave NaN (G = 0 or NaN by the
    geometry).  The combination is refused naming ``shadowing``; without shadowing the model is
    finite."""
    kw = dict(slopes=models.UnitSlopes(), coating=1.64407475916633e16, substrate=math.inf)
    with pytest.raises(ValueError, match=r"^shadowing must be 'none' for UnitSlopes"):
        models.SubsurfaceFacetBRDF(shadowing="smith-correlated", **kw)
    ti, tr, pr = (np.array(a) for a in ([1.2203411874478651, 0.7009319684757405, 0.969828478477087],) * 3)
    _judge(models.SubsurfaceFacetBRDF(**kw), *_angles((ti, tr, pr)))
