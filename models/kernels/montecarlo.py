"""The Monte Carlo of :class:`scatterbench.models.RoughDiffuseBRDF` (seed 003 Sec. 2.5), compiled.

The numpy implementation (:meth:`scatterbench.models.RoughDiffuseBRDF._block`) evaluates every
(geometry, facet pair) entry of a block as arrays and reduces them with ``mean`` and
``std``; here one loop per geometry walks the same facet pairs (the model's, drawn once
from its seed: the random numbers are identical) and accumulates the mean and the spread
as it goes (Welford's update), with no temporaries.  Pairs that cannot connect the two
directions contribute exact zeros in both implementations, so they are counted, not
evaluated.  Where a geometry's estimates are so large that squares would overflow
(``|x| >= safe``), the geometry is walked again with each element scaled by its largest
magnitude, as the numpy path rescales its block.

The facet refraction is :func:`scatterbench.models.kernels.facet.btdf_jones` (the FacetBTDF kernel's);
the tests hold this module to the numpy path within 1e-12 relative to ``M00``.

The rough interface's R-bar (:func:`exit_transmittance`: every pair's exit facet for 512
directions, per walker of a fit) needs only the transmitted fraction of unpolarized light, so
its loop builds no basis and no Jones matrix (:func:`_exit_t00`) and runs on SIMD lanes over the
directions: 61 -> 9 ms for 2000 pairs on one thread (``python benchmarks/ptfe_batch_cost.py``
gives what that does to a fit's batch).  The entry facets depend on the incidence alone: a
range of geometries computes them once per run of equal incidences (:func:`_entries`), which a
measurement's rows make long (a PTFE batch's per-geometry Monte Carlo 0.339 -> 0.234 s, the same
script, 76 rows at six incidences).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .common import hg_density, mueller16
from .facet import btdf_jones, cross3, dot3, transmission_factors
from .threads import spread

__all__ = ["estimate", "exit_transmittance"]

#: Mueller elements a real Jones matrix can reach (the others couple V and vanish here)
_REACHED = np.array([0, 1, 2, 4, 5, 6, 8, 9, 10, 15])
#: the basis returned for a ray that does not exist (never read)
_NO_BASIS = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


@njit(forceinline=True)
def _ray_basis(k):
    """``(s, p)`` of ray ``k``: ``s = unit(z x k)``, ``+y`` along the z axis
    (:func:`scatterbench.models.facet_btdf.ray_basis`)."""
    norm = math.sqrt(k[1] * k[1] + k[0] * k[0])
    if norm <= 1e-15:
        s = (0.0, 1.0, 0.0)
    else:
        s = (-k[1] / norm, k[0] / norm, 0.0)
    return s, cross3(k, s)


@njit(forceinline=True)
def _entry(k_i, e_i, ci, si, n_i, zx, m, n):
    """The incident ray through facet ``m`` (slope x ``zx``): ``(weight, k1, basis of k1,
    Jones, flux factor)``; weight 0 where the facet is not struck or the ray does not go
    down."""
    w = max(ci - si * zx, 0.0) / n_i
    eta = 1.0 / n
    c = -dot3(k_i, m)
    ct = math.sqrt(max(1.0 - eta * eta * (1.0 - c * c), 0.0))
    f = eta * c - ct
    k1 = (eta * k_i[0] + f * m[0], eta * k_i[1] + f * m[1], eta * k_i[2] + f * m[2])
    if not (w > 0.0 and c > 0.0 and -k1[2] > 0.0):
        return 0.0, k1, _NO_BASIS, (0.0, 0.0, 0.0, 0.0), 0.0
    e1 = _ray_basis(k1)
    ss, ps, sp, pp, c_in, c_out = btdf_jones(k_i, k1, m, n, e_i, e1)
    return w, k1, e1, (ss, ps, sp, pp), n * c_out / (c_in if c_in > 0.0 else 1.0)


@njit(error_model="numpy", forceinline=True)
def _leaving(k_r, n_r, zx, zy, m, n):
    """The internal ray ``k2`` that leaves along ``k_r`` through facet ``m`` (slopes ``zx, zy``):
    ``(weight, cos(k_r, m), k2, whether it exists)``."""
    w = max(k_r[2] + k_r[0] * zx + k_r[1] * zy, 0.0) / n_r
    eta = 1.0 / n
    c = dot3(k_r, m)
    ct = math.sqrt(max(1.0 - eta * eta * (1.0 - c * c), 0.0))
    f = eta * c - ct
    k2 = (eta * k_r[0] - f * m[0], eta * k_r[1] - f * m[1], eta * k_r[2] - f * m[2])
    return w, c, k2, w > 0.0 and c > 0.0 and k2[2] > 0.0


@njit(forceinline=True)
def _exit(k_r, e_r, n_r, zx, zy, m, n):
    """The internal ray that leaves along ``k_r`` through facet ``m`` (slopes ``zx, zy``):
    ``(weight, k2, basis of k2, Jones, flux factor)``, weight 0 where no such ray exists."""
    w, _, k2, live = _leaving(k_r, n_r, zx, zy, m, n)
    if not live:
        return 0.0, k2, _NO_BASIS, (0.0, 0.0, 0.0, 0.0), 0.0
    e2 = _ray_basis(k2)
    ss, ps, sp, pp, c_in, c_out = btdf_jones(k2, k_r, (-m[0], -m[1], -m[2]), 1.0 / n, e2, e_r)
    return w, k2, e2, (ss, ps, sp, pp), c_out / (n * (c_in if c_in > 0.0 else 1.0))


@njit(forceinline=True)
def _volume(x, k1, e1, ji, k2, e2, jo, base, depth, prm):
    """One live pair's Mueller estimate into ``x``: the totally diffuse term and the single
    scattering (depolarizing: a scalar; polarized: the Jones chain of Eq. 4-5)."""
    diffuse, single, g, polarized = prm[1], prm[2], prm[3], prm[4] != 0.0
    cos_scat = dot3(k1, k2)
    dens = hg_density(g, cos_scat)
    rows = (
        0.5 * (ji[0] * ji[0] + ji[1] * ji[1] + ji[2] * ji[2] + ji[3] * ji[3]),
        0.5 * (ji[0] * ji[0] - ji[1] * ji[1] + ji[2] * ji[2] - ji[3] * ji[3]),
        ji[0] * ji[1] + ji[2] * ji[3],
    )
    cols = (
        0.5 * (jo[0] * jo[0] + jo[1] * jo[1] + jo[2] * jo[2] + jo[3] * jo[3]),
        0.5 * (jo[0] * jo[0] + jo[1] * jo[1] - jo[2] * jo[2] - jo[3] * jo[3]),
        jo[0] * jo[2] + jo[3] * jo[1],
    )
    scal = diffuse * base
    if not polarized:
        scal = scal + single * base * dens * depth
    x[:] = 0.0
    for a in range(3):
        ca = cols[a] * scal
        for q in range(3):
            x[4 * a + q] = ca * rows[q]
    if polarized and single > 0.0:
        (s1, p1), (s2, p2) = e1, e2
        ph = ((dot3(s2, s1), dot3(s2, p1)), (dot3(p2, s1), dot3(p2, p1)))
        t = (
            (ph[0][0] * ji[0] + ph[0][1] * ji[2], ph[0][0] * ji[1] + ph[0][1] * ji[3]),
            (ph[1][0] * ji[0] + ph[1][1] * ji[2], ph[1][0] * ji[1] + ph[1][1] * ji[3]),
        )
        root = math.sqrt(single * base * dens * depth * 2.0 / (1.0 + cos_scat * cos_scat))
        z = 0.0  # a real Jones matrix: its Mueller elements outside _REACHED are zero
        m = mueller16(
            (jo[0] * t[0][0] + jo[1] * t[1][0]) * root,
            z,
            (jo[0] * t[0][1] + jo[1] * t[1][1]) * root,
            z,
            (jo[2] * t[0][0] + jo[3] * t[1][0]) * root,
            z,
            (jo[2] * t[0][1] + jo[3] * t[1][1]) * root,
            z,
        )
        for e in _REACHED:
            x[e] += m[e]


#: rows of the entry table (:func:`_entries`): weight, k1 (3), k1's s and p (3 each), Jones (4), flux
_ENTRY_ROWS = 15


@njit(inline="always")
def _entries(ti, n_i, z, m, n, ent):
    """Every pair's entry facet for the incidence ``ti`` (:func:`_entry`) into the columns of
    ``ent``: its weight (row 0; the other rows unset where it is 0), the internal ray ``k1``, its
    basis, the Jones matrix and the flux factor.  They depend on the incidence alone, which the
    geometries of a measurement share (a few incidences, many scattering directions)."""
    ci, si = math.cos(ti), math.sin(ti)
    k_i = (si, 0.0, -ci)
    s_i = (0.0, 1.0, 0.0)
    e_i = (s_i, cross3(k_i, s_i))
    for j in range(z.shape[1]):
        w1, k1, e1, ji, f_in = _entry(k_i, e_i, ci, si, n_i, z[0, j], (m[0, j], m[1, j], m[2, j]), n)
        ent[0, j] = w1
        if w1 == 0.0:
            continue
        ent[1, j], ent[2, j], ent[3, j] = k1
        ent[4, j], ent[5, j], ent[6, j] = e1[0]
        ent[7, j], ent[8, j], ent[9, j] = e1[1]
        ent[10, j], ent[11, j], ent[12, j], ent[13, j] = ji
        ent[14, j] = f_in


@njit
def _walk(geo, ent, z, m, prm, inv_scale, x, mean, m2, peak):
    """Welford's running mean and sum of squared deviations (``mean``, ``m2``) of the live
    pairs' estimates times ``inv_scale``, and their largest magnitudes (``peak``); returns
    the number of live pairs.  The entry facets are the table ``ent`` (:func:`_entries`)."""
    k_r, e_r, n_r = geo
    n = prm[0]
    live = 0
    mean[:] = 0.0
    m2[:] = 0.0
    peak[:] = 0.0
    for j in range(z.shape[1]):
        w1 = ent[0, j]
        if w1 == 0.0:
            continue
        mj = (m[3, j], m[4, j], m[5, j])
        w2, k2, e2, jo, f_out = _exit(k_r, e_r, n_r, z[2, j], z[3, j], mj, n)
        if w2 == 0.0:
            continue
        k1 = (ent[1, j], ent[2, j], ent[3, j])
        e1 = ((ent[4, j], ent[5, j], ent[6, j]), (ent[7, j], ent[8, j], ent[9, j]))
        ji = (ent[10, j], ent[11, j], ent[12, j], ent[13, j])
        base = w1 * w2 * ent[14, j] * f_out / (n * n)
        _volume(x, k1, e1, ji, k2, e2, jo, base, 1.0 / (-k1[2] + k2[2]), prm)
        live += 1
        inv = 1.0 / live
        for e in _REACHED:
            v = x[e] * inv_scale[e]
            d = v - mean[e]
            mean[e] += d * inv
            m2[e] += d * (v - mean[e])
            peak[e] = max(peak[e], abs(v))
    return live


@njit(inline="always")
def _geometry(tr, pr, n_r, ent, z, m, prm, safe, mean, err, col):
    """Mean and standard error of one geometry into ``mean[:, col]``, ``err[:, col]``, its
    incidence's entry facets the table ``ent``."""
    cr, sr, cp, sp = math.cos(tr), math.sin(tr), math.cos(pr), math.sin(pr)
    k_r = (sr * cp, sr * sp, cr)
    s_r = (-sp, cp, 0.0)
    geo = (k_r, (s_r, cross3(k_r, s_r)), n_r)
    x, mu, m2, peak, scale = np.empty(16), np.empty(16), np.empty(16), np.empty(16), np.ones(16)
    live = _walk(geo, ent, z, m, prm, scale, x, mu, m2, peak)
    if peak.max() >= safe:
        # squares of such values overflow: walk again with each element over its largest
        for e in range(16):
            scale[e] = peak[e] if peak[e] > 0.0 else 1.0
        live = _walk(geo, ent, z, m, prm, 1.0 / scale, x, mu, m2, peak)
    pairs = z.shape[1]
    dead = pairs - live
    for e in _REACHED:
        # the dead pairs' exact zeros joined to the live ones (Chan et al.'s pairwise update)
        total = mu[e] * live / pairs
        ss = m2[e] + mu[e] * mu[e] * live * dead / pairs
        mean[e, col] = total * scale[e]
        err[e, col] = math.sqrt(ss / (pairs - 1)) / math.sqrt(pairs) * scale[e]


@njit(cache=True, nogil=True)
def _range(ti, tr, pr, n_i, n_r, z, m, prm, safe, mean, err, lo, hi):
    """Geometries ``lo .. hi - 1`` (a range of :func:`~scatterbench.models.kernels.threads.spread`),
    the entry facets computed once per run of geometries with the same incidence (and
    normalization): the same numbers as for each geometry, in a fraction of the time where the
    geometries come by incidence, as a measurement's do."""
    ent = np.empty((_ENTRY_ROWS, z.shape[1]))
    have, last_t, last_n = False, 0.0, 0.0
    for i in range(lo, hi):
        mean[:, i] = 0.0
        err[:, i] = 0.0
        if not (ti[i] < 0.5 * math.pi and tr[i] < 0.5 * math.pi):
            continue
        # the same bits (a -0.0 incidence gives -0.0 sines: the same values, other zeros)
        same = ti[i] == last_t and math.copysign(1.0, ti[i]) == math.copysign(1.0, last_t)
        if not (have and same and n_i[i] == last_n):
            _entries(ti[i], n_i[i], z, m, prm[0], ent)
            have, last_t, last_n = True, ti[i], n_i[i]
        _geometry(tr[i], pr[i], n_r[i], ent, z, m, prm, safe, mean, err, i)


def estimate(ti, tr, pr, n_i, n_r, z, m, prm, safe, parallel):
    """Mean and standard error ``(16, n)`` of the volume terms at flat angles ``(n,)``.

    Parameters
    ----------
    ti, tr, pr : ndarray
        Flat float64 angles, one per geometry.
    n_i, n_r : ndarray
        The exact normalizations ``N_k`` of the incident and scattered directions (1 where
        ``N_k`` vanishes), one per geometry.
    z : ndarray
        ``(4, pairs)``: slopes x, y of the entry facets, then of the exit facets.
    m : ndarray
        ``(6, pairs)``: the unit normals of the entry facets, then of the exit facets.
    prm : ndarray
        ``(n, diffuse factor rho / pi / (1 - rho R-bar), single weight, g, polarized)``.
    safe : float
        The magnitude from which a geometry's estimates are rescaled before squaring.
    parallel : bool
        Spread the geometries over the cores.
    """
    # copies, writable and contiguous: a read-only array (the conformance kit's inputs) is
    # another argument type, which compiled the loop again; a copy, not np.require, which
    # reads the writeable flag of a broadcast view (numpy's FutureWarning); n floats beside
    # the walk over every facet pair of each geometry
    ti, tr, pr, n_i, n_r = (np.array(a, dtype=np.float64, order="C") for a in (ti, tr, pr, n_i, n_r))
    mean = np.empty((16, ti.size))
    err = np.empty((16, ti.size))
    args = (ti, tr, pr, n_i, n_r, z, m, prm, float(safe), mean, err)
    spread(
        _range, args, ti.size, 1 if parallel else ti.size
    )  # a geometry walks every pair: one is work enough
    return mean, err


def exit_transmittance(tr, pr, n_r, z, m, n):
    """``<w_r M_out[0, 0]>`` over the exit facets for flat directions ``(tr, pr)``
    (:meth:`scatterbench.models.RoughDiffuseBRDF._exit_transmittance`), the directions over the
    cores in ranges of :data:`EXIT_GRAIN`."""
    out = np.empty(tr.size)
    spread(_exit_range, (tr, pr, n_r, z, m, n, out), tr.size, EXIT_GRAIN)
    return out


#: directions per range of :func:`_exit_range` at least: its inner loop runs over them on SIMD lanes
EXIT_GRAIN = 32


@njit(error_model="numpy", forceinline=True)
def _exit_t00(k_r, n_r, zx, zy, m, n):
    """``w_r M_out[0, 0]`` of one exit facet (slopes ``zx, zy``, unit normal ``m``) for the
    direction ``k_r``, without a branch the compiler keeps (the direction loop around it
    vectorizes).  ``M_out[0, 0]`` is half the squared Frobenius norm of the facet's Jones
    matrix (:func:`_exit`), which no orthonormal choice of the rays' bases changes:
    ``(t_s^2 + t_p^2) / 2`` with :func:`~scatterbench.models.kernels.facet.btdf_jones`'s
    ``t_s`` and ``t_p = t_s + delta sin^2`` (its dyadic maps the p vector of the entering ray to
    that of the leaving one, scaled by ``t_p``, and s to s by ``t_s``), so neither basis is
    built.  Zero beyond the critical angle, as there ``t_s = delta = 0``."""
    w, c, k2, live = _leaving(k_r, n_r, zx, zy, m, n)
    c_in = min(max(dot3(k2, m), 0.0), 1.0)
    ts, delta = transmission_factors(c_in, 1.0 / n)
    tp = ts + delta * (1.0 - c_in * c_in)
    flux = min(max(c, 0.0), 1.0) / (n * (c_in if c_in > 0.0 else 1.0))
    return 0.5 * (ts * ts + tp * tp) * flux * w if live else 0.0


@njit(cache=True, nogil=True, error_model="numpy")
def _exit_range(tr, pr, n_r, z, m, n, out, lo, hi):
    """:func:`exit_transmittance` of the directions ``lo .. hi - 1`` into ``out``: the facets
    outer, the directions inner (a loop of selects over contiguous arrays that the compiler
    vectorizes), each direction's sum taken in the facets' order."""
    g = hi - lo
    cr, ax, ay, acc = np.empty(g), np.empty(g), np.empty(g), np.zeros(g)
    for i in range(g):
        s = math.sin(tr[lo + i])
        cr[i], ax[i], ay[i] = math.cos(tr[lo + i]), s * math.cos(pr[lo + i]), s * math.sin(pr[lo + i])
    nr = n_r[lo:hi]
    for j in range(z.shape[1]):
        zx, zy, mj = z[2, j], z[3, j], (m[3, j], m[4, j], m[5, j])
        for i in range(g):
            acc[i] += _exit_t00((ax[i], ay[i], cr[i]), nr[i], zx, zy, mj, n)
    for i in range(g):
        out[lo + i] = acc[i] / z.shape[1]
