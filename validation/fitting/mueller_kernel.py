"""The Mueller likelihood's per-row sum, fused (numba): the model's psps elements restated in
the data's basis, normalized, and their Gaussian log-densities summed per row in one pass, where
the numpy form (:meth:`~.mueller_likelihood.MuellerLikelihood.residuals`, kept as the reference the
tests hold this to, within 1e-11 relative) makes a temporary array per element and operation:
measured on 24 walkers x 7296 rows x 16 elements, 0.09 s of numpy arithmetic where the models'
kernels took 0.054 s.  Each element's branches sit outside its row loops so that those compile
to SIMD loops: 24 walkers took 7.4 ms where the row loop with the branches inside took 28.8 ms
(one thread, both timed alternately in one process; the same bits).

A model that is a kernel or a sum of kernels (:func:`loglike_terms`) is evaluated range by range
of rows into buffers that stay in the cache and its likelihood taken there; other models give
their ``(16, W, N)`` elements first (:func:`loglike_rows`).  Both routes run the same row loop
(:func:`_rows`), so they give the same bits.  Once the elements came from the cache the row
loop's divisions showed: multiplying by ``1 / M11`` (once per row) and by ``0.5 / variance``
(once per element), and one pass per element over its sources instead of one per source, took
it from 16.0 to 7.0 ms per batch of 24 walkers on one thread (cProfile, ad hoc, 2026-11-29).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from scatterbench.models.kernels import uncached
from scatterbench.models.kernels.threads import spread

__all__ = ["pack_map", "loglike_rows", "loglike_terms"]

_LOG2PI = math.log(2.0 * math.pi)


def pack_map(maps, elements):
    """``(src (E, 4), coef (E, 4, N), nsrc (E,))`` of the row maps of ``elements`` (indices)."""
    n = len(next(iter(maps.values()))[0][1])
    src = np.zeros((len(elements), 4), dtype=np.int64)
    coef = np.zeros((len(elements), 4, n))
    nsrc = np.zeros(len(elements), dtype=np.int64)
    for k, e in enumerate(elements):
        for j, (f, c) in enumerate(maps[e]):
            src[k, j], coef[k, j] = f, c
        nsrc[k] = len(maps[e])
    return src, coef, nsrc


#: rows of a walker per range of :func:`loglike_terms`: the 16 psps rows of that many geometries
#: in float64, in two buffers (the first term's, a later term's), 512 kB, stay in the cache
#: (:data:`RANGE_ROWS` of 1024 -> 4096 measured 120, 114, 144 ns per geometry for the PTFE
#: scene's two terms on one thread, against 154 through a whole (16, W * N) array: ad hoc,
#: 2026-11-29)
RANGE_ROWS = 2048


def loglike_rows(M, src, coef, nsrc, obs, is_m11, c, s2, errvar, out):
    """Per-row log-likelihood into ``out`` ``(W, N)`` from the psps elements ``M`` ``(16, W, N)``
    (element 0 is M11 in every basis); ``obs`` ``(E, N)``: ln M11 or the normalized element;
    ``c`` ``(W,)`` the calibration; ``s2`` ``(E, W)`` the noise variances; ``errvar`` ``(E, N)``.
    The walkers over the cores (:func:`~scatterbench.models.kernels.threads.spread`: a
    ``prange`` entry compiles through numba's parallel pipeline, seconds more of a cold
    cache), each walker's rows in the serial order (:func:`_rows`)."""
    W, N = out.shape
    flat = np.ascontiguousarray(M).reshape(M.shape[0], W * N)
    args = _row_args(src, coef, nsrc, obs, is_m11, c, s2, errvar, out)

    def walkers(lo, hi):
        for w in range(lo, hi):
            _rows(flat, w * N, w, 0, N, *args)

    spread(walkers, (), W, 1)


def loglike_terms(terms, angles, src, coef, nsrc, obs, is_m11, c, s2, errvar, out):
    """:func:`loglike_rows` of the sum of ``terms`` ``[(kernel, index)]``
    (:meth:`scatterbench.models.base.Model.indexed_kernel`) at the flat angles ``angles``
    ``(theta_i, theta_r, phi)`` over ``(W, N)`` geometries, without the whole ``(16, W, N)``
    array: range by range of :data:`RANGE_ROWS` rows of a walker, each term's elements into a
    buffer that stays in the cache, the later terms added in order (the bits of
    :class:`~scatterbench.models.base.Sum` and of :func:`loglike_rows` on its result), and the
    range's likelihood taken at once, where the whole route writes the 22 MB of a fit's 24
    walkers x 7296 rows, reads and writes them again for the second term and reads them for
    the likelihood.  Measured (the PTFE joint scene, 24 walkers at new positions, the two
    routes interleaved over 25 batches in one process, 2 threads, ad hoc, 2026-11-29): best
    18.7 against 21.9 ms, median 23.4 against 24.1 ms; ``benchmarks/ptfe_joint_fit.py`` prints
    both routes."""
    W, N = out.shape
    per = -(-N // RANGE_ROWS)  # ranges per walker, of equal size
    step = -(-N // per)
    ti, tr, pr = (a if a.flags.writeable else a.copy() for a in map(np.ascontiguousarray, angles))
    args = _row_args(src, coef, nsrc, obs, is_m11, c, s2, errvar, out)
    (first, index0), *later = [(kernel.range_writer(), index) for kernel, index in terms]

    def ranges(lo, hi):
        buf = np.empty((16, step))
        more = np.empty((16, step)) if later else None
        for t in range(lo, hi):
            w, a = divmod(t, per)
            a *= step
            b = min(a + step, N)
            g = w * N + a
            first(ti, tr, pr, index0, buf, g, g + b - a)
            for write, index in later:
                write(ti, tr, pr, index, more, g, g + b - a)
                np.add(buf[:, : b - a], more[:, : b - a], out=buf[:, : b - a])
            _rows(buf, 0, w, a, b, *args)

    spread(ranges, (), W * per, 1)


def _row_args(src, coef, nsrc, obs, is_m11, c, s2, errvar, out):
    """:func:`_rows`' arguments after the range, both routes': whether the data have errors
    (the row loop's second branch) found once per batch."""
    return (src, coef, nsrc, obs, is_m11, c, s2, errvar, bool(np.any(errvar != 0.0)), out)


@numba.njit(cache=True, nogil=True)
def _rows(
    M, col, w, a, b, src, coef, nsrc, obs, is_m11, c, s2, errvar, has_err, out
):  # pragma: no cover - compiled
    """Rows ``a .. b - 1`` of walker ``w`` into ``out[w, a:b]``, row ``a + j``'s psps elements in
    ``M[:, col + j]``: element by element along the rows (a dozen memory streams; row by row,
    every element's arrays at once, ran 5x slower), each element's prediction first into ``val``
    (the sources summed in order), the branches outside the row loops so that those compile to
    SIMD loops (24 walkers took 7.4 ms where the row loop with the branches inside took 28.8 ms)."""
    L = b - a
    lm = np.empty(L)
    inv = np.empty(L)
    val = np.empty(L)
    o = out[w, a:b]
    lc = math.log(c[w])
    for j in range(L):
        m11 = M[0, col + j]
        ok = m11 > 0.0 and math.isfinite(m11)
        lm[j] = math.log(m11) if ok else math.nan
        inv[j] = 1.0 / m11
        o[j] = 0.0 if ok else -math.inf
    for k in range(src.shape[0]):
        ob = obs[k, a:b]
        if is_m11[k]:
            for j in range(L):
                val[j] = ob[j] - (lc + lm[j])
        else:
            _normalized(M, col, src[k], nsrc[k], coef[k, :, a:b], ob, inv, val)
        _add_density(val, s2[k, w], errvar[k, a:b], has_err, o)
    for j in range(L):
        if not math.isfinite(o[j]):
            o[j] = -math.inf


@numba.njit
def _normalized(M, col, src, n, cf, ob, inv, val):  # pragma: no cover - compiled
    """``val = ob -`` the element of ``n`` sources ``M[src[i], col + j]`` weighted by ``cf[i, j]``
    (summed from 0 in order) over M11 (times ``inv``, its reciprocal): one loop per number of
    sources, so that each pass reads every stream once (a pass per source, adding into ``val``,
    read and wrote it four times)."""
    m0, m1, m2, m3 = M[src[0]], M[src[1]], M[src[2]], M[src[3]]
    c0, c1, c2, c3 = cf[0], cf[1], cf[2], cf[3]
    if n == 0:  # no source: the element is 0 (0 / M11, as numpy's)
        for j in range(val.shape[0]):
            val[j] = ob[j] - 0.0 * inv[j]
    elif n == 1:
        for j in range(val.shape[0]):
            val[j] = ob[j] - (0.0 + c0[j] * m0[col + j]) * inv[j]
    elif n == 2:
        for j in range(val.shape[0]):
            val[j] = ob[j] - (0.0 + c0[j] * m0[col + j] + c1[j] * m1[col + j]) * inv[j]
    elif n == 3:
        for j in range(val.shape[0]):
            v = 0.0 + c0[j] * m0[col + j] + c1[j] * m1[col + j] + c2[j] * m2[col + j]
            val[j] = ob[j] - v * inv[j]
    else:
        for j in range(val.shape[0]):
            v = 0.0 + c0[j] * m0[col + j] + c1[j] * m1[col + j] + c2[j] * m2[col + j] + c3[j] * m3[col + j]
            val[j] = ob[j] - v * inv[j]


@numba.njit
def _add_density(r, v0, errvar, has_err, out):  # pragma: no cover - compiled
    """``out -=`` the Gaussian's negative log-density of residuals ``r``: variance ``v0`` plus
    the rows' ``errvar`` where the data have errors."""
    if has_err:
        for n in range(r.shape[0]):
            v = v0 + errvar[n]
            out[n] -= 0.5 * (r[n] * r[n] / v + _LOG2PI + math.log(v))
    else:
        half_log, half_inv = 0.5 * (_LOG2PI + math.log(v0)), 0.5 / v0
        for n in range(r.shape[0]):
            out[n] -= r[n] * r[n] * half_inv + half_log


def _signature():
    """The argument types both routes pass :func:`_rows` (C-contiguous, writable)."""
    f, i, b = numba.float64, numba.int64, numba.boolean
    a = lambda t, n: numba.types.Array(t, n, "C")  # noqa: E731
    return (
        a(f, 2),
        i,
        i,
        i,
        i,
        a(i, 2),
        a(f, 3),
        a(i, 1),
        a(f, 2),
        a(b, 1),
        a(f, 1),
        a(f, 2),
        a(f, 2),
        b,
        a(f, 2),
    )


def cold() -> bool:
    """Whether the fused likelihood is not in numba's cache yet."""
    return uncached(_rows)


def warm():
    """Compile (or load from the cache) the fused likelihood for the types a fit passes, without
    running it: a first report compiles it on a worker process beside the kernels
    (``validation.report.build.compile_ahead``), where its PTFE section compiled it on the main
    process (~2.4 s of CPU).  Returns ``"likelihood"``."""
    if hasattr(_rows, "compile"):
        _rows.compile(_signature())
    return "likelihood"
