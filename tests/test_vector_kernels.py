"""The vectorized loops (:mod:`scatterbench.models.kernels.vector`) and their call-free math
(:mod:`scatterbench.models.kernels.vector_math`): the same bits as the scalar loop, compiled to SIMD
instructions, and the polynomials within 2 ulp of the C library (``erfc`` within 5)."""

import math
import os
import subprocess
import sys
from fractions import Fraction

import numpy as np
import pytest
from numba import njit
from test_kernels import CONFIGS, _geometries

from scatterbench import models
from scatterbench.models.kernel_specs import GGX, SHADOWING_KINDS
from scatterbench.models.kernels import Compiled, common, drive, memory, vector
from scatterbench.models.kernels.vector_math import (
    REDUCED_MAX,
    atan2,
    erfc,
    exp_neg,
    exp_neg_square,
    hypot,
    sincos,
    sqrt,
)
from scatterbench.models.shadowing import smith_g

#: test_kernels' configurations, and Cook-Torrance under strokes (its azimuth's cosine and
#: sine are parameter rows)
STROKES = [
    models.CookTorranceBRDF(slopes=models.StrokeSlopes(0.05, 0.2, 0.7), substrate=1.37 + 7.62j, shadowing=sh)
    for sh in ("none", "blinn", "smith")
] + [
    models.VarnishedCookTorranceBRDF(
        slopes=models.StrokeSlopes(0.3, 0.1, -2.0), convention="corrected", shadowing=sh
    )
    for sh in ("none", "smith")
]
VECTORIZED = [m for m in CONFIGS + STROKES if Compiled(m, *m._kernel_spec()).vectorized]
#: azimuths beyond the polynomial's range (the C library's there), and at its edge
FAR = np.array([REDUCED_MAX, -REDUCED_MAX, 3.0e6, -1.0e7, 1.0e300])


def _inputs():
    ti, tr, pr = _geometries()
    k = np.arange(FAR.size)
    return np.concatenate([ti, ti[k]]), np.concatenate([tr, tr[k]]), np.concatenate([pr, FAR])


def _both(kernel, ti, tr, pr):
    """The scalar and the vector loop's ``(16, n)`` results."""
    prm = kernel.params("float64")
    n = max(ti.size, prm.shape[1])
    a, b = np.empty((16, n)), np.empty((16, n))
    kernel.scalar(ti, tr, pr, prm, drive.NO_INDEX, kernel.iopt, a, 0, 0, n)
    kernel.lanes(ti, tr, pr, prm, drive.NO_INDEX, kernel.iopt, b, 0, 0, n)
    return a, b


def test_the_vectorized_models_are_the_ones_meant():
    names = {type(m).__name__ for m in VECTORIZED}
    cook = {"CookTorranceBRDF", "VarnishedCookTorranceBRDF"}
    closed = {
        "FacetBRDF",
        "SubsurfaceFacetBRDF",
        "SingleScatterBRDF",
        "DiffuseSubsurfaceBRDF",
        "MaxwellBeardBRDF",
    }
    assert names == closed | cook
    facets = [m for m in VECTORIZED if type(m).__name__.endswith("FacetBRDF")]
    assert {type(m.slopes).__name__ for m in facets} == {"ExponentialSlopes", "GaussianSlopes", "GGXSlopes"}
    # Smith's G only of the isotropic slopes with a closed-form Lambda (Gaussian, GGX)
    shadowed = {(type(m.slopes).__name__, m.shadowing) for m in facets if m.shadowing != "none"}
    assert {s for _, s in shadowed} == {"smith", "smith-correlated"}
    assert {k for k, _ in shadowed} <= {"GaussianSlopes", "GGXSlopes"}
    # Cook-Torrance's Smith G too, isotropic or under strokes (the rotation's cosine and sine
    # are parameter rows: no call left in the loop)
    assert {m.shadowing for m in VECTORIZED if type(m).__name__ in cook} == {"none", "blinn", "smith"}


@pytest.mark.parametrize("model", VECTORIZED, ids=lambda m: type(m).__name__)
def test_vector_loop_gives_the_scalar_loops_bits(model):
    a, b = _both(Compiled(model, *model._kernel_spec()), *_inputs())
    assert np.array_equal(a, b)


@pytest.mark.parametrize("model", VECTORIZED[::3], ids=lambda m: type(m).__name__)
def test_vector_loop_model_sets_and_broadcast_angles(model):
    """Parameters per geometry (a model set's rows, gathered into the scratch) and angles of
    length 1: the scalar loop's bits."""
    ti, tr, pr = _inputs()
    kernel = Compiled(model, *model._kernel_spec())
    prm = kernel.params("float64")
    rng = np.random.default_rng(3)
    kernel.prm["float64"] = prm * (1.0 + 0.01 * rng.random((prm.shape[0], ti.size)))
    a, b = _both(kernel, ti, tr, pr)
    assert np.array_equal(a, b)
    a, b = _both(kernel, ti[:1], tr, pr[:1])
    assert np.array_equal(a, b)


@pytest.mark.parametrize("model", VECTORIZED[1::3], ids=lambda m: type(m).__name__)
def test_vector_loop_ranges_take_what_every_block_shares(model):
    """The rows every block shares (:func:`~scatterbench.models.kernels.vector.shared`: angles of
    length 1, a single model's parameters) are written once per call, in the call's first
    block's columns: ranges that start inside a block and end short of one (as the threads and
    the fused likelihood call them) give the bits of one call over all geometries, and the
    scalar loop's.  Fails if a later block reads columns the first did not fill."""
    ti, tr, pr = _inputs()
    kernel = Compiled(model, *model._kernel_spec())
    prm, n = kernel.params("float64"), ti.size
    for angles in ((ti, tr, pr), (ti[:1], tr, pr[:1]), (ti, tr[:1], pr)):
        whole, parts = np.empty((16, n)), np.empty((16, n))
        kernel.lanes(*angles, prm, drive.NO_INDEX, kernel.iopt, whole, 0, 0, n)
        for lo, hi in ((0, 3), (3, 290), (290, n)):
            kernel.lanes(*angles, prm, drive.NO_INDEX, kernel.iopt, parts, 0, lo, hi)
        scalar = np.empty((16, n))
        kernel.scalar(*angles, prm, drive.NO_INDEX, kernel.iopt, scalar, 0, 0, n)
        assert np.array_equal(parts, whole) and np.array_equal(whole, scalar)


@njit
def _copied(dst, src):
    memory.copy_into(dst, 0, src, 0, 3)


@njit
def _rows(dst, dst_at, dst_step, src, src_at, src_step, rows, count, stream):
    memory.copy_rows(dst, dst_at, dst_step, src, src_at, src_step, rows, count, stream)


@pytest.mark.parametrize(
    "copy",
    [
        _copied,
        lambda d, s: _rows(d, 0, 3, s, 0, 3, 1, 3, False),
        lambda d, s: _rows(d, 0, 3, s, 0, 3, 1, 3, True),
    ],
    ids=["copy_into", "copy_rows", "copy_rows-streamed"],
)
def test_block_copies_refuse_strided_arrays(copy):
    """The scratch copies (``memcpy``, rows, streamed rows) take C-contiguous arrays of one dtype;
    a strided one is refused when the caller compiles, not copied as if contiguous."""
    from numba.core.errors import TypingError

    dst, src = np.zeros(3), np.arange(6.0)
    copy(dst, src)
    assert dst.tolist() == [0.0, 1.0, 2.0]
    with pytest.raises(TypingError, match="C-contiguous"):
        copy(dst, src[::2])
    with pytest.raises(TypingError, match="one dtype"):
        copy(dst, src.astype(np.float32))


@pytest.mark.parametrize("stream", [False, True])
def test_copied_rows_are_the_elements(stream):
    """:func:`~scatterbench.models.kernels.memory.copy_rows`, ``memcpy`` or streamed (a ``memcpy``
    to the first line boundary, whole lines streamed, a ``memcpy`` of the rest), at every start
    modulo a cache line, row steps that shift it, lengths around a line: exactly the elements,
    nothing written outside them."""
    src = np.random.default_rng(4).random(400)
    per = memory.LINE_BYTES // 8
    for dst_at in range(2 * per):
        for count in (0, 1, per - 1, per, per + 1, 3 * per + 5, 70):
            for rows, step in ((1, 0), (3, 97), (4, 128)):
                dst = np.full(700, -1.0)
                _rows(dst, dst_at, step, src, 7, 101, rows, count, stream)
                want = np.full(700, -1.0)
                for r in range(rows):
                    want[dst_at + r * step : dst_at + r * step + count] = src[
                        7 + 101 * r : 7 + 101 * r + count
                    ]
                assert np.array_equal(dst, want), (dst_at, count, rows)


@njit
def _filled(dst, dst_at, count, value):
    memory.fill(dst, dst_at, count, value)


@njit
def _picked(dst, dst_at, dst_step, src, index, lo, rows, count):
    memory.pick_rows(dst, dst_at, dst_step, src, index, lo, rows, count)


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "python"])
def test_filled_and_picked_rows_are_the_elements(compiled):
    """:func:`~scatterbench.models.kernels.memory.fill` and
    :func:`~scatterbench.models.kernels.memory.pick_rows` (the lanes' scratch rows shared by every
    block, and picked by a model set's column per geometry), compiled and as the Python they
    stand for: exactly the elements, at every offset and length, nothing written outside them."""
    fill, pick = (_filled, _picked) if compiled else (_filled.py_func, _picked.py_func)
    rng = np.random.default_rng(5)
    src = rng.random((4, 9))
    index = rng.integers(0, 9, 300)
    for at in (0, 1, 7, 8, 9):
        for count in (0, 1, 7, 8, 9, 33):
            dst = np.full(200, -1.0)
            fill(dst, at, count, 0.25)
            want = np.full(200, -1.0)
            want[at : at + count] = 0.25
            assert np.array_equal(dst, want), (at, count)
            for rows, step, lo in ((1, 0, 0), (3, 40, 5), (4, 41, 200)):
                dst = np.full(200, -1.0)
                pick(dst, at, step, src, index, lo, rows, count)
                want = np.full(200, -1.0)
                for r in range(rows):
                    want[at + r * step : at + r * step + count] = src[r, index[lo : lo + count]]
                assert np.array_equal(dst, want), (at, count, rows)


def test_fill_and_pick_refuse_strided_arrays():
    """Like the copies, the fill and the picking take C-contiguous arrays (the picking one dtype,
    a 2-d source and 64-bit column numbers): anything else is refused when the caller compiles."""
    from numba.core.errors import TypingError

    dst, src, index = np.zeros(6), np.arange(12.0).reshape(2, 6), np.array([5, 0, 3])
    with pytest.raises(TypingError, match="C-contiguous"):
        _filled(dst[::2], 0, 2, 1.0)
    with pytest.raises(TypingError, match="C-contiguous"):
        _picked(dst, 0, 3, src[:, ::2], index, 0, 2, 3)
    with pytest.raises(TypingError, match="index is a C-contiguous"):
        _picked(dst, 0, 3, src, np.array([5, 0, 3, 1])[::2], 0, 2, 2)
    with pytest.raises(TypingError, match="64-bit"):
        _picked(dst, 0, 3, src, index.astype(np.int32), 0, 2, 3)
    with pytest.raises(TypingError, match="src is 2-d"):
        _picked(dst, 0, 3, src.reshape(-1), index, 0, 1, 3)
    _picked(dst, 0, 3, src, index, 0, 2, 3)
    assert dst.tolist() == [5.0, 0.0, 3.0, 11.0, 6.0, 9.0]


_NO_STREAMS = """
import numpy as np
from numba import njit
from scatterbench.models.kernels import memory
memory.STREAMS = False  # as on a CPU other than x86-64, before anything compiles

@njit
def rows(dst, src):
    memory.copy_rows(dst, 1, 40, src, 2, 30, 3, 25, True)

dst, src = np.zeros(120), np.arange(100.0)
rows(dst, src)
want = np.zeros(120)
for r in range(3):
    want[1 + 40 * r : 26 + 40 * r] = src[2 + 30 * r : 27 + 30 * r]
ir = "".join(rows.inspect_llvm().values())
print(np.array_equal(dst, want), "nontemporal" in ir, "sfence" in ir)
"""


def test_rows_are_copied_without_streaming_code_elsewhere(tmp_path):
    """Where streaming stores are not compiled (``memory.STREAMS`` false: a CPU other than
    x86-64, whose LLVM has no ``sfence``), a streamed copy is each row's ``memcpy``: the same
    elements, and neither a non-temporal store nor the fence in the code."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    res = subprocess.run(
        [sys.executable, "-c", _NO_STREAMS], env=env, capture_output=True, text=True, check=True
    )
    assert res.stdout.split() == ["True", "False", "False"], res.stdout + res.stderr


def test_results_stream_only_beyond_what_callers_read_back():
    """Results of more than ``STREAM_MIN`` elements are streamed to memory; the buffers the
    kernels' callers fill and read back at once (a chunk of a result that is not written in
    place, ``kernels.Compiled.write``; a range of ``Compiled.accumulate`` or of a fit's fused
    likelihood) never are."""
    from scatterbench.models import evaluation, kernels
    from scatterbench.validation.fitting import mueller_kernel

    assert 16 * evaluation.KERNEL_CHUNK <= memory.STREAM_MIN
    assert 16 * max(kernels.ADD_CHUNK, drive.BLOCK) <= memory.STREAM_MIN
    assert 16 * mueller_kernel.RANGE_ROWS <= memory.STREAM_MIN  # a fit's fused likelihood's ranges


@pytest.mark.parametrize("model", VECTORIZED[::4], ids=lambda m: type(m).__name__)
def test_streamed_results_are_the_stored_ones(model):
    """A result beyond ``STREAM_MIN`` elements (streamed, its rows at every alignment: an odd
    length) holds the bits of the same geometries evaluated in ranges into a small one."""
    n = memory.STREAM_MIN // 16 + 37
    rng = np.random.default_rng(6)
    ti, tr, pr = rng.uniform(0.0, 1.5, n), rng.uniform(0.0, 1.5, n), rng.uniform(-np.pi, np.pi, n)
    kernel = Compiled(model, *model._kernel_spec())
    prm = kernel.params("float64")
    whole = np.empty((16, n))
    kernel.lanes(ti, tr, pr, prm, drive.NO_INDEX, kernel.iopt, whole, 0, 0, n)
    part = np.empty((16, 4096))
    for lo in range(0, n, 4096):
        hi = min(n, lo + 4096)
        kernel.lanes(ti, tr, pr, prm, drive.NO_INDEX, kernel.iopt, part, -lo, lo, hi)
        assert np.array_equal(whole[:, lo:hi], part[:, : hi - lo]), lo


@pytest.mark.parametrize("shadowing", ["none", "smith"])
def test_facet_lanes_coating_per_block_and_per_lane(shadowing):
    """The facet loop on SIMD lanes takes its coating from a pass per block
    (:func:`~scatterbench.models.kernels.vector.facet_prepass`): computed where a column of the
    block is coated, ones and the outer angles where none is.  A model set whose coating is 1
    in some columns and not in others, in blocks that hold both, blocks of only uncoated
    columns and blocks of only coated ones (the first 300 columns 1, then alternating): the
    scalar loop's bits, which read the coating per geometry."""
    ti, tr, pr = _inputs()
    n = ti.size
    coat = np.where((np.arange(n) < 300) | (np.arange(n) % 2 == 0), 1.0, 1.5)
    coat[-vector.VBLOCK // 2 :] = 1.5  # the last block: coated columns only

    def facets(coating):
        return models.SubsurfaceFacetBRDF(
            slopes=models.GGXSlopes(0.2), coating=coating, substrate=1.37 + 7.62j, shadowing=shadowing
        )

    def kernel(coating):
        m = facets(coating)
        return Compiled(m, *m._kernel_spec())

    mixed = kernel(coat)
    assert mixed.vectorized
    a, b = _both(mixed, ti, tr, pr)
    assert np.array_equal(a, b)
    _, c = _both(kernel(1.0), ti, tr, pr)
    assert np.array_equal(b[:, :300], c[:, :300])  # the uncoated blocks: the plain model's
    assert not np.array_equal(b[:, 301], c[:, 301])  # a coated column is not


@pytest.mark.parametrize("model", VECTORIZED[::3], ids=lambda m: type(m).__name__)
def test_loops_read_parameter_columns_through_an_index(model):
    """An index (``drive.column``): geometry ``k`` reads parameter column ``index[k]`` of ``G``
    columns, bit for bit the rows gathered per geometry, in the scalar and the vector loop;
    ``[j]`` alone reads column ``j + k * p`` (one geometry: column ``j``)."""
    ti, tr, pr = _inputs()
    kernel = Compiled(model, *model._kernel_spec())
    rng = np.random.default_rng(5)
    cols = kernel.params("float64") * (1.0 + 0.01 * rng.random((drive.PARAM_ROWS, 7)))
    index = rng.integers(0, 7, ti.size)
    n = ti.size
    for loop in (kernel.scalar, kernel.lanes):
        got, ref = np.empty((16, n)), np.empty((16, n))
        loop(ti, tr, pr, cols, index, kernel.iopt, got, 0, 0, n)
        loop(ti, tr, pr, np.ascontiguousarray(cols[:, index]), drive.NO_INDEX, kernel.iopt, ref, 0, 0, n)
        assert np.array_equal(got, ref)
        one = np.empty((16, 1))
        loop(ti[3:4], tr[3:4], pr[3:4], cols, np.array([5]), kernel.iopt, one, 0, 0, 1)
        loop(
            ti[3:4],
            tr[3:4],
            pr[3:4],
            np.ascontiguousarray(cols[:, 5:6]),
            drive.NO_INDEX,
            kernel.iopt,
            ref,
            0,
            0,
            1,
        )
        assert np.array_equal(one[:, 0], ref[:, 0])


def test_models_take_the_vector_loop_and_agree_with_numpy():
    """Large calls of a vectorized model run :mod:`~scatterbench.models.kernels.vector` and stay within
    the model's derived tolerance of the numpy reference (relative to M00)."""
    from test_kernels import _relative, tol

    ti, tr, pr = (np.resize(x, 3000) for x in _inputs())
    m = models.SubsurfaceFacetBRDF(slopes=models.GaussianSlopes(0.2))
    mk = m.mueller(ti, tr, pr)
    with models.backend("numpy"):
        mn = m.mueller(ti, tr, pr)
    assert _relative(mk, mn) <= tol(m)


_PROBE = """
import re
import numpy as np
from scatterbench import models
from scatterbench.models.kernels import Compiled, drive
smith = models.FacetBRDF(slopes=models.GaussianSlopes(0.2), shadowing="smith")
ct_smith = models.CookTorranceBRDF(slopes=models.StrokeSlopes(0.05, 0.2, 0.7), shadowing="smith")
for m in (models.FacetBRDF(), smith, models.CookTorranceBRDF(), models.VarnishedCookTorranceBRDF(), ct_smith):
    k = Compiled(m, *m._kernel_spec())
    label = type(m).__name__ + ("-smith" if m is smith or m is ct_smith else "")
    k.run(np.linspace(0.0, 1.0, 64), np.full(1, 0.3), np.full(1, 0.2), 16)
    k.scalar(np.zeros(4), np.zeros(4), np.zeros(4), k.prm["float64"], drive.NO_INDEX, k.iopt, np.empty((16, 4)), 0, 0, 4)
    for name, fn in (("lanes", k.lanes), ("scalar", k.scalar)):  # each kernel's one compiled loop
        ir = "".join(fn.inspect_llvm().values())
        # the package's functions it calls, by name (numba's mangling: _ZN, then length-prefixed parts)
        called = set()
        for sym in re.findall(r'call [^@\\n]*@"?(_ZN12scatterbench[0-9A-Za-z_]+)', ir):
            parts, rest = [], sym[3:]
            while (d := re.match(r"\\d+", rest)) and int(d.group()) <= len(rest) - d.end():
                parts.append(rest[d.end() : d.end() + int(d.group())])
                rest = rest[d.end() + int(d.group()) :]
            called.add(parts[-1] if parts else sym)
        bodies = len(re.findall(r"^vector\\.body[.\\w]*:", ir, re.M))
        streamed = ir.count("!nontemporal")
        print(label, name, bodies, ir.count(" x double>"), streamed, ",".join(sorted(called)) or "-")
"""


# an earlier process that compiled two of the Cook-Torrance kernel's helpers in a cached
# function of its own (a test or a study calling them): when the helpers were cached
# dispatchers, numba loaded them as object code in the next process, which called them
# instead of inlining them, and its Cook loops stayed scalar (6 vector loops instead of 8;
# 0.12 instead of 0.065 us per geometry)
_EARLIER = """
from numba import njit
from scatterbench.models.kernels import common, cook

@njit(cache=True)
def both():
    return cook.fresnel_average(0.5, 1.5, 0.1, False), common.stroke_d(0.1, 0.2, 0.9, 0.3, 0.3, 1.0, 0.0)

both()
"""


def test_the_lanes_are_vectorized_loops(tmp_path):
    """In a process that compiles the vector loop (its IR is inspected: a function loaded
    from the cache has none), after an earlier process cached a function that inlines some of
    the kernels' helpers: each model's vector loop (:func:`scatterbench.models.kernels.vector.lane_entries`)
    holds LLVM's vectorized loops (their ``vector.body`` blocks, on ``<N x double>`` values),
    the facet kernel's and Cook-Torrance's (under strokes) under Smith shadowing too (``erfc``,
    the ellipse's rotation from parameter rows);
    its scalar entry (:mod:`~scatterbench.models.kernels.drive`) has none.  Fails when a change puts a call or an exception
    back in a kernel the vector path takes, caches a helper again (:mod:`scatterbench.models.kernels`),
    or leaves a call to a kernel helper (anything but the block copies) in a lane loop."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    earlier = tmp_path / "earlier.py"  # a file: numba caches no function of ``-c``'s
    earlier.write_text(_EARLIER)
    subprocess.run([sys.executable, str(earlier)], env=env, check=True)
    res = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True, check=True)
    rows = [ln.split() for ln in res.stdout.splitlines()]
    counts = {tuple(r[:2]): (int(r[2]), int(r[3]), int(r[4]), set(r[5].split(",")) - {"-"}) for r in rows}
    assert len(counts) == 10, res.stdout
    for (model, loop), (bodies, vectors, streamed, called) in counts.items():
        if loop == "lanes":  # one option set per entry: its loop, and LLVM's remainder copies
            assert bodies >= 1 and vectors > 0, (model, bodies, vectors)
            # a large result's rows streamed to memory (memory.copy_rows), on x86-64
            assert (streamed > 0) == memory.STREAMS, (model, streamed)
            # the block copies stay calls (kernels.helper's forceinline=None); a kernel's helper
            # called, not inlined, kept Cook-Torrance's loop 3.5-5x slower with vector bodies left
            called = {c for c in called if not c.startswith("run_range")}  # its own Python wrapper's
            assert called <= {"gather", "shared", "put", "facet_prepass"}, (model, called)
        else:
            assert bodies == 0, (model, bodies)


@njit
def _math(x, y):
    s, c, e, r = np.empty_like(x), np.empty_like(x), np.empty_like(x), np.empty_like(x)
    for i in range(x.size):
        s[i], c[i] = sincos(x[i])
        e[i] = exp_neg(y[i])
        r[i] = sqrt(x[i])
    return s, c, e, r


def _ulps(got, ref):
    return float(np.max(np.abs(got - ref) / np.spacing(np.abs(ref))))


@pytest.mark.parametrize("span", [math.pi / 2, 4.0, 1e3, REDUCED_MAX])
def test_sincos_and_exp_within_two_ulp(span):
    rng = np.random.default_rng(7)
    x = rng.uniform(-span, span, 200_000)
    y = rng.uniform(0.0, 710.0, x.size)
    s, c, e, r = _math(x, y)
    assert _ulps(s, np.sin(x)) <= 2.0
    assert _ulps(c, np.cos(x)) <= 2.0
    live = y < 700.0
    assert _ulps(e[live], np.exp(-y[live])) <= 2.0
    assert np.all(e[~live] == 0.0)  # exactly zero from 700 on, as the numpy path
    ok = x >= 0
    assert np.array_equal(r[ok], np.sqrt(x[ok]))  # IEEE: the same bits
    assert np.all(np.isnan(r[~ok]))


def _each(f, a, b):
    """``f(a[i], b[i])`` for every ``i``: a kernel helper of two arguments over arrays, in a
    compiled loop that names it (a helper is an overload, not a value compiled code can take)."""

    @njit
    def loop(a, b):
        out = np.empty_like(a)
        for i in range(a.size):
            out[i] = f(a[i], b[i])
        return out

    return loop(a, b)


@pytest.mark.parametrize("scale", [1.0, 1e-300, 1e300])
def test_atan2_within_two_ulp(scale):
    """Every quadrant, the reduction's seam at tan(pi/8) and the axes, from subnormal to huge
    arguments; the C library's signs at the zeros."""
    rng = np.random.default_rng(11)
    y = rng.uniform(-1.0, 1.0, 200_000) * scale
    x = rng.uniform(-1.0, 1.0, y.size) * scale
    seam = rng.uniform(0.1, 1.0, 20_000)
    y = np.concatenate([y, seam, seam, np.full(4, 0.5), [0.0, -0.0, 0.0, -0.0]])
    x = np.concatenate([x, seam / math.tan(math.pi / 8) * (1 + rng.uniform(-1e-9, 1e-9, seam.size)), -seam,
                        [0.0, -0.0, 1e-320, -1e-320], [0.0, 0.0, -0.0, -0.0]])  # fmt: skip
    ref = np.arctan2(y, x)
    got = _each(atan2, y, x)
    assert _ulps(got[ref != 0], ref[ref != 0]) <= 2.0
    assert np.array_equal(np.signbit(got), np.signbit(ref)) and np.array_equal(got[ref == 0], ref[ref == 0])


@pytest.mark.parametrize("scale", [1.0, 1e-300, 1e300])
def test_hypot_within_two_ulp(scale):
    """Any signs and ratios, from subnormal to huge arguments (whose squares overflow or
    underflow unscaled), the axes and zero."""
    rng = np.random.default_rng(12)
    x = rng.uniform(-1.0, 1.0, 200_000) * scale * np.exp(rng.uniform(-30.0, 0.0, 200_000))
    y = rng.uniform(-1.0, 1.0, x.size) * scale
    x = np.concatenate([x, [0.0, -0.0, 1e-320, 3.0, 0.0]])
    y = np.concatenate([y, [0.0, 2.0, 0.0, -4.0, -1e308]])
    ref = np.hypot(x, y)
    got = _each(hypot, x, y)
    assert np.all(np.isfinite(got)) and _ulps(got[ref != 0], ref[ref != 0]) <= 2.0
    assert np.array_equal(got[ref == 0], ref[ref == 0])


@njit
def _ggx_g_each(form, ci, si, co, so, cpo, spo, alpha):
    """The kernels' GGX Smith ``G`` (:func:`scatterbench.models.kernels.common.smith_g`) of every
    pair of directions, incidence in the plane of azimuth 0."""
    out = np.empty_like(ci)
    for k in range(ci.size):
        di, do = (ci[k], si[k], -1.0, 0.0), (co[k], so[k], cpo[k], spo[k])
        out[k] = common.smith_g(form, GGX, di, do, alpha, alpha, 1.0, 0.0)
    return out


@pytest.mark.parametrize("alpha", [1e-3, 0.2, 1.0, 30.0])
@pytest.mark.parametrize("form", ["smith", "smith-correlated"])
def test_ggx_smith_g_of_one_division_is_the_references(form, alpha):
    """The kernels take GGX's ``G`` over one division, ``|c|`` multiplied out of ``h``
    (:func:`~scatterbench.models.kernels.common.smith_h`): within 2e-15 relative (9 float64
    epsilons; about ten roundings on each side, measured at most 8.7e-16) of
    :func:`scatterbench.models.shadowing.smith_g` over the hemisphere, and exactly 0 (not NaN)
    where a direction is grazing, its cosine exactly 0, one or both."""
    rng = np.random.default_rng(5)
    ti, to, po = (rng.uniform(lo, hi, 50_000) for lo, hi in ((0, np.pi / 2), (0, np.pi / 2), (-np.pi, np.pi)))
    ci, si, co, so = np.cos(ti), np.sin(ti), np.cos(to), np.sin(to)
    ci[:3], si[:3], co[:3], so[:3] = [0.0, 1.0, 0.0], [1.0, 0.0, 1.0], [0.5, 0.0, 0.0], [0.75**0.5, 1.0, 1.0]
    got = _ggx_g_each(SHADOWING_KINDS[form], ci, si, co, so, np.cos(po), np.sin(po), alpha)
    ref = smith_g(form, models.GGXSlopes(alpha=alpha), (ci, si, -1.0, 0.0), (co, so, np.cos(po), np.sin(po)))
    assert np.array_equal(got[:3], np.zeros(3))
    assert np.all(np.abs(got - ref) <= 2e-15 * np.abs(ref))


def test_only_the_entry_points_are_cached():
    """Every numba function of :mod:`scatterbench.models.kernels` but the entry points Python calls is
    compiled without the on-disk cache (the rule and its reason: :mod:`scatterbench.models.kernels`), and
    every entry caches in :func:`scatterbench.models.kernels.cache_dir`."""
    import importlib
    import pkgutil

    from numba.core.registry import CPUDispatcher
    from numba.core.typing.templates import builtin_registry

    import scatterbench.models.kernels as kernels

    registered = {fn for fn, _ in builtin_registry.globals}  # overloads: helper's and numba's

    entries = {
        "drive": {"angles_ok", "outside_range"},  # and the entries per kernel, below
        "montecarlo": {"_range", "_exit_range"},
        "aperture": {"nodes", "_tiles"},
        "disc": {"points"},
        "rough": {"_moments", "write"},
    }
    helpers = 0
    cached_seen = set()
    # every module of the package, so that a new one is held to the rule too
    for name in (info.name for info in pkgutil.iter_modules(kernels.__path__)):
        mod = importlib.import_module(f"scatterbench.models.kernels.{name}")
        for attr, fn in vars(mod).items():
            if getattr(fn, "__module__", None) == mod.__name__ and fn in registered:
                helpers += 1  # kernels.helper.helper's: compiled in each caller's process, never cached
                assert attr not in entries.get(name, ()), f"{name}.{attr} is an entry, not a helper"
            if isinstance(fn, CPUDispatcher) and fn.py_func.__module__ == mod.__name__:
                cached = type(fn._cache).__name__ != "NullCache"
                assert cached == (attr in entries.get(name, ())), f"{name}.{attr} cached: {cached}"
                if cached:  # in the package's cache directory, never beside the (read-only) package
                    cached_seen.add((name, attr))
                    where = fn._cache._cache_path
                    assert where.startswith(models.kernels.cache_dir()), f"{name}.{attr} caches in {where}"
                    # compiled by helper.entry_point: without the C wrapper nothing calls
                    assert fn.targetoptions.get("no_cfunc_wrapper"), f"{name}.{attr} has a C wrapper"
    # every entry named above found (the scan reached every module), and the helpers with them
    assert cached_seen == {(m, a) for m, names in entries.items() for a in names}, cached_seen
    assert helpers > 60, helpers
    # the loop per kernel (and per option set on SIMD lanes): closures, not module names
    per_kernel = list(drive.ENTRIES)
    per_kernel += [vector.lane_entries(c, np.zeros(3, dtype=np.int64)) for c in (0, 2, 3, 4, 5)]
    for fn in per_kernel:
        assert type(fn._cache).__name__ != "NullCache", fn
        assert fn.targetoptions.get("no_cfunc_wrapper"), fn
        assert fn._cache._cache_path.startswith(models.kernels.cache_dir()), fn
    names = {fn.py_func.__qualname__ for fn in per_kernel}
    assert len(names) == len(per_kernel)  # cache files of their own


@njit
def _erfc_each(x):
    e, s = np.empty_like(x), np.empty_like(x)
    for i in range(x.size):
        e[i], s[i] = erfc(x[i]), exp_neg_square(abs(x[i]))
    return e, s


@pytest.mark.parametrize("span", [(-6.0, 0.0), (0.0, 1.0), (1.0, 6.0), (6.0, 27.0)])
def test_erfc_within_five_ulp_and_exp_of_the_square_within_two(span):
    """``erfc`` within 5 ulp of the C library's (which is within 2 of the exact value: ours is
    within 5, ``scripts/fit_erfc_coefficients.py``'s reference), down to the normal range; exactly
    zero from ``x^2 = 700`` on; ``exp(-x^2)`` within 2 ulp of ``exp`` of the exact square (the
    float64 product of ``x`` with itself is rounded: ``math.exp(-x * x)`` is up to ``x^2`` ulp off,
    so the reference takes the square's rounding error out, to first order)."""
    rng = np.random.default_rng(13)
    x = np.concatenate([rng.uniform(*span, 200_000), np.array(span)])
    got, sq = _erfc_each(x)
    ref = np.array([math.erfc(v) for v in x])
    live = ref > 1e-300
    assert _ulps(got[live], ref[live]) <= 5.0
    assert np.all(got[np.abs(x) >= math.sqrt(700.0)] == 0.0)
    x, sq = x[::10], sq[::10]
    p = x * x
    # the square's rounding error in exact rational arithmetic (not the kernel's Dekker split)
    err = np.array([float(Fraction(v) ** 2 - Fraction(w)) for v, w in zip(x, p, strict=True)])
    ref_sq = np.exp(-p) * (1.0 - err)
    live = (p < 700.0) & (ref_sq > 1e-300)
    assert _ulps(sq[live], ref_sq[live]) <= 2.0


def test_erfc_at_the_edges():
    """The values Smith's ``Lambda`` meets: zero, infinity (``mu`` at normal incidence), the
    underflow, NaN."""
    got, sq = _erfc_each(np.array([0.0, -0.0, np.inf, -np.inf, 26.4, 26.5, 1e300, np.nan]))
    assert np.array_equal(got[[0, 1, 2, 3, 5, 6]], [1.0, 1.0, 0.0, 2.0, 0.0, 0.0])
    assert abs(got[4] - math.erfc(26.4)) <= 5 * math.ulp(math.erfc(26.4))
    assert np.isnan(got[7])
    assert np.array_equal(sq[:4], [1.0, 1.0, 0.0, 0.0])


def test_option_sets_are_every_set_the_lanes_take():
    """:func:`~scatterbench.models.kernels.vector.option_sets` (what ``kernels.warm`` compiles
    ahead) holds every option set :func:`~scatterbench.models.kernels.vector.lane_options` gives a
    vectorized kernel, over every option value a kernel reads: a set missing there compiles
    lazily, in each process that reaches it, on a report's first run."""
    seen = {c: set() for c in drive.CODES.values()}
    for code in drive.CODES.values():
        # o[0]: slope kind or form; o[1]: convention or shadowing (3 kinds); o[2]: Cook-Torrance's
        # shadowing (3 kinds) or Maxwell-Beard's polarized flag (2)
        for iopt in np.ndindex(8, 3, 2 if code == drive.MAXWELL else 3):
            iopt = np.array(iopt, dtype=np.int64)
            if vector.vectorized(code, iopt):
                seen[code].add(vector.lane_options(code, iopt))
    for code, sets in seen.items():
        assert sets == set(vector.option_sets(code)), (drive.NAMES[code], sets)
