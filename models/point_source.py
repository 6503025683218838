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
follow the integrand's features, the lobe about the point whose local specular direction meets
the observer and the incident basis turning about the source's foot.
:mod:`scatterbench.models.disc_cubature` is that quadrature: coordinates about the foot that
absorb the irradiance, cells cut and graded at the lobe, adaptive cubature
(:mod:`scatterbench.models.cubature`), and the product rule first where the lobe is broad.  A
geometry that reaches :data:`MAX_REGIONS` regions stops there with an :class:`AccuracyWarning`
naming how many did and their estimated error; :meth:`PointSourceBRDF.accuracy` returns the
estimates themselves.  An anisotropic inner model is rotated per node as a model set
(``model.rotated(array)``, one call per block of nodes); one whose ``rotated`` takes a single
angle (a user's model) is rotated node by node, one call per distinct azimuth, on the same
nodes: the same quadrature, only slower.

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

from .base import Model, _Wrapper, is_isotropic, rotated_set
from .constraints import Instance, Integer, Interval, OneOf, Options, ScalarOrArray
from .cook_torrance import CookTorranceBRDF
from .cubature import AccuracyWarning
from .disc_cubature import BLOCK, Accuracy, Disc, refine
from .facts import Correspondence
from .geometry import disc_quadrature
from .params import param

__all__ = ["PointSourceBRDF", "point_source_geometry", "Accuracy", "AccuracyWarning", "MAX_REGIONS"]


def point_source_geometry(lo_deg, hi_deg):
    """``(psi_c, d / R)``: the central incidence (radians) and the source height in units
    of the sample radius for which a disc sample spans incidences ``[lo_deg, hi_deg]``.

    With ``x = d tan(psi)`` (Eq. 26) the disc spans ``x_c - R .. x_c + R``:
    ``d / R = 2 / (tan hi - tan lo)`` and ``tan psi_c = (tan lo + tan hi) / 2``.
    Seed 001 prints such ranges for its iron plate but no distance or sample size.
    """
    tl, th = math.tan(math.radians(lo_deg)), math.tan(math.radians(hi_deg))
    return math.atan(0.5 * (tl + th)), 2.0 / (th - tl)


#: :meth:`PointSourceBRDF.resolution_at` (the shift method's node count) for ``"auto"``: nodes
#: per (incidence spread / lobe width), and the bounds
AUTO_FACTOR = 10.0
_AUTO_MIN, _AUTO_MAX = 16, 4096

#: ``resolution="auto"``: the regions per geometry at which refinement stops (each region a
#: 17-point rule: at most ~70,000 inner-model evaluations per geometry)
MAX_REGIONS = 4096
#: a fixed resolution's node arrays per chunk of geometries (bytes; PointSourceBRDF._superpose)
NODE_BYTES = 256 * 2**20
#: float64 arrays of one geometry's nodes alive at once (source_nodes: X, rho, psi, Phi, cos, w;
#: the shift's angles and masks)
NODE_ARRAYS = 8
#: ``tol``: below ~1e-13 the rounding of the sums dominates; above 0.1 it is no statement
_TOL_MIN, _TOL_MAX = 1e-13, 0.1
_TOL_DEFAULT = 1e-4


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
        _TOL_DEFAULT,
        "accuracy of resolution='auto', relative to max(M00, M00 at the lobe centre)",
        Interval(_TOL_MIN, _TOL_MAX),
        edges=(),
    )

    correspondence = Correspondence("seed 001 Eq. 25-30")
    #: the kit's instance: 4 radial nodes over the disc (``"auto"`` refines each geometry to
    #: ``tol``, hundreds to thousands of evaluations; the kit checks the wrapper's shapes and
    #: physics, not its quadrature)
    kit_variant = MappingProxyType({"resolution": 4})

    def _validate(self):
        super()._validate()
        if self.resolution != "auto" and self.tol != _TOL_DEFAULT:
            # a fixed resolution is unrefined: a tol beside it would be silently ignored
            raise ValueError(
                f"tol applies to resolution='auto' only (refined until every element is within tol); "
                f"resolution={self.resolution} is a fixed, unestimated rule: give tol with "
                f"resolution='auto', or a fixed resolution without tol; got tol={self.tol:g}"
            )

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
            return self.model.flat_mueller16(ti, tr, pr)
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
            M = auto.model.flat_mueller16(ti, tr, pr)
            res = Accuracy(M, np.zeros(ti.size), np.abs(M[0]), np.ones(ti.size, int), np.zeros(ti.size, bool))
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
        """``resolution="auto"`` on flat angles: :class:`Accuracy` (flat), zeros at grazing
        incidence."""
        res = Accuracy.zeros(ti.size)
        live = np.flatnonzero(ti < 0.5 * math.pi)
        if live.size:
            got = self._refined(ti[live], tr[live], pr[live], self._scales(ti[live]))
            for f in dataclasses.fields(res):
                getattr(res, f.name)[..., live] = getattr(got, f.name)
        return res

    def _refined(self, ti, tr, pr, scale):
        """Every geometry refined until its estimated error is within ``tol * max(M00, scale)``."""
        return refine(self._disc(ti, tr, pr), scale, self.tol, MAX_REGIONS)

    def _disc(self, ti, tr, pr):
        """The disc as the ``"auto"`` quadrature sees these geometries (:class:`~.disc_cubature.Disc`),
        with the inner lobe's width at each incidence where it is specular (nan elsewhere) and
        the incidence spread."""
        width, spread = np.full(ti.size, np.nan), np.zeros(ti.size)
        uniq, inv = np.unique(ti, return_inverse=True)
        for j, t in enumerate(uniq.tolist()):
            lb = self.model.lobe(t)
            lo, hi = self.incidence_range(t)
            spread[inv == j] = hi - lo
            if lb is not None and lb[0] == t and lb[1] == 0.0:
                width[inv == j] = lb[2]
        return Disc(self.sample_radius / self.distance, ti, tr, pr, width, spread, self._local)

    @cached_property
    def _rotation(self):
        """How :meth:`_local` turns the sample by the nodes' azimuths: ``"none"`` for an isotropic
        inner model (:func:`~scatterbench.models.base.is_isotropic`), ``"set"`` where its
        ``rotated`` takes an array of angles (a model set: one call), ``"each"`` where it takes
        one angle (one call per distinct azimuth)."""
        if is_isotropic(self.model):
            return "none"
        return "set" if rotated_set(self.model, np.array([0.0, 1.0])) is not None else "each"

    def _local(self, psi, Phi, tr, pr):
        """The inner model's Mueller elements ``(16, m, P)`` at local incidences ``(psi, Phi)``
        ``(m, P)`` for the observations ``(tr, pr)`` ``(m,)``: the sample rotated by ``-Phi``."""
        m, P = psi.shape
        psi, Phi, tr, pr = psi.ravel(), Phi.ravel(), np.repeat(tr, P), (pr[:, None] - Phi).ravel()
        if self._rotation != "each":
            model = self.model if self._rotation == "none" else self.model.rotated(-Phi)
            return model.flat_mueller16(psi, tr, pr).reshape(16, m, P)
        # a sample that cannot rotate by an array: one call per distinct azimuth (the product
        # rule's nodes share theirs across the geometries of an incidence; the cubature's do not)
        out = np.empty((16, psi.size))
        uniq, inv = np.unique(Phi, return_inverse=True)
        order = np.argsort(inv, kind="stable")
        ends = np.searchsorted(inv[order], np.arange(uniq.size + 1))
        for j, phi in enumerate(uniq.tolist()):
            idx = order[ends[j] : ends[j + 1]]
            out[:, idx] = self.model.rotated(-phi).flat_mueller16(psi[idx], tr[idx], pr[idx])
        return out.reshape(16, m, P)

    def _superpose(self, ti, tr, pr, resolution):
        """Eq. 28 (or the shift approximation) at ``resolution`` radial nodes: ``(16, n)``,
        in chunks of geometries whose node arrays (``psi``, ``Phi``, ``w`` and the temporaries
        of :meth:`source_nodes` and the shift, :data:`NODE_ARRAYS` arrays of ``2 resolution^2``
        float64 per geometry) stay within :data:`NODE_BYTES`: unchunked they grew as geometries
        x 2 resolution^2 (8 geometries at resolution 2048 needed more than 3 GB).  A geometry's
        value does not depend on the others in its chunk, so the chunks give the same numbers.
        One geometry's arrays are the floor: 200 MB at resolution 2048, 800 MB at 4096."""
        per = NODE_ARRAYS * 8 * 2 * resolution * resolution
        step = max(1, NODE_BYTES // per)
        if ti.size <= step:
            return self._superpose_chunk(ti, tr, pr, resolution)
        out = np.empty((16, ti.size))
        for a in range(0, ti.size, step):
            sl = slice(a, a + step)
            out[:, sl] = self._superpose_chunk(ti[sl], tr[sl], pr[sl], resolution)
        return out

    def _superpose_chunk(self, ti, tr, pr, resolution):
        """:meth:`_superpose` of one chunk of geometries."""
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
        step = max(1, BLOCK // ti.size)  # the local models in one call per block of nodes
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
        step = max(1, BLOCK // n)
        for k0 in range(0, K, step):
            sl = slice(k0, min(K, k0 + step))
            kb = sl.stop - sl.start
            M = model.flat_mueller16(a[:, sl].ravel(), b[:, sl].ravel(), c[:, sl].ravel())
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
        # scipy.signal (with scipy.stats, which it imports) took ~0.4 s of every process's
        # import of the models, a fit worker's included: loaded here, where it is used
        from scipy import signal

        return signal.correlate(F, K, mode="valid", method="fft")
