"""Thin-film stacks: amplitude coefficients of planar multilayers (transfer-matrix method).

A :class:`FilmStack` is a sequence of films (index ``n + ik`` and thickness in
nm, listed from the incident side down) on a ``substrate``, at one vacuum
wavelength.  The incident medium is not part of the stack: it is the real
index of whatever the light arrives from (the ambient, or a coating), given
when coefficients are asked for, so a stack can stand wherever a substrate
index can (``FacetBRDF(slopes=..., substrate=FilmStack(...))``).

Conventions are those of :mod:`models.fresnel` (Born & Wolf, SCATMECH): with
``kz_j = n_j cos(theta_j) = sqrt(n_j^2 - (n_0 sin theta_0)^2)`` on the branch
with ``Im >= 0`` (decaying, as :func:`models.fresnel._w`), each interface
``j | j+1`` has

    r_s = (kz_j - kz_j1) / (kz_j + kz_j1)
    r_p = (n_j1^2 kz_j - n_j^2 kz_j1) / (n_j1^2 kz_j + n_j^2 kz_j1)
    t_s = 2 kz_j / (kz_j + kz_j1),  t_p = 2 n_j n_j1 kz_j / (n_j1^2 kz_j + n_j^2 kz_j1)

(``t_p``: ratio of the p components of the electric fields; ``r_p = -r_s`` at
normal incidence), and the films are summed from the substrate up (Rouard's
method, the product of the layers' 2x2 transfer matrices written as a
recursion):

    r <- (r_j + r e) / (1 + r_j r e),   t <- t_j t sqrt(e) / (1 + r_j r e),
    e = exp(2 i beta),  beta = 2 pi d kz / lambda  (the film's phase thickness).

A zero-thickness film therefore changes nothing (``(r01 + r12)/(1 + r01 r12) =
r02`` for both polarizations, phases included) and a stack without films is
the bare interface, evaluated by :func:`models.fresnel.fresnel_coefficients`
itself.  A perfect-conductor substrate (``math.inf``) has ``r_s = -1``,
``r_p = +1``, ``t = 0`` at the last interface.

Dispersion: every index (films and substrate) may be a number or a callable
of the wavelength in nm returning ``n + ik`` (e.g. :class:`TabulatedIndex`);
:meth:`FilmStack.at` gives the same stack at another wavelength.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .fresnel import _w, fresnel_coefficients, reflection_rs_k
from .params import Declared, check_index, check_real, param

__all__ = ["FilmStack", "TabulatedIndex"]


@dataclass(frozen=True)
class TabulatedIndex(Declared):
    """A dispersive index ``n(lambda) + i k(lambda)`` from a table, linear between points.

    Outside the table it raises ``ValueError`` (no extrapolation).  Call it with a
    wavelength in nm.
    """

    wavelength_nm: tuple = param((400.0, 700.0), "wavelengths (nm), increasing", kind="object")
    n: tuple = param((1.5, 1.5), "real parts at those wavelengths (> 0)", kind="object")
    k: tuple = param((0.0, 0.0), "imaginary parts (>= 0)", kind="object")

    def _validate(self):
        w, n, k = (np.asarray(v, dtype=float) for v in (self.wavelength_nm, self.n, self.k))
        if w.ndim != 1 or w.size < 2 or not np.all(np.isfinite(w)) or np.any(np.diff(w) <= 0):
            raise ValueError("wavelength_nm must be at least two finite, strictly increasing values")
        if n.shape != w.shape or not np.all(np.isfinite(n)) or np.any(n <= 0):
            raise ValueError("n must hold one finite value > 0 per wavelength")
        if k.shape != w.shape or not np.all(np.isfinite(k)) or np.any(k < 0):
            raise ValueError("k must hold one finite value >= 0 per wavelength")
        for name, v in (("wavelength_nm", w), ("n", n), ("k", k)):
            object.__setattr__(self, name, tuple(v.tolist()))

    def __call__(self, wavelength_nm):
        lo, hi = self.wavelength_nm[0], self.wavelength_nm[-1]
        check_real("wavelength_nm", wavelength_nm, lo, hi)
        n = np.interp(wavelength_nm, self.wavelength_nm, self.n)
        k = np.interp(wavelength_nm, self.wavelength_nm, self.k)
        return complex(n, k)


def _resolve(name, value, wavelength_nm):
    """An index (number or callable of the wavelength) at ``wavelength_nm``, validated."""
    if callable(value):
        value = value(wavelength_nm)
    return check_index(name, value)


@dataclass(frozen=True)
class FilmStack(Declared):
    """Thin films on a substrate, usable wherever a substrate index is (module docstring).

    Parameters
    ----------
    layers : tuple of (index, thickness_nm)
        Films from the incident side down; ``index`` is ``n + ik`` (``k >= 0``) or a
        callable of the wavelength in nm; ``thickness_nm >= 0``.
    substrate : complex, math.inf or callable
        The medium below the last film (``math.inf``: a perfect conductor).
    wavelength_nm : float
        Vacuum wavelength (nm) at which the indices and phases are evaluated.
    """

    layers: tuple = param((), "films ((index, thickness_nm), ...) from the incident side", kind="object")
    substrate: complex = param(1.5 + 0j, "index below the films (n + ik, inf, or callable)", kind="object")
    wavelength_nm: float = param(550.0, "vacuum wavelength (nm)", low=0.0, low_open=True)

    def _validate(self):
        try:
            pairs = tuple((idx, d) for idx, d in self.layers)
        except (TypeError, ValueError):
            raise ValueError(
                f"layers must be a sequence of (index, thickness_nm) pairs; got {self.layers!r}"
            ) from None
        # check_real, not float(): a bool or a string is no thickness (float(True) is 1.0)
        layers = tuple(
            (idx, check_real(f"layers[{j}] thickness_nm", d, 0.0)) for j, (idx, d) in enumerate(pairs)
        )
        object.__setattr__(self, "layers", layers)
        _ = self.indices  # validates every index at this wavelength

    @cached_property
    def indices(self):
        """``(film indices, substrate index)`` at :attr:`wavelength_nm` (films finite)."""
        films = []
        for j, (idx, _) in enumerate(self.layers):
            n = _resolve(f"layers[{j}] index", idx, self.wavelength_nm)
            if n == math.inf:
                raise ValueError(f"layers[{j}] index must be finite (n + ik); got inf")
            films.append(n)
        return tuple(films), _resolve("substrate", self.substrate, self.wavelength_nm)

    def at(self, wavelength_nm):
        """The same stack at another vacuum wavelength (nm)."""
        return self.replace(wavelength_nm=wavelength_nm)

    def coefficients(self, cos_i, n_incident=1.0):
        """``(r_s, r_p, t_s, t_p)`` for light in the real ``n_incident`` at incidence cosine ``cos_i``."""
        n0 = check_real("n_incident", n_incident, 0.0, low_open=True)
        films, sub = self.indices
        c = np.asarray(cos_i, dtype=float)
        if not films:
            return fresnel_coefficients(c, n0, sub)
        kz = [n0 * c + 0j] + [n0 * _w(c, n / n0) for n in films]  # n_j cos(theta_j), Im >= 0
        ns = [complex(n0)] + list(films)
        r, t = _bottom(kz[-1], ns[-1], c, n0, sub)
        for j in range(len(films), 0, -1):
            e_half = np.exp(2j * math.pi * self.layers[j - 1][1] / self.wavelength_nm * kz[j])
            e = e_half * e_half
            rj, tj = _interface(kz[j - 1], kz[j], ns[j - 1], ns[j])
            den = [1.0 + rj[q] * r[q] * e for q in (0, 1)]
            r = [(rj[q] + r[q] * e) / den[q] for q in (0, 1)]
            t = [tj[q] * t[q] * e_half / den[q] for q in (0, 1)]
        return r[0], r[1], t[0], t[1]

    def reflection_rs_k(self, cos_i, n_incident):
        """``r_s`` and ``K = (r_s + r_p) / sin^2(theta)`` (:func:`models.fresnel.reflection_rs_k`).

        ``K`` multiplies terms of order ``sin^2(theta)`` in the facet Jones matrix, so
        its rounding error there stays ~1e-16 however small ``sin``; at exactly
        normal incidence, where ``r_s + r_p = 0``, it is set to 0.
        """
        films, sub = self.indices
        c = np.asarray(cos_i, dtype=float)
        if not films:
            return reflection_rs_k(c, sub if sub == math.inf else sub / n_incident)
        rs, rp, _, _ = self.coefficients(c, n_incident)
        s2 = (1.0 - c) * (1.0 + c)
        return rs, np.where(s2 > 0.0, (rs + rp) / np.where(s2 > 0.0, s2, 1.0), 0.0)

    def reflectance_transmittance(self, cos_i, n_incident=1.0):
        """``(R_s, R_p, T_s, T_p)``: ``|r|^2`` and the transmitted normal Poynting flux
        ``T_s = Re(kz_sub) |t_s|^2 / (n_0 cos)``, ``T_p = Re(conj(n_sub) kz_sub / n_sub) |t_p|^2 /
        (n_0 cos)`` into the substrate (0 for a perfect conductor)."""
        rs, rp, ts, tp = self.coefficients(cos_i, n_incident)
        _, sub = self.indices
        c = np.asarray(cos_i, dtype=float)
        if sub == math.inf:
            zero = np.zeros(c.shape)
            return np.abs(rs) ** 2, np.abs(rp) ** 2, zero, zero.copy()
        kz = n_incident * _w(c, sub / n_incident)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = np.where(c > 0, 1.0 / (n_incident * np.where(c > 0, c, 1.0)), 0.0)
        ts2 = kz.real * np.abs(ts) ** 2 * inv
        tp2 = (np.conj(sub) * kz / sub).real * np.abs(tp) ** 2 * inv
        return np.abs(rs) ** 2, np.abs(rp) ** 2, ts2, tp2


def _interface(kz1, kz2, n1, n2):
    """``((r_s, r_p), (t_s, t_p))`` of one interface (module docstring)."""
    a = n2 * n2 * kz1
    b = n1 * n1 * kz2
    rs = (kz1 - kz2) / (kz1 + kz2)
    rp = (a - b) / (a + b)
    return (rs, rp), (2.0 * kz1 / (kz1 + kz2), 2.0 * n1 * n2 * kz1 / (a + b))


def _bottom(kz_last, n_last, c, n0, sub):
    """``([r_s, r_p], [t_s, t_p])`` of the last film's interface with the substrate."""
    if sub == math.inf:
        one = np.ones(c.shape, dtype=complex)
        return [-one, one.copy()], [0.0 * one, 0.0 * one]
    kz_sub = n0 * _w(c, sub / n0)
    (rs, rp), (ts, tp) = _interface(kz_last, kz_sub, n_last, sub)
    return [rs, rp], [ts, tp]
