"""Smith shadowing-masking for facet models (Smith 1967; Heitz 2014, "Understanding
the masking-shadowing function in microfacet-based BRDFs").

For a direction ``v`` at polar angle ``theta`` (from the mean normal, on either
side of the surface) and azimuth ``phi``, with ``mu = |cot theta|``, the Smith
masking of a microsurface whose slopes have the (coverage-normalized) density
``P3`` is ``G1 = chi+(v.m / v.n) / (1 + Lambda(mu, phi))`` with

    Lambda(mu) = (1/mu) int_mu^inf (q - mu) P2(q) dq               (Heitz Eq. 72)
               = 1/(pi mu) int_mu^inf P4(r) [sqrt(r^2 - mu^2) - mu arccos(mu/r)] dr,

``P2`` the marginal density of the slope along ``phi`` and ``P4`` the density of
the slope magnitude (seed 000 Eq. 26; the second line integrates the first over
the slope plane in polar coordinates).  ``chi+`` is 0 for a direction on the
back of the facet normal ``m`` (Heitz Sec. 5.1).  Closed forms:

* Gaussian slopes (Beckmann with ``alpha = sigma``; ``P3 = exp(-(z/sigma)^2) /
  (pi sigma^2)``, so ``P2(q) = exp(-(q/sigma)^2) / (sqrt(pi) sigma)``), ``a = mu /
  sigma``: ``Lambda = (erf(a) - 1) / 2 + exp(-a^2) / (2 a sqrt(pi))``;
* GGX: ``Lambda = (sqrt(1 + alpha^2 / mu^2) - 1) / 2``;
* elliptical anisotropic slopes (Gaussian, GGX, exponential): the isotropic
  unit form at ``mu / alpha(phi)``, ``alpha(phi)^2 = (alpha_x cos phi')^2 +
  (alpha_y sin phi')^2`` with ``phi'`` the azimuth in the distribution's axes
  (the marginal along ``phi`` is the unit one stretched by ``alpha(phi)``);
* any other isotropic distribution: :class:`LambdaTable`, the integral above
  tabulated once per distribution and interpolated (cubic Hermite), to 1e-10.

The separable form is ``G = G1(i) G1(o)``; the height-correlated one (Heitz
Eq. 99) ``G = chi+ chi+ / (1 + Lambda_i + Lambda_o)`` in reflection and
``G = chi+ chi+ B(1 + Lambda_i, 1 + Lambda_o)`` (the Beta function; Heitz Sec. 6) in
transmission, where the facet is seen from both sides of the surface
(:func:`correlated_g` derives both).  ``Lambda`` uses the
distribution normalized to unit coverage: the masking is by the microsurface
itself (with ``C < 1``, e.g. sparse flakes, Smith's model is an assumption).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy import integrate, special

from .slopes import (
    GaussianSlopes,
    GGXSlopes,
    SlopeDistribution,
)

__all__ = [
    "azimuthal_width",
    "is_elliptical",
    "SHADOWING",
    "LambdaTable",
    "lambda_gaussian",
    "lambda_ggx",
    "smith_lambda",
    "smith_g1",
    "smith_g",
    "correlated_g",
    "check_shadowing",
]

#: the ``shadowing`` choices of the facet models
SHADOWING = ("none", "smith", "smith-correlated")

_INV_SQRT_PI = 1.0 / math.sqrt(math.pi)


def check_shadowing(shadowing, slopes):
    """Raise ``ValueError`` unless ``shadowing`` is a known choice that ``slopes`` supports."""
    if shadowing not in SHADOWING:
        raise ValueError(f"shadowing must be one of {', '.join(map(repr, SHADOWING))}; got {shadowing!r}")
    if shadowing != "none" and not slopes.density:
        # Lambda's integral diverges (P3 = 1 everywhere): its table holds inf, G came out 0 or
        # NaN by the geometry
        raise ValueError(
            f"shadowing must be 'none' for {type(slopes).__name__} (not a probability density of "
            f"slopes: Smith's Lambda diverges); got {shadowing!r}"
        )
    if shadowing != "none" and not _supported(slopes):
        raise ValueError(
            "shadowing 'smith' needs isotropic or elliptical (anisotropic Gaussian, GGX or exponential) "
            f"slopes; got {slopes!r}"
        )


def _supported(slopes):
    return slopes.isotropic or is_elliptical(slopes)


def is_elliptical(slopes) -> bool:
    """True for elliptical slopes, an isotropic density stretched along rotated axes (the
    anisotropic Gaussian, GGX and exponential families): they give that unit density
    (``_isotropic_unit()``), to which :func:`azimuthal_width` reduces them along an azimuth."""
    return hasattr(slopes, "_isotropic_unit")


def lambda_gaussian(mu, sigma):
    """Smith ``Lambda`` of Gaussian (Beckmann) slopes at ``mu = |cot theta|`` (exact erf form)."""
    a = np.asarray(mu, dtype=float) / sigma
    with np.errstate(divide="ignore"):
        tail = np.exp(-a * a) * _INV_SQRT_PI / (2.0 * a)  # inf at grazing (a = 0)
    # erfc keeps (erf(a) - 1)/2 accurate where it is tiny; the two terms cancel only
    # for large a, where both are below 1e-12 (absolute error ~1e-16 of them).
    return tail - 0.5 * special.erfc(a)


def lambda_ggx(mu, alpha):
    """Smith ``Lambda`` of GGX slopes at ``mu = |cot theta|``: ``(sqrt(1 + (alpha/mu)^2) - 1) / 2``."""
    mu = np.asarray(mu, dtype=float)
    with np.errstate(divide="ignore"):
        x = alpha / mu  # inf at grazing
    # written as x (x / (1 + hypot(1, x))) / 2 so that small x loses no digits and large x
    # (mu = 1e-300: x^2 overflowed to inf, and inf / inf was NaN) no range: the ratio is < 1
    with np.errstate(invalid="ignore"):
        out = 0.5 * x * (x / (1.0 + np.hypot(1.0, x)))
    return np.where(np.isinf(x), np.inf, out)


class LambdaTable:
    """Smith ``Lambda`` of an isotropic slope distribution, tabulated once.

    ``F(mu) = mu Lambda(mu) = 1/pi int_mu^inf P4(r) K(r, mu) dr`` (module
    docstring) and ``F'(mu) = -1/pi int_mu^inf P4(r) arccos(mu/r) dr`` are
    computed on a uniform grid of ``s = mu / (mu + scale)`` in [0, 1] (one
    vectorized adaptive quadrature for all nodes, in ``r = mu + u^2`` so that the
    integrands have no square-root endpoint singularity); between nodes ``F``
    is the cubic Hermite interpolant.  ``F`` is smooth and bounded in ``s``
    (``F(0) = <zeta_+>``, the mean positive slope along a direction; ``F -> 0``
    at normal incidence), so ``Lambda = F / mu`` and ``G1 = mu / (mu + F)``
    inherit its accuracy, 1e-10 with the default 2049 nodes (measured in the
    tests against the closed forms and a direct two-dimensional quadrature).
    """

    def __init__(self, slopes, nodes=2049):
        if not slopes.isotropic:
            raise ValueError(f"slopes must be isotropic for a Lambda table; got {slopes!r}")
        self.scale = float(slopes.scale)
        s = np.linspace(0.0, 1.0, nodes)
        self._h = s[1] - s[0]
        mu = self.scale * s[:-1] / (1.0 - s[:-1])
        f, df = _lambda_integrals(slopes._p4_unit, mu, self.scale)
        # at s = 1 (normal incidence) F vanishes; its s-derivative need not (GGX: -alpha/4),
        # so it is extrapolated from the last nodes (cubic, error O(h^4))
        self._f = np.append(f, 0.0)
        d = df * self.scale / (1.0 - s[:-1]) ** 2  # dF/ds = F'(mu) dmu/ds
        self._df = np.append(d, 4.0 * d[-1] - 6.0 * d[-2] + 4.0 * d[-3] - d[-4])

    def mu_lambda(self, mu):
        """``F(mu) = mu Lambda(mu)`` by cubic Hermite interpolation in ``s``."""
        mu = np.asarray(mu, dtype=float)
        with np.errstate(invalid="ignore"):
            s = np.where(np.isinf(mu), 1.0, mu / (mu + self.scale))
        x = s / self._h
        k = np.minimum(x.astype(np.intp), self._f.size - 2)
        t = x - k
        t2 = t * t
        t3 = t2 * t
        h00 = 2 * t3 - 3 * t2 + 1
        h10 = t3 - 2 * t2 + t
        h01 = -2 * t3 + 3 * t2
        h11 = t3 - t2
        f, d = self._f, self._df * self._h
        return h00 * f[k] + h10 * d[k] + h01 * f[k + 1] + h11 * d[k + 1]

    def __call__(self, mu):
        """``Lambda(mu)`` (inf at grazing, mu = 0)."""
        mu = np.asarray(mu, dtype=float)
        with np.errstate(divide="ignore"):
            return self.mu_lambda(mu) / mu


def _lambda_integrals(p4, mu, scale):
    """``(F(mu), F'(mu))`` at every ``mu`` (one adaptive vector quadrature)."""

    def integrand(u):
        r = mu + u * u
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.where(r > 0, mu / np.where(r > 0, r, 1.0), 1.0)
        acos = np.arccos(np.minimum(ratio, 1.0))
        kern = u * np.sqrt(r + mu) - mu * acos  # sqrt(r^2 - mu^2) - mu arccos(mu/r)
        w = 2.0 * u * p4(r) / math.pi  # dr = 2u du
        return np.concatenate([w * kern, -w * acos])

    # u^2 spans the slope magnitudes: split the range at the distribution's scale
    bounds = math.sqrt(scale) * np.array([0.0, 0.3, 1.0, 3.0, 10.0, 30.0])
    total = np.zeros(2 * mu.size)
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        total += integrate.quad_vec(integrand, a, b, epsabs=1e-15, epsrel=1e-13, norm="max", limit=2000)[0]
    total += integrate.quad_vec(integrand, bounds[-1], np.inf, epsabs=1e-15, epsrel=1e-13, norm="max")[0]
    return total[: mu.size], total[mu.size :]


@functools.lru_cache(maxsize=64)
def _table(slopes):
    return LambdaTable(slopes)


def _unit(slopes):
    """``(isotropic unit distribution, alpha_x, alpha_y, rotation)`` of elliptical slopes."""
    return slopes._isotropic_unit(), slopes.sigma_x, slopes.sigma_y, slopes.rotation


def _isotropic_lambda(slopes, mu):
    if isinstance(slopes, GaussianSlopes):
        return lambda_gaussian(mu, slopes.sigma)
    if isinstance(slopes, GGXSlopes):
        return lambda_ggx(mu, slopes.alpha)
    return _table(slopes)(mu)


def smith_lambda(slopes, cos_theta, sin_theta, cos_phi, sin_phi):
    """Smith ``Lambda`` of ``slopes`` for directions given by their polar cosine and sine
    (``|cos|`` is used: a direction below the surface is masked from below) and azimuth."""
    c = np.abs(np.asarray(cos_theta, dtype=float))
    s = np.asarray(sin_theta, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        mu = np.where(s > 0, c / np.where(s > 0, s, 1.0), np.inf)  # |cot theta|
    if slopes.isotropic:
        return _isotropic_lambda(slopes, mu)
    unit, alpha = azimuthal_width(slopes, cos_phi, sin_phi)
    return _isotropic_lambda(unit, mu / alpha)


def azimuthal_width(slopes, cos_phi, sin_phi):
    """``(unit, alpha)`` of elliptical slopes: their isotropic unit distribution, and their
    width along azimuth ``phi`` (the slope component along ``phi`` is ``alpha`` times the
    unit distribution's), ``alpha^2 = (sigma_x cos phi')^2 + (sigma_y sin phi')^2`` with
    ``phi' = phi - rotation``."""
    unit, ax, ay, rot = _unit(slopes)
    cr, sr = math.cos(rot), math.sin(rot)
    cl = cos_phi * cr + sin_phi * sr
    sl = sin_phi * cr - cos_phi * sr
    return unit, np.sqrt((ax * cl) ** 2 + (ay * sl) ** 2)


def smith_g1(slopes, cos_theta, sin_theta, cos_phi, sin_phi, cos_local=None):
    """``G1 = chi+(v.m / v.n) / (1 + Lambda)``; ``cos_local = v.m`` (omit: front-facing).

    ``cos_theta`` is ``v.n`` (negative for a direction below the surface).
    """
    g = 1.0 / (1.0 + smith_lambda(slopes, cos_theta, sin_theta, cos_phi, sin_phi))
    if cos_local is not None:
        g = np.where(np.asarray(cos_local) * np.asarray(cos_theta) > 0.0, g, 0.0)
    return g


def smith_g(shadowing, slopes, dir_i, dir_o, cos_local_i=None, cos_local_o=None):
    """Shadowing-masking ``G`` for ``shadowing`` in :data:`SHADOWING` (``"none"``: 1).

    ``dir_i`` and ``dir_o`` are ``(cos_theta, sin_theta, cos_phi, sin_phi)`` of the
    two directions, each pointing away from the surface; ``cos_local_*`` their
    cosines with the facet normal (for the back-facing test).
    """
    if shadowing == "none":
        return 1.0
    if shadowing == "smith":
        return smith_g1(slopes, *dir_i, cos_local_i) * smith_g1(slopes, *dir_o, cos_local_o)
    g = correlated_g(
        smith_lambda(slopes, *dir_i), smith_lambda(slopes, *dir_o), np.asarray(dir_i[0]) * dir_o[0] < 0.0
    )
    for cl, d in ((cos_local_i, dir_i), (cos_local_o, dir_o)):
        if cl is not None:
            g = np.where(np.asarray(cl) * np.asarray(d[0]) > 0.0, g, 0.0)
    return g


def correlated_g(lam_i, lam_o, transmission):
    """The height-correlated ``G`` (without the back-facing tests) of two directions with
    Smith ``Lambda`` values ``lam_i``, ``lam_o``; ``transmission``: the two lie on opposite
    sides of the surface.

    A facet at height ``h`` is seen from a direction above the surface with probability
    ``C(h)^Lambda`` (``C`` the heights' distribution function; Heitz 2014 Sec. 6) and from a
    direction below it with probability ``(1 - C(h))^Lambda``: the microsurface above the
    facet masks the one, the microsurface below it the other.  Integrated over the facet's
    height (``u = C(h)`` uniform on [0, 1]):

    * reflection (both above): ``int_0^1 u^(Li + Lo) du = 1 / (1 + Li + Lo)`` (Heitz Eq. 99);
    * transmission: ``int_0^1 u^Li (1 - u)^Lo du = B(1 + Li, 1 + Lo)``, the Beta function
      (Heitz Sec. 6), which equals the reflection form only where a Lambda is 0.

    A Lambda of inf (grazing) gives 0 either way."""
    lam_i, lam_o = np.asarray(lam_i, dtype=float), np.asarray(lam_o, dtype=float)
    reflected = 1.0 / (1.0 + (lam_i + lam_o))
    dead = np.isinf(lam_i) | np.isinf(lam_o)
    with np.errstate(invalid="ignore"):
        through = np.where(dead, 0.0, special.beta(1.0 + lam_i, 1.0 + lam_o))
    return np.where(transmission, through, reflected)


def lambda_direct(slopes, mu):
    """``Lambda(mu)`` by direct two-dimensional quadrature over the slope plane (for tests):
    ``(1/mu) int int_{x > mu} (x - mu) P3(x, y) dx dy`` for isotropic ``slopes``."""
    if not isinstance(slopes, SlopeDistribution) or not slopes.isotropic:
        raise ValueError(f"slopes must be an isotropic slope distribution; got {slopes!r}")
    p3 = lambda y, x: (x - mu) * float(slopes._p3_unit(np.array(x), np.array(y)))  # noqa: E731
    val, _ = integrate.dblquad(p3, mu, np.inf, -np.inf, np.inf, epsabs=1e-14, epsrel=1e-12)
    return val / mu
