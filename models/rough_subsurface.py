"""A Lambertian diffuser under a rough interface: the totally diffuse term of seed 003 Sec. 2.5
(Eq. 21, 23, 36) as its expectation over facet pairs, by quadrature instead of Monte Carlo.

:class:`~scatterbench.models.RoughDiffuseBRDF` averages, over pairs of facet slopes
``(zeta_1, zeta_2)`` drawn independently, the product of an entry factor (the incident ray
refracted by ``zeta_1``) and an exit factor (the scattered ray's reversed path refracted by
``zeta_2``).  Without single scattering (``single = 0``) nothing couples the two facets, so the
expectation of the product is the product of the expectations::

    M = (rho / pi) / (1 - rho R-bar) / n^2 * t(theta_r) (x) t(theta_i),
    t(theta) = < w (T_bar, cos(2 eta) dT / 2) >,

with ``w = (cos theta - k_xy . zeta)_+ / N(theta)`` the Eq. 36 weight of the facets a ray at
``theta`` meets, ``T_bar = (T_s + T_p) / 2`` and ``dT = T_s - T_p`` the facet's Fresnel
transmittances at its local incidence, and ``eta`` the angle between the ray's plane of
incidence on the facet and on the mean surface.  The exit factor equals the entry factor (the
facet's transmittance is the same both ways, and the exit's ``1/n^2`` is the ``1/n^2`` above),
which is what makes the model reciprocal.  Only ``M00, M01, M10, M11`` are non-zero (the
``cos 2 eta`` terms odd in ``zeta_y`` average to zero), and an isotropic interface makes ``t``
a function of the polar angle alone.  ``R-bar`` is the rough interface's internal reflectance
(``feedback="rough"``: ``1 - (2 / n^2) int_0^1 t_0(u) u du``, so that at ``rho = 1`` the term
returns all the light that entered) or Sec. 2.3's flat one (``"flat"``).

How ``t`` is computed (the same rule in numpy, the reference, and in the compiled loops of
:mod:`scatterbench.models.kernels.rough`):

* In the slope plane, polar coordinates ``(rho, phi)``: the facets a ray sees are those with
  ``rho cos(phi) < cot(theta)``, an arc of each circle beyond ``rho_0 = cot(theta)``.  The
  radius is split at ``rho_0`` (the arc's length has a square-root onset there; the outer part
  is integrated in ``s`` with ``rho = rho_0 + (rho_max - rho_0) s^2``), Gauss-Legendre
  (:data:`RADIAL` nodes a part, ``rho_max = sqrt(42) sigma``: the Gaussian's tail beyond it
  is 6e-19), and each arc ``[phi_c, pi]`` (mirror symmetry gives the other half) by
  Gauss-Legendre with :data:`ARC` nodes: the integrand is smooth on it.
* The Fresnel transmittances depend on the index and the local cosine alone, so they enter as
  Chebyshev series of degree :data:`MOMENTS` in the local cosine (within 2e-10 for
  ``1.1 <= n <= 2.5``): the quadrature gives the slopes' moments of that basis once per slope
  width, and every index of a joint fit's wavelengths costs a dot product.
* ``t`` is computed at Chebyshev nodes of ``u = cos(theta)`` on two panels, ``[0, u_b]`` and
  ``[u_b, 1]`` with ``u_b = min(1/2, 6 sigma)`` (a narrow interface changes ``t`` within a few
  ``sigma`` of grazing), ``nodes`` a panel, and each geometry's ``t`` is the interpolating
  Chebyshev series there; ``R-bar`` integrates the same node values (Fejer's first rule).

Accuracy (``tests/test_rough_subsurface.py``): against the Monte Carlo model at 400 000 facet
pairs, every element within 4 of its standard errors (a flipped ``cos 2 eta`` or an exit factor
off by ``1/n^2`` gives 1900 and 1500); against the slope quadrature itself at 40 x 24 nodes,
evaluated at each cosine without the interpolation, ``t0`` and ``t1`` within 1e-5 of ``t0`` at
normal incidence for ``sigma`` 0.01-1.5 and ``n`` 1.2-1.7 (measured worst 2.7e-6, at ``sigma``
1.5, where the interpolation in ``u`` converges slowest); more ``nodes`` buy more.  Gaussian
slopes only (their radial density is the one integrated here); other families and single
scattering are :class:`RoughDiffuseBRDF`'s (Monte Carlo).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache, cached_property

import numpy as np

from . import evaluation
from .base import Model
from .constraints import Instance, Integer, Interval, Options, ScalarOrArray
from .facts import Correspondence
from .params import coating_param, param
from .slopes import GaussianSlopes
from .smooth_interface import interface_amplitudes, internal_hemispherical_reflectance

__all__ = ["RoughSubsurfaceBRDF", "transmission_factor", "transmission_at"]

#: Gauss-Legendre nodes per radial part of the slope plane
RADIAL = 20
#: Gauss-Legendre nodes per arc of visible facets
ARC = 10
#: degree of the Chebyshev series of the facet's transmittances in the local cosine
MOMENTS = 20
#: the slope radius integrated to, in units of sigma (the Gaussian's tail beyond: exp(-42))
RHO_MAX = math.sqrt(42.0)


@cache
def _slope_rules(radial=RADIAL, arc=ARC):
    """The slope plane's Gauss-Legendre rules ``(rx, rw, ax, aw)``, radial and arc (read-only)."""
    return _frozen(*np.polynomial.legendre.leggauss(radial), *np.polynomial.legendre.leggauss(arc))


@cache
def _node_rules(nodes):
    """``(x, fejer, dct)``: the ``nodes`` Chebyshev points of the first kind on [-1, 1], Fejer's
    first weights there, and the matrix ``(nodes, nodes)`` taking values at the points to the
    interpolating series' coefficients (read-only)."""
    k = np.arange(nodes)
    tk = np.pi * (k + 0.5) / nodes
    j = np.arange(1, nodes // 2 + 1)
    fejer = (2.0 / nodes) * (
        1.0 - 2.0 * np.sum(np.cos(2.0 * j[None, :] * tk[:, None]) / (4.0 * j * j - 1.0), axis=1)
    )
    x = np.cos(tk)
    scale = np.full(nodes, 2.0 / nodes)
    scale[0] *= 0.5
    return _frozen(x, fejer, np.polynomial.chebyshev.chebvander(x, nodes - 1) * scale)


def _frozen(*arrays):
    for a in arrays:
        a.setflags(write=False)
    return arrays


def _panels(sigma, nodes):
    """``(u_b, u)``: the panel break(s) and the ``2 nodes`` u-nodes (first panel, then second),
    for a slope width or an array of them (``(..., 2 nodes)``)."""
    x = 0.5 * (_node_rules(nodes)[0] + 1.0)
    ub = np.minimum(0.5, 6.0 * np.asarray(sigma, dtype=float))[..., None]
    return ub[..., 0], np.concatenate([ub * x, ub + (1.0 - ub) * x], axis=-1)


def _moments_numpy(sigma, nodes):
    """``(A0, A1)`` ``(2 nodes, MOMENTS + 1)``: the normalized moments ``<w T_m(2 c - 1)>`` and
    ``<w cos(2 eta) T_m(2 c - 1)>`` at the u-nodes of :func:`_panels` (``c``: the local cosine)."""
    return _moments_at(sigma, _panels(sigma, nodes)[1])


def _moments_at(sigma, us, radial=RADIAL, arc=ARC):
    """:func:`_moments_numpy` at cosines ``us`` (and slope-plane rules ``radial``, ``arc``)."""
    rx, rw, ax, aw = _slope_rules(radial, arc)
    rmax = RHO_MAX * sigma
    A0 = np.empty((us.size, MOMENTS + 1))
    A1 = np.empty_like(A0)
    for j, u in enumerate(us):
        s = math.sqrt(1.0 - u * u)
        rho0 = u / s if s > 0.0 else math.inf
        rho, wr = _radial_nodes(rho0, rmax, rx, rw)
        wr = wr * rho * np.exp(-((rho / sigma) ** 2))
        ratio = np.minimum(rho0 / rho, 1.0)
        phic = np.arccos(ratio)[:, None]
        half = 0.5 * (math.pi - phic)
        phi = phic + half * (ax[None, :] + 1.0)
        weight = (wr[:, None] * half * aw[None, :]).ravel()
        zx = (rho[:, None] * np.cos(phi)).ravel()
        q2 = np.repeat(1.0 + rho * rho, arc)
        proj = np.maximum(u - s * zx, 0.0)
        c = np.minimum(proj / np.sqrt(q2), 1.0)
        km2 = q2 - proj * proj
        safe = km2 > 1e-300
        cos2 = np.where(safe, 2.0 * (u * zx + s) ** 2 / np.where(safe, km2, 1.0) - 1.0, 1.0)
        T = np.polynomial.chebyshev.chebvander(2.0 * c - 1.0, MOMENTS)  # (nodes, M + 1)
        wp = weight * proj
        norm = np.sum(wp)
        A0[j] = (wp @ T) / norm
        A1[j] = ((wp * cos2) @ T) / norm
    return A0, A1


def _radial_nodes(rho0, rmax, rx, rw):
    """Radii and weights of the slope plane's radial rule: ``[0, min(rho0, rmax)]`` plain, then
    ``[rho0, rmax]`` in ``s`` (``rho = rho0 + (rmax - rho0) s^2``) where ``rho0 < rmax``."""
    a = min(rho0, rmax)
    r1 = 0.5 * a * (rx + 1.0)
    w1 = 0.5 * a * rw
    if rho0 >= rmax:
        return r1, w1
    sv = 0.5 * (rx + 1.0)
    r2 = rho0 + (rmax - rho0) * sv * sv
    w2 = (rmax - rho0) * sv * rw  # d rho = 2 (rmax - rho0) s ds, ds = dx / 2
    return np.concatenate([r1, r2]), np.concatenate([w1, w2])


def _fresnel_series(n):
    """Chebyshev coefficients ``(a, b)`` ``(..., MOMENTS + 1)`` in ``x = 2 c - 1`` of
    ``(T_s + T_p) / 2`` and ``(T_s - T_p) / 2`` at local cosine ``c`` entering index ``n`` (a
    float or an array): the smooth interface's amplitudes
    (:func:`~scatterbench.models.smooth_interface.interface_amplitudes`, ``T = n a^2``)
    interpolated at the ``MOMENTS + 1`` Chebyshev points."""
    x, _, dct = _node_rules(MOMENTS + 1)
    n = np.asarray(n, dtype=float)[..., None]
    _, _, a_s, a_p = interface_amplitudes(0.5 * (x + 1.0), n)
    ts, tp = n * a_s * a_s, n * a_p * a_p
    return (0.5 * (ts + tp)) @ dct, (0.5 * (ts - tp)) @ dct


def transmission_factor(sigma, n, nodes=17):
    """``(u, t0, t1)``: the factor ``t`` of the module docstring at the u-nodes, for Gaussian
    slopes of rms slope ``sigma`` and index ``n`` (numpy: the reference)."""
    A0, A1 = _moments_numpy(sigma, nodes)
    a, b = _fresnel_series(n)
    return _panels(sigma, nodes)[1], A0 @ a, A1 @ b


def transmission_at(sigma, n, u, radial=RADIAL, arc=ARC):
    """``(t0, t1)`` at cosines ``u`` by the slope-plane quadrature itself, without the
    interpolation in ``u`` (finer ``radial``, ``arc``: a reference for the model's rule)."""
    A0, A1 = _moments_at(sigma, np.asarray(u, dtype=float).reshape(-1), radial, arc)
    a, b = _fresnel_series(n)
    return A0 @ a, A1 @ b


def _tables(sigma, n, rho, nodes, feedback):
    """``(coef (E, 2, 2, nodes), ub (E,), scale (E,))`` for elements ``(sigma, n, rho)``: each
    panel's Chebyshev coefficients of ``t0`` and ``t1`` in ``cos(theta)``, the panel break, and
    ``(rho / pi) / (1 - rho R-bar) / n^2``, from the u-node values of :func:`_node_values`, for
    all elements at once."""
    t0, t1 = _node_values(sigma, n, nodes)
    dct = _node_rules(nodes)[2]
    coef = np.stack([t0.reshape(-1, 2, nodes) @ dct, t1.reshape(-1, 2, nodes) @ dct], axis=2)
    ub = _panels(sigma, nodes)[0]
    rbar = _rbar(sigma, n, nodes, t0) if feedback == "rough" else _flat_rbar(n)
    return coef, ub, (rho / math.pi) / (1.0 - rho * rbar) / (n * n)


def _node_values(sigma, n, nodes):
    """``(t0, t1)`` ``(E, 2 nodes)`` at the u-nodes of elements ``(sigma, n)`` (flat arrays): the
    slope quadrature once per distinct width (compiled on the numba backend,
    :mod:`scatterbench.models.kernels.rough`), the Fresnel series for all elements at once."""
    widths, which = np.unique(sigma, return_inverse=True)
    compiled = _compiled()
    if compiled is not None:
        A0, A1 = compiled.moments(widths, nodes, *_slope_rules(), _node_rules(nodes)[0])
    else:
        A0, A1 = (np.stack(m) for m in zip(*(_moments_numpy(float(w), nodes) for w in widths), strict=True))
    which = which.reshape(-1)
    a, b = _fresnel_series(n)
    return np.einsum("ejm,em->ej", A0[which], a), np.einsum("ejm,em->ej", A1[which], b)


def _rbar(sigma, n, nodes, t0):
    """The rough interface's R-bar, ``1 - (2 / n^2) int_0^1 t0(u) u du``, from the u-node values
    ``t0`` ``(..., 2 nodes)`` (Fejer's rule on each panel)."""
    ub, u = _panels(sigma, nodes)
    f = _node_rules(nodes)[1]
    w = np.concatenate([0.5 * ub[..., None] * f, 0.5 * (1.0 - ub[..., None]) * f], axis=-1)
    return 1.0 - 2.0 / (n * n) * np.sum(w * u * t0, axis=-1)


def _flat_rbar(n):
    """Sec. 2.3's flat R-bar of each index (its quadrature once per distinct index)."""
    values, inverse = np.unique(n, return_inverse=True)
    return np.array([internal_hemispherical_reflectance(float(v)) for v in values])[inverse.reshape(-1)]


@dataclass(frozen=True)
class RoughSubsurfaceBRDF(Model):
    """Lambertian diffuser under a rough interface (seed 003 Sec. 2.5's totally diffuse term,
    Eq. 21, 23, 36), its expectation over facet pairs by quadrature: no Monte Carlo error.

    Parameters
    ----------
    slopes : GaussianSlopes
        Gaussian facet slopes of the interface (coverage 1).
    coating : float
        Real index ``n`` of the binder above the diffuser.
    rho : float
        Diffuse reflectance of the material under the interface, in [0, 1].
    feedback : str
        ``"rough"``: R-bar of Eq. 23 is the rough interface's internal reflectance; ``"flat"``:
        Sec. 2.3's flat one (as :class:`RoughDiffuseBRDF`).
    nodes : int
        Chebyshev nodes of ``cos(theta)`` per panel (speed against accuracy).
    """

    slopes: GaussianSlopes = param(
        GaussianSlopes(0.2),
        "Gaussian facet slopes of the interface (coverage 1)",
        Instance(GaussianSlopes, text="a models.GaussianSlopes"),
    )
    coating: float = coating_param(
        1.5, "index n of the binder above the diffuser, entered through the rough interface (real)"
    )
    rho: float = param(
        0.93, "diffuse reflectance of the material under the interface", ScalarOrArray(Interval(0.0, 1.0))
    )
    feedback: str = param(
        "rough", "R-bar of Eq. 23: of the rough interface or of the flat one", Options("rough", "flat")
    )
    nodes: int = param(17, "Chebyshev nodes of cos(theta) per panel", Integer(4, 64), edges=(4, 17))

    depolarizing = True
    _numpy_sets = True
    correspondence = Correspondence(
        "seed 003 Sec. 2.5 (its totally diffuse term's expectation), Eq. 21, 23, 36"
    )

    def _validate(self):
        if np.any(np.asarray(self.slopes.coverage) != 1.0):
            raise ValueError(
                "slopes must have coverage 1 (a continuous interface: every path crosses it twice)"
            )

    # -- the tables: per distinct element ------------------------------------------------
    def _flat_params(self, size):
        """``(sigma, n, rho)`` flat float64 arrays of length ``size`` (scalars repeated)."""
        return tuple(
            np.broadcast_to(np.asarray(v, dtype=float).real.reshape(-1), (size,))
            if np.size(v) in (1, size)
            else np.asarray(v, dtype=float).reshape(-1)
            for v in (self.slopes.sigma, self.coating, self.rho)
        )

    def tables(self, sigma, n, rho):
        """:func:`_tables` of elements ``(sigma, n, rho)`` (flat arrays) with this model's
        ``nodes`` and ``feedback``."""
        return _tables(sigma, n, rho, self.nodes, self.feedback)

    def _mueller16(self, ti, tr, pr):
        size = max(ti.size, tr.size, 1)
        sigma, n, rho = self._flat_params(1 if not self._sets else size)
        keys = np.stack([sigma, n, rho], axis=1)
        uniq, inverse = np.unique(keys, axis=0, return_inverse=True)
        out = np.empty((16, size))
        self._write(self.tables(*uniq.T.copy()), inverse.reshape(-1), ti, tr, out)
        return out

    def _brdf_flat(self, ti, tr, pr):
        return self._mueller16(ti, tr, pr)[0]

    def _write(self, tables, index, ti, tr, out):
        compiled = _compiled()
        n = out.shape[1]
        ti, tr = (np.broadcast_to(a, (n,)) if a.size == 1 else a for a in (ti, tr))
        if compiled is not None:  # writable C arrays: one compiled type whatever the caller holds
            index, ti, tr = (
                np.require(np.broadcast_to(x, (n,)), dtype=t, requirements=["C", "W"])
                for x, t in ((index, np.int64), (ti, np.float64), (tr, np.float64))
            )
            compiled.write(*tables, index, ti, tr, out, 0, n, 0)
        else:
            _write_numpy(*tables, index, ti, tr, out)
        return out

    # -- a fit's model set: walkers x wavelengths, each element's tables once ---------------
    def flat_mueller16_indexed(self, index, ti, tr, pr, out, add=False):
        G = math.prod(self.param_shape) if self._sets else 1
        tables = self.tables(*self._flat_params(G))
        inplace = type(out) is np.ndarray and out.flags.c_contiguous and out.dtype == np.float64
        if add or not inplace:
            values = self._write(tables, np.asarray(index), ti, tr, np.empty(out.shape))
            if add:
                out += values
            else:
                out[...] = values
            return out
        return self._write(tables, np.asarray(index), ti, tr, out)

    def indexed_kernel(self, index):
        """``(writer, index)`` for a fit's fused likelihood (``range_writer()``, as
        :class:`~scatterbench.models.kernels.Compiled`), or ``None`` on the numpy backend."""
        compiled = _compiled()
        if compiled is None:
            return None
        G = math.prod(self.param_shape) if self._sets else 1
        index = np.ascontiguousarray(index, dtype=np.int64)
        if index.size and (index.min() < 0 or index.max() >= G):
            raise ValueError(f"index: every entry must lie in [0, {G - 1}] (the model set's elements)")
        return _Writer(compiled, self.tables(*self._flat_params(G))), index

    @cached_property
    def rbar(self):
        """R-bar of Eq. 23 (a float, or an array in a model set): :func:`_tables`' own."""
        sigma, n, rho = self._flat_params(math.prod(self.param_shape) if self._sets else 1)
        if self.feedback == "flat":
            vals = _flat_rbar(n)
        else:
            vals = _rbar(sigma, n, self.nodes, _node_values(sigma, n, self.nodes)[0])
        return vals.reshape(self.param_shape) if self._sets else float(vals[0])


class _Writer:
    """:meth:`RoughSubsurfaceBRDF.indexed_kernel`'s kernel: the tables bound, ``range_writer``."""

    def __init__(self, compiled, tables):
        self._compiled, self._tables = compiled, tables

    def range_writer(self):
        fill, tables = self._compiled.write, self._tables

        def write(ti, tr, pr, index, buf, lo, hi):
            fill(*tables, index, ti, tr, buf, lo, hi, -lo)

        return write


def _compiled():
    """:mod:`scatterbench.models.kernels.rough` on the numba backend, else ``None`` (numpy)."""
    if evaluation.current_backend() != "numba":
        return None
    from .kernels import rough  # numba (heavy): compiled kernels load when one first runs

    return rough


def _series_at(coef, ub, u):
    """``t0``, ``t1`` at ``u`` from one element's panels (numpy Chebyshev evaluation)."""
    first = u < ub
    x = np.where(first, 2.0 * u / ub - 1.0, 2.0 * (u - ub) / (1.0 - ub) - 1.0)
    t = np.empty((2,) + u.shape)
    for c in range(2):
        t[c] = np.where(
            first,
            np.polynomial.chebyshev.chebval(x, coef[0, c]),
            np.polynomial.chebyshev.chebval(x, coef[1, c]),
        )
    return t


def _write_numpy(coef, ub, scale, index, ti, tr, out):
    out[...] = 0.0
    index = np.broadcast_to(index, ti.shape)
    for e in np.unique(index):
        sel = np.flatnonzero(index == e)
        a = _series_at(coef[e], ub[e], np.cos(ti[sel]))
        b = _series_at(coef[e], ub[e], np.cos(tr[sel]))
        s = scale[e]
        out[0, sel] = s * b[0] * a[0]
        out[1, sel] = s * b[0] * a[1]
        out[4, sel] = s * b[1] * a[0]
        out[5, sel] = s * b[1] * a[1]
