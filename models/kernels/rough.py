"""The rough-interface diffuser of :class:`scatterbench.models.RoughSubsurfaceBRDF`, compiled: the
slope-plane quadrature of its moments (once per distinct slope width) and the per-geometry
Chebyshev evaluation; each element's tables are the numpy reference's own
(:func:`scatterbench.models.rough_subsurface._tables`).  The rule is the numpy reference's
(:mod:`scatterbench.models.rough_subsurface`, which documents it), written as loops; the tests
hold the two within 1e-12 relative to ``M00``."""

from __future__ import annotations

import math

import numpy as np

from .helper import entry_point, helper
from .threads import spread
from .vector_math import atan2, exp_neg, sincos, sqrt

#: degree of the transmittances' series (:data:`scatterbench.models.rough_subsurface.MOMENTS`)
_M = 20
_RHO_MAX = math.sqrt(42.0)


@entry_point(nogil=True)
def _moments(sigmas, nodes, rx, rw, ax, aw, cheb, A0, A1, lo, hi):  # pragma: no cover - compiled
    """``A0[k], A1[k]`` ``(2 nodes, _M + 1)`` of slope widths ``sigmas[lo:hi]``: per u-node, the
    radial nodes (:func:`_radii`), then every arc node into flat arrays (local cosine, weights;
    one loop over radius x arc node), then :func:`_reduce`: each a loop on SIMD lanes, with the
    polynomial exponential, arctangent and cosine."""
    R, P = rx.shape[0], ax.shape[0]
    L = 2 * R * P
    xc, w0, w1, tp, tc = np.empty(L), np.empty(L), np.empty(L), np.empty(L), np.empty(L)
    rad = np.empty((5, 2 * R))
    for k in range(lo, hi):
        sigma = sigmas[k]
        ub = min(0.5, 6.0 * sigma)
        for j in range(2 * nodes):
            x = 0.5 * (cheb[j % nodes] + 1.0)
            u = ub * x if j < nodes else ub + (1.0 - ub) * x
            s = sqrt(1.0 - u * u)
            nr = _radii(u / s, sigma, rx, rw, rad)
            rho, wr, phic, half, q2 = rad[0], rad[1], rad[2], rad[3], rad[4]
            for r in range(nr):
                rr, ww, pc, hh, qq = rho[r], wr[r], phic[r], half[r], q2[r]
                iq = 1.0 / sqrt(qq)
                for p in range(P):
                    i = r * P + p
                    zx = rr * sincos(pc + hh * (ax[p] + 1.0))[1]
                    proj = max(u - s * zx, 0.0)
                    c = min(proj * iq, 1.0)
                    km2 = qq - proj * proj
                    d = u * zx + s
                    cos2 = 2.0 * d * d / km2 - 1.0 if km2 > 1e-300 else 1.0
                    wp = ww * aw[p] * proj
                    xc[i] = 2.0 * c - 1.0
                    w0[i] = wp
                    w1[i] = wp * cos2
            _reduce(xc, w0, w1, nr * P, tp, tc, A0[k, j], A1[k, j])


@helper
def _radii(rho0, sigma, rx, rw, rad):  # pragma: no cover - compiled
    """The radial rule at ``rho0 = cot(theta)`` into ``rad`` (radius, weight x density x half
    arc, arc start, half arc, ``1 + rho^2``); returns how many radii (one part or two)."""
    R = rx.shape[0]
    rmax = _RHO_MAX * sigma
    a = min(rho0, rmax)
    nr = R if rho0 >= rmax else 2 * R
    for r in range(nr):
        outer = r >= R
        m = r - R if outer else r
        sv = 0.5 * (rx[m] + 1.0)
        rho = rho0 + (rmax - rho0) * sv * sv if outer else a * sv
        w = (rmax - rho0) * sv * rw[m] if outer else 0.5 * a * rw[m]
        q = rho / sigma
        ratio = min(rho0 / rho, 1.0)
        phic = atan2(sqrt(1.0 - ratio * ratio), ratio)
        half = 0.5 * (math.pi - phic)
        rad[0, r] = rho
        rad[1, r] = w * rho * exp_neg(q * q) * half
        rad[2, r] = phic
        rad[3, r] = half
        rad[4, r] = 1.0 + rho * rho
    return nr


@helper(fastmath={"reassoc"})
def _reduce(x, w0, w1, L, tp, tc, a0, a1):  # pragma: no cover - compiled
    """``a0[m] = sum w0 T_m(x) / sum w0``, ``a1[m] = sum w1 T_m(x) / sum w0`` over ``L`` nodes,
    the recurrence on arrays: sums reassociated (``fastmath={"reassoc"}``), so that each runs
    on SIMD lanes (an order of summation of its own; the numpy reference's is BLAS's)."""
    s0 = 0.0
    s1 = 0.0
    for i in range(L):
        tp[i] = 1.0
        tc[i] = x[i]
        s0 += w0[i]
        s1 += w1[i]
    a0[0], a1[0] = s0, s1
    s0 = 0.0
    s1 = 0.0
    for i in range(L):
        s0 += w0[i] * x[i]
        s1 += w1[i] * x[i]
    a0[1], a1[1] = s0, s1
    for m in range(2, _M + 1):
        s0 = 0.0
        s1 = 0.0
        for i in range(L):
            t = 2.0 * x[i] * tc[i] - tp[i]
            tp[i] = tc[i]
            tc[i] = t
            s0 += w0[i] * t
            s1 += w1[i] * t
        a0[m], a1[m] = s0, s1
    norm = a0[0]
    for m in range(_M + 1):
        a0[m] /= norm
        a1[m] /= norm


#: geometries of one element a pass of :func:`write` takes (arrays that stay in L1)
_BLOCK = 256


@entry_point(nogil=True)
def write(coef, ub, scale, index, ti, tr, out, lo, hi, col):  # pragma: no cover - compiled
    """Geometries ``lo .. hi - 1`` (element ``index[i]``; angles of length 1 or ``n``) into
    ``out[:, i + col]``, a run of one element (at most :data:`_BLOCK` geometries) at a time in
    passes over arrays (loops on SIMD lanes): both angles' cosines, the Clenshaw recurrences of
    ``t0`` and ``t1`` of each (:func:`_clenshaw`), then the four elements.  One geometry at a
    time the recurrences' latency bound the loop; a fit's rows are long runs of one element (a
    walker's wavelength)."""
    a, b = ti.shape[0] > 1, tr.shape[0] > 1
    xi, xr = np.empty(_BLOCK), np.empty(_BLOCK)
    ai0, ai1, ar0, ar1 = np.empty(_BLOCK), np.empty(_BLOCK), np.empty(_BLOCK), np.empty(_BLOCK)
    b1, b2, d1, d2 = np.empty(_BLOCK), np.empty(_BLOCK), np.empty(_BLOCK), np.empty(_BLOCK)
    low = np.empty(_BLOCK, dtype=np.bool_)
    i = lo
    while i < hi:
        e = index[i]
        L = 1
        while i + L < hi and L < _BLOCK and index[i + L] == e:
            L += 1
        for q in range(L):
            xi[q] = sincos(ti[(i + q) * a])[1]
            xr[q] = sincos(tr[(i + q) * b])[1]
        _clenshaw(coef[e], ub[e], xi, low, L, ai0, ai1, b1, b2, d1, d2)
        _clenshaw(coef[e], ub[e], xr, low, L, ar0, ar1, b1, b2, d1, d2)
        j = i + col
        s = scale[e]
        for r in (2, 3, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15):
            for q in range(L):
                out[r, j + q] = 0.0
        for q in range(L):
            out[0, j + q] = s * ar0[q] * ai0[q]
            out[1, j + q] = s * ar0[q] * ai1[q]
            out[4, j + q] = s * ar1[q] * ai0[q]
            out[5, j + q] = s * ar1[q] * ai1[q]
        i += L


@helper
def _clenshaw(c, u_b, u, low, L, t0, t1, b1, b2, d1, d2):  # pragma: no cover - compiled
    """``t0``, ``t1`` at ``u[:L]`` (overwritten by the panels' variable) of one element's panels
    ``c`` ``(2, 2, K)``: both series at once, each lane's coefficients selected from the two
    panels' (no gather; ``low``: scratch, whether a lane is on the first panel)."""
    K = c.shape[2]
    for q in range(L):
        first = u[q] < u_b
        low[q] = first
        u[q] = 2.0 * u[q] / u_b - 1.0 if first else 2.0 * (u[q] - u_b) / (1.0 - u_b) - 1.0
        b1[q] = b2[q] = d1[q] = d2[q] = 0.0
    for k in range(K - 1, 0, -1):
        p0, q0, p1, q1 = c[0, 0, k], c[1, 0, k], c[0, 1, k], c[1, 1, k]
        for q in range(L):
            x2 = 2.0 * u[q]
            v = x2 * b1[q] - b2[q] + (p0 if low[q] else q0)
            w = x2 * d1[q] - d2[q] + (p1 if low[q] else q1)
            b2[q] = b1[q]
            d2[q] = d1[q]
            b1[q] = v
            d1[q] = w
    p0, q0, p1, q1 = c[0, 0, 0], c[1, 0, 0], c[0, 1, 0], c[1, 1, 0]
    for q in range(L):
        t0[q] = u[q] * b1[q] - b2[q] + (p0 if low[q] else q0)
        t1[q] = u[q] * d1[q] - d2[q] + (p1 if low[q] else q1)


def signatures():
    """``[(entry, argument types)]`` of this module's cached entries, as the model calls them
    (compile-ahead: :func:`scatterbench.models.kernels.warm`)."""
    from numba import types

    f, i = types.float64, types.int64
    a = lambda n: types.Array(f, n, "C")  # noqa: E731
    ro, ix = types.Array(f, 1, "C", readonly=True), types.Array(i, 1, "C")
    return [
        (_moments, (ro, i, ro, ro, ro, ro, ro, a(3), a(3), i, i)),
        (write, (a(4), a(1), a(1), ix, a(1), a(1), a(2), i, i, i)),
    ]


def moments(widths, nodes, rx, rw, ax, aw, cheb):
    """:func:`scatterbench.models.rough_subsurface._moments_numpy` of each slope width of
    ``widths`` (distinct), compiled and spread over the cores: ``(A0, A1)`` ``(K, 2 nodes,
    MOMENTS + 1)``."""
    widths = np.ascontiguousarray(widths, dtype=np.float64)
    widths.setflags(write=False)  # one type: the rules are read-only too
    A0 = np.empty((widths.shape[0], 2 * nodes, _M + 1))
    A1 = np.empty_like(A0)
    spread(_moments, (widths, nodes, rx, rw, ax, aw, cheb, A0, A1), widths.shape[0], 1)
    return A0, A1
