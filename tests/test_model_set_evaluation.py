"""How model sets are evaluated: derived per-element quantities computed once per distinct
element, and the same kernel route (float64 and float32) as single models."""

import math

import numpy as np
import pytest

from scatterbench import models
from scatterbench.models import smooth_interface


def test_diffuse_subsurface_set_runs_one_quadrature_per_distinct_coating(monkeypatch):
    """R-bar is a quadrature (QUADPACK, ``_compiled_quad``; ``quad`` in Python where that gives
    nothing): a set of 64 coatings evaluated in several chunks runs it 64 times (it ran twice
    per coating: once deciding on the kernel, once per chunk)."""
    # the compiled integrand exists once the kernels have loaded: run alone, this test built
    # the set before anything loaded them, and every coating fell back to Python's quad
    from scatterbench.models import kernels  # noqa: F401

    calls = []
    quad, python = smooth_interface._compiled_quad, smooth_interface._python_quad
    monkeypatch.setattr(smooth_interface, "_compiled_quad", lambda *a: calls.append(1) or quad(*a))
    monkeypatch.setattr(smooth_interface, "_python_quad", lambda *a: calls.append(2) or python(*a))
    smooth_interface._rbar.cache_clear()
    coating = np.linspace(1.1, 1.9, 64).reshape(64, 1)
    m = models.DiffuseSubsurfaceBRDF(coating=coating, rho=0.9)
    ti = np.linspace(0.0, 1.4, 2000)  # 128000 geometries: two kernel chunks
    M = m.mueller(ti, 0.3, 0.0)
    assert calls == [1] * 64
    for w in (0, 37, 63):
        one = models.DiffuseSubsurfaceBRDF(coating=float(coating[w, 0]), rho=0.9)
        assert one.rbar == m.rbar[w, 0]
        assert np.array_equal(one.mueller(ti, 0.3, 0.0), M[w])
    assert calls == [1] * 64


SETS = [
    (models.FacetBRDF, {"slopes": models.GaussianSlopes(np.array([[0.2], [0.3]]))}),
    (
        models.SubsurfaceFacetBRDF,
        {
            # sigma >= 0.1: inside the float32-safe domain (models.float32_domain; 0.05 is not)
            "slopes": models.ExponentialSlopes(np.array([[0.1], [0.15], [0.3]])),
            "coating": np.array([[1.2], [1.5], [1.9]]),
            "substrate": np.array([[1.37 + 7.62j], [1.5 + 0j], [math.inf]]),
        },
    ),
    (models.DiffuseSubsurfaceBRDF, {"coating": np.array([[1.1], [1.5], [1.9]]), "rho": 0.9}),
    (models.MaxwellBeardBRDF, {"rho_d": np.array([[0.01], [0.1]])}),
]


def _element(kwargs, w):
    """The keyword arguments of element ``w`` of a set along its first axis."""

    def one(v):
        if isinstance(v, np.ndarray):
            return models.modelset.scalar_value(v[w, 0])
        if isinstance(v, models.GaussianSlopes | models.ExponentialSlopes):
            return type(v)(one(v.sigma))
        return v

    return {k: one(v) for k, v in kwargs.items()}


@pytest.mark.parametrize("cls, kwargs", SETS, ids=lambda x: getattr(x, "__name__", ""))
def test_model_sets_use_the_float32_kernels_like_their_elements(cls, kwargs, tmp_path):
    """A model set's float32 result is its elements' float32 results, bit for bit (the
    float32 kernels, not the float64 result rounded), in a new array and in a memmap."""
    m = cls(**kwargs)
    assert m.float32_fallback is None, "a set whose elements the float32 kernels evaluate"
    ti = np.linspace(0.0, 1.5, 300)
    tr = np.linspace(0.1, 1.4, 300)[::-1].copy()
    M32 = m.mueller(ti, tr, 0.3, precision="float32")
    B32 = m.brdf(ti, tr, 0.3, precision="float32")
    shape, _ = m.mueller16(ti, tr, 0.3)
    mm = np.lib.format.open_memmap(
        tmp_path / "m.npy", mode="w+", dtype=np.float32, shape=(16, math.prod(shape))
    )
    m.mueller16(ti, tr, 0.3, out=mm, precision="float32")
    assert M32.dtype == B32.dtype == np.float32
    assert not np.array_equal(M32, m.mueller(ti, tr, 0.3).astype(np.float32))
    for w in range(m.param_shape[0]):
        one = cls(**_element(kwargs, w))
        assert np.array_equal(M32[w], one.mueller(ti, tr, 0.3, precision="float32"))
        assert np.array_equal(B32[w], one.brdf(ti, tr, 0.3, precision="float32"))
        ref = one.mueller16(ti, tr, 0.3, precision="float32")[1]
        assert np.array_equal(np.asarray(mm).reshape(16, -1, len(ti))[:, w], ref)


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_flat_mueller16_indexed_gives_the_bits_of_the_set_broadcast_to_the_geometries(backend):
    """``Model.flat_mueller16_indexed`` (a fit's walkers x wavelengths gathered per row) equals the set
    whose parameters are the gathered ones, evaluated at the same angles, bit for bit, on
    both routes (over two kernel chunks), and derives R-bar once per element, not per row."""
    rng = np.random.default_rng(3)
    coating = np.array([1.2, 1.35, 1.5, 1.7])
    rho = np.array([0.5, 0.9, 0.95, 0.99])
    n = models.evaluation.KERNEL_CHUNK + 1000
    index = rng.integers(0, 4, n)
    ti, tr, pr = rng.uniform(0, 1.5, n), rng.uniform(0, 1.5, n), rng.uniform(-3, 3, n)
    small = models.DiffuseSubsurfaceBRDF(coating=coating, rho=rho) + models.FacetBRDF(
        slopes=models.GaussianSlopes(np.array([0.1, 0.2, 0.3, 0.4])), substrate=1.5
    )
    whole = models.DiffuseSubsurfaceBRDF(coating=coating[index], rho=rho[index]) + models.FacetBRDF(
        slopes=models.GaussianSlopes(np.array([0.1, 0.2, 0.3, 0.4])[index]), substrate=1.5
    )
    with models.evaluation.backend(backend):
        for (_, a), (_, b) in zip(small.terms, whole.terms, strict=True):
            got = a.flat_mueller16_indexed(index, ti, tr, pr, np.empty((16, n)))
            assert np.array_equal(got, b.mueller16(ti, tr, pr)[1])
    assert small.terms[0][1].rbar.shape == (4,)


def _gathered(model, index, ti, tr, pr):
    """The route ``flat_mueller16_indexed`` took before it read columns through an index: the
    kernel rows gathered per geometry into a kernel of their own."""
    from scatterbench.models.kernels import Compiled

    code, rows, options = model._kernel_spec()
    g = math.prod(model.param_shape)
    part = [np.asarray(r).reshape(-1)[index] if np.size(r) == g and np.ndim(r) else r for r in rows]
    out = np.empty((16, index.size))
    Compiled(model, code, part, options).write(out, slice(0, index.size), ti, tr, pr, "float64")
    return out


@pytest.mark.parametrize("kind", ["facet", "diffuse", "sum"])
def test_indexed_kernel_call_gives_the_gathered_rows_bits(kind, tmp_path):
    """The kernels reading parameter column ``index[k]`` in place give, bit for bit, the kernel
    over rows gathered per geometry (FacetBRDF, DiffuseSubsurfaceBRDF, each term of a sum and
    the sum as a fit adds it), into an ndarray in one call and into a memmap by chunks, and
    added to what ``out`` holds (``add=True``: cache-sized buffers over the cores, or the memmap's
    fallback) as ``out + result``; an index outside the set is refused."""
    from scatterbench.validation.fitting.mueller_likelihood import _mueller16

    rng = np.random.default_rng(11)
    G, n = 6, models.evaluation.KERNEL_CHUNK + 500  # the memmap by two chunks
    sig, nn, rho = rng.uniform(0.05, 0.5, G), rng.uniform(1.1, 1.8, G), rng.uniform(0.5, 0.99, G)
    facet = models.FacetBRDF(slopes=models.GaussianSlopes(sig), substrate=nn)
    diffuse = models.DiffuseSubsurfaceBRDF(coating=nn, rho=rho)
    model = {"facet": facet, "diffuse": diffuse, "sum": diffuse + facet}[kind]
    index = rng.integers(0, G, n)
    ti, tr, pr = rng.uniform(0, 1.5, n), rng.uniform(0, 1.5, n), rng.uniform(-3, 3, n)
    terms = [m for _, m in model.terms] if kind == "sum" else [model]
    ref = [_gathered(m, index, ti, tr, pr) for m in terms]
    got = _mueller16(model, index, (ti, tr, pr), np.empty((16, n)))
    assert np.array_equal(got, ref[0] + ref[1] if kind == "sum" else ref[0])
    for m, r in zip(terms, ref, strict=True):
        assert np.array_equal(m.flat_mueller16_indexed(index, ti, tr, pr, np.empty((16, n))), r)
        mm = np.lib.format.open_memmap(tmp_path / f"{kind}.npy", mode="w+", dtype=np.float64, shape=(16, n))
        assert np.array_equal(np.asarray(m.flat_mueller16_indexed(index, ti, tr, pr, mm)), r)
        base = rng.standard_normal((16, n))
        for into in (base.copy(), np.lib.format.open_memmap(tmp_path / "add.npy", mode="w+", shape=(16, n))):
            into[...] = base
            assert np.array_equal(
                np.asarray(m.flat_mueller16_indexed(index, ti, tr, pr, into, add=True)), base + r
            )
        row = _gathered(m, index, ti[:1], tr, pr[:1])  # angles of length 1 broadcast
        assert np.array_equal(
            m.flat_mueller16_indexed(index, ti[:1], tr, pr[:1], base.copy(), add=True), base + row
        )
        one = m.flat_mueller16_indexed(index[7:8], ti[7:8], tr[7:8], pr[7:8], np.empty((16, 1)))
        assert np.array_equal(one[:, 0], r[:, 7])
        with pytest.raises(ValueError, match="index"):
            m.flat_mueller16_indexed(np.full(n, G), ti, tr, pr, np.empty((16, n)))


def test_a_sum_adds_its_terms_in_order_and_returns_an_array_of_its_own(monkeypatch):
    """A sum's Mueller elements are its weighted terms added in order, bit for bit (a weight
    of 1 multiplies nothing, and the sum adds in place once it owns its array), and what it
    returns is the caller's to write, also for a single term of weight 1."""
    a = models.FacetBRDF(slopes=models.GaussianSlopes(0.2))
    b = models.DiffuseSubsurfaceBRDF(coating=1.5, rho=0.5)
    c = models.FacetBRDF(slopes=models.GGXSlopes(0.3))
    ti, tr, pr = np.linspace(0.0, 1.4, 7), np.linspace(0.1, 1.2, 7), np.linspace(-3.0, 3.0, 7)
    Ma, Mb, Mc = (m.flat_mueller16(ti, tr, pr) for m in (a, b, c))
    for terms, ref in [
        (((1.0, a), (1.0, b), (0.5, c)), Ma + Mb + 0.5 * Mc),
        (((0.5, c), (1.0, a), (1.0, b)), 0.5 * Mc + Ma + Mb),
        (((2.0, b),), 2.0 * Mb),
    ]:
        assert np.array_equal(models.Sum(terms=terms).flat_mueller16(ti, tr, pr), ref)
    # a term whose result is read-only (a user's model may return a cached array)
    shared = Ma.copy()
    shared.flags.writeable = False
    monkeypatch.setattr(models.FacetBRDF, "flat_mueller16", lambda self, ti, tr, pr: shared)
    for terms in [((1.0, a),), ((1.0, a), (1.0, a))]:
        got = models.Sum(terms=terms).flat_mueller16(ti, tr, pr)
        assert got is not shared and got.flags.writeable
        assert np.array_equal(got, Ma if len(terms) == 1 else Ma + Ma)
