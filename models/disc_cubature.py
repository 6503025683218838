"""The disc quadrature of :class:`scatterbench.models.PointSourceBRDF` at ``resolution="auto"``:
the light a disc sample sends to the observer, integrated over the disc until each geometry's
estimated error meets a tolerance (what that tolerance means: :mod:`scatterbench.models.point_source`,
Accuracy).  The quadrature follows the integrand's known features:

* the lobe, and for exponential slopes its cusp, sits where the local specular direction of the
  incidence meets the observer, the point ``P*`` at ``psi = theta_r``, ``Phi = phi_r`` (or the
  point of the disc nearest to it);
* the incident ``(s, p)`` basis turns with ``Phi`` around the foot ``H`` of the source, so the
  polarization elements have a direction-dependent limit there when ``H`` lies on the disc.

The disc is written in polar coordinates ``(t, chi)`` about ``H`` (when on the disc) or its
centre, ``rho = t rho_max(chi)``, which makes the basis smooth (about ``H`` the radial variable
is the square root of the ray's flux share within ``rho``, so that a source near the plane,
whose flux falls within a few ``d`` of ``H``, is no harder than a far one).  When ``H`` is off
the disc but the irradiance's poles (``d`` above and below ``H``) lie within a radius of its rim
(:data:`WEDGE_REACH`), the flux crowds at the rim by ``H``, which the centre's coordinates
miss, their error estimate with them (Gaussian slopes 0.05: 1.0e-3 of the peak with ``H``
2 ``d`` off a disc of 10 ``d``, estimated at 9.4e-5); the disc is then the wedge of rays from ``H`` that meet it,
``sin chi = sin phi / |HC|`` (no square-root edge at the tangents), each ray's flux share
between where it enters and leaves the disc the radial variable.  Every ``R / d`` in the
declared range is refined so, with no other rule (``tests/test_point_source_accuracy.py``
holds ``R / d`` up to 1e6 against an independent integration in units of ``d``).  The
coordinates are cut at ``P*`` into at most four cells (``t`` below and above ``t*``, ``chi``
on either side of ``chi*``), each graded exponentially towards ``P*`` over the lobe's width on
the disc (``width * d``; across the wedge's rays ``width / tan psi`` of azimuth, where a lobe at
grazing incidence is narrowest), and integrated by adaptive cubature (:mod:`scatterbench.models.cubature`:
Genz-Malik rules whose embedded difference, and the change a split makes, bound each region's
error; regions above their share are halved until the geometry meets ``tol``).  A lobe broad compared with the incidence spread (``spread <=
2 width``) or no lobe at all is tried first with the product rule in ``(t, chi)`` at 4 and 8
radial nodes (160 evaluations; the difference of the two is the estimate): geometries it
settles skip the cubature.  With the numba backend (the default) the node algebra, each point's
local incidence and irradiance weight, runs compiled (:mod:`scatterbench.models.kernels.disc`,
held to :meth:`Disc.angles`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import cubature, evaluation
from .geometry import polar_rule

__all__ = ["BLOCK", "WEDGE_REACH", "Accuracy", "Disc", "refine"]

#: Inner-model geometries per block (bounds the temporaries of one block).
BLOCK = 1 << 16

#: ``resolution="auto"`` integrates about the source's foot ``H`` over the wedge of directions
#: that meet the disc when ``H`` is off the disc and the irradiance's poles, ``d`` above and
#: below ``H``, are within this many radii of the rim (``hypot(|HC| / R - 1, d / R)``); farther,
#: the irradiance varies on the disc's scale and the centre's polar coordinates follow it
WEDGE_REACH = 1.0

#: the product rule's node counts of the first try
_FIRST = (4, 8)
#: the first try is made when the incidence spread is at most this many lobe widths
_BROAD = 2.0


@dataclass(frozen=True)
class Accuracy:
    """What :meth:`PointSourceBRDF.accuracy <scatterbench.models.PointSourceBRDF.accuracy>`
    measured, per geometry (the broadcast shape; flat, ``(16, n)`` and ``(n,)``, as :func:`refine`
    fills it).

    ``mueller`` ``(..., 4, 4)`` the result; ``error`` the estimated error of its worst element
    over ``scale``, comparable with ``tol``; ``scale`` ``max(M00, M00_c)``
    (:mod:`scatterbench.models.point_source`, Accuracy); ``evaluations`` the inner-model
    evaluations spent; ``capped`` True where the refinement stopped at
    :data:`~scatterbench.models.point_source.MAX_REGIONS` before ``error`` met ``tol``."""

    mueller: np.ndarray
    error: np.ndarray
    scale: np.ndarray
    evaluations: np.ndarray
    capped: np.ndarray

    @classmethod
    def zeros(cls, n):
        """Flat, for ``n`` geometries: all zero, none capped."""
        return cls(np.zeros((16, n)), np.zeros(n), np.zeros(n), np.zeros(n, int), np.zeros(n, bool))


def refine(disc, scale, tol, max_regions):
    """Every geometry of ``disc`` (:class:`Disc`) refined until its estimated error is within
    ``tol * max(M00, scale)``, or it reaches ``max_regions`` regions (``capped``): the product
    rule first where the lobe is broad (:data:`_BROAD`), the adaptive cubature where that does
    not settle it."""
    res = Accuracy.zeros(disc.tr.size)
    todo = np.arange(disc.tr.size)
    broad = np.flatnonzero(~(disc.spread > _BROAD * disc.width))  # also: no specular lobe (nan)
    if broad.size:
        done = _first_try(disc, broad, scale[broad], tol, res)
        todo = np.setdiff1d(todo, broad[done])
    if todo.size:
        _cubature(disc, todo, scale[todo], tol, max_regions, res)
    return res


def _first_try(disc, rows, scale, tol, res):
    """The product rule in ``(t, chi)`` at 4 and 8 radial nodes on ``rows``; where the two agree
    within the budget the 8-node value is kept (in ``res``).  Returns the settled mask."""
    vals = []
    for n_r in _FIRST:
        t, chi, w = _product_nodes(n_r)
        step = max(1, BLOCK // t.size)
        vals.append(np.concatenate([_weighted_mean(*disc.values(rows[a:a + step], t, chi, w))
                                    for a in range(0, rows.size, step)], axis=1))  # fmt: skip
    coarse, fine = vals
    err = np.max(np.abs(fine - coarse), axis=0)
    sc = np.maximum(np.abs(fine[0]), scale)
    done = err <= tol * sc
    res.evaluations[rows] = sum(2 * n * n for n in _FIRST)
    take = rows[done]
    res.mueller[:, take], res.scale[take] = fine[:, done], sc[done]
    res.error[take] = _ratio(err[done], sc[done])
    return done


def _cubature(disc, rows, scale, tol, max_regions, res):
    """Adaptive cubature over the cells of ``rows`` (module docstring), into ``res``."""
    cells = disc.cells(rows)

    def integrand(cell, u, v):
        t, chi, w = cells.point(cell, u, v)
        return disc.values(rows[cells.row[cell]], t, chi, w)

    def norm(diff, total):
        return np.max(diff[:16] + np.abs(total[:16] / total[16]) * diff[16], axis=0)

    def budget(total):
        return tol * np.maximum(np.abs(total[0] / total[16]), scale) * total[16]

    got = cubature.adaptive(integrand, cells.row, rows.size, norm, budget, max_regions)
    W = got.value[16]
    M = got.value[:16] / W
    sc = np.maximum(np.abs(M[0]), scale)
    res.mueller[:, rows], res.scale[rows], res.capped[rows] = M, sc, got.capped
    res.error[rows] = _ratio(got.error / W, sc)
    res.evaluations[rows] += cubature.GM_POINTS * got.evaluated  # split regions included


def _ratio(a, b):
    """``a / b`` with ``0 / 0 = 0`` (an exact zero known exactly)."""
    return np.divide(a, b, out=np.where(a > 0, np.inf, 0.0), where=b > 0)


def _weighted_mean(M, J):
    """``sum_p M J / sum_p J`` per row: ``(16, m)``."""
    return np.einsum("kmp,mp->km", M, J) / J.sum(axis=1)


def _product_nodes(n_r):
    """``(t, chi, w)`` ``(1, K)`` of :func:`scatterbench.models.geometry.polar_rule`; the area element is the
    integrand's."""
    return tuple(a[None, :] for a in polar_rule(n_r))


def _graded(beta, x):
    """``g(x) = expm1(beta x) / expm1(beta)`` on [0, 1] and ``g'(x)``: points clustered towards 0
    over a fraction ~1 / beta (``beta`` >= 1e-3, a smooth change of variables for any)."""
    e = np.expm1(beta)
    ex = np.exp(beta * x)
    return (ex - 1.0) / e, beta * ex / e


class Disc:
    """The disc as the ``"auto"`` quadrature sees it, per geometry (module docstring).

    Lengths on the disc are in units of its radius ``R``; the source's height ``d`` enters
    through ``k = R / d``.  Polar coordinates about ``O``, the foot ``H`` of the source when it
    lies on the disc, else the centre: a point is ``O + t rho(chi) (cos chi, sin chi)``, ``rho``
    the distance from ``O`` to the rim.  The quadrature's radial variable ``v`` is ``t`` about
    the centre; about ``H`` it absorbs the irradiance: ``v^2`` is the share of the ray's flux
    within ``r = t rho`` (``cos^3 psi r dr`` with ``tan psi = k r``), so that a source near the
    plane, whose flux falls within a few ``d`` of ``H``, is no harder than a far one, while
    ``v`` stays linear in ``r`` at ``H``.

    Parameters: ``k`` the disc's radius over the source's height; ``ti``, ``tr``, ``pr`` the
    geometries, flat (``ti`` the central incidence); ``width`` the inner model's lobe width at
    the central incidence where its lobe is specular (centred at ``(theta_i, 0)``, so that its
    peak or cusp sits at ``P*``), nan otherwise; ``spread`` the incidence spread over the disc;
    ``local(psi, Phi, tr, pr)`` the inner model's 16 Mueller elements ``(16, m, P)`` at the local
    incidences ``(psi, Phi)`` ``(m, P)`` for the observations ``(tr, pr)`` ``(m,)``.
    """

    def __init__(self, k, ti, tr, pr, width, spread, local):
        self.tr, self.pr, self.width, self.spread, self.local = tr, pr, width, spread, local
        self.k = min(k, 1e300)
        self.h1 = math.hypot(1.0, self.k)
        self.tan_c = np.tan(ti)  # H to C, in units of d
        self.sec_c = np.hypot(1.0, self.tan_c)  # 1 / cos psi_c
        xc = _over(self.tan_c, self.k)  # H to C, in units of R
        self.on_h = xc < 1.0
        self.ox = np.where(self.on_h, -xc, 0.0)  # O from C
        # H off the disc but near it: the flux crowds at the rim by H, which polar coordinates
        # about the centre miss (their error estimate with them); the wedge about H follows it
        near = np.hypot(xc - 1.0, 1.0 / self.k) < WEDGE_REACH  # (xc: at most 1e300)
        self.xc = np.where((xc >= 1.0) & near, xc, np.nan)
        self.wedge = ~np.isnan(self.xc)

    def rho(self, ox, c, s):
        """Distance from ``O`` (at ``ox``) to the rim along ``(c, s)``."""
        return np.sqrt(np.maximum(1.0 - (ox * s) ** 2, 0.0)) - ox * c

    def values(self, rows, v, chi, w):
        """``(M, J)`` at ``(v, chi)`` with quadrature weights ``w``: the 16 Mueller elements
        ``(16, m, P)`` and the irradiance weight ``J`` ``(m, P)`` (:meth:`angles`)."""
        if evaluation.current_backend() == "numba":
            psi, Phi, J = self._angles_compiled(rows, v, chi, w)
        else:
            psi, Phi, J = self.angles(rows, v, chi, w)
        return self.local(psi, Phi, self.tr[rows], self.pr[rows]), J

    def _angles_compiled(self, rows, v, chi, w):
        """:meth:`angles` compiled (:mod:`scatterbench.models.kernels.disc`, held to it)."""
        from .kernels import disc  # numba: loaded only where the compiled backend runs

        shape = np.broadcast_shapes((rows.size, 1), np.shape(v), np.shape(chi), np.shape(w))
        v, chi, w = (np.ascontiguousarray(np.broadcast_to(a, shape), dtype=float) for a in (v, chi, w))
        # writable: a read-only view (broadcast_to of an array of that shape already) is
        # another argument type, which compiled the loop a second time (6 s on a cold cache)
        v, chi, w = (a if a.flags.writeable else a.copy() for a in (v, chi, w))
        psi, Phi, J = np.empty(v.shape), np.empty(v.shape), np.empty(v.shape)
        disc.points(self.k, self.h1, self.tan_c[rows], self.sec_c[rows], self.on_h[rows], self.ox[rows],
                    self.xc[rows], v, chi, w, psi, Phi, J)  # fmt: skip
        return psi, Phi, J

    def angles(self, rows, v, chi, w):
        """``(psi, Phi, J)`` at ``(v, chi)`` with quadrature weights ``w``: the local incidence,
        polar and azimuth, and the irradiance weight ``J``, each ``(m, P)`` (per row up to a
        constant: ``rho^2 t cos^3 psi / cos^3 psi_c w`` about the centre,
        ``2 v rho^2 / (h (h + 1)) w`` about ``H``, ``h = hypot(1, k rho)``, scaled by the unit
        disc's); the numpy reference of :mod:`scatterbench.models.kernels.disc`."""
        on_h = self.on_h[rows][:, None]
        ox = self.ox[rows][:, None]
        c, s = np.cos(chi), np.sin(chi)
        rho = self.rho(ox, c, s)
        h = np.hypot(1.0, self.k * rho)
        t = np.where(on_h, _t_of_v(v, h, self.k * rho), v)
        r = rho * t
        tan_c = self.tan_c[rows][:, None]
        x = tan_c + self.k * (ox + r * c)  # from H, units of d
        y = self.k * r * s
        tan_psi = np.hypot(x, y)
        cos_ratio = self.sec_c[rows][:, None] / np.hypot(1.0, tan_psi)  # cos psi / cos psi_c
        J = np.where(on_h, 2.0 * v * (self.h1 / h) * ((self.h1 + 1.0) / (h + 1.0)), t * cos_ratio**3)
        J = w * rho * rho * J
        sel = self.wedge[rows]
        if sel.any():
            vw, cw, ww = (np.broadcast_to(a, x.shape)[sel] for a in (v, chi, w))
            x[sel], y[sel], J[sel] = _wedge(self.xc[rows][sel][:, None], self.k, vw, cw)
            J[sel] *= ww
            tan_psi[sel] = np.hypot(x[sel], y[sel])
        return np.arctan(tan_psi), np.arctan2(y, x), J

    def cells(self, rows):
        """The cells of ``rows``: the disc cut at ``P*`` (or its point nearest ``P*``) into ``v``
        below and above ``v*`` and ``chi`` on either side of ``chi*``, graded towards it."""
        vq, cq, bv, bc, turns = self._cusp(rows)
        out = []
        for span, b in ((1.0 - vq, bv[1]), (-vq, bv[0])):
            for turn in turns:
                ok = np.flatnonzero((span != 0.0) & (turn != 0.0))
                out.append((ok, vq[ok], span[ok], b[ok], cq[ok], turn[ok], bc[ok]))
        return _Cells(*(np.concatenate(a) for a in zip(*out, strict=True)))

    def _cusp(self, rows):
        """``(v*, chi*)`` of ``P*`` clamped to the disc, the grading exponents ``(inner,
        outer)`` along ``v`` and the one along ``chi`` (a half turn at ``t*``): the log of the
        cell's extent over the lobe's (``width / k`` on the disc), and the angular spans of the
        cells on either side of ``chi*`` (a half turn each; in the wedge, to its edges).
        Without a specular lobe: ``v* = 1, chi* = 0`` (no cut) and no grading."""
        tr, pr, k, ox, on_h = self.tr[rows], self.pr[rows], self.k, self.ox[rows], self.on_h[rows]
        tt = np.tan(np.minimum(tr, 0.5 * math.pi - 1e-12))
        px = _over(tt * np.cos(pr) - self.tan_c[rows], k)  # P* from C, units of R
        py = _over(tt * np.sin(pr), k)
        big = np.hypot(px, py)
        f = np.where(big > 1.0, 1.0 / np.where(big > 1.0, big, 1.0), 1.0)
        qx, qy = px * f - ox, py * f
        cq = np.arctan2(qy, qx)
        rq = self.rho(ox, np.cos(cq), np.sin(cq))
        tq = np.clip(np.hypot(qx, qy) / np.where(rq > 0, rq, 1.0), 0.0, 1.0)
        none = np.isnan(self.width[rows])
        tq, cq = np.where(none, 1.0, tq), np.where(none, 0.0, cq)
        lobe_t = _over(np.where(none, 1.0, self.width[rows]), k) / np.where(rq > 0, rq, 1.0)

        def v_of(t):
            return np.where(on_h, _v_of_t(t, k * rq), t)

        vq = v_of(tq)
        lobe_v = np.maximum(v_of(np.minimum(tq + lobe_t, 1.0)) - vq, vq - v_of(np.maximum(tq - lobe_t, 0.0)))
        bv = [_beta(span, lobe_v, none) for span in (vq, 1.0 - vq)]
        bc = _beta(math.pi * tq, lobe_t, none)
        turns = (np.full(rows.size, math.pi), np.full(rows.size, -math.pi))
        sel = self.wedge[rows]
        if sel.any():
            xc = self.xc[rows][sel]
            width = np.where(none, 1.0, self.width[rows])[sel]
            got = _wedge_cusp(xc, k, px[sel] * f[sel] + xc, py[sel] * f[sel], width, none[sel])
            vq[sel], cq[sel], bv[0][sel], bv[1][sel], bc[sel] = got
            turns[0][sel], turns[1][sel] = math.pi - cq[sel], -math.pi - cq[sel]
        return vq, cq, bv, bc, turns


def _wedge_ray(xc, k, phi):
    """The ray from ``H`` (``xc`` from the centre, units of ``R``, ``1 <= xc``) at wedge angle
    ``phi`` (``sin chi = sin phi / xc``, ``chi`` from the direction HC): ``cos chi``, ``sin chi``,
    the distances ``r_n``, ``r_f`` to where it enters and leaves the disc and ``hypot(1, k r)``
    at both (the rim's tangents, ``phi = +-pi/2``, have ``r_n = r_f``: no square-root edge)."""
    sc = np.sin(phi) / xc
    cc = np.sqrt(1.0 - sc * sc)
    r_f = xc * cc + np.cos(phi)
    # (xc^2 - 1) / r_f: no cancellation when H is at the rim (xc cos chi ~ cos phi)
    r_n = np.divide((xc - 1.0) * (xc + 1.0), r_f, out=np.zeros_like(r_f), where=r_f > 0)
    return cc, sc, r_n, r_f, np.hypot(1.0, k * r_n), np.hypot(1.0, k * r_f)


def _share(r, h):
    """``G(r) = r^2 / (h (h + 1))``: the flux share within ``r`` of ``H`` over ``k^2``
    (``dG = cos^3 psi r dr``, ``h = hypot(1, k r) = 1 / cos psi``)."""
    return r * (r / (h * (h + 1.0)))


def _wedge(xc, k, u, alpha):
    """``(x, y, J)``: the point of the wedge about ``H`` at ``(u, alpha)`` from ``H`` in units of
    ``d``, and the flux weight of ``du dalpha``.  ``phi = alpha / 2`` (``alpha`` taken modulo a
    turn); ``u`` the share of the ray's flux between ``r_n`` and ``r``, so that ``J = (G(r_f) -
    G(r_n)) dchi / dalpha = 2 cos^2 phi / (h_n h_f (h_n + h_f))`` is smooth.  ``G`` and ``1 -
    k^2 G = 1 / h`` are both linear in ``u`` (no cancellation at either end)."""
    phi = 0.5 * (np.remainder(alpha + math.pi, 2.0 * math.pi) - math.pi)
    cc, sc, r_n, r_f, h_n, h_f = _wedge_ray(xc, k, phi)
    g = (1.0 - u) * _share(r_n, h_n) + u * _share(r_f, h_f)
    a = (1.0 - u) / h_n + u / h_f  # cos psi
    r = np.sqrt(g * (1.0 + a)) / a  # r^2 = G (2 - k^2 G) / (1 - k^2 G)^2
    cp = np.cos(phi)
    return k * r * cc, k * r * sc, 2.0 * cp * cp / (h_n * h_f * (h_n + h_f))


def _wedge_u(xc, k, phi, r):
    """``u`` of the point at ``r`` from ``H`` along the wedge angle ``phi`` (clipped to the disc)."""
    _, _, r_n, r_f, h_n, h_f = _wedge_ray(xc, k, phi)
    r = np.clip(r, r_n, r_f)
    h = np.hypot(1.0, k * r)
    num = (r - r_n) * (r + r_n) / (h * h_n * (h + h_n))
    den = (r_f - r_n) * (r_f + r_n) / (h_f * h_n * (h_f + h_n))
    return np.clip(np.divide(num, den, out=np.zeros_like(num), where=den > 0), 0.0, 1.0)


def _wedge_cusp(xc, k, hx, hy, width, none):
    """``(u*, alpha*, inner and outer grading along u, grading along alpha)`` of ``P*`` at
    ``(hx, hy)`` from ``H`` (units of ``R``, on the disc), the lobe ``width`` (radians: taken
    as ``width d`` along the ray, as about ``H`` on the disc, and ``width / tan psi`` of
    azimuth across it, where a grazing lobe is narrowest)."""
    chi, r = np.arctan2(hy, hx), np.hypot(hx, hy)
    phi = np.arcsin(np.clip(xc * np.sin(chi), -1.0, 1.0))
    u = _wedge_u(xc, k, phi, r)
    lr = width / k
    lobe_u = np.maximum(_wedge_u(xc, k, phi, r + lr) - u, u - _wedge_u(xc, k, phi, r - lr))
    with np.errstate(divide="ignore", invalid="ignore"):
        # across the ray the lobe spans width / tan psi of azimuth (as about H on the disc);
        # dalpha = 2 xc cos chi dchi / cos phi
        lobe_a = 2.0 * (width / (k * r)) * xc * np.cos(chi) / np.cos(phi)
    u, a = np.where(none, 1.0, u), np.where(none, 0.0, 2.0 * phi)
    return u, a, _beta(u, lobe_u, none), _beta(1.0 - u, lobe_u, none), _beta(math.pi, lobe_a, none)


def _over(a, k):
    """``a / k`` clipped to +-1e300 (no overflow for a vanishing disc, ``k`` ~ 1e-300)."""
    lim = k * 1e300
    return np.clip(a, -lim, lim) / k


def _beta(extent, lobe, none):
    """The grading exponent of a cell of ``extent`` over a lobe of ``lobe`` (same units): its
    points cluster within ~1/beta of the corner; >= 1e-3, and 1e-3 without a lobe."""
    with np.errstate(divide="ignore", invalid="ignore"):
        b = np.log1p(extent / lobe)
    return np.where(none | ~np.isfinite(b), 1e-3, np.maximum(b, 1e-3))


def _v_of_t(t, krho):
    """The radial variable about ``H`` at ``t``: ``v = t sqrt(h (h + 1) / (g (g + 1)))``, ``g =
    hypot(1, k rho t)``, ``h = hypot(1, k rho)`` (written as ratios: no overflow, no underflow)."""
    h, g = np.hypot(1.0, krho), np.hypot(1.0, krho * t)
    return t * np.sqrt(h / g) * np.sqrt((h + 1.0) / (g + 1.0))


def _t_of_v(v, h, krho):
    """The inverse of :func:`_v_of_t`: ``t = v sqrt((2 - v^2 A) / (h (h + 1))) / (1 - v^2 A)``,
    ``A = 1 - 1/h``; clipped to the rim (at ``v`` -> 1 with ``h`` huge, ``1 - v^2 A`` rounds:
    it is at least ``1 / h``, its value at the rim)."""
    a = (krho / h) * (krho / (h + 1.0))
    s = np.maximum(1.0 - v * v * a, 1.0 / h)
    return np.minimum(v * np.sqrt(2.0 - v * v * a) / (np.sqrt(h) * np.sqrt(h + 1.0) * s), 1.0)


@dataclass
class _Cells:
    """Cells of the ``(v, chi)`` plane per geometry: ``v = v0 + dv g(u)``, ``chi = c0 + dc g(u')``
    on the unit square, graded (exponents ``bv``, ``bc``) from the corner ``(v0, c0)`` at ``P*``."""

    row: np.ndarray
    v0: np.ndarray
    dv: np.ndarray
    bv: np.ndarray
    c0: np.ndarray
    dc: np.ndarray
    bc: np.ndarray

    def point(self, cell, u, w):
        """``(v, chi, J)`` ``(m, P)`` of unit-square points ``(u, w)`` of ``cell``, ``J`` the map's Jacobian."""
        gv, dgv = _graded(self.bv[cell][:, None], u)
        gc, dgc = _graded(self.bc[cell][:, None], w)
        dv, dc = self.dv[cell][:, None], self.dc[cell][:, None]
        return self.v0[cell][:, None] + dv * gv, self.c0[cell][:, None] + dc * gc, np.abs(dv * dc) * dgv * dgc
