"""The node algebra of :class:`scatterbench.models.DetectorAperture`, compiled: the quadrature nodes'
directions, weights and analyzer rotations (:meth:`scatterbench.models.aperture._Frame.nodes`, the numpy
reference the tests hold this to), and the weighted sum of the inner model's rotated
matrices (:func:`scatterbench.models.aperture._rotate_rows_and_sum`).

Both run node-major (flat index ``k * n + g`` for node ``k`` of geometry ``g``), so the loop
over geometries is innermost: it has no C library call (:func:`~scatterbench.models.kernels.vector_math.atan2`,
the ``sqrt`` intrinsic) and no reduction, and LLVM runs it on SIMD lanes; the per-geometry
cosines and sines are taken once, before it.  The sum adds the nodes in order, as a loop over
``k`` in which every geometry's accumulators are updated at once.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .common import azimuths
from .helper import entry_point, helper
from .threads import spread
from .vector_math import atan2, inverse_binade, sincos, sqrt


@helper
def _double_angle(c, s):
    """``(cos 2x, sin 2x)`` of the angle of ``(c, s)``, both scaled first by the power of two
    that brings the larger near 1 (squares that would underflow near the normal: exact, and
    no division); ``(1, 0)`` for ``c = s = 0``, a node on the normal
    (:func:`scatterbench.models.aperture._double_angle_scaled`)."""
    big = max(abs(c), abs(s))
    on_axis = big == 0.0
    scale = inverse_binade(1.0 if on_axis else big)
    c = 1.0 if on_axis else c * scale
    s = s * scale
    cc, ss = c * c, s * s
    iq = 1.0 / (cc + ss)
    return (cc - ss) * iq, 2.0 * c * s * iq


#: rows of :func:`nodes`' output
TI, THETA, PHI, WEIGHT, COS2, SIN2 = range(6)
ROWS = 6


@entry_point
def nodes(ti, tr, pr, a, b, cos_u, w, out):
    """Every geometry's ``K`` nodes (offsets ``a``, ``b`` along ``p_r``, ``s_r``, ``cos u`` and
    area weights ``w``, each ``(K,)``), for ``n`` geometries ``(ti, tr, pr)``, into the rows
    of ``out`` ``(6, K * n)``, node-major: the incidence, polar angle, azimuth, weight
    (``cos theta dOmega``, zero below the horizon) and the double analyzer angle's cosine
    and sine."""
    n, K = tr.shape[0], a.shape[0]
    # each nominal direction's frame: cos tr, sin tr, p_r's z (as the vector form rounds it)
    # and the azimuth's cosine and sine (polynomials: loops on SIMD lanes)
    frame = np.empty((5, n))
    azimuths(pr, frame[3], frame[4])
    for g in range(n):
        st, ct = sincos(tr[g])
        cp, sp = frame[3, g], frame[4, g]
        frame[0, g], frame[1, g], frame[2, g] = ct, st, st * cp * cp + st * sp * sp
    for k in range(K):
        _node(ti, pr, frame, a[k], b[k], cos_u[k], w[k], out, k * n)


@njit(error_model="numpy", inline="always")
def _node(ti, pr, frame, a, b, cos_u, w, out, o):
    """One node of every geometry into ``out[:, o:o + n]`` (a loop on SIMD lanes)."""
    for g in range(pr.shape[0]):
        ct, st, prz = frame[0, g], frame[1, g], frame[2, g]
        kz = cos_u * ct + a * prz
        h = cos_u * st - a * ct
        weight = w * max(kz, 0.0)
        out[TI, o + g] = ti[g]
        out[THETA, o + g] = atan2(sqrt(h * h + b * b), kz) if weight > 0.0 else 0.0
        out[PHI, o + g] = pr[g] + atan2(b, h)
        out[WEIGHT, o + g] = weight
        out[COS2, o + g], out[SIN2, o + g] = _double_angle(h, -kz * b)


#: geometries per tile of :func:`rotate_sum`: the tile's accumulators (17 rows) stay in L1
TILE = 16


def rotate_sum(m, nodes_out, n, out, start):
    """``sum_k wt R_k M_k / sum_k wt`` into ``out[:, start:start + n]`` for the inner model's
    matrices ``m`` ``(16, K * n)`` at the nodes of :func:`nodes` (their rows ``nodes_out``)
    of ``n`` geometries: ``R_k`` keeps rows 0 and 3 and turns rows 1-2 by
    ``[[c2, s2], [-s2, c2]]``.  A tile of :data:`TILE` geometries at a time, tiles over the
    cores (:func:`~scatterbench.models.kernels.threads.spread`), the nodes added in order."""
    spread(_tiles, (m, nodes_out, n, out, start), (n + TILE - 1) // TILE, 4)


@entry_point(nogil=True)
def _tiles(m, nodes_out, n, out, start, t0, t1):
    """Tiles ``t0 .. t1 - 1`` of :func:`rotate_sum`."""
    for t in range(t0, t1):
        g0 = t * TILE
        _tile(m, nodes_out, n, out, start, g0, min(TILE, n - g0))


@njit(error_model="numpy", inline="always")
def _tile(m, nodes_out, n, out, start, g0, size):
    """:func:`rotate_sum` for geometries ``g0 .. g0 + size - 1``."""
    acc = np.zeros((17, TILE))  # the 16 rows and the weights' sum
    for k in range(m.shape[1] // n):
        o = k * n + g0
        for j in range(size):
            wt, c2, s2 = nodes_out[WEIGHT, o + j], nodes_out[COS2, o + j], nodes_out[SIN2, o + j]
            wc, ws = wt * c2, wt * s2
            for e in range(4):
                acc[e, j] += wt * m[e, o + j]
                acc[12 + e, j] += wt * m[12 + e, o + j]
                m1, m2 = m[4 + e, o + j], m[8 + e, o + j]
                acc[4 + e, j] += wc * m1 + ws * m2
                acc[8 + e, j] += wc * m2 - ws * m1
            acc[16, j] += wt
    for r in range(16):
        for j in range(size):
            out[r, start + g0 + j] = acc[r, j] / acc[16, j]
