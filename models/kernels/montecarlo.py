"""The Monte Carlo of :class:`scatterbench.models.RoughDiffuseBRDF` (seed 003 Sec. 2.5), compiled.

The numpy implementation (:meth:`scatterbench.models.RoughDiffuseBRDF._block`) evaluates every
(geometry, facet pair) entry of a block as arrays and reduces them with ``mean`` and
``std``; here each geometry walks the same facet pairs (the model's, drawn once from its
seed: the random numbers are identical) and accumulates the mean and the spread as it goes
(Welford's update), with no temporaries.  Pairs that cannot connect the two directions
contribute exact zeros in both implementations, so they are counted, not evaluated.  Where a
geometry's estimates are so large that squares would overflow (``|x| >= safe``), the geometry
is walked again with each element scaled by its largest magnitude, as the numpy path
rescales its block.

The geometries of one incidence walk together, :data:`_LANES` at a time (:func:`_walk`): the
pairs outer, the geometries inner on SIMD lanes, each geometry's updates in the pairs' order,
so that every geometry gets the bits it gets alone.  NIST's 1824 PTFE rows at 532 nm, 2000
pairs, one thread: 440.9 -> 148.3 ms (an ad hoc script timing ``_estimate`` of both trees in
turn, the same bits); its compilation 7.0 -> 8.1 s of CPU.

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
from .helper import entry_point, helper
from .threads import spread

__all__ = ["estimate", "exit_transmittance"]

#: Mueller elements a real Jones matrix can reach (the others couple V and vanish here)
_REACHED = np.array([0, 1, 2, 4, 5, 6, 8, 9, 10, 15])
#: the basis returned for a ray that does not exist (never read)
_NO_BASIS = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


@helper
def _ray_basis(k):
    """``(s, p)`` of ray ``k``: ``s = unit(z x k)``, ``+y`` along the z axis
    (:func:`scatterbench.models.facet_btdf.ray_basis`); selects, not a branch, so that a loop
    over rays (:func:`_walk`) stays on SIMD lanes."""
    norm = math.sqrt(k[1] * k[1] + k[0] * k[0])
    far = norm > 1e-15
    s = ((-k[1] / norm) if far else 0.0, (k[0] / norm) if far else 1.0, 0.0)
    return s, cross3(k, s)


@helper
def _refracted(k, m, eta):
    """``(cos, k_t)``: the cosine ``-k . m`` of ray ``k`` striking the facet of unit normal ``m``
    (from the side ``m`` points to) and the ray refracted through it at relative index ``eta``
    (``n_incident / n_transmitted``; its length below 1 beyond the critical angle, whose rays
    the callers drop)."""
    c = -dot3(k, m)
    ct = math.sqrt(max(1.0 - eta * eta * (1.0 - c * c), 0.0))
    f = eta * c - ct
    return c, (eta * k[0] + f * m[0], eta * k[1] + f * m[1], eta * k[2] + f * m[2])


@helper
def _entry(k_i, e_i, ci, si, n_i, zx, m, n):
    """The incident ray through facet ``m`` (slope x ``zx``): ``(weight, k1, basis of k1,
    Jones, flux factor)``; weight 0 where the facet is not struck or the ray does not go
    down."""
    w = max(ci - si * zx, 0.0) / n_i
    c, k1 = _refracted(k_i, m, 1.0 / n)
    if not (w > 0.0 and c > 0.0 and -k1[2] > 0.0):
        return 0.0, k1, _NO_BASIS, (0.0, 0.0, 0.0, 0.0), 0.0
    e1 = _ray_basis(k1)
    ss, ps, sp, pp, c_in, c_out = btdf_jones(k_i, k1, m, n, e_i, e1)
    return w, k1, e1, (ss, ps, sp, pp), n * c_out / (c_in if c_in > 0.0 else 1.0)


@helper
def _leaving(k_r, n_r, zx, zy, m, n):
    """The internal ray ``k2`` that leaves along ``k_r`` through facet ``m`` (slopes ``zx, zy``):
    ``(weight, cos(k_r, m), k2, whether it exists)``."""
    w = max(k_r[2] + k_r[0] * zx + k_r[1] * zy, 0.0) / n_r
    # the reversed ray: the one that arrives along -k_r, refracted, reversed (negations are exact)
    c, back = _refracted((-k_r[0], -k_r[1], -k_r[2]), m, 1.0 / n)
    k2 = (-back[0], -back[1], -back[2])
    return w, c, k2, w > 0.0 and c > 0.0 and k2[2] > 0.0


@helper
def _exit(k_r, e_r, n_r, zx, zy, m, n):
    """The internal ray that leaves along ``k_r`` through facet ``m`` (slopes ``zx, zy``):
    ``(whether it exists, weight, k2, basis of k2, Jones, flux factor)``, computed either way
    (the loop over directions around it stays on SIMD lanes; the caller selects)."""
    w, _, k2, live = _leaving(k_r, n_r, zx, zy, m, n)
    e2 = _ray_basis(k2)
    ss, ps, sp, pp, c_in, c_out = btdf_jones(k2, k_r, (-m[0], -m[1], -m[2]), 1.0 / n, e2, e_r)
    return live, w, k2, e2, (ss, ps, sp, pp), c_out / (n * (c_in if c_in > 0.0 else 1.0))


@helper
def _volume(k1, e1, ji, k2, e2, jo, base, depth, prm):
    """One live pair's Mueller estimate: its :data:`_REACHED` elements, in that order (the
    others are zero), the totally diffuse term and the single scattering (depolarizing: a
    scalar; polarized: the Jones chain of Eq. 4-5)."""
    diffuse, single, g, polarized = prm[1], prm[2], prm[3], prm[4] != 0.0
    cos_scat = dot3(k1, k2)
    dens = hg_density(g, cos_scat)
    r0 = 0.5 * (ji[0] * ji[0] + ji[1] * ji[1] + ji[2] * ji[2] + ji[3] * ji[3])
    r1 = 0.5 * (ji[0] * ji[0] - ji[1] * ji[1] + ji[2] * ji[2] - ji[3] * ji[3])
    r2 = ji[0] * ji[1] + ji[2] * ji[3]
    scal = diffuse * base
    if not polarized:
        scal = scal + single * base * dens * depth
    c0 = 0.5 * (jo[0] * jo[0] + jo[1] * jo[1] + jo[2] * jo[2] + jo[3] * jo[3]) * scal
    c1 = 0.5 * (jo[0] * jo[0] + jo[1] * jo[1] - jo[2] * jo[2] - jo[3] * jo[3]) * scal
    c2 = (jo[0] * jo[2] + jo[3] * jo[1]) * scal
    x = (c0 * r0, c0 * r1, c0 * r2, c1 * r0, c1 * r1, c1 * r2, c2 * r0, c2 * r1, c2 * r2, 0.0)
    if not (polarized and single > 0.0):
        return x
    (s1, p1), (s2, p2) = e1, e2
    ph = ((dot3(s2, s1), dot3(s2, p1)), (dot3(p2, s1), dot3(p2, p1)))
    t = (
        (ph[0][0] * ji[0] + ph[0][1] * ji[2], ph[0][0] * ji[1] + ph[0][1] * ji[3]),
        (ph[1][0] * ji[0] + ph[1][1] * ji[2], ph[1][0] * ji[1] + ph[1][1] * ji[3]),
    )
    root = math.sqrt(single * base * dens * depth * 2.0 / (1.0 + cos_scat * cos_scat))
    z = 0.0  # a real Jones matrix: its Mueller elements outside _REACHED are zero
    p = mueller16(
        (jo[0] * t[0][0] + jo[1] * t[1][0]) * root,
        z,
        (jo[0] * t[0][1] + jo[1] * t[1][1]) * root,
        z,
        (jo[2] * t[0][0] + jo[3] * t[1][0]) * root,
        z,
        (jo[2] * t[0][1] + jo[3] * t[1][1]) * root,
        z,
    )
    return (x[0] + p[0], x[1] + p[1], x[2] + p[2], x[3] + p[4], x[4] + p[5], x[5] + p[6],
            x[6] + p[8], x[7] + p[9], x[8] + p[10], x[9] + p[15])  # fmt: skip


#: rows of the entry table (:func:`_entries`): weight, k1 (3), k1's s and p (3 each), Jones (4), flux
_ENTRY_ROWS = 15
#: geometries the walk takes at once on SIMD lanes (:func:`_walk`): its accumulators, 31 rows of
#: this many doubles, stay in the L1 cache
_LANES = 64


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


@helper
def _welford(acc, q, g, v, inv, live):
    """Welford's update of element ``q`` of geometry ``g`` (rows ``q``, ``10 + q``, ``20 + q`` of
    ``acc``: mean, sum of squared deviations, largest magnitude) by ``v`` where ``live``, as
    selects: the loop over geometries stays on SIMD lanes."""
    # the other rows as offsets of the mean's: computed each from q, as ``(10 + q) * _LANES + g``,
    # they kept the walk off the SIMD lanes once one copy of this helper served every q
    # (kernels.helper; with a copy per literal q they did not)
    a = q * _LANES + g
    b, c = a + 10 * _LANES, a + 20 * _LANES
    mu, m2, peak = acc[a], acc[b], acc[c]
    d = v - mu
    mu_new = mu + d * inv
    acc[a] = mu_new if live else mu
    acc[b] = (m2 + d * (v - mu_new)) if live else m2
    acc[c] = max(peak, abs(v)) if live else peak


@helper(forceinline=None)
def _walk(dirs, count, ent, z, m, prm, inv_scale, acc):
    """Welford's running mean and sum of squared deviations of the live pairs' estimates times
    ``inv_scale`` (row ``q``: element ``q`` of :data:`_REACHED`), their largest magnitudes, and
    the number of live pairs, into ``acc`` (rows 0-9, 10-19, 20-29, 30) for the ``count``
    directions ``dirs`` (:func:`_block`).  The pairs outer, the geometries inner: each
    geometry's updates come in the pairs' order, as one geometry's walk would make them, and
    the inner loop runs on SIMD lanes (selects for the dead pairs' skips).  Every table is flat,
    row ``r`` of geometry ``g`` at ``r * _LANES + g``: with a stride the compiler knows, it
    proves the rows apart (with numpy's 2-D indexing it did not, and kept the loop scalar).
    The entry facets are the table ``ent`` (:func:`_entries`)."""
    n, L = prm[0], _LANES
    for k in range(31 * L):
        acc[k] = 0.0
    for j in range(z.shape[1]):
        w1 = ent[0, j]
        if w1 == 0.0:
            continue
        zx, zy, mj = z[2, j], z[3, j], (m[3, j], m[4, j], m[5, j])
        k1 = (ent[1, j], ent[2, j], ent[3, j])
        e1 = ((ent[4, j], ent[5, j], ent[6, j]), (ent[7, j], ent[8, j], ent[9, j]))
        ji = (ent[10, j], ent[11, j], ent[12, j], ent[13, j])
        f_in = ent[14, j]
        for g in range(count):
            k_r = (dirs[g], dirs[L + g], dirs[2 * L + g])
            e_r = (
                (dirs[3 * L + g], dirs[4 * L + g], 0.0),
                (dirs[5 * L + g], dirs[6 * L + g], dirs[7 * L + g]),
            )
            ok, w2, k2, e2, jo, f_out = _exit(k_r, e_r, dirs[8 * L + g], zx, zy, mj, n)
            base = w1 * w2 * f_in * f_out / (n * n)
            x = _volume(k1, e1, ji, k2, e2, jo, base, 1.0 / (-k1[2] + k2[2]), prm)
            live = acc[30 * L + g] + 1.0 if ok else acc[30 * L + g]
            acc[30 * L + g] = live
            inv = 1.0 / live
            # written out: a loop over the tuple's elements kept the geometries' loop off the lanes
            _welford(acc, 0, g, x[0] * inv_scale[g], inv, ok)
            _welford(acc, 1, g, x[1] * inv_scale[L + g], inv, ok)
            _welford(acc, 2, g, x[2] * inv_scale[2 * L + g], inv, ok)
            _welford(acc, 3, g, x[3] * inv_scale[3 * L + g], inv, ok)
            _welford(acc, 4, g, x[4] * inv_scale[4 * L + g], inv, ok)
            _welford(acc, 5, g, x[5] * inv_scale[5 * L + g], inv, ok)
            _welford(acc, 6, g, x[6] * inv_scale[6 * L + g], inv, ok)
            _welford(acc, 7, g, x[7] * inv_scale[7 * L + g], inv, ok)
            _welford(acc, 8, g, x[8] * inv_scale[8 * L + g], inv, ok)
            _welford(acc, 9, g, x[9] * inv_scale[9 * L + g], inv, ok)


@njit(inline="always")
def _finish(acc, g, scale, pairs, mean, err, col):
    """Mean and standard error of geometry ``g`` of ``acc`` (:func:`_walk`) into ``mean[:, col]``,
    ``err[:, col]``, scaled back by ``scale`` (row ``q``, as ``acc``): the dead pairs' exact
    zeros joined to the live ones (Chan et al.'s pairwise update)."""
    L = _LANES
    live = acc[30 * L + g]
    dead = pairs - live
    for q in range(10):
        e, mu, s = _REACHED[q], acc[q * L + g], scale[q * L + g]
        total = mu * live / pairs
        ss = acc[(10 + q) * L + g] + mu * mu * live * dead / pairs
        mean[e, col] = total * s
        err[e, col] = math.sqrt(ss / (pairs - 1)) / math.sqrt(pairs) * s


@njit(inline="always")
def _block(cols, count, tr, pr, n_r, ent, z, m, prm, safe, mean, err, work):
    """Geometries ``cols[:count]`` (at most :data:`_LANES`, one incidence: the entry table
    ``ent``) walked together (:func:`_walk`); those whose estimates are so large that squares
    would overflow walked again with each element over its largest magnitude.  ``work``: the
    tables (:func:`_tables`).  Loops, not numpy's slice assignments, fill and copy the tables:
    those took the kernel's compilation from 8 to 14.6 s of CPU (ad hoc, an empty cache)."""
    dirs, acc, scale, inv = work
    L = _LANES
    for g in range(count):
        i = cols[g]
        cr, sr, cp, sp = math.cos(tr[i]), math.sin(tr[i]), math.cos(pr[i]), math.sin(pr[i])
        k_r = (sr * cp, sr * sp, cr)
        p_r = cross3(k_r, (-sp, cp, 0.0))
        dirs[g], dirs[L + g], dirs[2 * L + g] = k_r
        dirs[3 * L + g], dirs[4 * L + g] = -sp, cp
        dirs[5 * L + g], dirs[6 * L + g], dirs[7 * L + g] = p_r
        dirs[8 * L + g] = n_r[i]
    for k in range(10 * L):
        scale[k] = 1.0
    for rescaled in range(2):
        _walk(dirs, count, ent, z, m, prm, inv if rescaled else scale, acc)
        big = 0
        for g in range(count):
            large = False
            for q in range(10):
                large = large or acc[(20 + q) * L + g] >= safe
            if rescaled or not large:
                _finish(acc, g, scale, z.shape[1], mean, err, cols[g])
                continue
            # squares of such values overflow: lane ``big`` takes it, each element over its largest
            for r in range(9):
                dirs[r * L + big] = dirs[r * L + g]
            cols[big] = cols[g]
            for q in range(10):
                peak = acc[(20 + q) * L + g]
                scale[q * L + big] = peak if peak > 0.0 else 1.0
                inv[q * L + big] = 1.0 / scale[q * L + big]
            big += 1
        if not big:
            return
        count = big


@njit(inline="always")
def _tables():
    """A block's flat tables (:func:`_block`): its directions (k_r, its s (x, y) and p, N_r),
    the accumulators (:func:`_walk`), the scales and their reciprocals."""
    L = _LANES
    return np.empty(9 * L), np.empty(31 * L), np.empty(10 * L), np.empty(10 * L)


@entry_point(nogil=True)
def _range(ti, tr, pr, n_i, n_r, z, m, prm, safe, mean, err, lo, hi):
    """Geometries ``lo .. hi - 1`` (a range of :func:`~scatterbench.models.kernels.threads.spread`),
    the entry facets computed once per run of geometries with the same incidence (and
    normalization): the same numbers as for each geometry, in a fraction of the time where the
    geometries come by incidence, as a measurement's do; such a run's geometries walked
    :data:`_LANES` at a time (:func:`_block`)."""
    ent = np.empty((_ENTRY_ROWS, z.shape[1]))
    work, cols = _tables(), np.empty(_LANES, dtype=np.int64)
    have, last_t, last_n, i = False, 0.0, 0.0, lo
    while i < hi:  # a block of one incidence's geometries at a time (one call: numba inlines it)
        count = 0
        while i < hi and count < _LANES:
            mean[:, i] = 0.0
            err[:, i] = 0.0
            if ti[i] < 0.5 * math.pi and tr[i] < 0.5 * math.pi:
                # the same bits (a -0.0 incidence gives -0.0 sines: the same values, other zeros)
                same = ti[i] == last_t and math.copysign(1.0, ti[i]) == math.copysign(1.0, last_t)
                if not (have and same and n_i[i] == last_n):
                    if count:
                        break  # walk the block first: geometry i starts the next
                    _entries(ti[i], n_i[i], z, m, prm[0], ent)
                    have, last_t, last_n = True, ti[i], n_i[i]
                cols[count] = i
                count += 1
            i += 1
        if count:
            _block(cols, count, tr, pr, n_r, ent, z, m, prm, safe, mean, err, work)


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


@helper
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


@entry_point(nogil=True)
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
