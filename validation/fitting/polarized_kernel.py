"""The polarized BRDF likelihood's per-row sum, fused (numba): each row's Stokes vector from
the model's Mueller elements and the incident light, its BRDF, principal angle, degree of
polarization and of circular polarization, their residuals and Gaussian log-densities, summed
per row in one pass.  The numpy form (:meth:`~.likelihood.Likelihood.predict`,
:meth:`~.likelihood.Likelihood.residuals` and :meth:`~.likelihood.Likelihood._pointwise_rows`)
makes a temporary array per quantity and operation; it is kept as the reference that the tests
hold this to (``tests/test_polarized_kernel.py``: the same rows of ``-inf``, each finite row
within 1e-12 of the sum of its terms' magnitudes).

What differs from the reference, and why its last bits may:

- the principal angle's residual is wrapped to a half-turn by subtracting the nearest
  multiple of pi (``d - pi floor(d / pi + 1/2)``), where the reference takes
  ``arg(exp(2 i d)) / 2`` (a sine, a cosine and an arctangent per row: 57 us of a 500 us
  likelihood call of 12 walkers x 200 rows, ad hoc).  Both are within an ulp or two of the
  exact wrap; at exactly +-pi/2 they give opposite signs, which the square removes;
- the angle's arctangent is :func:`~scatterbench.models.kernels.vector_math.atan2`, a
  polynomial within 2 ulp of the C library's that runs on SIMD lanes (the C library's call
  kept the loop scalar: 70 against 42 us for the call below), and the BRDF's logarithm the C
  library's, where numpy may use its own SIMD functions;
- :func:`~scatterbench.models.kernels.vector_math.atan2` takes finite arguments: a row whose
  Stokes Q or U is infinite (a model's infinite Mueller element) may get another eta term
  here, ``-inf`` where the polynomial gives NaN, than the reference's arctangent of the
  infinities.  The tests compare finite Mueller elements.

Each term is a loop over a walker's rows with no call and no branch inside, as in
:mod:`.mueller_kernel`.  Measured (ad hoc, 2026-12-07, one thread, 12 walkers x 200 rows of
seed 003's paint data): after the model's kernel, Maxwell-Beard with every term took 40 us
here (53 us with this module's Python) against ~210 us of numpy, the BRDF alone 18 (23)
against ~70 us.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from scatterbench.models.kernels import uncached
from scatterbench.models.kernels.vector_math import atan2, sqrt

__all__ = ["loglike_rows", "cold", "warm"]

_LOG2PI = math.log(2.0 * math.pi)


def loglike_rows(M, incident, same, brdf_in, obs, variances, out):
    """Per-row log-likelihood into ``out`` ``(W, N)`` (the reference's numbers, see the module).

    ``M`` ``(16, W * N)``: the Mueller elements of walker ``w``'s row ``n`` in column
    ``w * N + n``; ``incident`` ``(4, N)``, each row's incident Stokes vector, or ``(4, 1)``
    with ``same`` true, one for every row, whose zero elements are skipped (as the reference
    skips them: no NaN from an infinite element times 0); ``brdf_in`` ``(N,)`` the incident
    intensity that normalizes the BRDF; ``obs`` ``(4, N)`` the data's ln BRDF, eta (radians),
    P and P_C, the reference's order of the terms (the rows of terms not used are not read);
    ``variances``: in that order, each term's variance (a scalar, ``(W, 1)``, ``(N,)`` or
    ``(W, N)``), or ``None`` for a term not used (the BRDF's is always used)."""
    use = np.array([v is not None for v in variances[1:]])
    var, logvar = [], []
    for v in variances:
        if v is None:  # not read
            var.append(_ONE)
            logvar.append(_ONE)
            continue
        a = np.asarray(v, dtype=float)
        var.append(np.ascontiguousarray(a if a.ndim == 2 else a.reshape(1, -1)))
        with np.errstate(divide="ignore", invalid="ignore"):
            logvar.append(np.log(var[-1]))
    _rows(M, incident, same, brdf_in, obs, use, *var, *logvar, out)


_ONE = np.ones((1, 1))


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _rows(M, inc, same, brdf_in, obs, use, vb, ve, vp, vc, lb, le, lp, lc, out):  # pragma: no cover
    """Walker by walker: its rows' Stokes vectors (the incident elements' products added in
    order, as the reference's ``_stokes``), then the terms in the reference's order (BRDF, eta,
    P, P_C), each a loop over the rows with no call and no branch inside (SIMD lanes: the
    angle's arctangent is :func:`~scatterbench.models.kernels.vector_math.atan2`, within 2 ulp
    of the C library's), its residuals first, then their densities added (:func:`_add`)."""
    W, N = out.shape
    S = np.empty((4, N))
    r = np.empty(N)
    rows = 4 if use[0] or use[1] or use[2] else 1
    for w in range(W):
        _stokes(M, w * N, inc, same, rows, S)
        o = out[w]
        for n in range(N):
            o[n] = 0.0
            r[n] = obs[0, n] - math.log(S[0, n] / brdf_in[n])
        _add(o, r, vb, lb, w)
        if use[0]:
            for n in range(N):
                d = obs[1, n] - 0.5 * atan2(S[2, n], S[1, n])
                r[n] = d - math.pi * math.floor(d / math.pi + 0.5)
            _add(o, r, ve, le, w)
        if use[1]:
            for n in range(N):
                i = S[0, n]
                p = sqrt(S[1, n] * S[1, n] + S[2, n] * S[2, n] + S[3, n] * S[3, n]) / i
                r[n] = obs[2, n] - (p if i > 0.0 else math.nan)
            _add(o, r, vp, lp, w)
        if use[2]:
            for n in range(N):
                i = S[0, n]
                r[n] = obs[3, n] - (S[3, n] / i if i > 0.0 else math.nan)
            _add(o, r, vc, lc, w)


@numba.njit(error_model="numpy")
def _stokes(M, col, inc, same, rows, S):  # pragma: no cover - compiled
    """The first ``rows`` Stokes elements of the rows whose Mueller elements start at column
    ``col`` into ``S``: one incident vector (``same``) with its zero elements skipped, or one
    per row."""
    N = S.shape[1]
    for a in range(rows):
        s = S[a]
        if same:
            x = inc[0, 0]
            for n in range(N):
                s[n] = M[4 * a, col + n] * x
            for b in range(1, 4):
                x = inc[b, 0]
                if x != 0.0:
                    for n in range(N):
                        s[n] += M[4 * a + b, col + n] * x
        else:
            m0, m1, m2, m3 = M[4 * a], M[4 * a + 1], M[4 * a + 2], M[4 * a + 3]
            for n in range(N):
                x = m0[col + n] * inc[0, n]
                x += m1[col + n] * inc[1, n]
                x += m2[col + n] * inc[2, n]
                x += m3[col + n] * inc[3, n]
                s[n] = x


@numba.njit(error_model="numpy")
def _add(o, r, v, lv, w):  # pragma: no cover - compiled
    """``o +=`` the Gaussian log-density of residuals ``r``, ``-(r^2 / v + ln 2 pi + ln v) / 2``
    in the reference's order of operations, ``-inf`` where not finite; the variance ``v`` and
    its logarithm ``lv`` of walker ``w`` (broadcast from ``(1 or W, 1 or N)``), one for all rows
    or one per row."""
    vw, lw = v[w if v.shape[0] > 1 else 0], lv[w if lv.shape[0] > 1 else 0]
    one = vw.shape[0] == 1
    for n in range(o.shape[0]):
        ll = r[n] * r[n]
        ll /= vw[0 if one else n]
        ll += _LOG2PI
        ll += lw[0 if one else n]
        ll *= -0.5
        o[n] += ll if math.isfinite(ll) else -math.inf


def _signature():
    """The argument types :func:`loglike_rows` passes :func:`_rows`."""
    f, b = numba.float64, numba.boolean
    a = lambda t, n: numba.types.Array(t, n, "C")  # noqa: E731
    return (a(f, 2), a(f, 2), b, a(f, 1), a(f, 2), a(b, 1), *[a(f, 2)] * 8, a(f, 2))


def cold() -> bool:
    """Whether the fused likelihood is not in numba's cache yet."""
    return uncached(_rows)


def warm():
    """Compile (or load from the cache) the fused likelihood for the types a fit passes, without
    running it (the report's compile-ahead, ``validation.report.build``)."""
    if hasattr(_rows, "compile"):
        _rows.compile(_signature())
