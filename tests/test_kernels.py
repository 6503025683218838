"""The compiled kernels against the numpy reference implementation (relative to M00, within each
model's derived tolerance: :mod:`scatterbench.models.kernel_tolerance`), model sets, the
small-call path, float32, and the cache location."""

import contextlib
import math
import os
import subprocess
import sys
import threading
import time

import numba
import numpy as np
import pytest

from scatterbench import models
from scatterbench.models import kernel_specs
from scatterbench.models.evaluation import backend
from scatterbench.models.kernel_tolerance import kernel_tolerance as tol
from scatterbench.validation.checks.conformance_checks import _relative as relative_per_geometry
from scatterbench.validation.numerics.probes import extreme_geometries, random_geometries

AL = 1.37 + 7.62j


def _configs():
    S = models
    slopes = [
        S.ExponentialSlopes(0.1),
        S.GaussianSlopes(0.2, coverage=0.7),
        S.GGXSlopes(0.15),
        S.AnisotropicExponentialSlopes(0.05, 0.3, rotation=0.4),
        S.AnisotropicGaussianSlopes(0.1, 0.2, rotation=-1.0),
        S.AnisotropicGGXSlopes(0.3, 0.1, rotation=2.0),
        S.StrokeSlopes(0.05, 0.4, 0.3),
        S.UnitSlopes(),
        S.ExponentialSlopes(1e-4),
        S.GaussianSlopes(5.0),
    ]
    out = []
    for s in slopes:
        for sub in (AL, 1.5, math.inf, 1.0 + 0j, 0.2 + 3j):
            out.append(S.FacetBRDF(slopes=s, substrate=sub))
        out.append(S.SubsurfaceFacetBRDF(slopes=s, coating=1.5, substrate=AL))
        out.append(S.SubsurfaceFacetBRDF(slopes=s, coating=2.0, substrate=1.2))  # TIR at the flakes
        out.append(S.FacetBTDF(slopes=s, substrate=1.5))
        out.append(S.MaxwellBeardBRDF(slopes=s, rho_d=0.02, rho_v=0.01, polarized=True))
    for s in (S.GaussianSlopes(0.3), S.GGXSlopes(0.2), S.AnisotropicGaussianSlopes(0.1, 0.4, rotation=0.3)):
        for sh in ("smith", "smith-correlated"):
            out.append(S.FacetBRDF(slopes=s, substrate=AL, shadowing=sh))
            out.append(S.SubsurfaceFacetBRDF(slopes=s, coating=1.5, substrate=AL, shadowing=sh))
            if sh == "smith":  # the correlated transmission form (a Beta function) is numpy's
                out.append(S.FacetBTDF(slopes=s, substrate=1.7, shadowing=sh))
    for g, pol in ((0.3, True), (-0.9, False), (0.95, True), (0.0, False)):
        out.append(S.SingleScatterBRDF(coating=1.5, phase=S.HenyeyGreenstein(g, pol)))
        out.append(S.SingleScatterBRDF(coating=1.0, phase=S.HenyeyGreenstein(g, pol)))
    for n, rho in ((1.5, 0.93), (1.0, 1.0), (2.5, 0.0)):
        out.append(S.DiffuseSubsurfaceBRDF(coating=n, rho=rho))
    for conv in ("paper", "corrected"):
        for sh in ("blinn", "none"):
            for sub in (2.29 + 3.37j, math.inf, 1.0 + 0j):
                out.append(
                    S.CookTorranceBRDF(
                        slopes=S.GaussianSlopes(0.03), substrate=sub, convention=conv, shadowing=sh
                    )
                )
                out.append(
                    S.VarnishedCookTorranceBRDF(coating=1.5, substrate=sub, convention=conv, shadowing=sh)
                )
            out.append(
                S.VarnishedCookTorranceBRDF(
                    slopes=S.StrokeSlopes(0.05, 0.3, 0.7), coating=1.0, convention=conv
                )
            )
    out.append(S.MaxwellBeardBRDF(polarized=False, rho_d=0.1, rho_v=0.2, tau=0.1, omega=2.0))
    # Smith's G in the Cook-Torrance kernel: Gaussian (equal m) and anisotropic Gaussian (strokes)
    for slopes in (S.GaussianSlopes(0.3), S.StrokeSlopes(0.1, 0.4, 0.5), S.StrokeSlopes(1e-3, 1e-3, 0.0)):
        for sub in (2.29 + 3.37j, math.inf):
            for conv in ("paper", "corrected"):
                out.append(
                    S.CookTorranceBRDF(slopes=slopes, substrate=sub, convention=conv, shadowing="smith")
                )
                out.append(
                    S.VarnishedCookTorranceBRDF(
                        slopes=slopes, coating=1.5, substrate=sub, convention=conv, shadowing="smith"
                    )
                )
    return out


CONFIGS = _configs()


def _geometries():
    """400 random geometries up to 90 deg, then the extremes (polar 0, 1e-9, 30, 60, 89.99, 90
    deg in every pair; specular, retro at +-pi, out of plane, azimuth 1e-12)."""
    return tuple(
        np.concatenate(p)
        for p in zip(random_geometries(400, seed=12, max_deg=90.0), extreme_geometries(), strict=True)
    )


def _relative(mk, mn):
    """The worst geometry's max |M_kernel - M_numpy| relative to the numpy M00 (the conformance
    checks' per-geometry error; exact zeros stay zeros)."""
    return float(np.max(relative_per_geometry(mk, mn)))


@pytest.mark.parametrize("model", CONFIGS, ids=lambda m: type(m).__name__)
def test_kernel_equals_numpy_reference(model):
    assert model._kernel_spec() is not None, "a configuration the kernels cover"
    ti, tr, pr = _geometries()
    mk = model.mueller(ti, tr, pr)
    bk = model.brdf(ti, tr, pr)
    with backend("numpy"):
        mn = model.mueller(ti, tr, pr)
        bn = model.brdf(ti, tr, pr)
    assert np.all(np.isfinite(mk))
    assert _relative(mk, mn) <= tol(model)
    with np.errstate(divide="ignore", invalid="ignore"):
        assert float(np.max(np.where(bk == bn, 0.0, np.abs(bk - bn) / np.abs(bn)))) <= tol(model)
    # float32 angles are validated (and promoted) the same way on both paths
    t32 = [a.astype(np.float32) for a in (ti, tr, pr)]
    with backend("numpy"):
        mn32 = model.mueller(*t32)
    assert _relative(model.mueller(*t32), mn32) <= tol(model)


def test_uncovered_options_fall_back_to_numpy():
    for m in (
        models.FacetBRDF(slopes=models.TabulatedSlopes()),
        models.FacetBRDF(slopes=models.GaussianAngles(0.2)),
        models.FacetBRDF(slopes=models.ExponentialSlopes(0.2), shadowing="smith"),
        models.FacetBRDF(
            substrate=models.FilmStack(layers=((1.5, 100.0),), substrate=AL, wavelength_nm=550.0)
        ),
        models.FacetBTDF(convention="corrected"),
        models.FacetBTDF(slopes=models.GaussianSlopes(0.3), shadowing="smith-correlated"),
    ):
        assert m._kernel_spec() is None
        assert models.evaluation.compiled(m) is None


def test_model_sets_in_the_kernels():
    sig = np.array([0.05, 0.1, 0.3])[:, None]
    coat = np.array([1.2, 1.5, 1.9])[:, None]
    sub = np.array([AL, 1.5 + 0j, math.inf])[:, None]
    m = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(sigma=sig), coating=coat, substrate=sub)
    ti, tr, pr = (a[:50] for a in _geometries())
    assert m.param_shape == (3, 1)
    M = m.mueller(ti, tr, pr)
    assert M.shape == (3, 50, 4, 4)
    with backend("numpy"):
        Mn = m.mueller(ti, tr, pr)
    assert _relative(M, Mn) <= tol(m)
    for w in range(3):
        one = models.SubsurfaceFacetBRDF(
            slopes=models.ExponentialSlopes(float(sig[w, 0])),
            coating=float(coat[w, 0]),
            substrate=sub[w, 0].item(),
        )
        assert np.array_equal(one.mueller(ti, tr, pr), M[w])  # the same kernel, element by element
        assert np.array_equal(one.brdf(ti, tr, pr), m.brdf(ti, tr, pr)[w])
    s = m + models.DiffuseSubsurfaceBRDF(rho=np.array([0.1, 0.5, 0.9])[:, None])
    assert s.mueller(0.4, tr, 0.2).shape == (3, 50, 4, 4)


def _perturbed_set(model, rng, w=4):
    """``model`` as a set of ``w`` models, each real parameter scaled by a factor in [0.9, 1]
    and each finite index's real part by one in [1, 1.1] (staying in range), shape ``(w, 1)``."""
    from scatterbench.models import modelset

    leaves = {}
    for path, (v, kind) in modelset.scalar_leaves(model).items():
        if kind == "real":
            a = v * rng.uniform(0.9, 1.0, (w, 1))
        elif v != math.inf:
            z = complex(v)
            a = z.real * rng.uniform(1.0, 1.1, (w, 1)) + 1j * z.imag
        else:
            continue
        try:  # parameters pinned to one value (e.g. a coverage of 1) stay scalar
            modelset.rebuilt(model, {path: a})
        except ValueError:
            continue
        leaves[path] = a
    return modelset.rebuilt(model, leaves), leaves


@pytest.mark.parametrize("model", CONFIGS[::3], ids=lambda m: type(m).__name__)
def test_random_model_sets_equal_the_numpy_reference_and_their_elements(model):
    """A set of every kernel's models (random parameters) against numpy within its tolerance, and
    each element equal, bit for bit, to the single model with its values."""
    from scatterbench.models import modelset

    rng = np.random.default_rng(3)
    mset, leaves = _perturbed_set(model, rng)
    if not leaves:
        pytest.skip("no real or finite index parameter to vary")
    ti, tr, pr = (a[::4] for a in _geometries())
    M = mset.mueller(ti, tr, pr)
    assert M.shape == (4, len(ti), 4, 4) and np.all(np.isfinite(M))
    with backend("numpy"):
        Mn = mset.mueller(ti, tr, pr)
    assert _relative(M, Mn) <= tol(mset)
    for w in (0, 3):
        one = modelset.rebuilt(model, {p: modelset.scalar_value(a[w, 0]) for p, a in leaves.items()})
        assert np.array_equal(one.mueller(ti, tr, pr), M[w])


def test_model_set_validation_is_vectorized_and_names_the_first_bad_value():
    with pytest.raises(ValueError, match=r"sigma must be .*\[1e-08, 1e\+08\]; got -0.3 at index \(1, 0\)"):
        models.GaussianSlopes(sigma=np.array([[0.2], [-0.3], [-1.0]]))
    with pytest.raises(ValueError, match=r"substrate must be n \+ ik .*got \(1-1j\) at index \(1,\)"):
        models.FacetBRDF(substrate=np.array([1.5, 1 - 1j]))
    with pytest.raises(ValueError, match="must broadcast to one parameter shape"):
        models.SubsurfaceFacetBRDF(
            slopes=models.GaussianSlopes(np.ones((2, 1))), coating=np.full((3, 1), 1.5)
        )
    m = models.FacetBRDF(slopes=models.GaussianSlopes(0.1))
    trusted = m.with_values({"slopes.sigma": np.array([0.1, 0.2])}, check=False)
    assert trusted.param_shape == (2,) and m.param_shape == ()
    with pytest.raises(ValueError, match="sigma"):
        m.with_values({"slopes.sigma": np.array([0.1, -0.2])})


def test_small_calls_agree_with_the_general_path():
    m = models.SubsurfaceFacetBRDF()
    one = m.mueller(0.5, 0.6, 0.1)
    assert one.shape == (4, 4)
    assert np.array_equal(one, m.mueller(np.array([0.5]), 0.6, 0.1)[0])
    assert np.array_equal(one, m.mueller([0.5], [0.6], [0.1])[0])
    x = np.linspace(0.1, 1.4, 100)
    assert np.array_equal(m.mueller(x, x[::-1].copy(), 0.3), m.mueller(list(x), list(x[::-1]), 0.3))
    assert m.brdf(0.5, 0.6, 0.1).shape == ()
    with pytest.raises(ValueError, match="theta_r"):
        m.mueller(0.5, 1.7, 0.1)
    with pytest.raises(ValueError, match="phi_r"):
        m.mueller(x, x, np.full(100, np.nan))


def test_float32_kernels_and_their_error():
    m = models.SubsurfaceFacetBRDF()
    ti, tr, pr = _geometries()
    M64 = m.mueller(ti, tr, pr)
    M32 = m.mueller(ti, tr, pr, precision="float32")
    assert M32.dtype == np.float32
    rel = _relative(M32.astype(float), M64)
    assert 1e-9 < rel < 1e-3  # computed in float32: far from float64, far below the model's accuracy
    with pytest.raises(ValueError, match="precision"):
        m.mueller(0.5, 0.5, 0.0, precision="half")


def test_cache_directory_is_writable_and_keyed_by_the_sources(tmp_path, monkeypatch):
    import os

    from scatterbench.models import kernels

    d = kernels.cache_dir()
    assert os.path.basename(d) == f"scatterbench-{kernels._source_hash()}"
    assert os.access(d, os.W_OK)
    # NUMBA_CACHE_DIR unusable (as beside a read-only site-packages): the user cache instead
    blocked = tmp_path / "file"
    blocked.write_text("not a directory")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(blocked / "numba"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "user"))
    d = kernels.cache_dir()
    assert d.startswith(str(tmp_path / "user" / "numba")) and os.access(d, os.W_OK)
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocked / "user"))
    assert kernels.cache_dir().startswith(os.path.realpath(__import__("tempfile").gettempdir()))


def test_kernel_specs_have_no_numba_import():
    assert kernel_specs.slope_rows(models.TabulatedSlopes()) is None
    assert kernel_specs.index_rows(math.inf) == [math.inf, 0.0]


def test_one_compiled_specialization_per_entry_and_precision():
    """Read-only angles, a small call, a scalar call and a large one reach each entry point
    with the same argument types (no read-only array type, no ``Literal[int](0)``): each
    other type compiled every kernel again, ~10 s on a cold cache
    (:meth:`scatterbench.models.kernels.Compiled.call`, :meth:`scatterbench.models.kernels.Compiled.fast`)."""
    from scatterbench.models.kernels import drive, vector

    frozen = np.linspace(0.1, 1.2, 2048)
    frozen.flags.writeable = False
    for m in (models.FacetBRDF(), models.MaxwellBeardBRDF()):
        m.mueller(frozen, frozen, frozen)
        m.mueller(frozen[:100], 0.3, 0.2)
        m.mueller(frozen[:3], 0.3, 0.2)
        m.mueller(0.3, 0.2, 0.1)
    entries = [drive.ENTRIES[c] for c in (drive.FACET, drive.MAXWELL)] + list(vector._ENTRIES.values())
    assert len(entries) > 2  # the vector loops the calls above made
    for entry in entries:
        for sig in entry.signatures:
            assert "readonly" not in str(sig) and "Literal" not in str(sig), (entry, sig)
            assert all(t.mutable for t in sig if hasattr(t, "ndim")), (entry, sig)


_FIRST_CALL = """
import logging, sys
logging.basicConfig(stream=sys.stderr, level=logging.INFO, format="%(message)s")
from scatterbench import models
models.DiffuseSubsurfaceBRDF().mueller(0.3, 0.2, 0.1)
"""


def test_a_first_call_compiles_its_own_kernel_alone_and_says_so(tmp_path):
    """On a cold cache one geometry of DiffuseSubsurfaceBRDF compiles (and caches) that kernel's
    vector entry alone (a vectorized kernel's calls of any size take it, so its scalar loop is
    not compiled), saying so once; a second process loads it silently.  Fails when an
    entry dispatches over every kernel again (all six compiled on a first call, 23 s of CPU
    for one geometry) or the notice is lost (:mod:`scatterbench.models.kernels`)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    runs = [subprocess.run([sys.executable, "-c", _FIRST_CALL], env=env, capture_output=True, text=True, check=True)
            for _ in range(2)]  # fmt: skip
    assert runs[0].stderr.count("compiling the diffuse kernel (once per machine") == 1, runs[0].stderr
    assert runs[0].stderr.count("compiling") == 1, runs[0].stderr
    assert "compiling" not in runs[1].stderr, runs[1].stderr
    cached = {p.name.split("-")[0] for p in tmp_path.rglob("*.nbi")}
    # not R-bar's compiled integrand: the model's first call integrates R-bar before the kernels
    # load and hand it over (smooth_interface.INTEGRAND_SOURCE), with the Python integrand's bits
    assert cached == {"vector.run_range_diffuse_0_0_0"}, cached


_COLD_BY_TYPE = """
from scatterbench.models import kernels
print(kernels.cold("diffuse", "float32", [], True))
kernels.warm("diffuse", "float64", [], True)  # the scalar loop, float64
print(kernels.cold("diffuse", "float64", [], True), kernels.cold("diffuse", "float32", [], True))
kernels.warm("diffuse", "float32", [], True)
print(kernels.cold("diffuse", "float32", [], True))
"""


def test_a_loop_cached_in_one_precision_is_cold_in_the_other(tmp_path):
    """``kernels.cold`` asks the cache for the loop's signature, not only for its entry's index
    file, which the float64 and float32 scalar loops share: a first report compiles the
    float32 facet later, on a worker (``validation.report.build.compile_later``), which found it
    "cached" after the float64 loop and left the speed section to compile it (3.5 s)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    out = subprocess.run(
        [sys.executable, "-c", _COLD_BY_TYPE], env=env, capture_output=True, text=True, check=True
    )
    assert out.stdout.split() == ["True", "False", "True", "False"], out.stdout


def test_warm_compiles_the_types_the_calls_use():
    """:func:`scatterbench.models.kernels.warm` compiles each entry for the argument types that
    :class:`~scatterbench.models.kernels.Compiled` passes it: after it, one geometry, 100, 5000
    and 5000 in float32 add no specialization (a report's first run compiles ahead on its
    workers, ``validation.report.build.compile_ahead``; a type apart compiled again)."""
    from scatterbench.models import kernels

    kernels.warm("diffuse")
    kernels.warm("diffuse", "float32")
    entries = kernels._warm_entries("diffuse", "float64") + kernels._warm_entries("diffuse", "float32")
    before = {fn: list(fn.signatures) for fn, _ in entries}
    m = models.DiffuseSubsurfaceBRDF()
    t = np.linspace(0.0, 1.2, 5000)
    for call in (lambda: m.mueller(0.3, 0.2, 0.1), lambda: m.mueller(0.3, t[:100], 0.5),
                 lambda: m.mueller(0.3, t, 0.5), lambda: m.mueller(0.3, t, 0.5, precision="float32"),
                 lambda: m.mueller(0.3, t[:100], 0.5, precision="float32")):  # fmt: skip
        call()
    for fn, sig in entries:
        assert sig in fn.signatures, (fn, sig)
        assert fn.signatures == before[fn], (fn, before[fn], fn.signatures)
    assert not kernels.cold("diffuse") and not kernels.cold("diffuse", "float32")


def test_warm_compiles_the_node_algebra_and_monte_carlo_for_the_types_the_models_pass():
    """``kernels.warm("montecarlo" | "aperture" | "disc" | "angles")`` (a report's compile-ahead
    tasks) compiles those modules' entries for the types RoughDiffuseBRDF, DetectorAperture and
    PointSourceBRDF pass, and the small calls' angle check for theirs (a few geometries as a
    list): their calls add no specialization.  Fails when a model passes
    another type (a read-only table, a bool array), which a first report then compiled
    again, lazily, in each process."""
    from scatterbench.models import kernels

    entries = [
        e
        for name in ("montecarlo", "aperture", "disc", "angles")
        for e in kernels._warm_entries(name, "float64")
    ]
    for name in ("montecarlo", "aperture", "disc", "angles"):
        kernels.warm(name)
    before = {fn: list(fn.signatures) for fn, _ in entries}
    x = np.linspace(0.1, 1.0, 40)
    models.RoughDiffuseBRDF().mueller(0.3, x, 0.2)
    models.DetectorAperture(model=models.FacetBRDF(), aperture=0.05).mueller(0.3, x, 0.2)
    models.PointSourceBRDF(model=models.CookTorranceBRDF(), distance=1.0, sample_radius=1.0).mueller(
        0.3, x, 0.2
    )
    models.FacetBRDF().mueller([0.1, 0.2, 0.3], 0.4, 0.5)  # the small-call path checks its angles
    for fn, sig in entries:
        assert sig in before[fn] and fn.signatures == before[fn], (fn, before[fn], fn.signatures)
    # read-only angles (the conformance kit gives models read-only inputs) take the same loop
    frozen = x.copy()
    frozen.flags.writeable = False
    models.RoughDiffuseBRDF().mueller(0.3, frozen, frozen)
    assert all(fn.signatures == before[fn] for fn, _ in entries)


def test_spread_runs_ranges_on_threads_and_the_bits_do_not_depend_on_their_number():
    """:func:`scatterbench.models.kernels.threads.spread` covers ``0 .. n - 1`` once, in ranges
    on as many threads as ``numba.set_num_threads`` allows, and the kernels it runs give the
    same bits on one thread and on two (a vector loop, a scalar one with Smith shadowing, the
    Monte Carlo, the aperture's rotated sum).  Fails when ranges overlap or leave a gap, or a
    loop reads another range's columns."""
    import threading

    from scatterbench.models.kernels.threads import spread

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("one thread only (NUMBA_NUM_THREADS)")
    seen = []

    def loop(lo, hi):
        seen.append((lo, hi, threading.get_ident()))
        time.sleep(0.05)  # long enough that the other thread takes a range too

    spread(loop, (), 4096, 1024)
    assert sorted(r[:2] for r in seen) == [(0, 1024), (1024, 2048), (2048, 3072), (3072, 4096)], seen
    assert len({r[2] for r in seen}) == 2, seen
    x = np.linspace(0.0, 1.4, 5000)
    calls = [
        lambda: models.FacetBRDF().mueller(0.4, x, 0.3),
        lambda: models.FacetBRDF(shadowing="smith").mueller(0.4, x, 0.3),
        lambda: models.RoughDiffuseBRDF().mueller(0.4, x[::100], 0.3),
        lambda: models.DetectorAperture(model=models.FacetBRDF(), aperture=0.05).mueller(0.4, x, 0.3),
    ]
    threads = numba.get_num_threads()
    try:
        for call in calls:
            numba.set_num_threads(1)
            one = call()
            numba.set_num_threads(2)
            assert np.array_equal(one, call(), equal_nan=True)
    finally:
        numba.set_num_threads(threads)


_LANE_CALLS = """
import numpy as np
from scatterbench import models
m = models.SingleScatterBRDF()
t = np.linspace(0.0, 1.2, 5000)
m.mueller(0.3, t[:100], 0.5)
m.mueller(0.3, t, 0.5)
"""


def test_a_second_process_loads_the_vector_entries_without_compiling(tmp_path):
    """A second process making the same vector calls (small and parallel) loads every entry
    from the cache: no cache file is added or rewritten.  Fails when an entry's cache key
    differs between processes (a closure holding a dispatcher: its pickled form, which keys
    the cache, is new in each process, so every run compiled the loops again)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))

    def files():
        return {p.name: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}

    subprocess.run([sys.executable, "-c", _LANE_CALLS], env=env, check=True)
    first = files()
    assert any("run_range_single_" in name for name in first), sorted(first)
    subprocess.run([sys.executable, "-c", _LANE_CALLS], env=env, check=True)
    assert files() == first


NARROW = [
    *(models.FacetBRDF(slopes=models.GaussianSlopes(w), substrate=1.5) for w in (1e-2, 1e-4, 1e-6, 1e-8)),
    *(models.FacetBRDF(slopes=models.ExponentialSlopes(w), substrate=1.5) for w in (1e-4, 1e-6)),
    *(models.FacetBRDF(slopes=models.GGXSlopes(w), substrate=1.5) for w in (1e-4, 1e-6)),
    models.CookTorranceBRDF(slopes=models.GaussianSlopes(1e-3), substrate=math.inf),
]


def _near_specular(n=2000, seed=5):
    """Geometries within 1e-9..1e-1 rad of specular (where a narrow lobe is), in and out of plane."""
    rng = np.random.default_rng(seed)
    t0 = rng.uniform(0.0, 1.4, n)
    d = 10 ** rng.uniform(-9, -1, n) * rng.choice([-1.0, 1.0], n)
    return t0, np.clip(t0 + d, 0.0, math.pi / 2), rng.choice([0.0, math.pi], n) + d * rng.uniform(-1, 1, n)


@pytest.mark.parametrize("model", NARROW, ids=lambda m: f"{type(m.slopes).__name__}-{m.slopes.scale:g}")
def test_narrow_lobes_agree_within_their_derived_tolerance(model):
    """Kernel and numpy differ by the lobe's conditioning (the slope's last bits over the
    width), not by a flat 1e-12: measured 2.3e-7 for a Gaussian of width 1e-8, the narrowest
    declared.  Held to the derived bound; the narrowest ones exceed the old flat 1e-12, which
    is why the bound is per model."""
    ti, tr, pr = (np.concatenate(p) for p in zip(_geometries(), _near_specular(), strict=True))
    mk = model.mueller(ti, tr, pr)
    with backend("numpy"):
        mn = model.mueller(ti, tr, pr)
    err = _relative(mk, mn)
    assert err <= tol(model)
    if model.slopes.scale <= 1e-6:
        assert err > 1e-12  # the flat tolerance these models need more than


def test_a_long_evaluation_is_one_kernel_call_with_the_chunks_bits(monkeypatch):
    """Past one chunk, a single model's kernel is called once over every geometry (its threads
    share the whole range), and each geometry's bits are those of a call on its chunk alone;
    a single angle value is broadcast, not gathered.  Fails when ``fill`` goes chunk by chunk
    (three calls) or the one call misplaces a geometry."""
    from scatterbench.models import evaluation
    from scatterbench.models.kernels import Compiled

    m = models.FacetBRDF(slopes=models.GaussianSlopes(0.2), substrate=AL)
    n = 2 * evaluation.KERNEL_CHUNK + 17
    rng = np.random.default_rng(5)
    tr, pr = rng.uniform(0.0, 1.5, n), rng.uniform(-math.pi, math.pi, n)
    writes = []
    real = Compiled.write
    monkeypatch.setattr(
        Compiled, "write", lambda self, out, sl, *a, **k: writes.append(sl) or real(self, out, sl, *a, **k)
    )
    _, whole = m.mueller16(0.3, tr, pr)
    assert writes == [slice(0, n)]
    for a in range(0, n, evaluation.KERNEL_CHUNK):
        b = min(a + evaluation.KERNEL_CHUNK, n)
        np.testing.assert_array_equal(whole[:, a:b], m.mueller16(0.3, tr[a:b], pr[a:b])[1])


def _run_apart(calls):
    """Each of ``calls`` on a thread of its own, started 0.05 s apart (each call slowed by its
    test, so that they overlap), then joined."""
    threads = [threading.Thread(target=call) for call in calls]
    for t in threads:
        t.start()
        time.sleep(0.05)
    for t in threads:
        t.join()


def test_r_bar_integrand_first_uses_on_threads_restore_numba_s_cache_folder(monkeypatch):
    """Two threads' first calls of :func:`kernels.rbar_integrand` at once leave numba's
    ``config.CACHE_DIR`` as it was (the report's sections run on threads): each switches it
    for its import, one at a time (:func:`kernels.helper.caching_in`'s lock).  Fails without the lock:
    the second saves the first's setting and restores it last."""
    from numba.core import config

    from scatterbench.models import kernels

    switch = kernels._caching_in

    @contextlib.contextmanager
    def slow(path):
        with switch(path):
            time.sleep(0.2)  # the other thread's call starts meanwhile
            yield

    monkeypatch.setattr(kernels, "_caching_in", slow)
    monkeypatch.setattr(config, "CACHE_DIR", "users-own")
    _run_apart([kernels.rbar_integrand] * 2)
    assert config.CACHE_DIR == "users-own"


def test_vector_loops_first_made_on_threads_restore_numba_s_cache_folder(monkeypatch):
    """Two threads' first calls of :func:`vector.lanes_of` at once (two option sets) leave numba's
    ``config.CACHE_DIR`` as it was, each loop decorated with scatterbench's folder; and two
    threads' first calls for one option set get one loop.  Fails without the lock (the second
    thread saves the first's setting and restores it last) and without the second look-up."""
    from numba.core import config

    from scatterbench.models.kernels import vector

    made, folders = [], []
    real = vector.entry

    def slow(*key):
        folders.append(config.CACHE_DIR)
        time.sleep(0.2)  # the other thread's call starts meanwhile
        made.append(key)
        return real(*key)

    monkeypatch.setattr(vector, "entry", slow)
    monkeypatch.setattr(vector, "_ENTRIES", {})
    monkeypatch.setattr(config, "CACHE_DIR", "users-own")
    sets = vector.option_sets(vector.FACET)
    got = []
    for opts in ([sets[0], sets[1]], [sets[2], sets[2]]):
        _run_apart([lambda o=o: got.append(vector.lanes_of(vector.FACET, o)) for o in opts])
    assert config.CACHE_DIR == "users-own"
    assert folders == [vector._CACHE_DIR] * 3 and len(made) == 3  # the shared set made once
    assert got[2] is got[3]
