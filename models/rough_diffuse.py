"""Single and diffuse volume scattering beneath a rough interface: the Monte Carlo
model of seed 003 Sec. 2.5.

A path enters through one facet and leaves through another (the scattering is
assumed deep enough that the two facets are different).  For fixed incident
and scattered directions ``k_i``, ``k_r`` the model averages over pairs of
facet slopes ``(zeta_1, zeta_2)``:

* ``zeta_1`` is a facet struck by the incident ray, from the distribution seen
  by a ray along ``k`` (Eq. 36, normalized exactly rather than with Eq. 37's
  ``<cos i> ~ cos ti``)::

      P'_k(zeta) = P3^xy(zeta) (cos theta_k - k_xy . zeta)_+ / N_k,
      N_k = <(cos theta_k - k_xy . zeta)_+>_xy

  (``(cos theta_k - k_xy . zeta)_+ = cos(iota) sec(theta_n)``: the facet's area
  per unit xy area, projected on the beam).  ``zeta_2`` is drawn the same way
  for the reversed scattered ray ``-k_r``.
* Snell's law through each facet gives the internal directions ``k_1'``
  (Eq. 30) and ``k_2'`` (the internal ray that leaves along ``k_r``), and the
  facet Jones matrices (:func:`scatterbench.models.facet_btdf.facet_transmission_jones`,
  flux factors ``n cos(iota_t)/cos(iota_i)`` in and ``cos(iota_air)/(n
  cos(iota_int))`` out).
* Volume: single scattering, phase matrix of Eq. 7 (or depolarizing) times the
  depth factor ``1 / (cos theta_1' + cos theta_2')`` of Eq. 18-20 (depths along
  the mean normal); totally diffuse, Eq. 21 ``D rho / pi`` with the multiple
  reflection factor ``1 / (1 - rho R-bar)`` of Eq. 23, with R-bar the internal
  reflectance of the *rough* interface estimated from the model's exit facets
  (``feedback="rough"``, default; it tends to the flat R-bar as sigma -> 0) or
  Sec. 2.3's flat R-bar (``feedback="flat"``, which gains energy under a rough
  interface: the rough surface lets more internal light out than the flat one).
* The exit uses radiance conservation ``L / n^2`` (BTDF reciprocity), hence the
  overall ``1 / n^2``.

So that every geometry sees the same facet pairs, the pairs are drawn once
from ``P3^xy`` (``slopes.sample``: the generator for the xy-sampled
distribution) with the model's seed and importance-weighted by
``(cos theta_k - k_xy . zeta)_+ / N_k``: common random numbers make curves
smooth, results independent of how geometries are batched, and the same seed
gives the same numbers.  The weighting reproduces exactly the distribution
of the paper's acceptance scheme (:func:`sample_normals_seen_by`, the second
generator, which tests compare with it) and, unlike rejection, stays efficient
at grazing incidence.  ``N_k`` is computed deterministically from the radial
inverse CDF (2048 midpoint quantiles; relative error < 1e-6).

The mean over pairs is the estimate and ``std / sqrt(pairs)`` its standard
error (:meth:`RoughDiffuseBRDF.mueller_with_error`).  It is computed by the compiled
loop :mod:`scatterbench.models.kernels.montecarlo` (the default backend: one pass per geometry over
the same facet pairs, no temporaries) or, ``with models.backend("numpy")``, by the numpy
implementation here, the reference the tests hold the kernel to (1e-12 relative to
``M00``).  With ``surface=True`` the
direct reflection by the exposed rough surface (:class:`scatterbench.models.FacetBRDF`
with substrate ``n``, the coating's index) is added (deterministic, zero error).  No shadowing, as
in the paper.

Without single scattering (``single = 0``) the two facets of a path are independent and the
estimate's expectation is a product of one factor per direction: :class:`RoughSubsurfaceBRDF`
computes it by quadrature (Gaussian slopes), with no Monte Carlo error, fast enough for a fit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from types import MappingProxyType

import numpy as np

from . import evaluation, modelset
from .base import Model
from .constraints import FACTOR_MAX, Instance, Integer, Interval, OneOf, Options, ScalarOrArray
from .facet import FacetBRDF
from .facet_btdf import _dot, angle_basis, facet_transmission_jones, projected_area, ray_basis
from .facts import Correspondence
from .geometry import gauss_legendre
from .params import choice_alias, coating_param, convention_param, param
from .phase import HenyeyGreenstein
from .polarization import mueller16_from_jones
from .slopes import SLOPES, ExponentialSlopes, SlopeDistribution
from .smooth_interface import internal_hemispherical_reflectance

__all__ = ["RoughDiffuseBRDF", "sample_normals_seen_by", "projected_area"]

# Largest sample magnitude whose square, summed over the most pairs (1e7), stays finite.
_SUM_SAFE = 1e150

#: (geometry, pair) entries evaluated per block: keeps the temporaries in cache-sized arrays
BLOCK = 1 << 15


def sample_normals_seen_by(slopes, k, size, seed=None, max_rounds=100_000):
    """Slopes ``(zeta_x, zeta_y)`` of the facets struck by rays along ``k`` (Sec. 2.5's
    second generator): the acceptance scheme.

    Candidates come from the facet-*area* distribution ``P3^A ~ sec(theta_n)
    P3^xy`` (drawn by rejection from ``P3^xy`` with acceptance ``cos theta_n``
    inverted: radial inverse CDF of ``sqrt(1 + zeta^2) P4^xy``); a candidate is
    kept when a uniform number is below the projection ``-k . n``.  The result has
    density ``P3^xy (cos theta - k_xy . zeta)_+ / N`` (Eq. 36, normalized).
    ``k`` is one downward unit vector.  Rounds redraw only the rejected entries.
    """
    rng = np.random.default_rng(seed)
    k = np.asarray(k, dtype=float)
    grid, cdf = _area_cdf(slopes)
    zx = np.empty(size)
    zy = np.empty(size)
    todo = np.arange(size)
    for _ in range(max_rounds):
        if todo.size == 0:
            break
        r = np.interp(rng.random(todo.size), cdf, grid)
        phi = rng.random(todo.size) * 2.0 * math.pi
        x, y = r * np.cos(phi), r * np.sin(phi)
        proj = -(k[0] * x + k[1] * y + k[2]) / np.sqrt(1.0 + r * r)  # -k . n, n = (x, y, 1)/|.|
        keep = rng.random(todo.size) < proj
        zx[todo[keep]] = x[keep]
        zy[todo[keep]] = y[keep]
        todo = todo[~keep]
    if todo.size:  # pragma: no cover - only for absurd max_rounds
        raise RuntimeError("sample_normals_seen_by: acceptance too low")
    return zx, zy


def _area_cdf(slopes):
    grid, _ = slopes._radial_cdf
    # Radial density of the area distribution: sqrt(1 + zeta^2) P4^xy(zeta).
    pdf = np.sqrt(1.0 + grid * grid) * slopes._p4_unit(grid)
    c = np.concatenate([[0.0], np.cumsum(0.5 * (pdf[1:] + pdf[:-1]) * np.diff(grid))])
    return grid, c / c[-1]


def _normals(z):
    """Upward unit facet normals ``(3, 1, p)`` of slopes ``z`` ``(2, p)``."""
    inv = 1.0 / np.sqrt(1.0 + z[0] * z[0] + z[1] * z[1])
    return np.stack([z[0] * inv, z[1] * inv, inv])[:, None, :]


@dataclass(frozen=True)
class RoughDiffuseBRDF(Model):
    """Monte Carlo: volume scattering (single, Eq. 7, and totally diffuse, Eq. 21) beneath a
    rough interface, two facets per path, plus the exposed surface's facet reflection.

    Parameters
    ----------
    slopes : SlopeDistribution
        Isotropic facet slope distribution of the interface.
    coating : float
        Real index ``n`` of the binder around the scatterers, the medium light enters
        through the rough interface.  Old name ``n``.
    phase : HenyeyGreenstein
        Single-scattering phase function.
    rho : float
        Diffuse reflectance of the material (totally diffuse term), in [0, 1].
    pairs : int
        Facet pairs per geometry (the paper: 50 match data statistics, 5000 give smooth curves).
    seed : int or numpy.random.Generator
        Seed of the facet pairs; the same seed gives the same numbers.
    surface : bool
        Add the direct reflective facet term of the exposed surface.
    single : float
        Weight of the single-scattering term (1; 0 leaves the diffuse term alone).
    feedback : str
        ``"rough"``: the internal reflectance R-bar of Eq. 23 is that of the rough
        interface, ``1 - (1/(pi n^2)) int <w_r T_out> cos dOmega`` estimated with the
        model's own exit facets (then the diffuse term alone conserves energy:
        ``rho = 1`` returns everything that entered).  ``"flat"``: Sec. 2.3's flat R-bar
        (what Eq. 21 + 23 say literally; then light is gained under rough interfaces).
        Not part of ``convention``: the default is the rough R-bar, and joining the two
        would change what a model built with defaults computes.
    convention : "paper" | "corrected"
        The surface term.  ``"paper"``: :class:`scatterbench.models.FacetBRDF` as printed, with
        Eq. 37's ``1/cos(theta_i)`` normalization of the slopes seen by the incident ray
        (as SCATMECH).  ``"corrected"``: scaled by ``cos(theta_i) / N(theta_i)`` to the
        exact Eq. 36 normalization that the volume terms use (energy then stays <= 1 for
        wide slopes at grazing), at the price of reciprocity: without shadowing,
        ``1/N(theta_i)`` is not symmetric in the two directions (``reciprocal`` is then
        False).  The volume terms are reciprocal either way: their weight ``w_i w_r /
        (N(theta_i) N(theta_r))`` is symmetric, and with the exact normalization each
        incident ray, and each line of sight of the detector, meets exactly one facet.
        Old name ``surface_normalization`` (``"paper"``, ``"exact"``).
    """

    slopes: SlopeDistribution = param(
        ExponentialSlopes(2.0), "isotropic facet slope distribution of the interface", SLOPES
    )
    coating: float = coating_param(
        1.5, "index n of the binder around the scatterers, entered through the rough interface (real)"
    )
    phase: HenyeyGreenstein = param(
        HenyeyGreenstein(0.3),
        "single-scattering phase function",
        Instance(HenyeyGreenstein, text="a models.HenyeyGreenstein"),
    )
    rho: float = param(
        0.05, "diffuse reflectance of the material under the interface", ScalarOrArray(Interval(0.0, 1.0))
    )
    # Monte Carlo: swept at the fewest pairs allowed and a moderate count
    pairs: int = param(5000, "facet pairs per geometry", Integer(2, 10**7), edges=(2, 200))
    seed: object = param(
        0,
        "seed (int >= 0) or numpy.random.Generator",
        OneOf(Integer(0), Instance(np.random.Generator, text="a numpy.random.Generator")),
    )
    surface: bool = param(True, "add the exposed surface's facet reflection", Options(True, False))
    single: float = param(
        1.0,
        "weight of the single-scattering term",
        ScalarOrArray(Interval(0.0, FACTOR_MAX)),
        edges=(0.0, 1.0),
    )
    feedback: str = param(
        "rough", "R-bar of Eq. 23: of the rough interface (MC) or of the flat one", Options("rough", "flat")
    )
    convention: str = convention_param(
        "surface term: FacetBRDF with Eq. 37's normalization (paper) or exact Eq. 36 (corrected)"
    )

    aliases = {
        "n": "coating",
        "surface_normalization": choice_alias(
            "convention", "surface_normalization", {"paper": "paper", "exact": "corrected"}
        ),
    }
    depolarizing = True
    correspondence = Correspondence("seed 003 Sec. 2.5 (Monte Carlo), Eq. 7, 21")
    #: the kit's instance: 20 facet pairs per geometry (the kit checks shapes, finiteness,
    #: realizability and the seed of this Monte Carlo model, not its precision)
    kit_variant = MappingProxyType({"pairs": 20})

    @classmethod
    def sweep_base(cls):
        """A moderate pair count: the sweep looks for non-finite values, negative or
        unphysical matrices, not for Monte Carlo precision."""
        return cls(pairs=200)

    @property
    def reciprocal(self):  # type: ignore[override]
        return not (self.surface and self.convention == "corrected")

    def _validate(self):
        if not self.slopes.isotropic:
            raise ValueError(f"slopes must be an isotropic slope distribution; got {self.slopes!r}")
        if getattr(self.slopes, "coverage", 1.0) != 1.0:
            raise ValueError(
                "slopes must have coverage 1 (a continuous interface: every path crosses it twice)"
            )
        # Draw the facet pairs now: a Generator passed in is consumed once, here.
        rng = np.random.default_rng(self.seed)
        z1 = self.slopes.sample(self.pairs, rng)
        z2 = self.slopes.sample(self.pairs, rng)
        object.__setattr__(self, "_z1", np.stack(z1))
        object.__setattr__(self, "_z2", np.stack(z2))

    def _element(self, leaves, index):
        # validated: the facet pairs are drawn from the element's own slopes and seed
        return modelset.rebuilt(self, {p: modelset.scalar_value(a[index]) for p, a in leaves.items()})

    @cached_property
    def _rbar(self):
        if self.feedback == "flat" or self.rho == 0.0:
            return internal_hemispherical_reflectance(self.coating)
        return self._rough_rbar()

    def _exit_transmittance(self, tr, pr):
        """``<w_r M_out[0, 0]>`` over the exit facets, ``(g,)`` for flat ``tr``, ``pr``."""
        n = self.coating
        z2 = self._z2
        cr, sr = np.cos(tr)[:, None], np.sin(tr)[:, None]
        cp, sp = np.cos(pr)[:, None], np.sin(pr)[:, None]
        k_r = np.stack([sr * cp, sr * sp, cr])
        m2 = _normals(z2)
        w2 = np.maximum(cr + (sr * cp) * z2[0][None, :] + (sr * sp) * z2[1][None, :], 0.0) / self._norm(cr)
        eta = 1.0 / n
        c2 = _dot(k_r, m2)
        ct2 = np.sqrt(np.maximum(1.0 - eta * eta * (1.0 - c2 * c2), 0.0))
        k2 = -(eta * (-k_r) + (eta * c2 - ct2) * m2)
        live = (w2 > 0) & (c2 > 0) & (k2[2] > 0)
        jout, ci_out, ct_out = facet_transmission_jones(k2, k_r, -m2, n, 1.0, ray_basis(k2), ray_basis(k_r))
        f_out = ct_out / (n * np.where(ci_out > 0, ci_out, 1.0))
        t00 = 0.5 * sum(j * j for j in jout) * f_out * w2
        return np.where(live, t00, 0.0).mean(axis=-1)

    def _rough_rbar(self, n_u=32, n_phi=16):
        """R-bar of the rough interface: one minus the fraction of internal Lambertian light
        that leaves, ``(1/(pi n^2)) int <w_r T_out> cos(tr) dOmega_r`` (``u = cos tr``
        Gauss-Legendre, uniform azimuth; the flat limit is exact)."""
        x, w = gauss_legendre(n_u)
        u = 0.5 * (x + 1.0)
        wu = 0.5 * w
        phi = (np.arange(n_phi) + 0.5) * (2.0 * math.pi / n_phi)
        U, P = np.meshgrid(u, phi, indexing="ij")
        tr, pr = np.arccos(U).ravel(), P.ravel()
        mc = self._montecarlo()
        if mc is not None:
            t = mc.exit_transmittance(
                tr, pr, self._norm(np.cos(tr)[:, None])[:, 0], *self._facets, self.coating
            )
        else:
            per = max(1, BLOCK // self.pairs)
            t = np.concatenate(
                [self._exit_transmittance(tr[k : k + per], pr[k : k + per]) for k in range(0, tr.size, per)]
            )
        total = np.sum(t.reshape(U.shape) * (wu * u)[:, None]) * (2.0 * math.pi / n_phi)
        return 1.0 - total / (math.pi * self.coating * self.coating)

    @property
    def _diffuse(self):
        """The totally diffuse factor ``(rho / pi) / (1 - rho R-bar)`` (Eq. 21, 23)."""
        return (self.rho / math.pi) / (1.0 - self.rho * self._rbar)

    @cached_property
    def _surface_model(self):
        return FacetBRDF(slopes=self.slopes, substrate=self.coating)

    # ------------------------------------------------------------------ one block
    def _block(self, ti, tr, pr, z1, z2):
        """Per-pair Mueller estimates ``(16, g, p)`` for geometries ``(g,)`` and pairs ``(p,)``."""
        n = self.coating
        g, p = ti.size, z1.shape[1]
        ci, si = np.cos(ti)[:, None], np.sin(ti)[:, None]
        cr, sr = np.cos(tr)[:, None], np.sin(tr)[:, None]
        cp, sp = np.cos(pr)[:, None], np.sin(pr)[:, None]
        zero = np.zeros((g, 1))
        k_i = np.stack([si, zero, -ci])  # (3, g, 1)
        k_r = np.stack([sr * cp, sr * sp, cr])

        m1, m2 = _normals(z1), _normals(z2)
        # Eq. 36 weights, normalized exactly: (cos - k_xy . zeta)_+ / N
        w1 = np.maximum(ci - si * z1[0][None, :], 0.0) / self._norm(ci)
        w2 = np.maximum(cr + (sr * cp) * z2[0][None, :] + (sr * sp) * z2[1][None, :], 0.0) / self._norm(cr)
        # entry: refract k_i through m1 (normal on the incident side)
        c1 = -_dot(k_i, m1)
        eta = 1.0 / n
        ct1 = np.sqrt(np.maximum(1.0 - eta * eta * (1.0 - c1 * c1), 0.0))
        k1 = eta * k_i + (eta * c1 - ct1) * m1  # internal, should travel downward
        # exit: the reversed ray -k_r refracts through m2 to -k2
        c2 = _dot(k_r, m2)
        ct2 = np.sqrt(np.maximum(1.0 - eta * eta * (1.0 - c2 * c2), 0.0))
        k2 = -(eta * (-k_r) + (eta * c2 - ct2) * m2)  # internal ray travelling up to the exit facet
        c1z = -k1[2]
        c2z = k2[2]
        live = (w1 > 0) & (w2 > 0) & (c1 > 0) & (c2 > 0) & (c1z > 0) & (c2z > 0)
        live &= (ti < 0.5 * math.pi)[:, None] & (tr < 0.5 * math.pi)[:, None]
        # external bases from the angles (pole limit along the azimuth, as the other models)
        e_i = angle_basis(k_i, zero, zero + 1.0)
        e_r = angle_basis(k_r, -sp, cp)
        (jin, ci_in, ct_in) = facet_transmission_jones(k_i, k1, m1, 1.0, n, e_i, ray_basis(k1))
        (jout, ci_out, ct_out) = facet_transmission_jones(k2, k_r, -m2, n, 1.0, ray_basis(k2), e_r)
        f_in = n * ct_in / np.where(ci_in > 0, ci_in, 1.0)
        f_out = ct_out / (n * np.where(ci_out > 0, ci_out, 1.0))
        base = np.where(live, w1 * w2 * f_in * f_out / (n * n), 0.0)
        depth = 1.0 / np.where(live, c1z + c2z, 1.0)
        cos_scat = _dot(k1, k2)
        dens = self.phase.density(cos_scat)
        diffuse = self._diffuse
        out = np.zeros((16, g, p))
        # column 0 of M(J_out) and row 0 of M(J_in) (real Jones: no V components)
        ss, ps, sp_, pp = jin
        r0 = 0.5 * (ss * ss + ps * ps + sp_ * sp_ + pp * pp)
        r1 = 0.5 * (ss * ss - ps * ps + sp_ * sp_ - pp * pp)
        r2 = ss * ps + sp_ * pp
        ss, ps, sp_, pp = jout
        c0 = 0.5 * (ss * ss + ps * ps + sp_ * sp_ + pp * pp)
        c1_ = 0.5 * (ss * ss + ps * ps - sp_ * sp_ - pp * pp)
        c2_ = ss * sp_ + pp * ps
        scal = diffuse * base
        if not self.phase.polarized:
            scal = scal + self.single * base * dens * depth
        for a, col in enumerate((c0, c1_, c2_)):
            ca = col * scal
            for b, row in enumerate((r0, r1, r2)):
                out[4 * a + b] = ca * row
        if self.phase.polarized and self.single > 0:
            # J_out . J_phase . J_in with J_phase_ab = e_a(k2) . e_b(k1) (Eq. 4-5)
            e1, e2 = ray_basis(k1), ray_basis(k2)
            ph = [[_dot(ea, eb) for eb in e1] for ea in e2]
            ji = [[jin[0], jin[1]], [jin[2], jin[3]]]
            jo = [[jout[0], jout[1]], [jout[2], jout[3]]]
            tmp = [[ph[a][0] * ji[0][b] + ph[a][1] * ji[1][b] for b in range(2)] for a in range(2)]
            tot = [[jo[a][0] * tmp[0][b] + jo[a][1] * tmp[1][b] for b in range(2)] for a in range(2)]
            wgt = self.single * base * dens * depth * 2.0 / (1.0 + cos_scat * cos_scat)
            root = np.sqrt(wgt)
            zr = 0.0  # real Jones matrix
            parts = [
                (tot[0][0] * root, zr),
                (tot[0][1] * root, zr),
                (tot[1][0] * root, zr),
                (tot[1][1] * root, zr),
            ]
            out += mueller16_from_jones(*parts)
        return out

    def _norm(self, cos_theta):
        # N_k for each geometry; exact zero only at grazing, where the weights vanish too
        nk = projected_area(self.slopes, cos_theta[:, 0])[:, None]
        return np.where(nk > 0, nk, 1.0)

    # ------------------------------------------------------------------ estimates
    @cached_property
    def _facets(self):
        """The facet pairs as the kernel reads them: slopes ``(4, pairs)`` (entry x, y, exit
        x, y) and unit normals ``(6, pairs)`` (entry, exit), contiguous."""
        z = np.ascontiguousarray(np.concatenate([self._z1, self._z2]))
        m = np.ascontiguousarray(np.concatenate([_normals(self._z1)[:, 0], _normals(self._z2)[:, 0]]))
        return z, m

    @staticmethod
    def _montecarlo():
        """The compiled Monte Carlo (:mod:`scatterbench.models.kernels.montecarlo`), or ``None`` on the
        numpy backend (the reference it is tested against)."""
        if evaluation.current_backend() != "numba":
            return None
        from .kernels import montecarlo  # numba (heavy): compiled kernels load when one first runs

        return montecarlo

    def _estimate(self, ti, tr, pr):
        """Mean and standard error ``(16, n)`` of the volume terms."""
        mc = self._montecarlo()
        if mc is not None:
            prm = np.array(
                [self.coating, self._diffuse, self.single, self.phase.g, float(self.phase.polarized)]
            )
            norms = (self._norm(np.cos(t)[:, None])[:, 0] for t in (ti, tr))
            parallel = ti.size > 1 and ti.size * self.pairs >= BLOCK
            return mc.estimate(ti, tr, pr, *norms, *self._facets, prm, _SUM_SAFE, parallel)
        return self._estimate_numpy(ti, tr, pr)

    def _estimate_numpy(self, ti, tr, pr):
        """:meth:`_estimate` on the numpy path, block by block of :data:`BLOCK` entries."""
        n = ti.size
        mean = np.empty((16, n))
        err = np.empty((16, n))
        per = max(1, BLOCK // self.pairs)
        for start in range(0, n, per):
            sl = slice(start, min(start + per, n))
            x = self._block(ti[sl], tr[sl], pr[sl], self._z1, self._z2)
            scale = np.max(np.abs(x), axis=-1, keepdims=True)
            if not np.all(scale < _SUM_SAFE):
                # huge weights (e.g. single ~ 1e300): sums and squares would overflow;
                # the same statistics of x / scale, scaled back
                scale = np.where(scale > 0, scale, 1.0)
                x = x / scale
            else:
                scale = np.ones_like(scale)
            mean[:, sl] = x.mean(axis=-1) * scale[..., 0]
            err[:, sl] = x.std(axis=-1, ddof=1) / math.sqrt(self.pairs) * scale[..., 0]
        return mean, err

    def _surface16(self, ti, tr, pr):
        out = self._surface_model.flat_mueller16(ti, tr, pr)
        if self.convention == "corrected":
            ci = np.cos(ti)
            out = out * (ci / np.maximum(projected_area(self.slopes, ci), 1e-300))
        return out

    def _mueller16(self, ti, tr, pr):
        mean, _ = self._estimate(ti, tr, pr)
        if self.surface:
            mean += self._surface16(ti, tr, pr)
        return mean

    def mueller_with_error(self, theta_i, theta_r, phi_r=0.0):
        """``(M, standard_error)``, both ``(..., 4, 4)``: the Monte Carlo estimate and its
        standard error per element (the surface term adds no error)."""
        shape, (ti, tr, pr) = self._angles(theta_i, theta_r, phi_r)
        mean, err = self._estimate(ti, tr, pr)
        if self.surface and ti.size:
            mean += self._surface16(ti, tr, pr)

        def shaped(a):
            return np.moveaxis(a.reshape((4, 4) + shape), (0, 1), (-2, -1))

        return shaped(mean), shaped(err)

    def lobe(self, theta_i):
        return self._surface_model.lobe(theta_i) if self.surface else None
