"""The Mueller likelihood's per-row sum, fused (numba): the model's psps elements restated in
the data's basis, normalized, and their Gaussian log-densities summed per row in one pass, where
the numpy form (:meth:`~.mueller_likelihood.MuellerLikelihood.residuals`, kept as the reference the
tests hold this to) makes a temporary array per element and operation: measured on 24 walkers x
7296 rows x 16 elements, 0.09 s of numpy arithmetic where the models' kernels took 0.054 s.
"""

from __future__ import annotations

import math

import numba
import numpy as np

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


@numba.njit(cache=True)
def loglike_rows(M, src, coef, nsrc, obs, is_m11, c, s2, errvar, out):  # pragma: no cover - compiled
    """Per-row log-likelihood into ``out`` ``(W, N)`` from the psps elements ``M`` ``(16, W, N)``
    (element 0 is M11 in every basis); ``obs`` ``(E, N)``: ln M11 or the normalized element;
    ``c`` ``(W,)`` the calibration; ``s2`` ``(E, W)`` the noise variances; ``errvar`` ``(E, N)``.
    Element by element along the rows (a dozen memory streams; row by row, every element's
    arrays at once, ran 5x slower)."""
    E = src.shape[0]
    W, N = out.shape
    has_err = np.any(errvar != 0.0)
    lm = np.empty(N)
    for w in range(W):
        lc = math.log(c[w])
        for n in range(N):
            m11 = M[0, w, n]
            ok = m11 > 0.0 and math.isfinite(m11)
            lm[n] = math.log(m11) if ok else math.nan
            out[w, n] = 0.0 if ok else -math.inf
        for k in range(E):
            v0 = s2[k, w]
            half_log = 0.5 * (_LOG2PI + math.log(v0))
            for n in range(N):
                if is_m11[k]:
                    r = obs[k, n] - (lc + lm[n])
                else:
                    val = 0.0
                    for j in range(nsrc[k]):
                        val += coef[k, j, n] * M[src[k, j], w, n]
                    r = obs[k, n] - val / M[0, w, n]
                if has_err:
                    v = v0 + errvar[k, n]
                    out[w, n] -= 0.5 * (r * r / v + _LOG2PI + math.log(v))
                else:
                    out[w, n] -= 0.5 * r * r / v0 + half_log
        for n in range(N):
            if not math.isfinite(out[w, n]):
                out[w, n] = -math.inf
