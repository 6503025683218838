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
(``dA = d^2 tan psi sec^2 psi d psi d Phi``).  The quadrature is Gauss-Legendre
in the radius (``resolution`` nodes, weight ``rho d rho``) times the periodic
trapezoid rule in the azimuth (``2 resolution`` nodes) over the disc.

Resolution.  The nodes must resolve the collimated lobe as the incidence sweeps over the
disc: a fixed 16 leaves Cook-Torrance m = 0.01 at d/R = 3 off by more than half the peak
(``tests/test_point_source_resolution.py`` shows it).  The default ``resolution="auto"``
takes ``N = max(16, ceil(10 s / w))`` per incidence, with ``s`` the incidence spread over
the sample (:meth:`incidence_range`) and ``w`` the inner model's lobe width
(:meth:`Model.lobe`; 16 for a model without a narrow lobe).  For smooth lobes (Gaussian
and Cook-Torrance slopes, GGX) of width 0.02 to 0.2 rad at d/R 1 and 3 the change on
doubling ``N`` is at most 1e-6 of the peak (the same test holds it there).  A cusped lobe
(exponential slopes) converges only algebraically and is not held to that bound: give a
larger ``resolution`` and measure it (``scatterbench tradeoff``'s point-source resolution
knob).  The cost grows as ``N^2`` inner evaluations per geometry.

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
from dataclasses import dataclass

import numpy as np
from scipy import signal

from .base import Model, _Wrapper
from .geometry import disc_quadrature
from .params import param

__all__ = ["PointSourceBRDF", "point_source_geometry"]

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


#: ``resolution="auto"``: nodes per (incidence spread / lobe width), and the bounds
AUTO_FACTOR = 10.0
_AUTO_MIN, _AUTO_MAX = 16, 4096


def _check_resolution(name, r):
    if isinstance(r, str) and r == "auto":
        return r
    if isinstance(r, (int, np.integer)) and not isinstance(r, bool) and 1 <= r <= 4096:
        return int(r)
    raise ValueError(f"{name} must be 'auto' or an integer in [1, 4096]; got {r!r}")


def _check_distance(name, d):
    ok = (
        isinstance(d, (int, float))
        and not isinstance(d, bool)
        and (d == math.inf or (math.isfinite(d) and d > 0))
    )
    if not ok:
        raise ValueError(f"{name} must be a finite real number > 0 or math.inf; got {d!r}")
    return float(d)


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
        Radial quadrature nodes over the disc (azimuthal nodes: twice as many), or
        ``"auto"``: chosen per incidence from the lobe width and the incidence spread
        (module docstring, "Resolution").
    """

    model: Model = param(dataclasses.MISSING, "the collimated model", kind="object")
    distance: float = param(
        100.0, "source height d above the sample plane (> 0, or inf)", kind="object", check=_check_distance
    )
    sample_radius: float = param(1.0, "sample radius R", low=0.0, low_open=True)
    method: str = param(
        "exact", "Eq. 28 superposition or Eq. 29-30 shift", kind="choice", choices=("exact", "shift")
    )
    resolution: int | str = param(
        "auto",
        "radial quadrature nodes over the disc (1-4096), or 'auto' from the lobe width",
        kind="object",
        check=_check_resolution,
    )

    def lobe(self, theta_i):
        lb = self.model.lobe(theta_i)
        if lb is None:
            return None
        lo, hi = self.incidence_range(theta_i)
        return (lb[0], lb[1], lb[2] + (hi - lo))

    # -- source geometry ------------------------------------------------------------
    def resolution_at(self, theta_i):
        """The radial node count used at central incidence ``theta_i`` (a float)."""
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
        if self.distance == math.inf:
            return self.model._m16(ti, tr, pr)
        out = np.zeros((16, ti.size))
        live = ti < 0.5 * math.pi
        if not live.all():
            idx = np.flatnonzero(live)
            if idx.size:
                out[:, idx] = self._mueller16(ti[idx], tr[idx], pr[idx])
            return out
        # one node set per resolution: a geometry's value does not depend on the others in the call
        uniq, inv = np.unique(ti, return_inverse=True)
        res = np.array([self.resolution_at(float(t)) for t in uniq])[inv]
        for r in np.unique(res):
            idx = np.flatnonzero(res == r)
            out[:, idx] = self._superpose(ti[idx], tr[idx], pr[idx], int(r))
        return out

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
        isotropic = self.model.rotated(1.0) is self.model
        if isotropic:
            self._accumulate(
                out, self.model, psi, np.broadcast_to(tr[:, None], psi.shape), pr[:, None] - Phi, w, None
            )
            return out
        # Anisotropic sample: rotate it per node; Phi depends on theta_i only.
        for t in np.unique(ti):
            rows = np.flatnonzero(ti == t)
            j0 = rows[0]
            for k in range(psi.shape[1]):
                m = self.model.rotated(-float(Phi[j0, k]))
                M = m._m16(np.full(rows.size, psi[j0, k]), tr[rows], pr[rows] - Phi[j0, k])
                out[:, rows] += w[j0, k] * M
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
