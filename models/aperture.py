"""A detector of finite aperture around any reflection model.

A real scatterometer does not measure the BRDF in one direction: its detector
collects the light scattered into a cone of full angle ``aperture`` around the
nominal direction ``(theta_r, phi_r)`` (seed 000 Sec. 3 measured with a
0.7 deg aperture).  The measured BRDF is the flux into the cone over the
incident flux and the cone's projected solid angle,

    f_meas = integral_cone f(k) cos(theta_k) dOmega / integral_cone cos(theta_k) dOmega,

so a Lambertian surface reads its own BRDF for any aperture; directions below
the horizon (a cone that reaches past grazing) carry no light and no weight.

Quadrature.  With the polar offset ``u`` from the nominal axis and
``r = 2 sin(u / 2)``, the solid-angle element is ``r dr dchi`` (Lambert's
equal-area map), so the cone is a disc of radius ``2 sin(aperture / 4)`` and
:func:`scatterbench.models.geometry.disc_quadrature` applies (``resolution`` Gauss-Legendre
radial nodes x ``2 resolution`` azimuths).

Polarization.  The model's Mueller matrix at a direction ``k`` of the cone is in
``k``'s own ``(s, p)`` basis; the detector's analyzer is fixed in the
laboratory.  Each node's matrix is therefore re-expressed, before averaging, in
the nominal basis carried to ``k``: ``s' = unit(s_r - (s_r . k) k)``,
``p' = k x s'`` (the Jones rotation ``E_s' = c E_s + s E_p``, ``E_p' = -s E_s +
c E_p`` with ``c = s' . s_k``, ``s = s' . p_k``, through the one Jones-to-Mueller
map).  Without this, a cone around the surface normal, where the local ``s``
vector turns through every azimuth, would average polarization away.

The result is a sum of Mueller matrices (depolarizing) and not reciprocal (the
aperture is on the detector only).  ``aperture = 0`` is the model itself.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np

from . import evaluation
from .base import Model, _Wrapper
from .constraints import Instance, Integer, Interval, ScalarOrArray
from .facts import Correspondence
from .geometry import disc_quadrature, scattered_direction, sp_basis_angles
from .params import param
from .polarization import mueller16_from_jones
from .slopes import ExponentialSlopes
from .subsurface_facet import SubsurfaceFacetBRDF

__all__ = ["DetectorAperture"]

#: inner-model evaluations per block (bounds the temporaries of one block)
_BLOCK = 1 << 15


@dataclass(frozen=True)
class DetectorAperture(_Wrapper):
    """A model seen by a detector whose aperture is a cone of full angle ``aperture``.

    Parameters
    ----------
    model : Model
        Any reflection model.
    aperture : float
        Full cone angle of the detector (radians), in [0, pi/2]; 0: the model itself.
    resolution : int
        Radial quadrature nodes over the cone (azimuthal nodes: twice as many).
    """

    model: Model = param(
        dataclasses.MISSING,
        "the model seen through the aperture",
        Instance(Model, text="a reflection model (models.Model)"),
    )
    # swept at a point, a hair, seed 000's 0.7 deg and the widest cone allowed
    aperture: float = param(
        math.radians(0.7),
        "full cone angle of the detector (rad)",
        ScalarOrArray(Interval(0.0, 0.5 * math.pi)),
        edges=(0.0, 1e-6, math.radians(0.7), 0.5 * math.pi),
    )
    resolution: int = param(4, "radial quadrature nodes over the cone", Integer(1, 256), edges=(1, 64))

    correspondence = Correspondence("detector aperture around any model (no seed equation)")

    @classmethod
    def sweep_base(cls):
        """A narrow lobe (rms slope 0.02) under seed 000's 0.7 deg aperture: the aperture matters."""
        return cls(model=SubsurfaceFacetBRDF(slopes=ExponentialSlopes(0.02)), aperture=math.radians(0.7))

    def lobe(self, theta_i):
        lb = self.model.lobe(theta_i)
        return None if lb is None else (lb[0], lb[1], lb[2] + 0.5 * self.aperture)

    @property
    def _nodes(self):
        """Unit offsets ``(a, b)`` along the nominal ``(p_r, s_r)`` axes, ``cos u`` and area
        weights (read-only, shared by every aperture of the same size and resolution)."""
        return _unit_nodes(self.resolution, self.aperture)

    def directions(self, theta_r, phi_r, nodes=slice(None)):
        """Directions ``(n, K, 3)`` of the quadrature nodes (``nodes``: a slice of them)
        in the cones around the nominal directions, and their unnormalized weights
        ``(n, K)``: ``cos theta_k dOmega``, zero below the horizon."""
        a, b, cos_u, w = (v[nodes] for v in self._nodes)
        kr = scattered_direction(theta_r, phi_r)
        s_r, p_r = sp_basis_angles(theta_r, phi_r)
        k = (
            cos_u[None, :, None] * kr[:, None, :]
            + a[None, :, None] * p_r[:, None, :]
            + b[None, :, None] * s_r[:, None, :]
        )
        return k, w[None, :] * np.maximum(k[..., 2], 0.0)

    def _mueller16(self, ti, tr, pr):
        if self.aperture == 0.0:
            return self.model.flat_mueller16(ti, tr, pr)
        if evaluation.current_backend() == "numba":
            return self._mueller16_compiled(ti, tr, pr)
        n = ti.size
        out = np.empty((16, n))
        K = self._nodes[0].size
        step = max(1, _BLOCK // K)  # geometries per block, with all their nodes
        for g0 in range(0, n, step):
            g = slice(g0, min(n, g0 + step))
            th, ph, wt, c2, s2 = _Frame(tr[g], pr[g]).nodes(*self._nodes)
            M = self.model.flat_mueller16(np.repeat(ti[g], K), th.ravel(), ph.ravel()).reshape(16, -1, K)
            out[:, g] = _rotate_rows_and_sum(M, wt, c2, s2) / wt.sum(axis=1)
        return out

    def _mueller16_compiled(self, ti, tr, pr):
        """:meth:`_mueller16` with the node algebra and the rotated sum compiled
        (:mod:`scatterbench.models.kernels.aperture`, held to the numpy route above), the inner model
        evaluated once per block of :data:`_BLOCK` nodes (``python benchmarks/wrappers.py
        --blocks``, one run: blocks of 2^12 to 2^15 nodes alike, 1.7-2.5 us per geometry; 2^16,
        whose 16 result rows are 8 MB, 2.8-3.3 from 8000 geometries on)."""
        from .kernels import aperture as kernel  # numba (heavy): compiled kernels load when one first runs

        a, b, cos_u, w = self._nodes
        K, n = a.size, ti.size
        ti, tr, pr = (np.require(x, np.float64, ["C", "W"]) for x in (ti, tr, pr))
        out = np.empty((16, n))
        step = max(1, _BLOCK // K)
        for g0 in range(0, n, step):
            m = min(n, g0 + step) - g0
            at = np.empty((kernel.ROWS, K * m))
            g = slice(g0, g0 + m)
            kernel.nodes(ti[g], tr[g], pr[g], a, b, cos_u, w, at)
            M = self.model.flat_mueller16(at[kernel.TI], at[kernel.THETA], at[kernel.PHI])
            kernel.rotate_sum(M, at, m, out, g0)
        return out

    def _mueller16_reference(self, ti, tr, pr):
        """:meth:`_mueller16` the direct way, kept as the reference the tests hold it to
        (1e-12 of ``M00``): the node directions as vectors, their angles by ``arctan2``, both
        bases built and the analyzer basis carried over by projection, and
        each node's full ``4 x 4`` rotation applied by a matrix product."""
        if self.aperture == 0.0:
            return self.model.flat_mueller16(ti, tr, pr)
        n = ti.size
        out = np.zeros((16, n))
        wsum = np.zeros(n)
        s_r, _ = sp_basis_angles(tr, pr)
        K = self._nodes[0].size
        step = max(1, _BLOCK // n)
        for k0 in range(0, K, step):
            sl = slice(k0, min(K, k0 + step))
            k, wt = self.directions(tr, pr, sl)
            kb = wt.shape[1]
            # the polar angle from both components (arccos of k_z alone loses digits near the
            # normal: at 0.3 deg from it, 2e-14 rad); dead nodes (weight 0) at 0
            th = np.where(wt > 0, np.arctan2(np.hypot(k[..., 0], k[..., 1]), k[..., 2]), 0.0)
            ph = np.arctan2(k[..., 1], k[..., 0])
            s_k, p_k = sp_basis_angles(th, ph)  # the basis the model's matrix at (th, ph) is in
            sa = s_r[:, None, :] - np.sum(s_r[:, None, :] * k, axis=-1, keepdims=True) * k
            sa /= np.linalg.norm(sa, axis=-1, keepdims=True)
            c = np.sum(sa * s_k, axis=-1)
            s = np.sum(sa * p_k, axis=-1)
            zero = np.zeros_like(c)
            R = mueller16_from_jones((c, zero), (s, zero), (-s, zero), (c, zero)).reshape(4, 4, n, kb)
            M = self.model.flat_mueller16(np.repeat(ti, kb), th.ravel(), ph.ravel()).reshape(4, 4, n, kb)
            out += np.einsum("ijnk,jlnk,nk->iln", R, M, wt).reshape(16, n)
            wsum += wt.sum(axis=1)
        return out / wsum


@functools.lru_cache(maxsize=64)
def _unit_nodes(resolution, aperture):
    """:attr:`DetectorAperture._nodes`, computed once per size and resolution: a fit builds the
    aperture afresh for every evaluation, and the rule took 50 us per instance
    (``python benchmarks/kernel_ab.py --what wrappers`` against d6f7214, fresh instances: 1.60x
    faster at 1 geometry, 1.20x at 50, 1.05x at 800)."""
    # only the weights' ratios matter (the cone's area ~aperture^2 underflows)
    x, y, w = disc_quadrature(resolution, 2.0 * math.sin(0.25 * aperture), unit_weights=True)
    r = np.hypot(x, y)
    cos_u = 1.0 - 0.5 * r * r  # r = 2 sin(u/2)
    sin_u = r * np.sqrt(np.maximum(1.0 - 0.25 * r * r, 0.0))  # sin u = 2 sin(u/2) cos(u/2)
    scale = np.where(r > 0, sin_u / np.where(r > 0, r, 1.0), 0.0)
    out = (x * scale, y * scale, cos_u, w)
    for v in out:
        v.flags.writeable = False
    return out


class _Frame:
    """The nominal directions' frames ``(k_r, p_r, s_r)``, for the node algebra of
    :meth:`DetectorAperture._mueller16`.

    A node ``k = cos_u k_r + a p_r + b s_r`` has the height ``k_z = cos_u cos tr + a p_rz``,
    horizontal components ``(h, b)`` along ``(cos pr, sin pr)`` and ``s_r`` with
    ``h = cos_u sin tr - a cos tr``, so its azimuth is ``pr + arctan2(b, h)``.  The
    analyzer basis carried to ``k`` (``s_r`` less its ``k`` part) makes with the node's own
    ``(s_k, p_k)`` the Jones rotation ``(c, s)``, proportional to ``(s_r . (z x k),
    s_r . (k x (z x k))) = (h, -k_z b)``; only the double angle enters the Mueller
    rotation, ``cos 2x = (c^2 - s^2) / (c^2 + s^2)``, ``sin 2x = 2 c s / (c^2 + s^2)``, so
    nothing is normalized and no basis vector is built.
    """

    def __init__(self, tr, pr):
        _, p_r = sp_basis_angles(tr, pr)
        self.ct, self.st = np.cos(tr)[:, None], np.sin(tr)[:, None]
        self.prz = p_r[:, 2][:, None]  # = sin tr, rounded as the vector form rounds it
        self.pr = pr[:, None]

    def nodes(self, a, b, cos_u, w):
        """``(theta, phi, weight, cos 2x, sin 2x)``, each ``(n, K)``, of the nodes given by the
        offsets ``a``, ``b`` along ``p_r``, ``s_r``, ``cos u`` and area weights ``w`` (``(K,)``)."""
        kz = cos_u * self.ct + a * self.prz
        wt = w * np.maximum(kz, 0.0)
        h = cos_u * self.st - a * self.ct
        b = np.broadcast_to(b, h.shape)
        # the polar angle from the horizontal part (h, b) and k_z: arccos(k_z) lost digits
        # near the normal (2e-14 rad at 0.3 deg, 6e-12 of a Gaussian lobe's tail); dead
        # nodes (weight 0) at 0
        th = np.where(wt > 0, np.arctan2(np.sqrt(h * h + b * b), kz), 0.0)
        ph = self.pr + np.arctan2(b, h)
        c, s = h, -kz * b
        cc, ss = c * c, s * s
        q = cc + ss
        if not q.min() > 1e-280:  # squares near underflow (a node near the normal): scale them first
            return th, ph, wt, *_double_angle_scaled(c, s)
        iq = 1.0 / q
        return th, ph, wt, (cc - ss) * iq, 2.0 * c * s * iq


def _double_angle_scaled(c, s):
    """``(cos 2x, sin 2x)`` of the angle of ``(c, s)``, scaled so that the squares cannot
    underflow; a node exactly on the normal (``c = s = 0``) is in the nominal basis turned by
    its azimuth offset, 0 or pi: ``(1, 0)``."""
    big = np.maximum(np.abs(c), np.abs(s))
    on_axis = big == 0
    c = np.where(on_axis, 1.0, c) / np.where(on_axis, 1.0, big)
    s = np.where(on_axis, 0.0, s) / np.where(on_axis, 1.0, big)
    q = c * c + s * s
    return (c * c - s * s) / q, 2.0 * c * s / q


def _rotate_rows_and_sum(M, wt, c2, s2):
    """``sum_k wt R_k M_k`` ``(16, n)`` for the Mueller rotations ``R_k`` of double angles
    ``(c2, s2)``: ``R`` keeps rows 0 and 3 and turns rows 1-2 by ``[[c2, s2], [-s2, c2]]``,
    so it is applied as weighted sums of the rows (``M``: ``(16, n, K)``)."""
    wc, ws = wt * c2, wt * s2
    m1, m2 = M[4:8], M[8:12]
    return np.concatenate(
        [
            np.einsum("enk,nk->en", M[0:4], wt),
            np.einsum("enk,nk->en", m1, wc) + np.einsum("enk,nk->en", m2, ws),
            np.einsum("enk,nk->en", m2, wc) - np.einsum("enk,nk->en", m1, ws),
            np.einsum("enk,nk->en", M[12:16], wt),
        ]
    )
