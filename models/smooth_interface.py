"""Transmission through a smooth non-absorbing interface, shared by the seed 003 models.

For a ray at external polar angle ``theta`` (cosine ``c``) entering a medium of
real index ``n >= 1`` (internal cosine ``c'``), the Fresnel amplitudes are
``t_s = 2c / (c + n c')``, ``t_p = 2c / (n c + c')`` (Born & Wolf, as in
:mod:`scatterbench.models.fresnel`, with ``w = n c'``).  Seed 003 Eq. 14, 20, 24-27 always
multiply ``|t|^2`` by ``c'/c``; the amplitudes carrying that factor,

    a_s = t_s sqrt(c'/c) = 2 sqrt(c c') / (c + n c'),
    a_p = t_p sqrt(c'/c) = 2 sqrt(c c') / (n c + c'),

have no division by ``cos(theta)`` and vanish at grazing incidence, so the
models need no special case there.  ``n a^2 = T`` (intensity transmittance).
By reciprocity of the transmittance the same amplitudes describe the exit of a
ray leaving at ``theta`` (seed 003 Eq. 11, 25).

Thin films on the interface (ambient | films | coating, ``coating_films`` of the coated
models; :mod:`scatterbench.models.thin_film`).  The films change neither direction (the Snell invariant
``sin theta`` is the same in every layer) nor the solid-angle and projection factors; they
change the amplitudes of the two crossings, which become complex:

* entrance (F1): ``t_in = t_01(theta)``, the stack's transmission from the ambient into the
  coating (:meth:`scatterbench.models.FilmStack.transmission_down`);
* exit (F2): the ray leaves the coating at ``theta'`` and emerges at ``theta`` with the
  stack's upward amplitude ``t_10`` (:meth:`scatterbench.models.FilmStack.transmission_up`).  Seed 000
  Eq. 14-15 and seed 003 Eq. 11, 25 write the exit with ``t(theta; 1, n)``, which for one
  interface is ``t_10 kz_0 / kz_s`` (``kz_0 = cos theta``, ``kz_s = n cos theta'``): the
  Fresnel exit amplitude with the ratio of the normal wavevectors that the radiance
  bookkeeping (``n^2`` and the ``cos'/cos`` of the refracted solid angle) puts beside it.  With films the exit factor is therefore
  ``t_out = t_10 kz_0 / kz_s``, in both polarizations, complex.

Flux (F3): ``n |a|^2`` with ``a = t sqrt(c'/c)`` is the transmittance of the crossing, for
either factor: ``T_01 = (kz_s / kz_0) |t_01|^2`` and ``T_10 = (kz_0 / kz_s) |t_10|^2``, the
ratios of the normal Poynting fluxes (``Re(kz)`` of real outer media is ``kz``).  An
absorbing film lowers both below ``1 - R``, so the models' energy still balances.
Reciprocity (F4): the stack obeys ``t_10 kz_0 = t_01 kz_s`` (:mod:`scatterbench.models.thin_film`,
(R)), so ``t_out(theta) = t_in(theta)`` and a model built from (F1)-(F2) keeps the bare
model's Helmholtz reciprocity; the exit is nonetheless computed from ``t_10`` (the
physics), and the reciprocity tests compare the two crossings.  The relative s/p phase
of ``t`` enters the Jones matrices (polarized models); only ``|a|^2`` enters the
depolarizing ones.  A zero-thickness film, or one whose index is the coating's or the
ambient's, gives the bare interface.

R-bar with films (F5): seed 003 Eq. 22's average (``1/pi``) of the internal reflectance
``R_10`` of the stack seen from inside the coating (:meth:`scatterbench.models.FilmStack.upward`),
``int_0^1 R_10 du`` over ``u = sin^2 theta'``.  With films the Stokes shortcut of
:func:`internal_hemispherical_reflectance` does not hold (an absorbing film makes
``R_10 != R_01`` and ``R_10 < 1`` beyond the critical angle), so it is integrated:
:func:`film_hemispherical_reflectance`.
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
from scipy import integrate
from scipy.integrate import _quadpack

from .cubature import AccuracyWarning
from .fresnel import coating_cos
from .geometry import gauss_legendre
from .thin_film import FilmStack

__all__ = [
    "interface_amplitudes",
    "internal_hemispherical_reflectance",
    "depolarized_between",
    "squared_modulus",
    "film_transmission",
    "film_amplitudes",
    "film_hemispherical_reflectance",
]

_TINY = 1e-300


def interface_amplitudes(cos_ext, n):
    """``(sin_int, cos_int, a_s, a_p)`` for external cosines ``cos_ext`` (any shape)."""
    c = np.asarray(cos_ext, dtype=float)
    # np.cos(pi/2) = 6e-17: cosines below 1e-15 (within ~1e-15 rad of grazing, a few
    # ulps of pi/2) are exactly grazing, so theta = pi/2 gives exact zeros.
    c = np.where(c < 1e-15, 0.0, c)
    s_int = np.sqrt(1.0 - c * c) * (1.0 / n)
    c_int = coating_cos(c, n)  # not sqrt(1 - s_int^2): that cancels near grazing
    root = 2.0 * np.sqrt(c * c_int)
    # For n = 1 at grazing both terms of the denominators vanish with the numerator
    # (a = 1 in the limit, but the ray carries no projected flux): 0/tiny = 0.
    a_s = root / np.maximum(c + n * c_int, _TINY)
    a_p = root / np.maximum(n * c + c_int, _TINY)
    return s_int, c_int, a_s, a_p


def squared_modulus(a):
    """``|a|^2``: ``a * a`` for the real amplitudes of a bare interface (as before films), the
    squared modulus for the complex ones through films."""
    if np.iscomplexobj(a):
        return a.real * a.real + a.imag * a.imag
    return a * a


def depolarized_between(a_s_in, a_p_in, a_s_out, a_p_out, scale):
    """Mueller elements ``(16, n)`` of light transmitted in, fully depolarized, and transmitted
    out: ``scale x M(t_out)[:, 0] (x) M(t_in)[0, :]`` (seed 003 Eq. 28's structure) from the
    interface amplitudes (:func:`interface_amplitudes`, or complex ones through films,
    :func:`film_amplitudes`) of the two crossings.  Only the intensity and the linear s/p
    diattenuation survive (elements 00, 01, 10, 11)."""
    a, b = squared_modulus(a_s_out), squared_modulus(a_p_out)
    c, d = squared_modulus(a_s_in), squared_modulus(a_p_in)
    s_out, d_out = 0.5 * (a + b) * scale, 0.5 * (a - b) * scale
    s_in, d_in = 0.5 * (c + d), 0.5 * (c - d)
    out = np.zeros((16,) + np.shape(s_in * s_out))
    out[0] = s_out * s_in
    out[1] = s_out * d_in
    out[4] = d_out * s_in
    out[5] = d_out * d_in
    return out


def internal_hemispherical_reflectance(n: float) -> float:
    """``R-bar`` of seed 003 Eq. 22 with the cos-weighted average normalized by ``1/pi``.

    ``R-bar = (1/pi) int R_int(theta') cos(theta') dOmega'`` for light inside a
    medium of index ``n`` hitting the interface with air.  Seed 003 Eq. 22
    prints ``1/(2 pi)``, which would average to 1/2 for a perfect reflector; the
    cos-weighted hemispherical average needs ``1/pi`` (DESIGN.md; with it
    the model has unit albedo at ``rho = 1``, checked in the tests).

    Computed exactly (to ~1e-15): with ``u = sin^2(theta')`` the average is
    ``int_0^1 R du``; beyond the critical angle ``R = 1`` (contributing
    ``1 - 1/n^2``), and below it the internal reflectance equals the external
    one at the refracted angle (Stokes relations), so with the external cosine
    ``c``: ``R-bar = 1 - (1 - int_0^1 R_ext(c) 2c dc) / n^2``.  The last
    integrand is analytic on [0, 1] and is integrated adaptively, once per index (cached:
    a model set, or each chunk of one, asks again for the indices it holds), by QUADPACK with
    the integrand compiled (:func:`_compiled_quad`: the bits of ``quad`` with the Python
    integrand, 20x faster).  Not the closed form of the hemispherical Fresnel reflectance:
    it rounds differently from this quadrature, so every R-bar, and a fit's log posteriors,
    would change in their last bits.
    """
    return _rbar(float(n))


@functools.lru_cache(maxsize=4096)
def _rbar(n: float) -> float:
    if n == 1.0:
        return 0.0
    if n == math.inf:  # a conductor: R = 1 everywhere (the float form below would give NaN)
        return 1.0
    # The integrand has a branch point at c = i sqrt(n^2 - 1): near n = 1 it is
    # sharp close to c = 0, so give quad breakpoints there.
    point = min(0.5, 10.0 * math.sqrt(n * n - 1.0))
    val = _compiled_quad(n * n, point)
    if val is None:
        val = _python_quad(n * n, point)
    return 1.0 - (1.0 - val) / (n * n)


def _integrand(c, nn):
    """0.5 (Rs + Rp) * 2c: fresnel._reflectance(c, 1, n) written in floats, the operations
    numpy's complex ones reduce to with zero imaginary parts (w = sqrt(n^2 - 1 + c^2) is real
    for n > 1; a complex quotient is a * (1 / b)), so the same bits (tested) at 1/40 of the cost."""
    w = math.sqrt((nn - 1.0) + c * c)
    rs = (c - w) * (1.0 / (c + w))
    rp = (nn * c - w) * (1.0 / (nn * c + w))
    return (rs * rs + rp * rp) * c


def _python_quad(nn, point):
    """``int_0^1`` of :func:`_integrand` by ``quad`` (QUADPACK's ``qagp``) in Python: the reference
    of :func:`_compiled_quad`, and its stand-in where that gives nothing (``quad`` then warns as it does)."""
    val, _ = integrate.quad(
        _integrand, 0.0, 1.0, args=(nn,), points=[point], epsabs=1e-14, epsrel=1e-12, limit=200
    )
    return val


#: where R-bar's compiled integrand comes from: a function that returns the numba ``cfunc``
#: (:func:`scatterbench.models.kernels.rbar_integrand`), set by :mod:`scatterbench.models.kernels`
#: when it loads, since the kernels sit above this module's layer; until then (and with numba's
#: JIT off) R-bar integrates the Python integrand: the same bits, 20x slower
INTEGRAND_SOURCE = None


def _compiled_integrand():
    """The compiled integrand as a :class:`scipy.LowLevelCallable`; ``None`` where it cannot be
    had (the kernels not loaded yet; ``NUMBA_DISABLE_JIT=1``: a Python function)."""
    return None if INTEGRAND_SOURCE is None else _low_level(INTEGRAND_SOURCE)


@functools.cache
def _low_level(source):
    from scipy import LowLevelCallable

    fn = getattr(source(), "ctypes", None)
    return None if fn is None else LowLevelCallable(fn)


def _compiled_quad(nn, point):
    """:func:`_python_quad`'s value, bit for bit, with the compiled integrand: the same QUADPACK
    routine that ``quad`` calls for breakpoints (``_qagpe``, the breakpoints as ``quad`` passes
    them: in (0, 1), then two zeros) and the same samples of the same float operations
    (:mod:`scatterbench.models.kernels.rbar`), without ``quad``'s Python (its ``np.unique`` of the
    breakpoints was a fifth of R-bar's time); ``None`` where QUADPACK reports a problem (``quad``
    then warns) or scipy's private entry differs."""
    fn = _compiled_integrand()
    if fn is None or not 0.0 < point < 1.0:
        return None
    try:
        val, _, ier = _quadpack._qagpe(fn, 0.0, 1.0, np.array([point, 0.0, 0.0]), (nn,), 0, 1e-14, 1e-12, 200)
    except (AttributeError, TypeError, ValueError):  # scipy's private signature changed
        return None
    return val if ier == 0 else None


def film_transmission(cos_in, cos_out, stack: FilmStack):
    """``((t_s, t_p) in, (t_s, t_p) out)``: the complex amplitudes (F1)-(F2) (module docstring)
    that replace ``t(theta; 1, n)`` for a ray entering at the external cosine ``cos_in``, and
    one leaving at ``cos_out``, through the films of ``stack`` (a :class:`scatterbench.models.FilmStack` on
    the coating's index, under the ambient 1).  Each crossing is computed at its own cosine
    only: the entrance from ``t_01``, the exit from ``t_10`` (F4: not from ``t_01``)."""
    c = np.asarray(cos_out, dtype=float)
    ts, tp = stack.transmission_down(cos_in)
    us, up = stack.transmission_up(c)
    n = stack.indices[1].real
    kz_s = n * coating_cos(c, n)
    # kz_0 / kz_s; kz_s = 0 only for n = 1 at grazing, where the ray carries no flux
    ratio = np.where(kz_s > 0.0, c / np.where(kz_s > 0.0, kz_s, 1.0), 0.0)
    return (ts, tp), (us * ratio, up * ratio)


def film_amplitudes(cos_ext, stack: FilmStack):
    """``(sin_int, cos_int, (a_s, a_p) in, (a_s, a_p) out)``: :func:`interface_amplitudes` with
    films, ``a = t sqrt(c'/c)`` of each crossing of :func:`film_transmission` (complex).
    ``cos_ext`` stacks the incidence's cosines (row 0) and the exit's (row 1); ``sin_int``
    and ``cos_int`` keep both rows, the entrance amplitudes are row 0's, the exit's row 1's."""
    c = np.asarray(cos_ext, dtype=float)
    c = np.where(c < 1e-15, 0.0, c)  # exactly grazing, as interface_amplitudes
    n = stack.indices[1].real
    s_int = np.sqrt(1.0 - c * c) * (1.0 / n)
    c_int = coating_cos(c, n)
    # sqrt(c'/c): t_in and the exit's kz_0 / kz_s vanish like c, so a -> 0 at grazing
    g = np.where(c > 0.0, np.sqrt(c_int / np.where(c > 0.0, c, 1.0)), 0.0)
    (ts, tp), (us, up) = film_transmission(c[0], c[1], stack)
    return s_int, c_int, (ts * g[0], tp * g[0]), (us * g[1], up * g[1])


def film_hemispherical_reflectance(stack: FilmStack, tol: float = 1e-14) -> float:
    """``R-bar`` (F5): ``int_0^1 R_10 du``, ``u = sin^2 theta'`` inside the coating (``1/pi``
    normalization, as :func:`internal_hemispherical_reflectance`), for the films of
    ``stack`` (a :class:`scatterbench.models.FilmStack` on the coating's real index) under the ambient 1.

    ``R_10`` has square-root branch points where the ambient's and the coating's normal
    wavevectors vanish (the critical angle and internal grazing; the films' own are even in
    their ``kz`` and cancel).  Two substitutions make each part smooth on ``phi in [0, pi/2]``:
    ``u = sin^2(phi) / n^2`` below the critical angle and ``u = 1/n^2 + (1 - 1/n^2) sin^2(phi)``
    beyond it (``kz`` of the ambient and of the coating are then ``cos phi``, ``sin phi``
    times constants).  Composite 16-point Gauss-Legendre, panels doubled until two estimates
    differ by at most ``tol`` (interference fringes of thick films need many panels); at
    2^14 panels the last estimate stands (a film thousands of wavelengths thick, whose
    fringes are finer than any measurement resolves), with an :class:`~scatterbench.models.cubature.AccuracyWarning`
    giving the last two estimates' difference.
    """
    n = stack.indices[1].real
    up = stack.upward()
    x, w = gauss_legendre(16)

    def estimate(panels):
        edges = np.linspace(0.0, 0.5 * math.pi, panels + 1)
        half = 0.5 * np.diff(edges)
        phi = ((edges[:-1] + half)[:, None] + half[:, None] * x).ravel()
        weight = (half[:, None] * w).ravel() * np.sin(2.0 * phi)
        total = 0.0
        parts = [(1.0 / (n * n), np.sqrt(1.0 - (np.sin(phi) / n) ** 2))]  # below the critical angle
        if n > 1.0:
            parts.append((1.0 - 1.0 / (n * n), math.sqrt(1.0 - 1.0 / (n * n)) * np.cos(phi)))
        for du, cos_int in parts:
            rs, rp, _, _ = up.coefficients(cos_int, n)
            total += du * float(np.dot(weight, 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)))
        return total

    panels, last = 4, estimate(4)
    while panels < 2**14:
        panels *= 2
        new = estimate(panels)
        if abs(new - last) <= tol:
            return new
        diff, last = abs(new - last), new
    warnings.warn(
        f"film_hemispherical_reflectance: {panels} panels, the last two estimates differ by {diff:.3g} "
        f"(tol {tol:g}); the last stands",
        AccuracyWarning,
        stacklevel=2,
    )
    return last
