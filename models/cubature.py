"""Adaptive cubature over unit squares, many integrals at once (vectorized).

Each integral (a *row*) is the sum of integrals over *cells*, each cell parametrized by
the unit square ``(u, v) in [0, 1]^2`` (the caller maps it to its domain and includes the
Jacobian in the integrand).  Every region, a rectangle of a cell, is integrated with the
Genz-Malik rule of degree 7 (17 points in two dimensions) and its embedded rule of degree 5
(Genz & Malik, J. Comput. Appl. Math. 6, 295 (1980)).  A region's error bound is their
difference (the error of the degree-5 rule: the degree-7 value returned is usually far more
accurate) or, once it comes from a split, half the change the split made to its parent's
value if that is larger: two rules can straddle a kink alike and agree by accident, a split
cannot hide it.  Rows whose summed bound exceeds their budget split their worst regions (above
their fair share of the budget and above :data:`WORST` of the row's worst) in two, across the
axis along which the fourth difference is larger, until each row meets its budget or reaches
``max_regions``.  Only the new regions are evaluated; rows that are done cost nothing more.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

__all__ = ["GM_POINTS", "Cubature", "adaptive"]


def _genz_malik():
    """Points on ``[-1, 1]^2`` and the weights (summing to 1) of the degree-7 and embedded
    degree-5 rules; the fourth-difference points are indices 1-8."""
    l2, l3, l5 = math.sqrt(9 / 70), math.sqrt(9 / 10), math.sqrt(9 / 19)
    pts = [(0.0, 0.0)]
    pts += [(l2, 0.0), (-l2, 0.0), (l3, 0.0), (-l3, 0.0)]  # along u
    pts += [(0.0, l2), (0.0, -l2), (0.0, l3), (0.0, -l3)]  # along v
    pts += [(a * l3, b * l3) for a in (1, -1) for b in (1, -1)]  # lambda_4 = lambda_3 in 2-D
    pts += [(a * l5, b * l5) for a in (1, -1) for b in (1, -1)]
    w7 = [-3816 / 19683] + [980 / 6561, 980 / 6561, 1020 / 19683, 1020 / 19683] * 2
    w7 += [200 / 19683] * 4 + [6859 / 19683 / 4] * 4
    w5 = [-971 / 729] + [245 / 486, 245 / 486, 65 / 1458, 65 / 1458] * 2 + [25 / 729] * 4 + [0.0] * 4
    p = np.array(pts)
    return 0.5 * (p[:, 0] + 1.0), 0.5 * (p[:, 1] + 1.0), np.array(w7), np.array(w5)


GM_U, GM_V, _W7, _W5 = _genz_malik()
#: a region is split when its error exceeds this fraction of its row's worst region's
WORST = 0.25
#: points per region
GM_POINTS = GM_U.size


class AccuracyWarning(RuntimeWarning):
    """A refinement stopped at its cap before its estimated error met the tolerance (the
    adaptive quadratures of :class:`scatterbench.models.PointSourceBRDF` and of
    :func:`scatterbench.models.smooth_interface.film_hemispherical_reflectance`)."""


@dataclass
class Cubature:
    """The result of :func:`adaptive`: ``value`` ``(k + 1, n_rows)`` the integrals, ``error``
    ``(n_rows,)`` the summed regional error estimates (the units of ``norm``), ``regions``
    ``(n_rows,)`` how many regions each row ended with, ``capped`` ``(n_rows,)`` True where a
    row stopped at ``max_regions`` before meeting its budget, or has an error that is not finite,
    ``evaluated`` ``(n_rows,)`` how many regions each row evaluated, split ones included (the
    integrand's points spent: ``GM_POINTS * evaluated``)."""

    value: np.ndarray
    error: np.ndarray
    regions: np.ndarray
    capped: np.ndarray
    evaluated: np.ndarray


def _rule(integrand, r):
    """Degree-7 values ``(k + 1, m)``, the magnitudes of their embedded differences and the
    split axis ``(m,)`` (True: across v) of the regions ``r``."""
    u = r.u0[:, None] + r.du[:, None] * GM_U[None, :]
    v = r.v0[:, None] + r.dv[:, None] * GM_V[None, :]
    f, w = integrand(r.cell, u, v)  # (k, m, 17), (m, 17)
    area = (r.du * r.dv)[:, None]
    w7, w5 = w * (_W7 * area), w * (_W5 * area)
    # einsum sums each region's points in one fixed order: a row's value does not depend on
    # how many other regions share the call (a BLAS product may block differently)
    i7 = np.concatenate([np.einsum("kmp,mp->km", f, w7), w7.sum(axis=1)[None]])
    diff = np.abs(i7 - np.concatenate([np.einsum("kmp,mp->km", f, w5), w5.sum(axis=1)[None]]))
    # fourth differences along u and v of the component whose error estimate is largest: the
    # axis to split across is where that component varies most
    k = np.argmax(diff, axis=0)
    g = f[np.minimum(k, f.shape[0] - 1), np.arange(k.size)]
    g = np.where((k == f.shape[0])[:, None], 1.0, g) * w  # (m, 17); the last component is w itself
    d = [np.abs(g[:, a] + g[:, a + 1] - 2 * g[:, 0] - (g[:, a + 2] + g[:, a + 3] - 2 * g[:, 0]) / 7.0)
         for a in (1, 5)]  # fmt: skip
    return i7, diff, d[1] > d[0]


@dataclass
class _Regions:
    """Rectangles ``[u0, u0 + du] x [v0, v0 + dv]`` of the cells ``cell``, with their degree-7
    values ``val`` ``(k + 1, m)``, error bounds ``diff`` ``(k + 1, m)`` and split axes."""

    cell: np.ndarray
    u0: np.ndarray
    du: np.ndarray
    v0: np.ndarray
    dv: np.ndarray
    val: np.ndarray = None
    diff: np.ndarray = None
    axis: np.ndarray = None

    def arrays(self):
        return [getattr(self, f.name) for f in dataclasses.fields(self)]

    def take(self, idx):
        return _Regions(*(None if a is None else a[..., idx] for a in self.arrays()))

    def evaluate(self, integrand, block):
        parts = [_rule(integrand, self.take(slice(a, a + block))) for a in range(0, self.cell.size, block)]
        self.val, self.diff, self.axis = (np.concatenate(p, axis=-1) for p in zip(*parts, strict=True))

    def halves(self):
        """Both halves of every region, across ``axis`` (not evaluated)."""
        across_u = ~self.axis
        du = np.where(across_u, 0.5 * self.du, self.du)
        dv = np.where(across_u, self.dv, 0.5 * self.dv)
        u1 = self.u0 + np.where(across_u, du, 0.0)
        v1 = self.v0 + np.where(across_u, 0.0, dv)
        return _Regions(*(np.r_[a, b] for a, b in ((self.cell, self.cell), (self.u0, u1), (du, du), (self.v0, v1), (dv, dv))))  # fmt: skip


def _join(a, b):
    return _Regions(*(np.concatenate([x, y], axis=-1) for x, y in zip(a.arrays(), b.arrays(), strict=True)))


def _start(n_cells, start):
    grid = np.arange(start) / start
    size = np.full(n_cells * start * start, 1.0 / start)
    return _Regions(
        np.repeat(np.arange(n_cells), start * start),
        np.tile(np.repeat(grid, start), n_cells),
        size,
        np.tile(np.tile(grid, start), n_cells),
        size.copy(),
    )


def _refine(regions, split, integrand, block):
    """``regions`` with those flagged ``split`` replaced by their evaluated halves.  A half's
    error bound is at least half the change refining made to its parent's value: an embedded
    estimate alone can be small by accident across a kink both rules straddle alike."""
    parent = regions.take(split)
    kids = parent.halves()
    kids.evaluate(integrand, block)
    m = parent.cell.size
    change = np.abs(parent.val - kids.val[:, :m] - kids.val[:, m:])
    kids.diff = np.maximum(kids.diff, 0.5 * np.concatenate([change, change], axis=1))
    return _join(regions.take(~split), kids)


def _worst_splits(split, err, row, room):
    """``split`` kept for at most ``room[r]`` regions of each row ``r``, its largest errors."""
    idx = np.flatnonzero(split)
    order = idx[np.lexsort((-err[idx], row[idx]))]
    r = row[order]
    rank = np.arange(r.size) - np.searchsorted(r, r, side="left")
    out = np.zeros_like(split)
    out[order[rank < room[r]]] = True
    return out


def adaptive(integrand, cell_row, n_rows, norm, budget, max_regions, start=2, block=4096, max_evaluated=None):
    """Integrate ``integrand`` over every cell and sum the cells per row, refining adaptively.

    Parameters
    ----------
    integrand : callable
        ``integrand(cell, u, v)``: ``cell`` ``(m,)`` cell indices, ``u``, ``v`` ``(m, P)``
        points of the unit square; returns ``(f, w)``: ``k`` functions ``f`` ``(k, m, P)``
        and a weight ``w`` ``(m, P)`` (Jacobians included).  The ``k + 1`` integrals are
        those of ``f w`` and of ``w`` itself (the last).
    cell_row : ndarray of int, shape (n_cells,)
        The row each cell belongs to.
    n_rows : int
        Number of rows.
    norm : callable
        ``norm(diff, value)``: the scalar error ``(m,)`` of regions from the bounds ``diff``
        ``(k + 1, m)`` on their integrals and their rows' current totals ``value`` ``(k + 1, m)``.
    budget : callable
        ``budget(value)``: the error ``(n_rows,)`` allowed for the totals ``value``
        ``(k + 1, n_rows)``.
    max_regions : int
        Regions per row beyond which it is not refined (reported in ``capped``).
    max_evaluated : int, optional
        Regions a row may evaluate in all (its initial ones, and two per split): a pass splits
        at most what is left of it, the worst regions first, and a row with no split left is
        ``capped``.  So ``GM_POINTS * max_evaluated`` bounds the integrand's points per row
        (given that the initial regions fit in it).
    start : int
        Each cell starts as ``start x start`` regions (an embedded estimate on one region
        can miss a feature that both rules straddle alike; a few regions expose it).
    block : int
        Regions evaluated per call of ``integrand`` (bounds the temporaries).

    Returns
    -------
    Cubature
    """
    regions = _start(cell_row.size, start)
    regions.evaluate(integrand, block)
    capped = np.zeros(n_rows, dtype=bool)
    evaluated = np.bincount(cell_row[regions.cell], minlength=n_rows)
    # a row that stops refining keeps its figures here and its regions leave the loop: each
    # pass then costs what its rows still refining hold (every figure is per row, summed in
    # the regions' order, which leaving does not change: the same bits)
    total = np.zeros((regions.val.shape[0], n_rows))
    row_err = np.zeros(n_rows)
    count = np.zeros(n_rows, dtype=int)
    active = np.ones(n_rows, dtype=bool)
    while True:
        row = cell_row[regions.cell]
        summed = np.stack([np.bincount(row, weights=x, minlength=n_rows) for x in regions.val])
        total[:, active] = summed[:, active]
        err = norm(regions.diff, total[:, row])
        row_err[active] = np.bincount(row, weights=err, minlength=n_rows)[active]
        count[active] = np.bincount(row, minlength=n_rows)[active]
        allowed = budget(total)
        todo = active & ~(row_err <= allowed)  # a NaN error is not converged
        # rows at the cap, or whose error is not finite (no split can repair it), are reported
        capped |= todo & ((count >= max_regions) | ~np.isfinite(row_err))
        if max_evaluated is not None:
            room = (max_evaluated - evaluated) // 2  # splits each row can still afford
            capped |= todo & (room < 1)
        todo &= ~capped
        # the worst regions are split: those above both their fair share of the row's budget
        # and a fraction of the row's worst (the share alone would soon split nearly all)
        worst = np.zeros(n_rows)
        np.maximum.at(worst, row, np.where(np.isfinite(err), err, 0.0))  # NaN rows are capped
        split = todo[row] & (err > np.maximum(allowed[row] / count[row], WORST * worst[row]))
        if max_evaluated is not None:
            split = _worst_splits(split, err, row, room)
        if not split.any():
            return Cubature(total, row_err, count, capped, evaluated)
        evaluated += 2 * np.bincount(row[split], minlength=n_rows)
        active = todo
        keep = todo[row]
        regions = _refine(regions.take(keep), split[keep], integrand, block)
