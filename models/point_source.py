"""Non-collimated illumination by a point source, seed 001 Eq. 25-30, around any model.

Geometry (DESIGN.md frame).  A disc-shaped sample of radius ``R``
(``sample_radius``) is centred at the origin C; the point source L is at height
``d`` (``distance``, the paper's d: the distance from L to the surface plane, in
the same unit as ``R``) in the plane ``y = 0``, placed so that the ray LC arrives
at C with the incidence ``psi_c = theta_i``: ``L = (-d tan psi_c, 0, d)``.  A ray
LP to a point P of the sample arrives with polar angle ``psi`` (``x = |HP| =
d tan psi``, Eq. 26) and travels horizontally at azimuth ``Phi`` from LC's
direction.  The observer is far away in direction ``(theta_r, phi_r)``.

Exact superposition (Eq. 28).  The light reaching the observer is the sum over
the sample of the local BRDF ``f(psi, theta, phi - Phi)`` (for an anisotropic
model, the sample rotated by ``-Phi`` so that the local incidence is in the
model's standard frame) weighted by the light each point receives.  The result
is normalized by the total received flux so that it is a BRDF (1/sr) that tends
to the collimated one as the source recedes:

    f_g(theta, phi) = sum_k w_k f(psi_k, theta, phi - Phi_k),   w_k ~ E(P_k) dA_k,  sum_k w_k = 1.

``E`` is the irradiance of an isotropic point source, ``cos^3 psi / d^2``.  The
paper's weights are not used: Eq. 25 is the *one-dimensional* Cauchy density
``d / (pi (d^2 + x^2))``, which is not integrable over the plane (its integral
over a disc of radius ``X`` grows like ``ln X``); the irradiance of a point
source on a plane is the bivariate Cauchy density ``d / (2 pi (d^2 + x^2)^{3/2})``,
and Eq. 28's measure ``d psi d Phi`` is not the area element
(``dA = d^2 tan psi sec^2 psi d psi d Phi``).

Accuracy (``resolution="auto"``, the default, exact method).  The user states the accuracy,
``tol``, and every geometry is refined until its estimated error meets it: each Mueller element
is then within ``tol * max(M00, M00_c)`` of the exact superposition, ``M00`` the geometry's own
value and ``M00_c`` the value at the inner model's lobe centre at the same incidence
(:meth:`Model.lobe`; 0 without a lobe, so that the bound is relative to ``M00`` alone).
``M00_c`` is at most the peak, so every value is within ``tol`` of the peak, and within ``tol``
relative where it exceeds ``M00_c``.  A geometry's value does not depend on the others in the
call.  A fixed 16 nodes left Cook-Torrance m = 0.01 at d/R = 3 off by more than half the peak,
and the product rule about the sample's centre converges only algebraically on the cusp of
exponential slopes (3e-3 of the peak for sigma = 0.05 at d/R = 3 with the earlier lobe-based
node count, 1.6e-4 with 256 radial nodes: ``benchmarks/wrappers.py``): the quadrature must
follow the integrand's features, which are known:

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
settles skip the cubature.  A geometry that reaches :data:`MAX_REGIONS` regions stops there with
an :class:`AccuracyWarning` naming how many did and their estimated error;
:meth:`PointSourceBRDF.accuracy` returns the estimates themselves.  An anisotropic inner model
is rotated per node as a model set (``model.rotated(array)``, one call per block of nodes); one
whose ``rotated`` takes a single angle (a user's model) is rotated node by node, one call per
distinct azimuth, on the same nodes: the same quadrature, only slower.
With the numba backend (the default) the node algebra, each point's local incidence and
irradiance weight, runs compiled (:mod:`scatterbench.models.kernels.disc`, held to :meth:`_Disc.angles`).

A fixed ``resolution`` (an int) is the product rule of earlier versions, unrefined and
unestimated: Gauss-Legendre in the radius about the disc centre (``resolution`` nodes, weight
``rho d rho``) times the periodic trapezoid rule in the azimuth (``2 resolution`` nodes), whose
cost grows as ``resolution^2`` (``scatterbench tradeoff``'s point-source resolution knob).

Shift approximation (Eq. 29-30).  Every local BRDF is taken to be the central
one ``f_c = f(psi_c, ., .)`` shifted so that its specular direction follows the
incidence: ``f(psi, theta, phi - Phi) ~ f_c(theta + psi_c - psi, phi - Phi)``
(a negative polar angle is continued through the normal to ``phi + pi``).
Pointwise (:meth:`mueller`/:meth:`brdf`) this costs as much as the exact sum;
its speed comes from :meth:`brdf_grid`: ``f_c`` is evaluated once on the
observation grid (extended by the shifts) and the weights are splatted
(bilinearly) onto grid offsets, so Eq. 30's convolution is one FFT correlation.

The wrapper is not reciprocal (``reciprocal = False``): swapping source and
observer turns an extended source into an extended detector and vice versa.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass
from functools import cached_property
from types import MappingProxyType

import numpy as np
from scipy import signal

from . import cubature, evaluation
from .base import Model, _Wrapper, is_isotropic, rotated_set
from .constraints import Instance, Integer, Interval, OneOf, Options, ScalarOrArray
from .cook_torrance import CookTorranceBRDF
from .cubature import AccuracyWarning
from .facts import Correspondence
from .geometry import disc_quadrature, polar_rule
from .params import param

__all__ = ["PointSourceBRDF", "point_source_geometry", "Accuracy", "AccuracyWarning", "MAX_REGIONS"]

#: Inner-model geometries per block (bounds the temporaries of one block).
_BLOCK = 1 << 16


def point_source_geometry(lo_deg, hi_deg):
    """``(psi_c, d / R)``: the central incidence (radians) and the source height in units
    of the sample radius for which a disc sample spans incidences ``[lo_deg, hi_deg]``.

    With ``x = d tan(psi)`` (Eq. 26) the disc spans ``x_c - R .. x_c + R``:
    ``d / R = 2 / (tan hi - tan lo)`` and ``tan psi_c = (tan lo + tan hi) / 2``.
    Seed 001 prints such ranges for its iron plate but no distance or sample size.
    """
    tl, th = math.tan(math.radians(lo_deg)), math.tan(math.radians(hi_deg))
    return math.atan(0.5 * (tl + th)), 2.0 / (th - tl)


#: ``resolution="auto"`` integrates about the source's foot ``H`` over the wedge of directions
#: that meet the disc when ``H`` is off the disc and the irradiance's poles, ``d`` above and
#: below ``H``, are within this many radii of the rim (``hypot(|HC| / R - 1, d / R)``); farther,
#: the irradiance varies on the disc's scale and the centre's polar coordinates follow it
WEDGE_REACH = 1.0

#: :meth:`PointSourceBRDF.resolution_at` (the shift method's node count) for ``"auto"``: nodes
#: per (incidence spread / lobe width), and the bounds
AUTO_FACTOR = 10.0
_AUTO_MIN, _AUTO_MAX = 16, 4096

#: ``resolution="auto"``: the regions per geometry at which refinement stops (each region a
#: 17-point rule: at most ~70,000 inner-model evaluations per geometry)
MAX_REGIONS = 4096
#: the product rule's node counts of the first try
_FIRST = (4, 8)
#: the first try is made when the incidence spread is at most this many lobe widths
_BROAD = 2.0
#: ``tol``: below ~1e-13 the rounding of the sums dominates; above 0.1 it is no statement
_TOL_MIN, _TOL_MAX = 1e-13, 0.1


@dataclass(frozen=True)
class Accuracy:
    """What :meth:`PointSourceBRDF.accuracy` measured, per geometry (the broadcast shape).

    ``mueller`` ``(..., 4, 4)`` the result; ``error`` the estimated error of its worst element
    over ``scale``, comparable with ``tol``; ``scale`` ``max(M00, M00_c)`` (module docstring,
    Accuracy); ``evaluations`` the inner-model evaluations spent; ``capped`` True where the
    refinement stopped at :data:`MAX_REGIONS` before ``error`` met ``tol``."""

    mueller: np.ndarray
    error: np.ndarray
    scale: np.ndarray
    evaluations: np.ndarray
    capped: np.ndarray


@dataclass(frozen=True)
class PointSourceBRDF(_Wrapper):
    """A model illuminated by a point source at height ``distance`` over a disc
    sample of radius ``sample_radius`` (seed 001 Eq. 25-30).

    ``theta_i`` is the incidence at the sample centre (``psi_c``).  Depolarizing
    (a sum of Mueller matrices); ``M00`` is the flux-weighted mean BRDF.

    Parameters
    ----------
    model : Model
        Any reflection model (the collimated BRDF).
    distance : float
        Height of the source above the sample plane (same unit as
        ``sample_radius``), > 0, or ``math.inf`` (collimated: the model itself).
    sample_radius : float
        Radius of the illuminated disc, > 0.
    method : "exact" | "shift"
        Eq. 28 superposition, or the shift approximation Eq. 29-30.
    resolution : int or "auto"
        ``"auto"``: refined per geometry until the estimated error meets ``tol`` (module
        docstring, "Accuracy"); an int: the fixed product rule with that many radial nodes
        (azimuthal nodes: twice as many), no estimate.  The shift method takes
        :meth:`resolution_at` nodes.
    tol : float
        The accuracy ``"auto"`` refines to, in [1e-13, 0.1]: every Mueller element within
        ``tol * max(M00, M00_c)`` of the exact superposition, ``M00_c`` the value at the inner
        model's lobe centre at the same incidence (at most the peak).
    """

    model: Model = param(
        dataclasses.MISSING, "the collimated model", Instance(Model, text="a reflection model (models.Model)")
    )
    # swept at the sample's edge, near, far and at infinity (seed 001 Eq. 25-30)
    distance: float = param(
        100.0,
        "source height d above the sample plane (> 0, or inf)",
        Interval(0.0, math.inf, closed="right"),
        edges=(1.0, 10.0, 1e4, math.inf),
    )
    sample_radius: float = param(1.0, "sample radius R", ScalarOrArray(Interval(0.0, closed="right")))
    method: str = param("exact", "Eq. 28 superposition or Eq. 29-30 shift", Options("exact", "shift"))
    resolution: int | str = param(
        "auto",
        "'auto': refined to tol; or a fixed count of radial quadrature nodes over the disc (1-4096)",
        OneOf(Options("auto"), Integer(1, 4096)),
        edges=(1, 64),
    )
    # Not swept (edges=()): at 1e-13 every geometry refines to MAX_REGIONS (~70,000 inner
    # evaluations); tests/test_point_source_accuracy.py holds the estimates to tol instead.
    tol: float = param(
        1e-4,
        "accuracy of resolution='auto', relative to max(M00, M00 at the lobe centre)",
        Interval(_TOL_MIN, _TOL_MAX),
        edges=(),
    )

    correspondence = Correspondence("seed 001 Eq. 25-30")
    #: the kit's instance: 4 radial nodes over the disc (``"auto"`` refines each geometry to
    #: ``tol``, hundreds to thousands of evaluations; the kit checks the wrapper's shapes and
    #: physics, not its quadrature)
    kit_variant = MappingProxyType({"resolution": 4})

    @classmethod
    def sweep_base(cls):
        """The energy-normalized Cook-Torrance metal 100 sample radii below the source."""
        return cls(model=CookTorranceBRDF(convention="corrected"), distance=100.0, sample_radius=1.0)

    def lobe(self, theta_i):
        lb = self.model.lobe(theta_i)
        if lb is None:
            return None
        lo, hi = self.incidence_range(theta_i)
        return (lb[0], lb[1], lb[2] + (hi - lo))

    # -- source geometry ------------------------------------------------------------
    def resolution_at(self, theta_i):
        """The product rule's radial node count at central incidence ``theta_i`` (a float): a
        fixed ``resolution``, or for ``"auto"`` (used by the shift method, whose error is its
        approximation's) ``max(16, ceil(10 spread / lobe width))``."""
        if self.resolution != "auto":
            return self.resolution
        lb = self.model.lobe(theta_i)
        if lb is None or self.distance == math.inf:
            return _AUTO_MIN
        lo, hi = self.incidence_range(theta_i)
        n = AUTO_FACTOR * ((hi - lo) / lb[2]) if lb[2] > 0 else math.inf  # a delta lobe: the cap
        return int(min(max(_AUTO_MIN, math.ceil(n)), _AUTO_MAX))

    def _disc_nodes(self, resolution):
        """The disc's quadrature nodes and the unit disc's weights: only their ratios matter
        (``R^2`` leaves the float64 range for an extreme ``sample_radius``)."""
        return disc_quadrature(resolution, self.sample_radius, unit_weights=True)

    def source_nodes(self, theta_i, resolution=None):
        """``(psi, Phi, w)``, each ``(n_geom, K)``: incidence polar angle and
        azimuth at each quadrature point of the disc and normalized weights;
        ``resolution``: the radial node count (default: :meth:`resolution_at` of the
        first incidence)."""
        ti = np.atleast_1d(np.asarray(theta_i, dtype=float))
        px, py, wa = self._disc_nodes(self.resolution_at(float(ti[0])) if resolution is None else resolution)
        d = self.distance
        X = px[None, :] + (d * np.tan(np.minimum(ti, 0.5 * math.pi - 1e-12)))[:, None]
        Y = np.broadcast_to(py[None, :], X.shape)
        rho = np.hypot(X, Y)
        psi = np.arctan2(rho, d)
        Phi = np.arctan2(Y, X)
        c = np.cos(psi)
        w = wa[None, :] * c * c * c  # irradiance cos^3(psi) / d^2 times dA
        w /= w.sum(axis=1, keepdims=True)
        return psi, Phi, w

    def incidence_range(self, theta_i):
        """``(psi_min, psi_max)`` of the incidence over the sample (radians)."""
        if self.distance == math.inf:
            return (theta_i, theta_i)
        d, R = self.distance, self.sample_radius
        xc = d * math.tan(min(theta_i, 0.5 * math.pi - 1e-12))
        lo = math.atan2(max(xc - R, 0.0), d)
        return lo, math.atan2(xc + R, d)

    # -- evaluation -----------------------------------------------------------------------
    def _mueller16(self, ti, tr, pr):
        if self.distance == math.inf or self.sample_radius / self.distance == 0.0:
            return self.model._m16(ti, tr, pr)
        if self.resolution == "auto" and self.method == "exact":
            res = self._auto(ti, tr, pr)
            if res.capped.any():
                k = int(res.capped.sum())
                warnings.warn(
                    f"PointSourceBRDF: {k} of {ti.size} geometries stopped at the refinement cap "
                    f"with an estimated error up to {np.max(res.error[res.capped]):.2g} of their scale, "
                    f"above tol = {self.tol:g} (PointSourceBRDF.accuracy reports each)",
                    AccuracyWarning,
                    stacklevel=2,
                )
            return res.mueller
        out = np.zeros((16, ti.size))
        live = np.flatnonzero(ti < 0.5 * math.pi)
        ti, tr, pr = ti[live], tr[live], pr[live]
        # one node set per resolution: a geometry's value does not depend on the others in the call
        uniq, inv = np.unique(ti, return_inverse=True)
        res = np.array([self.resolution_at(float(t)) for t in uniq], dtype=int)[inv]
        for r in np.unique(res):
            idx = np.flatnonzero(res == r)
            out[:, live[idx]] = self._superpose(ti[idx], tr[idx], pr[idx], int(r))
        return out

    # -- resolution="auto": refined to tol (module docstring, Accuracy) ---------------------------
    def accuracy(self, theta_i, theta_r, phi_r=0.0):
        """The ``"auto"`` evaluation of the exact superposition with its error estimates
        (:class:`Accuracy`), whatever ``resolution`` and ``method`` this instance has (a single
        model: not a model set, whose elements :meth:`mueller` evaluates one by one)."""
        if self._sets:
            raise ValueError("accuracy() takes a single model, not a model set (array parameters)")
        auto = (
            self
            if (self.resolution, self.method) == ("auto", "exact")
            else self.replace(resolution="auto", method="exact")
        )
        shape, (ti, tr, pr) = auto._angles(theta_i, theta_r, phi_r)
        if auto.distance == math.inf or auto.sample_radius / auto.distance == 0.0:
            M = auto.model._m16(ti, tr, pr)
            res = _Result(M, np.zeros(ti.size), np.abs(M[0]), np.ones(ti.size, int), np.zeros(ti.size, bool))
        else:
            res = auto._auto(ti, tr, pr)
        return Accuracy(
            np.moveaxis(res.mueller.reshape((4, 4) + shape), (0, 1), (-2, -1)),
            *(a.reshape(shape) for a in (res.error, res.scale, res.evaluations, res.capped)),
        )

    @cached_property
    def _scale_cache(self):
        """``{theta_i: M00_c}``, filled as incidences are met (dropped with the parameters)."""
        return {}

    def _scales(self, ti):
        """``M00_c`` per geometry: the value at the inner lobe's centre at its incidence, itself
        refined to ``tol`` relative to itself (0 without a lobe)."""
        cache = self._scale_cache
        uniq, inv = np.unique(ti, return_inverse=True)
        todo = [float(t) for t in uniq if float(t) not in cache]
        lobes = [self.model.lobe(t) for t in todo]
        at = [(t, lb) for t, lb in zip(todo, lobes, strict=True) if lb is not None and t < 0.5 * math.pi]
        cache.update((t, 0.0) for t in todo)
        if at:
            c = np.array([[t, lb[0], lb[1]] for t, lb in at]).T
            ok = c[1] <= 0.5 * math.pi  # a lobe centre below the horizon: no scale there
            if ok.any():
                m = self._refined(c[0][ok], c[1][ok], c[2][ok], np.zeros(int(ok.sum())))
                cache.update(zip(c[0][ok].tolist(), np.abs(m.mueller[0]).tolist(), strict=True))
        out = np.array([cache[float(t)] for t in uniq])[inv]
        if len(cache) > 4096:  # a bound on what a long run of distinct incidences keeps
            cache.clear()
        return out

    def _auto(self, ti, tr, pr):
        """``resolution="auto"`` on flat angles: :class:`_Result`, zeros at grazing incidence."""
        n = ti.size
        res = _Result(np.zeros((16, n)), np.zeros(n), np.zeros(n), np.zeros(n, int), np.zeros(n, bool))
        live = np.flatnonzero(ti < 0.5 * math.pi)
        if live.size:
            got = self._refined(ti[live], tr[live], pr[live], self._scales(ti[live]))
            for f in dataclasses.fields(res):
                getattr(res, f.name)[..., live] = getattr(got, f.name)
        return res

    def _refined(self, ti, tr, pr, scale):
        """Every geometry refined until its estimated error is within ``tol * max(M00, scale)``."""
        disc = _Disc(self, ti, tr, pr)
        n = ti.size
        res = _Result(np.zeros((16, n)), np.zeros(n), np.zeros(n), np.zeros(n, int), np.zeros(n, bool))
        todo = np.arange(n)
        broad = np.flatnonzero(~(disc.spread > _BROAD * disc.width))  # also: no specular lobe (nan)
        if broad.size:
            done = self._first_try(disc, broad, scale[broad], res)
            todo = np.setdiff1d(todo, broad[done])
        if todo.size:
            self._cubature(disc, todo, scale[todo], res)
        return res

    @cached_property
    def _isotropic(self):
        return is_isotropic(self.model)

    @cached_property
    def _rotates(self):
        """True when the local models can be evaluated in one call: an isotropic inner model, or
        one whose ``rotated`` takes an array of angles (a model set)."""
        return self._isotropic or rotated_set(self.model, np.array([0.0, 1.0])) is not None

    def _local(self, psi, Phi, tr, pr):
        """The inner model's Mueller elements ``(16, m, P)`` at local incidences ``(psi, Phi)``
        ``(m, P)`` for the observations ``(tr, pr)`` ``(m,)``: the sample rotated by ``-Phi``."""
        m, P = psi.shape
        psi, Phi, tr, pr = psi.ravel(), Phi.ravel(), np.repeat(tr, P), (pr[:, None] - Phi).ravel()
        if self._rotates:
            model = self.model if self._isotropic else self.model.rotated(-Phi)
            return model._m16(psi, tr, pr).reshape(16, m, P)
        # a sample that cannot rotate by an array: one call per distinct azimuth (the product
        # rule's nodes share theirs across the geometries of an incidence; the cubature's do not)
        out = np.empty((16, psi.size))
        uniq, inv = np.unique(Phi, return_inverse=True)
        order = np.argsort(inv, kind="stable")
        ends = np.searchsorted(inv[order], np.arange(uniq.size + 1))
        for j, phi in enumerate(uniq.tolist()):
            idx = order[ends[j] : ends[j + 1]]
            out[:, idx] = self.model.rotated(-phi)._m16(psi[idx], tr[idx], pr[idx])
        return out.reshape(16, m, P)

    def _first_try(self, disc, rows, scale, res):
        """The product rule in ``(t, chi)`` at 4 and 8 radial nodes on ``rows``; where the two agree
        within the budget the 8-node value is kept (in ``res``).  Returns the settled mask."""
        vals = []
        for n_r in _FIRST:
            t, chi, w = _product_nodes(n_r)
            step = max(1, _BLOCK // t.size)
            vals.append(np.concatenate([_weighted_mean(*disc.values(rows[a:a + step], t, chi, w))
                                        for a in range(0, rows.size, step)], axis=1))  # fmt: skip
        coarse, fine = vals
        err = np.max(np.abs(fine - coarse), axis=0)
        sc = np.maximum(np.abs(fine[0]), scale)
        done = err <= self.tol * sc
        res.evaluations[rows] = sum(2 * n * n for n in _FIRST)
        take = rows[done]
        res.mueller[:, take], res.scale[take] = fine[:, done], sc[done]
        res.error[take] = _ratio(err[done], sc[done])
        return done

    def _cubature(self, disc, rows, scale, res):
        """Adaptive cubature over the cells of ``rows`` (module docstring, Accuracy), into ``res``."""
        cells = disc.cells(rows)
        tol = self.tol

        def integrand(cell, u, v):
            t, chi, w = cells.point(cell, u, v)
            return disc.values(rows[cells.row[cell]], t, chi, w)

        def norm(diff, total):
            return np.max(diff[:16] + np.abs(total[:16] / total[16]) * diff[16], axis=0)

        def budget(total):
            return tol * np.maximum(np.abs(total[0] / total[16]), scale) * total[16]

        got = cubature.adaptive(integrand, cells.row, rows.size, norm, budget, MAX_REGIONS)
        W = got.value[16]
        M = got.value[:16] / W
        sc = np.maximum(np.abs(M[0]), scale)
        res.mueller[:, rows], res.scale[rows], res.capped[rows] = M, sc, got.capped
        res.error[rows] = _ratio(got.error / W, sc)
        res.evaluations[rows] += cubature.GM_POINTS * got.evaluated  # split regions included

    def _superpose(self, ti, tr, pr, resolution):
        """Eq. 28 (or the shift approximation) at ``resolution`` radial nodes: ``(16, n)``."""
        out = np.zeros((16, ti.size))
        psi, Phi, w = self.source_nodes(ti, resolution)
        if self.method == "shift":
            tt = tr[:, None] + (ti[:, None] - psi)
            pp = pr[:, None] - Phi
            neg = tt < 0.0
            tt = np.abs(tt)
            pp = np.where(neg, pp + math.pi, pp)
            ok = tt < 0.5 * math.pi
            self._accumulate(out, self.model, np.broadcast_to(ti[:, None], tt.shape), tt, pp, w * ok, ok)
            return out
        step = max(1, _BLOCK // ti.size)  # the local models in one call per block of nodes
        for k0 in range(0, psi.shape[1], step):
            sl = slice(k0, k0 + step)
            out += np.einsum("eik,ik->ei", self._local(psi[:, sl], Phi[:, sl], tr, pr), w[:, sl])
        return out

    @staticmethod
    def _accumulate(out, model, a, b, c, w, ok):
        """``out[:, i] += sum_k w[i, k] M(a[i, k], b[i, k], c[i, k])`` in bounded blocks."""
        n, K = w.shape
        a = np.ascontiguousarray(np.broadcast_to(a, (n, K)))
        b = np.ascontiguousarray(np.broadcast_to(b, (n, K)))
        c = np.ascontiguousarray(np.broadcast_to(c, (n, K)))
        if ok is not None:
            b = np.where(ok, b, 0.0)  # weight is 0 there; any valid angle will do
        step = max(1, _BLOCK // n)
        for k0 in range(0, K, step):
            sl = slice(k0, min(K, k0 + step))
            kb = sl.stop - sl.start
            M = model._m16(a[:, sl].ravel(), b[:, sl].ravel(), c[:, sl].ravel())
            out += np.einsum("eik,ik->ei", M.reshape(16, n, kb), w[:, sl])

    def brdf_grid(self, theta_i, theta_r, phi_r):
        """``M00`` on the grid ``theta_r x phi_r`` (1-D, uniformly spaced, ascending)
        at one incidence ``theta_i``; shape ``(len(theta_r), len(phi_r))``.

        ``exact``: the pointwise superposition at every grid point.  ``shift``:
        Eq. 30, one evaluation of the central BRDF on the (extended) grid and an
        FFT correlation with the splatted weights; the values are exact at grid
        nodes up to the shift approximation and the bilinear interpolation of
        the central BRDF between nodes.
        """
        tr = np.asarray(theta_r, dtype=float)
        pr = np.asarray(phi_r, dtype=float)
        for name, g in (("theta_r", tr), ("phi_r", pr)):
            if (
                g.ndim != 1
                or g.size < 2
                or not np.allclose(np.diff(g), g[1] - g[0], rtol=1e-9, atol=1e-12)
                or g[1] <= g[0]
            ):
                raise ValueError(f"{name} must be a 1-D ascending, uniformly spaced grid of >= 2 points")
        if self.method == "exact" or self.distance == math.inf:
            T, P = np.meshgrid(tr, pr, indexing="ij")
            return self.brdf(theta_i, T, P)
        ti = float(theta_i)
        psi, Phi, w = (a[0] for a in self.source_nodes(ti))
        dt, dp = tr[1] - tr[0], pr[1] - pr[0]
        # Offsets of the central BRDF to read at: theta + (psi_c - psi_k), phi - Phi_k.
        ot = (ti - psi) / dt
        op = -Phi / dp
        i0, j0 = np.floor(ot).astype(int), np.floor(op).astype(int)
        ft, fp = ot - i0, op - j0
        imin, imax = i0.min(), i0.max() + 1
        jmin, jmax = j0.min(), j0.max() + 1
        K = np.zeros((imax - imin + 1, jmax - jmin + 1))
        for di, dj, ww in (
            (0, 0, (1 - ft) * (1 - fp)),
            (1, 0, ft * (1 - fp)),
            (0, 1, (1 - ft) * fp),
            (1, 1, ft * fp),
        ):
            np.add.at(K, (i0 - imin + di, j0 - jmin + dj), w * ww)
        # Central BRDF on the extended grid (negative theta continued through the normal).
        te = tr[0] + dt * np.arange(imin, len(tr) + imax)
        pe = pr[0] + dp * np.arange(jmin, len(pr) + jmax)
        T, P = np.meshgrid(te, pe, indexing="ij")
        neg = T < 0
        T = np.abs(T)
        P = np.where(neg, P + math.pi, P)
        ok = T < 0.5 * math.pi
        F = np.zeros(T.shape)
        F[ok] = self.model.brdf(ti, T[ok], P[ok])
        return signal.correlate(F, K, mode="valid", method="fft")


@dataclass
class _Result:
    """Flat ``"auto"`` results: Mueller elements ``(16, n)`` and per-geometry estimates."""

    mueller: np.ndarray
    error: np.ndarray
    scale: np.ndarray
    evaluations: np.ndarray
    capped: np.ndarray


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


class _Disc:
    """The disc as the ``"auto"`` quadrature sees it, per geometry (module docstring, Accuracy).

    Lengths on the disc are in units of its radius ``R``; the source's height ``d`` enters
    through ``k = R / d``.  Polar coordinates about ``O``, the foot ``H`` of the source when it
    lies on the disc, else the centre: a point is ``O + t rho(chi) (cos chi, sin chi)``, ``rho``
    the distance from ``O`` to the rim.  The quadrature's radial variable ``v`` is ``t`` about
    the centre; about ``H`` it absorbs the irradiance: ``v^2`` is the share of the ray's flux
    within ``r = t rho`` (``cos^3 psi r dr`` with ``tan psi = k r``), so that a source near the
    plane, whose flux falls within a few ``d`` of ``H``, is no harder than a far one, while
    ``v`` stays linear in ``r`` at ``H``.  ``width``: the inner model's lobe width at the
    central incidence where its lobe is specular (centred at ``(theta_i, 0)``, so that its peak
    or cusp sits at ``P*``), nan otherwise; ``spread``: the incidence spread.
    """

    def __init__(self, ps, ti, tr, pr):
        self.ps, self.tr, self.pr = ps, tr, pr
        self.k = min(ps.sample_radius / ps.distance, 1e300)
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
        self.width = np.full(ti.size, np.nan)
        self.spread = np.zeros(ti.size)
        uniq, inv = np.unique(ti, return_inverse=True)
        for j, t in enumerate(uniq.tolist()):
            lb = ps.model.lobe(t)
            lo, hi = ps.incidence_range(t)
            self.spread[inv == j] = hi - lo
            if lb is not None and lb[0] == t and lb[1] == 0.0:
                self.width[inv == j] = lb[2]

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
        return self.ps._local(psi, Phi, self.tr[rows], self.pr[rows]), J

    def _angles_compiled(self, rows, v, chi, w):
        """:meth:`angles` compiled (:mod:`scatterbench.models.kernels.disc`, held to it)."""
        from .kernels import disc  # numba (heavy): compiled kernels load when one first runs

        shape = np.broadcast_shapes((rows.size, 1), np.shape(v), np.shape(chi), np.shape(w))
        v, chi, w = (np.ascontiguousarray(np.broadcast_to(a, shape), dtype=float) for a in (v, chi, w))
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
