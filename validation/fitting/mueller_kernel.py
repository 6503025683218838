"""The Mueller likelihood's per-row sum, fused (numba): the model's psps elements restated in
the data's basis, normalized, and their Gaussian log-densities summed per row in one pass, where
the numpy form (:meth:`~.mueller_likelihood.MuellerLikelihood.residuals`, kept as the reference the
tests hold this to) makes a temporary array per element and operation: measured on 24 walkers x
7296 rows x 16 elements, 0.09 s of numpy arithmetic where the models' kernels took 0.054 s.
The walkers run over the cores, and each element's branches sit outside its row loops so that
those compile to SIMD loops: 24 walkers took 7.4 ms where the row loop with the branches inside
took 28.8 ms (one thread, both timed alternately in one process; the same bits).  Multiplying by a hoisted ``1 / M11`` instead of dividing gained nothing measurable
(the loop is bound by memory), so the division, and the numpy reference's bits, stay.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from scatterbench.models.kernels import uncached
from scatterbench.models.kernels.threads import spread

__all__ = ["pack_map", "loglike_rows"]

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


def loglike_rows(M, src, coef, nsrc, obs, is_m11, c, s2, errvar, out):
    """Per-row log-likelihood into ``out`` ``(W, N)`` from the psps elements ``M`` ``(16, W, N)``
    (element 0 is M11 in every basis); ``obs`` ``(E, N)``: ln M11 or the normalized element;
    ``c`` ``(W,)`` the calibration; ``s2`` ``(E, W)`` the noise variances; ``errvar`` ``(E, N)``.
    The walkers over the cores (:func:`~scatterbench.models.kernels.threads.spread`: a
    ``prange`` entry compiles through numba's parallel pipeline, seconds more of a cold
    cache), each walker's rows in the serial order (:func:`_walker`)."""
    has_err = bool(np.any(errvar != 0.0))
    spread(_walkers, (M, src, coef, nsrc, obs, is_m11, c, s2, errvar, has_err, out), out.shape[0], 1)


@numba.njit(cache=True, nogil=True)
def _walkers(
    M, src, coef, nsrc, obs, is_m11, c, s2, errvar, has_err, out, lo, hi
):  # pragma: no cover - compiled
    """Walkers ``lo .. hi - 1`` of :func:`loglike_rows`."""
    for w in range(lo, hi):
        _walker(M, w, src, coef, nsrc, obs, is_m11, math.log(c[w]), s2[:, w], errvar, has_err, out[w])


@numba.njit
def _walker(M, w, src, coef, nsrc, obs, is_m11, lc, s2, errvar, has_err, out):  # pragma: no cover - compiled
    """One walker's rows: element by element along the rows (a dozen memory streams; row by
    row, every element's arrays at once, ran 5x slower), each element's prediction first into
    ``val`` (the sources summed in order), the branches outside the row loops so that those
    compile to SIMD loops."""
    N = out.shape[0]
    lm = np.empty(N)
    val = np.empty(N)
    for n in range(N):
        m11 = M[0, w, n]
        ok = m11 > 0.0 and math.isfinite(m11)
        lm[n] = math.log(m11) if ok else math.nan
        out[n] = 0.0 if ok else -math.inf
    for k in range(src.shape[0]):
        if is_m11[k]:
            for n in range(N):
                val[n] = obs[k, n] - (lc + lm[n])
        else:
            val[:] = 0.0
            for j in range(nsrc[k]):
                f = src[k, j]
                for n in range(N):
                    val[n] += coef[k, j, n] * M[f, w, n]
            for n in range(N):
                val[n] = obs[k, n] - val[n] / M[0, w, n]
        _add_density(val, s2[k], errvar[k], has_err, out)
    for n in range(N):
        if not math.isfinite(out[n]):
            out[n] = -math.inf


@numba.njit
def _add_density(r, v0, errvar, has_err, out):  # pragma: no cover - compiled
    """``out -=`` the Gaussian's negative log-density of residuals ``r``: variance ``v0`` plus
    the rows' ``errvar`` where the data have errors."""
    if has_err:
        for n in range(r.shape[0]):
            v = v0 + errvar[n]
            out[n] -= 0.5 * (r[n] * r[n] / v + _LOG2PI + math.log(v))
    else:
        half_log = 0.5 * (_LOG2PI + math.log(v0))
        for n in range(r.shape[0]):
            out[n] -= 0.5 * r[n] * r[n] / v0 + half_log


def _signature():
    """The argument types :func:`loglike_rows` passes :func:`_walkers` (C-contiguous, writable)."""
    f, i, b = numba.float64, numba.int64, numba.boolean
    a = lambda t, n: numba.types.Array(t, n, "C")  # noqa: E731
    return (a(f, 3), a(i, 2), a(f, 3), a(i, 1), a(f, 2), a(b, 1), a(f, 1), a(f, 2), a(f, 2), b, a(f, 2), i, i)


def cold() -> bool:
    """Whether the fused likelihood is not in numba's cache yet."""
    return uncached(_walkers)


def warm():
    """Compile (or load from the cache) the fused likelihood for the types a fit passes, without
    running it: a first report compiles it on a worker process beside the kernels
    (``validation.report.build.compile_ahead``), where its PTFE section compiled it on the main
    process (~2.4 s of CPU).  Returns ``"likelihood"``."""
    if hasattr(_walkers, "compile"):
        _walkers.compile(_signature())
    return "likelihood"
