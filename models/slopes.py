"""Facet slope and angle distributions (seed 000 Sec. 2.C, Eq. 21-42).

One interface for every distribution, in the spirit of ``scipy.stats``:

* ``p1(theta_n, phi_n, sampling)``: density per solid angle of the facet normal (Eq. 22)
* ``p2(theta_n, sampling)``: density of the polar angle of the normal (Eq. 23-24)
* ``p3(zeta_x, zeta_y, sampling)``: density per unit slope area (Eq. 25)
* ``p4(zeta, sampling)``: density of the slope magnitude (Eq. 26-27)
* ``coverage`` ``C`` and ``mean_sec()`` ``<sec theta_n>`` (Eq. 36)
* ``sample(size, seed)``: slopes drawn from ``P3^xy / C``

``sampling="xy"`` samples points uniformly on the mean surface plane; the
``xy`` densities integrate to ``C`` (Eq. 31-34).  ``sampling="A"`` samples the
actual facet area; those integrate to 1 (Eq. 37-40).  The conversions are
Eq. 29 (``P3 = cos^3 P1``), Eq. 30 (``P4 = cos^2 P2``), Eq. 35
(``P1^A = sec P1^xy / (C <sec>)``) and Eq. 41; tests check each numerically.

Slopes are those of the facet normal, ``zeta = (n_x / n_z, n_y / n_z)``
(Eq. 21), as in SCATMECH's ``evaluate_sdf``.  Angles are in radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy import integrate

from . import kernel_specs
from .constraints import Instance, Interval, Samples, ScalarOrArray
from .params import Declared, param, width_param

__all__ = [
    "SlopeDistribution",
    "ExponentialSlopes",
    "GaussianSlopes",
    "AnisotropicExponentialSlopes",
    "AnisotropicGaussianSlopes",
    "GaussianAngles",
    "ExponentialAngles",
    "TabulatedSlopes",
    "UnitSlopes",
    "GGXSlopes",
    "AnisotropicGGXSlopes",
]

_SQRT6 = math.sqrt(6.0)

#: the stability sweep's widths (rms slopes, GGX alpha): a near-mirror, a smooth surface, a
#: rough one (45-degree facets typical) and an extremely rough one
WIDTH_EDGES = (1e-4, 1e-2, 1.0, 10.0)
#: the sweep's azimuths of an anisotropic distribution's axes
ROTATION_EDGES = (0.0, 1.0, -math.pi)


def coverage_param():
    """The projected coverage ``C`` in (0, 1] (seed 000 Eq. 33), swept at 1e-3 and 1."""
    return param(
        1.0, "projected coverage C", ScalarOrArray(Interval(0.0, 1.0, closed="right")), edges=(1e-3, 1.0)
    )


def rotation_param(doc):
    """An azimuth (rad) of a distribution's axes: any finite angle, swept at 0, 1 and -pi."""
    return param(0.0, doc, ScalarOrArray(Interval()), edges=ROTATION_EDGES)


def _exp_neg(x):
    """``exp(-x)`` for ``x >= 0``, exactly zero below ~1e-304 instead of a subnormal.

    Far tails of the slope densities then vanish without an IEEE underflow and
    without subnormal arithmetic downstream.
    """
    x = np.asarray(x, dtype=float)
    return np.exp(-np.minimum(x, 700.0)) * (x < 700.0)


def _check_sampling(sampling):
    if sampling not in ("xy", "A"):
        raise ValueError(f"sampling must be 'xy' or 'A'; got {sampling!r}")


class SlopeDistribution(Declared):
    """Base class: subclasses define ``_p3_unit`` (normalized ``P3^xy`` for ``C = 1``)."""

    isotropic = True
    #: whether ``P3`` is a probability density (integrates to the coverage): Smith's ``Lambda``,
    #: the mean slope seen along a direction, is defined only then
    density = True
    #: the compiled kernels' code of this family (:mod:`scatterbench.models.kernel_specs`), with
    #: :meth:`kernel_row` its parameters; ``None``: no kernel evaluates it (the numpy path)
    kernel_code = None
    #: SCATMECH's slope distribution function of this family (parameter ``s`` = ``sigma``);
    #: ``None``: SCATMECH has none with the same parameters
    scatmech_sdf = None

    # --- what subclasses provide -------------------------------------------------
    def _p3_unit(self, zx, zy):  # pragma: no cover - abstract
        raise NotImplementedError

    def kernel_row(self) -> list:
        """``[sx, sy, rotation, coverage]``: the kernels' parameters of a family with a
        :attr:`kernel_code` (the widths along the axes rotated by ``rotation`` from x)."""
        raise NotImplementedError(f"{type(self).__name__} has no kernel code")

    def scatmech_parameters(self) -> dict | None:
        """``{"sdf": name, "sdf.s": sigma}``: SCATMECH's equivalent of this distribution, or
        ``None`` (no equivalent family, a coverage below 1, or an array of a model set)."""
        if self.scatmech_sdf is None or any(isinstance(v, np.ndarray) for v in (self.sigma, self.coverage)):
            return None
        return {"sdf": self.scatmech_sdf, "sdf.s": self.sigma} if self.coverage == 1.0 else None

    def _p4_unit(self, zeta):
        """Normalized ``P4^xy`` (C = 1).  Isotropic default: ``2 pi zeta P3(zeta, 0)``."""
        zeta = np.asarray(zeta, dtype=float)
        if self.isotropic:
            return 2.0 * math.pi * zeta * self._p3_unit(zeta, np.zeros_like(zeta))
        # Anisotropic: integrate P3 over the azimuth of the slope (periodic, so the
        # trapezoid rule converges geometrically).
        phi = np.linspace(0.0, 2.0 * math.pi, 256, endpoint=False)
        z = zeta[..., None]
        vals = self._p3_unit(z * np.cos(phi), z * np.sin(phi))
        return zeta * vals.mean(axis=-1) * 2.0 * math.pi

    @property
    def scale(self) -> float:
        """A characteristic slope (rms slope for the analytic families)."""
        return float(getattr(self, "sigma", 0.1))

    def _sample_radius_unit(self, u):
        """Inverse CDF of ``P4^xy / C`` (generic: tabulated on a fine grid)."""
        grid, cdf = self._radial_cdf
        return np.interp(u, cdf, grid)

    @cached_property
    def _radial_cdf(self):
        zmax = self._zeta_max
        grid = np.concatenate([[0.0], np.geomspace(zmax * 1e-7, zmax, 20000)])
        pdf = self._p4_unit(grid)
        cdf = np.concatenate([[0.0], np.cumsum(0.5 * (pdf[1:] + pdf[:-1]) * np.diff(grid))])
        cdf /= cdf[-1]
        return grid, cdf

    @property
    def _zeta_max(self) -> float:
        return 60.0 * self.scale

    # --- public interface ---------------------------------------------------------
    def p3(self, zeta_x, zeta_y, sampling="xy"):
        """Slope density ``P3(zeta_x, zeta_y)`` (Eq. 25; ``A`` sampling via Eq. 35)."""
        _check_sampling(sampling)
        zx = np.asarray(zeta_x, dtype=float)
        zy = np.asarray(zeta_y, dtype=float)
        v = self.coverage * self._p3_unit(zx, zy)
        if sampling == "A":
            # P3^A = cos^3 P1^A = sec P3^xy / (C <sec>)  (Eq. 29 with Eq. 35)
            v = np.sqrt(1.0 + zx * zx + zy * zy) * v / (self.coverage * self.mean_sec())
        return v

    def p4(self, zeta, sampling="xy"):
        """Density of the slope magnitude ``P4(zeta)`` (Eq. 26-27)."""
        _check_sampling(sampling)
        zeta = np.asarray(zeta, dtype=float)
        v = self.coverage * self._p4_unit(zeta)
        if sampling == "A":
            v = np.sqrt(1.0 + zeta * zeta) * v / (self.coverage * self.mean_sec())
        return v

    def p1(self, theta_n, phi_n, sampling="xy"):
        """Density per solid angle of the facet normal ``P1(theta_n, phi_n)`` (Eq. 22, 29, 41)."""
        _check_sampling(sampling)
        t = np.asarray(theta_n, dtype=float)
        p = np.asarray(phi_n, dtype=float)
        tan = np.tan(t)
        c = np.cos(t)
        v = self.p3(tan * np.cos(p), tan * np.sin(p), "xy") / c**3  # Eq. 29
        if sampling == "A":
            v = v / (c * self.coverage * self.mean_sec())  # Eq. 35
        return v

    def p2(self, theta_n, sampling="xy"):
        """Density of the polar angle of the facet normal ``P2(theta_n)`` (Eq. 23, 30)."""
        _check_sampling(sampling)
        t = np.asarray(theta_n, dtype=float)
        c = np.cos(t)
        v = self.p4(np.tan(t), "xy") / c**2  # Eq. 30
        if sampling == "A":
            v = v / (c * self.coverage * self.mean_sec())
        return v

    def mean_sec(self) -> float:
        """``<sec theta_n>`` over the covered mean plane (Eq. 36)."""
        return self._mean_sec

    @cached_property
    def _mean_sec(self) -> float:
        f = lambda z: math.sqrt(1.0 + z * z) * float(self._p4_unit(np.array(z)))  # noqa: E731
        val, _ = integrate.quad(f, 0.0, np.inf, limit=400, epsabs=0, epsrel=1e-12)
        return val

    def sample(self, size, seed=None):
        """Draw slopes ``(zeta_x, zeta_y)`` from ``P3^xy / C``; ``seed`` is an int or Generator."""
        rng = np.random.default_rng(seed)
        r = self._sample_radius_unit(rng.random(size))
        phi = rng.random(size) * 2.0 * math.pi
        return r * np.cos(phi), r * np.sin(phi)

    def rotated(self, angle):
        """The same distribution rotated by ``angle`` about z (isotropic: itself)."""
        return self


@dataclass(frozen=True)
class ExponentialSlopes(SlopeDistribution):
    """Exponential slope distribution, seed 000 Eq. 42:

    ``P3^xy = C 3/(pi sigma^2) exp(-sqrt(6) zeta / sigma)`` with ``sigma`` the rms slope.
    SCATMECH: ``Exponential_Slope_Distribution_Function`` (parameter ``s``).
    """

    sigma: float = width_param(0.1, "rms slope, sqrt(<|zeta|^2>)", edges=WIDTH_EDGES)
    coverage: float = coverage_param()

    kernel_code = kernel_specs.EXPONENTIAL
    scatmech_sdf = "Exponential_Slope_Distribution_Function"

    def kernel_row(self):
        return [self.sigma, self.sigma, 0.0, self.coverage]

    def _p3_unit(self, zx, zy):
        z = np.sqrt(zx * zx + zy * zy)
        return (3.0 / (math.pi * self.sigma**2)) * _exp_neg(_SQRT6 * z / self.sigma)


@dataclass(frozen=True)
class GaussianSlopes(SlopeDistribution):
    """Gaussian slope distribution ``P3^xy = C exp(-(zeta/sigma)^2) / (pi sigma^2)``.

    ``sigma`` is the rms slope (``<zeta^2> = sigma^2``); it is Beckmann's
    distribution with ``alpha = sigma`` (Mitsuba ``beckmann``) and Cook-Torrance's
    ``m`` (seed 001 Eq. 8).  SCATMECH: ``Gaussian_Slope_Distribution_Function``.
    """

    sigma: float = width_param(0.1, "rms slope, sqrt(<|zeta|^2>)", edges=WIDTH_EDGES)
    coverage: float = coverage_param()

    kernel_code = kernel_specs.GAUSSIAN
    scatmech_sdf = "Gaussian_Slope_Distribution_Function"

    def kernel_row(self):
        return [self.sigma, self.sigma, 0.0, self.coverage]

    def _p3_unit(self, zx, zy):
        return _exp_neg((zx * zx + zy * zy) / self.sigma**2) / (math.pi * self.sigma**2)

    def _sample_radius_unit(self, u):
        return self.sigma * np.sqrt(-np.log1p(-np.asarray(u)))

    @property
    def _zeta_max(self):
        return 12.0 * self.sigma


@dataclass(frozen=True)
class _Elliptical(SlopeDistribution):
    """Anisotropic families whose slope density is an isotropic one stretched along axes
    rotated by ``rotation``: ``sigma_x`` and ``sigma_y`` are the stretches."""

    isotropic = False

    def kernel_row(self):
        return [self.sigma_x, self.sigma_y, self.rotation, self.coverage]

    def _local(self, zx, zy):
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        return c * zx + s * zy, -s * zx + c * zy

    @property
    def scale(self):
        return max(self.sigma_x, self.sigma_y)

    def sample(self, size, seed=None):
        rng = np.random.default_rng(seed)
        iso = self._isotropic_unit()
        r = iso._sample_radius_unit(rng.random(size))
        phi = rng.random(size) * 2.0 * math.pi
        u, v = r * np.cos(phi) * self.sigma_x, r * np.sin(phi) * self.sigma_y
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        return c * u - s * v, s * u + c * v

    def rotated(self, angle):
        return self.replace(rotation=(self.rotation + angle) % (2 * math.pi))


@dataclass(frozen=True)
class _Anisotropic(_Elliptical):
    """Shared parameters of the anisotropic exponential and Gaussian families."""

    sigma_x: float = width_param(
        0.1,
        "slope scale along the rotated x axis (rms slope along it: sigma_x / sqrt(2))",
        edges=(1e-4, 10.0),
    )
    sigma_y: float = width_param(
        0.1,
        "slope scale along the rotated y axis (rms slope along it: sigma_y / sqrt(2))",
        edges=(1e-4, 10.0),
    )
    rotation: float = rotation_param("rotation of the x axis from the sample x axis (rad)")
    coverage: float = coverage_param()


@dataclass(frozen=True)
class AnisotropicExponentialSlopes(_Anisotropic):
    """Anisotropic exponential slopes, as SCATMECH's
    ``Anisotropic_Exponential_Slope_Distribution_Function``:

    ``P3^xy = C 3/(pi sx sy) exp(-sqrt(6) sqrt((u/sx)^2 + (v/sy)^2))`` with
    ``(u, v)`` the slope in axes rotated by ``rotation`` from x.  For
    ``sigma_x = sigma_y = sigma`` it is Eq. 42 with rms slope ``sigma``; along
    each axis the rms slope is ``sigma_x / sqrt(2)``, ``sigma_y / sqrt(2)``.
    """

    kernel_code = kernel_specs.ANISO_EXPONENTIAL

    def _p3_unit(self, zx, zy):
        u, v = self._local(zx, zy)
        r = np.sqrt((u / self.sigma_x) ** 2 + (v / self.sigma_y) ** 2)
        return 3.0 / (math.pi * self.sigma_x * self.sigma_y) * _exp_neg(_SQRT6 * r)

    def _isotropic_unit(self):
        return ExponentialSlopes(sigma=1.0)


@dataclass(frozen=True)
class AnisotropicGaussianSlopes(_Anisotropic):
    """Anisotropic Gaussian slopes ``C exp(-(u/sx)^2 - (v/sy)^2) / (pi sx sy)``.

    ``(u, v)`` are the slopes in axes rotated by ``rotation``; per-axis rms slope
    ``sigma_x / sqrt(2)``; ``sigma_x = sigma_y = m`` is :class:`GaussianSlopes`
    with ``sigma = m`` (the Cook-Torrance / Beckmann distribution).
    """

    kernel_code = kernel_specs.ANISO_GAUSSIAN

    def _p3_unit(self, zx, zy):
        u, v = self._local(zx, zy)
        return _exp_neg((u / self.sigma_x) ** 2 + (v / self.sigma_y) ** 2) / (
            math.pi * self.sigma_x * self.sigma_y
        )

    def _isotropic_unit(self):
        return GaussianSlopes(sigma=1.0)


@dataclass(frozen=True)
class _AngleDistribution(SlopeDistribution):
    """Distributions declared as ``P1^A`` (sampled on the actual flake area), as
    flakes are usually characterized.  ``P3^xy = C <sec> cos^4 P1^A`` (Eq. 41)
    with ``<sec> = 1 / <cos theta_n>_A``, both normalizations exact on the
    hemisphere of normals."""

    sigma: float = width_param(
        0.1, "angular width (rad): the rms tilt in the small-angle limit", high=math.pi, edges=WIDTH_EDGES[:3]
    )
    # no kernel_code: their normalizations are quadratures (the numpy path)
    coverage: float = coverage_param()

    def _shape(self, theta):  # pragma: no cover - abstract
        raise NotImplementedError

    @cached_property
    def _norms(self):
        # (int shape dOmega, int cos * shape dOmega) over the hemisphere of normals.
        f0 = lambda t: self._shape(t) * math.sin(t)  # noqa: E731
        f1 = lambda t: self._shape(t) * math.sin(t) * math.cos(t)  # noqa: E731
        pts = [min(self.sigma * k, math.pi / 2) for k in (1, 3, 10)]
        a, _ = integrate.quad(f0, 0, math.pi / 2, points=pts, limit=400, epsrel=1e-13)
        b, _ = integrate.quad(f1, 0, math.pi / 2, points=pts, limit=400, epsrel=1e-13)
        return 2 * math.pi * a, 2 * math.pi * b

    def p1_area(self, theta_n):
        """``P1^A(theta_n)`` as declared (normalized over the hemisphere)."""
        t = np.asarray(theta_n, dtype=float)
        return np.where(t < math.pi / 2, self._shape(np.minimum(t, math.pi / 2)), 0.0) / self._norms[0]

    def _p3_unit(self, zx, zy):
        z2 = zx * zx + zy * zy
        t = np.arctan(np.sqrt(z2))
        cos4 = 1.0 / (1.0 + z2) ** 2
        a0, a1 = self._norms
        # C <sec> cos^4 P1^A with <sec> = 1/<cos>_A = a0/a1 and P1^A = shape/a0.
        return cos4 * self._shape(t) / a1

    def mean_sec(self):
        a0, a1 = self._norms
        return a0 / a1

    @property
    def _zeta_max(self):
        return math.tan(min(math.pi / 2 * 0.999999, 40 * self.sigma))


@dataclass(frozen=True)
class GaussianAngles(_AngleDistribution):
    """Gaussian distribution of flake tilt angles, ``P1^A ~ exp(-(theta_n / sigma)^2)``.

    Declared on the actual flake area (``A`` sampling) and normalized over the
    hemisphere of normals.  (SCATMECH's ``Gaussian_Angle_Distribution_Function``
    normalizes in ``theta dtheta`` instead of ``sin theta dtheta``, a small-angle
    approximation, so the two differ at large ``sigma``.)
    """

    def _shape(self, theta):
        return _exp_neg((np.asarray(theta) / self.sigma) ** 2)


@dataclass(frozen=True)
class ExponentialAngles(_AngleDistribution):
    """Exponential distribution of flake tilt angles, ``P1^A ~ exp(-sqrt(6) theta_n / sigma)``
    (``sigma`` is the rms tilt in the small-angle limit), declared on the flake area."""

    def _shape(self, theta):
        return _exp_neg(_SQRT6 * np.asarray(theta) / self.sigma)


@dataclass(frozen=True)
class TabulatedSlopes(SlopeDistribution):
    """Isotropic ``P3^xy`` from measured values (seed 000 Sec. 4, Fig. 4).

    ``zeta`` (increasing, >= 0) and ``values`` (> 0) are the measured slope density;
    between points ``log P3`` is interpolated linearly (exact for an exponential
    distribution), below the first point it is held, beyond the last it is
    zero (nothing was measured there).  ``coverage`` is *computed*: the Eq. 33
    integral of the table (the paper found 0.77 for its sample).  Use
    :meth:`normalized` for a table scaled to ``C = 1``.
    """

    zeta: tuple = param(
        (0.0, 1.0), "tabulated slopes (increasing, >= 0)", Samples(Interval(0.0), increasing=True)
    )
    values: tuple = param((1.0, 1.0), "P3^xy at those slopes (> 0)", Samples(Interval(0.0, closed="right")))

    # no kernel_code: a table (the numpy path)

    def _validate(self):
        if len(self.values) != len(self.zeta):
            raise ValueError(
                f"values must hold one P3 value per slope ({len(self.zeta)}); got {len(self.values)}"
            )

    @property
    def scale(self):
        """rms slope of the table, sqrt(<zeta^2>)."""
        f = lambda s: s * s * float(self._p4_unit(np.array(s)))  # noqa: E731
        val, _ = integrate.quad(f, 0, float(self.zeta[-1]), limit=800)
        return math.sqrt(val)

    @cached_property
    def _table(self):
        return np.asarray(self.zeta), np.log(np.asarray(self.values))

    def _p3_raw(self, zeta):
        z, lp = self._table
        v = np.exp(np.interp(zeta, z, lp))
        return np.where(zeta <= z[-1], v, 0.0)

    @cached_property
    def coverage(self) -> float:  # noqa: D401 - a computed parameter
        z = np.asarray(self.zeta)
        f = lambda s: 2 * math.pi * s * float(self._p3_raw(np.array(s)))  # noqa: E731
        val, _ = integrate.quad(f, 0, z[-1], points=list(z[1:-1])[:100], limit=800)
        return val

    def _p3_unit(self, zx, zy):
        return self._p3_raw(np.sqrt(zx * zx + zy * zy)) / self.coverage

    @property
    def _zeta_max(self):
        return float(self.zeta[-1])

    def normalized(self):
        """The same table scaled so that its coverage is 1."""
        c = self.coverage
        return TabulatedSlopes(zeta=self.zeta, values=tuple(np.asarray(self.values) / c))

    def mean_sec(self):
        z = np.asarray(self.zeta)
        f = lambda s: math.sqrt(1 + s * s) * float(self._p4_unit(np.array(s)))  # noqa: E731
        val, _ = integrate.quad(f, 0, z[-1], limit=800)
        return val


@dataclass(frozen=True)
class UnitSlopes(SlopeDistribution):
    """``P3(zeta) = 1`` for every slope: a facet model's BRDF *per unit slope density*.

    Not a probability distribution (it does not normalize); the facet BRDF is
    linear in ``P3`` (seed 000 Eq. 49), so a model built with it gives the kernel
    that slope-distribution inversion divides a measured BRDF by.
    """

    coverage: float = param(1.0, "fixed at 1", ScalarOrArray(Interval(1.0, 1.0)))

    density = False
    kernel_code = kernel_specs.UNIT

    def kernel_row(self):
        return [1.0, 1.0, 0.0, 1.0]

    def _p3_unit(self, zx, zy):
        return np.ones(np.broadcast_shapes(np.shape(zx), np.shape(zy)))


@dataclass(frozen=True)
class GGXSlopes(SlopeDistribution):
    """GGX (Trowbridge-Reitz) slopes ``P3^xy = C alpha^2 / (pi (alpha^2 + zeta^2)^2)``.

    The microfacet distribution of Walter et al. 2007 and Mitsuba's ``ggx``
    (``D(theta_n) = P3 / cos^4 theta_n``).  Its rms slope is *infinite*: the
    slope-magnitude density ``P4 = 2 C alpha^2 zeta / (alpha^2 + zeta^2)^2`` falls
    only like ``zeta^-3``, so ``<zeta^2>`` diverges logarithmically and there is no
    ``sigma``.  ``alpha`` plays the role of Beckmann's ``alpha`` (our Gaussian
    ``sigma``): half of the slopes lie within ``|zeta| < alpha`` (``P4``'s median),
    ``P3`` falls to half its peak at ``0.64 alpha``.  :attr:`scale` (the width that
    lobe hints and integrators read) is ``alpha``; a consumer that truncates the
    slope plane at ``k alpha`` loses ``1 / (1 + k^2)`` of the distribution.
    ``<sec theta_n>`` (Eq. 36) is finite.

    Parameters
    ----------
    alpha : float
        Width ``alpha > 0`` (``alpha^2 = <zeta^2>`` has no meaning here).
    coverage : float
        Projected coverage ``C`` in (0, 1].
    """

    alpha: float = width_param(0.1, "GGX width alpha (rms slope is infinite)", edges=WIDTH_EDGES)
    coverage: float = coverage_param()

    kernel_code = kernel_specs.GGX

    def kernel_row(self):
        return [self.alpha, self.alpha, 0.0, self.coverage]

    @property
    def scale(self):
        """``alpha``, the characteristic slope (the median slope magnitude)."""
        return self.alpha

    def _p3_unit(self, zx, zy):
        a2 = self.alpha * self.alpha
        d = a2 + zx * zx + zy * zy
        return a2 / (math.pi * d * d)

    def _sample_radius_unit(self, u):
        # CDF of P4: zeta^2 / (alpha^2 + zeta^2), inverted exactly.
        u = np.asarray(u, dtype=float)
        return self.alpha * np.sqrt(u / (1.0 - u))

    @property
    def _zeta_max(self):
        # the tail beyond zeta_max holds alpha^2 / (alpha^2 + zeta_max^2) <= 1e-10
        return 1e5 * self.alpha


@dataclass(frozen=True)
class AnisotropicGGXSlopes(_Elliptical):
    """Anisotropic GGX slopes ``C / (pi ax ay (1 + (u/ax)^2 + (v/ay)^2)^2)``.

    ``(u, v)`` are the slopes in axes rotated by ``rotation`` from x;
    ``alpha_x = alpha_y = alpha`` is :class:`GGXSlopes`.  Like it, the rms slope
    is infinite along every direction; :attr:`scale` is ``max(alpha_x, alpha_y)``.
    """

    # Swept to 200:1 (from the sweep's 0.05 x 0.2 base).  At 2e3:1 (1e-4 x 0.2) the
    # unshadowed albedo at 89.99 deg is ~148 and the integrator does not reach the sweep's
    # absolute 1e-3 within its 2e6-evaluation budget (148.39 +- 0.02; at 1e-3 x 0.2 it
    # converges to 148.396): a limit of the energy check at large albedos, not of the model.
    alpha_x: float = width_param(0.1, "GGX width along the rotated x axis", edges=(1e-3, 10.0))
    alpha_y: float = width_param(0.1, "GGX width along the rotated y axis", edges=(1e-3, 10.0))
    rotation: float = rotation_param("rotation of the x axis from the sample x axis (rad)")
    coverage: float = coverage_param()

    kernel_code = kernel_specs.ANISO_GGX

    # the axis widths under the names the elliptical base class reads (not rms slopes)
    sigma_x = property(lambda self: self.alpha_x)
    sigma_y = property(lambda self: self.alpha_y)

    def _p3_unit(self, zx, zy):
        u, v = self._local(zx, zy)
        d = 1.0 + (u / self.alpha_x) ** 2 + (v / self.alpha_y) ** 2
        return 1.0 / (math.pi * self.alpha_x * self.alpha_y * d * d)

    def _isotropic_unit(self):
        return GGXSlopes(alpha=1.0)

    @property
    def _zeta_max(self):
        return 1e5 * self.scale


#: A model's ``slopes`` parameter: any slope distribution
SLOPES = Instance(SlopeDistribution, text="a slope distribution (e.g. models.ExponentialSlopes)")
