"""Thin-film stacks: amplitude coefficients of planar multilayers (transfer-matrix method).

A :class:`FilmStack` is a sequence of films (index ``n + ik`` and thickness in
nm, listed from the incident side down) on a ``substrate``, at one vacuum
wavelength.  The incident medium is not part of the stack: it is the real
index of whatever the light arrives from (the ambient, or a coating), given
when coefficients are asked for, so a stack can stand wherever a substrate
index can (``FacetBRDF(slopes=..., substrate=FilmStack(...))``).

Conventions are those of :mod:`scatterbench.models.fresnel` (Born & Wolf, SCATMECH): with
``kz_j = n_j cos(theta_j) = sqrt(n_j^2 - (n_0 sin theta_0)^2)`` on the branch
with ``Im >= 0`` (decaying, as :func:`scatterbench.models.fresnel._w`), each interface
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

The code carries the recursion as the admittance below each film (:func:`_rouard_one`):
the same algebra, multiplied through so that ``1 + r_j r e`` is never formed (it rounds to 0
for a thin film of extreme index, both reflections near +-1).  A zero-thickness film
changes nothing (``(r01 + r12)/(1 + r01 r12) = r02`` for both polarizations, phases
included; in the admittance form its step leaves the admittance as it was), and the
recursion leaves such films out; two media of one index (equal admittances) meet in no
interface, their step a pure propagation.  A stack without films of positive thickness is
the bare interface, evaluated by :func:`scatterbench.models.fresnel.fresnel_coefficients`
itself.  A perfect-conductor substrate (``math.inf``) has ``r_s = -1``,
``r_p = +1``, ``t = 0`` at the last interface.

Dispersion: every index (films and substrate) may be a number or a callable
of the wavelength in nm returning ``n + ik`` (e.g. :class:`TabulatedIndex`);
:meth:`FilmStack.at` gives the same stack at another wavelength.

Transmission both ways (:meth:`FilmStack.transmission`).  Between the ambient ``n_0 = 1``
and a real substrate ``n_s >= 1`` (a coating), light crosses the
films down, ``t_01`` (the recursion above), and up, ``t_10``: the same recursion on the
reversed stack, incident from ``n_s``, at the same Snell invariant ``n_0 sin theta_0``.
The stack is reciprocal (isotropic films, absorbing or not: Lorentz reciprocity), so in
this field-amplitude convention, for s and p alike,

    t_10 kz_0 = t_01 kz_s,    kz_0 = n_0 cos theta_0,  kz_s = n_s cos theta_s,          (R)

as for one Fresnel interface (``t_s = 2 kz_j / (kz_j + kz_j1)`` and its reverse); the
tests check (R) on absorbing stacks rather than assume it.  The fluxes are
``T_01 = kz_s / kz_0 |t_01|^2`` and ``T_10 = kz_0 / kz_s |t_10|^2`` (both media real, so
``Re(kz) = kz``), each ``<= 1 - R`` with the difference absorbed in the films.

:class:`Films` are films with no substrate of their own: the layers and wavelength of a
stack that a model places on an index it holds (``coating_films`` of the coated models
sits on their ``coating``, :meth:`Films.on`), so that index is stated once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .constraints import (
    ComplexIndex,
    Constraint,
    Instance,
    Interval,
    OneOf,
    ParameterError,
    Samples,
    ScalarOrArray,
)
from .fresnel import _coefficients, _w, reflection_rs_k
from .params import Declared, check_index, check_real, param

__all__ = [
    "FilmStack",
    "Films",
    "TabulatedIndex",
    "check_films",
    "coating_films_param",
    "COATING_FILM_EDGES",
    "ABSORBING_FILMS",
    "INDEX_OR_STACK",
]


@dataclass(frozen=True)
class TabulatedIndex(Declared):
    """A dispersive index ``n(lambda) + i k(lambda)`` from a table, linear between points.

    Outside the table it raises ``ValueError`` (no extrapolation).  Call it with a
    wavelength in nm.
    """

    wavelength_nm: tuple = param(
        (400.0, 700.0), "wavelengths (nm), increasing", Samples(Interval(), increasing=True)
    )
    n: tuple = param(
        (1.5, 1.5), "real parts at those wavelengths (> 0)", Samples(Interval(0.0, closed="right"))
    )
    k: tuple = param((0.0, 0.0), "imaginary parts (>= 0)", Samples(Interval(0.0)))

    def _validate(self):
        for name in ("n", "k"):
            if len(getattr(self, name)) != len(self.wavelength_nm):
                raise ValueError(
                    f"{name} must hold one value per wavelength ({len(self.wavelength_nm)}); "
                    f"got {len(getattr(self, name))}"
                )

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


#: Thickest film (nm, 1 m) and shortest wavelength (nm, 1 pm) a stack takes.  The phase
#: 2 pi d kz / lambda of a film must be a finite float64 (d = 1e308 nm overflowed it to inf, and
#: exp(i inf) is NaN): with d / lambda <= 1e12 and |kz| <= 2 INDEX_MAX (3.6e16) it stays below
#: 2.3e29.  (Already above d |n| / lambda ~ 1 / eps = 4.5e15 the phase is not resolved to a
#: cycle: such a film is a thick slab, whose interference float64 cannot represent.)
THICKNESS_MAX_NM = 1e9
WAVELENGTH_MIN_NM = 1e-3
_WAVELENGTH = ScalarOrArray(Interval(WAVELENGTH_MIN_NM, None))


class Layers(Constraint):
    """Films as ``((index, thickness_nm), ...)``: each thickness a finite real ``>= 0``, each
    index ``n + ik`` or a callable of the wavelength, validated (at the stack's wavelength) by
    the stack that holds them.  Returned as a tuple of pairs, thicknesses as floats."""

    kind = "sequence"
    THICKNESS = Interval(0.0, THICKNESS_MAX_NM)

    def describe(self) -> str:
        return (
            "a sequence of (index, thickness_nm) pairs (index n + ik or a callable of the wavelength "
            f"in nm; thickness_nm {self.THICKNESS.describe()})"
        )

    def check(self, name, value) -> tuple:
        try:
            pairs = tuple((idx, d) for idx, d in value)
        except (TypeError, ValueError):
            self.fail(name, value)
        # a constraint, not float(): a bool or a string is no thickness (float(True) is 1.0)
        return tuple(
            (idx, self.THICKNESS.check(f"{name}[{j}] thickness_nm", d)) for j, (idx, d) in enumerate(pairs)
        )


class Dispersive(Constraint):
    """An index (:class:`scatterbench.models.constraints.ComplexIndex`; an array of them where
    a model set puts films on an array of coatings) or a callable of the wavelength in nm
    returning one.  A number is checked here and kept as given: the stack resolves it (as a
    complex) at its wavelength."""

    kind = "index"
    INDEX = ScalarOrArray(ComplexIndex())

    def describe(self) -> str:
        return f"{self.INDEX.describe()}, or a callable of the wavelength in nm returning one"

    def check(self, name, value):
        if not callable(value):
            try:
                self.INDEX.check(name, value)
            except ParameterError as exc:
                raise exc.restated(self.describe()) from None
        return value


_LAYERS = Layers()


def _film_indices(layers, wavelength_nm):
    """The films' indices at ``wavelength_nm``, validated and finite."""
    films = []
    for j, (idx, _) in enumerate(layers):
        n = _resolve(f"layers[{j}] index", idx, wavelength_nm)
        if n == math.inf:
            raise ValueError(f"layers[{j}] index must be finite (n + ik); got inf")
        films.append(n)
    return tuple(films)


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

    layers: tuple = param((), "films ((index, thickness_nm), ...) from the incident side", _LAYERS)
    substrate: complex = param(1.5 + 0j, "index below the films (n + ik, inf, or callable)", Dispersive())
    wavelength_nm: float = param(550.0, "vacuum wavelength (nm)", _WAVELENGTH)

    def _validate(self):
        _ = self.indices  # validates every index at this wavelength

    @cached_property
    def indices(self):
        """``(film indices, substrate index)`` at :attr:`wavelength_nm` (films finite)."""
        return _film_indices(self.layers, self.wavelength_nm), _resolve(
            "substrate", self.substrate, self.wavelength_nm
        )

    @cached_property
    def _thick(self):
        """``(indices, thicknesses)`` of the films of positive thickness, the ones the
        recursion sums: a zero-thickness film changes nothing (module docstring), but summed
        it would make the recursion 0/0 at exact grazing, where ``1 + r01 r12 = 0`` when the
        media on both sides have the same index (or the film sits on a perfect conductor)."""
        films = self.indices[0]
        kept = [(n, d) for n, (_, d) in zip(films, self.layers, strict=True) if d > 0.0]
        return tuple(n for n, _ in kept), tuple(d for _, d in kept)

    def at(self, wavelength_nm):
        """The same stack at another vacuum wavelength (nm)."""
        return self.replace(wavelength_nm=wavelength_nm)

    def coefficients(self, cos_i, n_incident=1.0):
        """``(r_s, r_p, t_s, t_p)`` for light in the real ``n_incident`` at incidence cosine ``cos_i``."""
        n0 = check_real("n_incident", n_incident, 0.0, low_open=True)
        (films, thickness), sub = self._thick, self.indices[1]
        c = np.asarray(cos_i, dtype=float)
        if not films:
            return _coefficients(c, n0, sub)
        kz = [n0 * c + 0j] + [n0 * _w(c, n / n0) for n in films]  # n_j cos(theta_j), Im >= 0
        ns = [complex(n0)] + list(films)
        return _rouard(kz, ns, thickness, self.wavelength_nm, _below(c, n0, sub))

    def reflection_rs_k(self, cos_i, n_incident):
        """``r_s`` and ``K = (r_s + r_p) / sin^2(theta)`` (:func:`scatterbench.models.fresnel.reflection_rs_k`).

        ``K`` multiplies terms of order ``sin^2(theta)`` in the facet Jones matrix, so
        its rounding error there stays ~1e-16 however small ``sin``; at exactly
        normal incidence, where ``r_s + r_p = 0``, it is set to 0.
        """
        films, sub = self._thick[0], self.indices[1]
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

    def transmission(self, cos_top):
        """``((t_s, t_p) down, (t_s, t_p) up)``: field transmission amplitudes through the films
        between the ambient (index 1) and this stack's substrate (module docstring, ``t_01``
        and ``t_10``), both at ``cos_top``: :meth:`transmission_down` and :meth:`transmission_up`."""
        return self.transmission_down(cos_top), self.transmission_up(cos_top)

    def transmission_down(self, cos_top):
        """``(t_s, t_p)``: ``t_01`` of a ray arriving from the ambient (index 1) at the cosine
        ``cos_top`` and crossing the films into the substrate (as :meth:`transmission_up`
        requires, a real index ``>= 1``)."""
        self._check_coating()
        _, _, ts, tp = self.coefficients(np.asarray(cos_top, dtype=float))
        return ts, tp

    def transmission_up(self, cos_top):
        """``(t_s, t_p)``: ``t_10`` of a ray leaving the substrate upwards that emerges in the
        ambient (index 1) at the cosine ``cos_top``.

        The substrate must be real and ``>= 1`` (a coating under the ambient), so that every
        direction above has a propagating partner below.  The amplitudes come from the same
        recursion as :meth:`coefficients` (not a second transfer-matrix code) run on the
        reversed layers from the substrate, with every layer's ``kz`` computed from
        ``cos_top`` as the downward ones are: ``kz_0 = cos_top`` exactly.  (From the
        substrate's cosine, ``kz_0 = sqrt(n_s^2 cos^2 theta_s - n_s^2 + 1)`` cancels near
        grazing exit: at ``theta_0 = pi/2 - 1e-9`` under ``n_s = 1.5`` it came out 0 instead
        of 1e-9, and the exit amplitudes erred by 2e-9 relative, a reciprocity error the
        stability sweep flagged.)
        """
        self._check_coating()
        (films, thickness), sub = self._thick, self.indices[1]
        c = np.asarray(cos_top, dtype=float)
        kz = [_w(c, sub)] + [_w(c, n) for n in films[::-1]]
        ns = [sub] + list(films[::-1])
        _, _, us, up = _rouard(kz, ns, thickness[::-1], self.wavelength_nm, (c + 0j, 1.0 + 0j))
        return us, up

    def _check_coating(self):
        """Transmission both ways needs a real substrate index ``>= 1`` (the ambient's)."""
        sub = self.indices[1]
        if sub == math.inf or sub.imag != 0 or sub.real < 1.0:
            raise ValueError(
                f"substrate must be a real index >= 1 (the ambient's) for transmission both ways; got {sub!r}"
            )

    def upward(self):
        """The stack as light leaving the substrate meets it: the films in reverse order on the
        ambient (index 1); its :meth:`coefficients` take the substrate's (real) index as
        ``n_incident``."""
        return FilmStack(layers=self.layers[::-1], substrate=1.0, wavelength_nm=self.wavelength_nm)


@dataclass(frozen=True)
class Films(Declared):
    """Thin films with no substrate of their own: a model places them on an index it holds.

    ``coating_films=Films(...)`` of :class:`scatterbench.models.SubsurfaceFacetBRDF`,
    :class:`scatterbench.models.SingleScatterBRDF` and :class:`scatterbench.models.DiffuseSubsurfaceBRDF` puts them on
    the coating's top surface (ambient | films | coating, :meth:`on` the model's
    ``coating``), so the coating's index is stated once, by the model.

    Parameters
    ----------
    layers : tuple of (index, thickness_nm)
        Films from the ambient side down, as :class:`FilmStack`'s ``layers``.
    wavelength_nm : float
        Vacuum wavelength (nm) at which the indices and phases are evaluated.
    """

    layers: tuple = param((), "films ((index, thickness_nm), ...) from the ambient side down", _LAYERS)
    wavelength_nm: float = param(550.0, "vacuum wavelength (nm)", _WAVELENGTH)

    def _validate(self):
        _ = self.indices

    @cached_property
    def indices(self):
        """The films' indices at :attr:`wavelength_nm`."""
        return _film_indices(self.layers, self.wavelength_nm)

    def on(self, substrate):
        """The :class:`FilmStack` of these films on ``substrate``."""
        return FilmStack(layers=self.layers, substrate=substrate, wavelength_nm=self.wavelength_nm)


class FilmedCoating:
    """Mixin of the models with ``coating_films`` (:class:`Films` or ``None``) on their real
    ``coating`` index: :attr:`_top_stack`, the one place the films are put on the coating."""

    @cached_property
    def _top_stack(self):
        """``coating_films`` on the coating index (a :class:`FilmStack`), or ``None``."""
        return None if self.coating_films is None else self.coating_films.on(self.coating)

    @classmethod
    def sweep_extras(cls):
        """The stability sweep's further instances (those of the model's other bases), then the
        coating swept to its edges once more under :data:`ABSORBING_FILMS`."""
        absorbing = cls.sweep_base().replace(coating_films=ABSORBING_FILMS)
        return (*super().sweep_extras(), (absorbing, ("coating",)))


class _FilmsOrNone(Instance):
    """``None`` (no films: the bare interface) or a :class:`Films`, which validated itself when
    built; a :class:`FilmStack` is refused with the hint that says why."""

    def __init__(self):
        super().__init__(Films, none=True, text="None or a models.Films (layers, wavelength_nm)")

    def check(self, name, value):
        if isinstance(value, FilmStack):
            self.fail(
                name,
                value,
                "; a FilmStack states its own substrate, and the films sit on the model's coating: pass "
                "Films(layers=..., wavelength_nm=...)",
            )
        return super().check(name, value)


_FILMS_OR_NONE = _FilmsOrNone()

#: A film stack whose absorption the stability sweep sweeps the coating under once more
ABSORBING_FILMS = Films(layers=((1.8 + 0.3j, 120.0), (2.4, 60.0)), wavelength_nm=550.0)
_AR = math.sqrt(1.5)
#: The stability sweep's films on a coating: a zero-thickness film, a quarter-wave
#: anti-reflection film on the default coating 1.5, a thick one and an absorbing pair
COATING_FILM_EDGES = (
    Films(layers=((2.0, 0.0),), wavelength_nm=550.0),
    Films(layers=((_AR, 550.0 / (4 * _AR)),), wavelength_nm=550.0),
    Films(layers=((2.6, 1e5),), wavelength_nm=550.0),
    ABSORBING_FILMS,
)


def coating_films_param(doc):
    """Declare a model's ``coating_films``: ``None`` or :class:`Films` on its coating, swept at
    :data:`COATING_FILM_EDGES`."""
    return param(None, doc, _FILMS_OR_NONE, edges=COATING_FILM_EDGES)


def check_films(name, value):
    """``value`` checked as a ``coating_films`` parameter: ``None`` (no films: the bare
    interface) or a :class:`Films`, which validated itself when built."""
    return _FILMS_OR_NONE.check(name, value)


#: A facet model's ``substrate``: an index (or an array of them, a model set) or a
#: :class:`FilmStack` (which validated itself when built)
INDEX_OR_STACK = OneOf(ScalarOrArray(ComplexIndex()), Instance(FilmStack, text="a models.FilmStack"))


def _rouard(kz, ns, thickness, wavelength_nm, below):
    """``(r_s, r_p, t_s, t_p)`` seen from the incident medium: the films summed from the bottom
    up (module docstring).  ``kz`` and ``ns`` list the incident medium then the films in order
    (film ``j`` has ``thickness[j - 1]`` nm); ``below`` is ``(kz, n)`` of the medium under the
    last film, or ``None`` for a perfect conductor."""
    if not thickness and below is not None and ns[0] == below[1]:  # one medium: no interface
        zero = np.zeros(np.broadcast(*kz, below[0]).shape, dtype=complex)
        return zero, zero.copy(), zero + 1.0, zero + 1.0
    (rs, ts), (rp, tp) = (_rouard_one(q, kz, ns, thickness, wavelength_nm, below) for q in (0, 1))
    return rs, rp, ts, tp


def _admittance(q, kz, n):
    """The admittance of polarization ``q`` (0: s, ``kz``; 1: p, ``kz / n^2``): in these
    conventions an interface has ``r = (eta_1 - eta_2) / (eta_1 + eta_2)`` and ``t = 2 eta_1 f /
    (eta_1 + eta_2)``, ``f = 1`` (s) or ``n_1 / n_2`` (p)."""
    return kz if q == 0 else kz / (n * n)


def _rouard_one(q, kz, ns, thickness, wavelength_nm, below):
    """``(r, t)`` of polarization ``q`` by Rouard's recursion, carried as the admittance
    ``Y = P / Q`` below each film and ``w = t / (1 + r)`` (the transmission from the film down
    over its total field there), so that nothing cancels and nothing divides by an admittance
    (zero at grazing): the printed form divides by ``1 + r_j r e``, which rounds to 0 when
    both reflections are near +-1 with opposite signs (a film of index 1e-12(1 + i), 1e-300 nm
    thick: r_p was 0/0; its error grew as eps / |n|^2 for thin films of small index).  Per
    film, ``a`` and ``b`` the admittances above and in it, ``x = 1 - e`` and ``xi = x / b``
    (``-expm1(z) / z`` times ``z / b``: finite at ``kz = 0``),

        P' = (2 - x) P + b x Q,   Q' = xi P + (2 - x) Q,
        w <- 2 f sqrt(e) w Q (a Q' + P') / (Q' (2 (a Q + P) - xi (a - b) (b Q - P))),

    the printed recursion multiplied through by ``(a + b)(b + Y)``; a zero-thickness film
    (``x = 0``) leaves ``Y`` as it was.  Then ``r = (a Q - P) / (a Q + P)`` and
    ``t = w (1 + r)``, ``a`` the incident medium's admittance."""
    one = np.ones(np.broadcast(*kz).shape, dtype=complex)
    if below is None:  # a perfect conductor: Y = inf (s), 0 (p); nothing transmitted
        P, Q, w = (one, 0.0 * one, 0.0 * one) if q == 0 else (0.0 * one, one, 0.0 * one)
    else:  # w = t / (1 + r) of the last interface is f: 1, or n_last / n_below
        P, Q, w = _admittance(q, below[0], below[1]) * one, one, (1.0 if q == 0 else ns[-1] / below[1]) * one
    for j in range(len(thickness), 0, -1):
        a, b = _admittance(q, kz[j - 1], ns[j - 1]), _admittance(q, kz[j], ns[j])
        half = 2j * math.pi * thickness[j - 1] / wavelength_nm  # sqrt(e) = exp(half kz)
        z = 2.0 * half * kz[j]
        small = np.abs(z) < 1e-8  # expm1(z) / z = 1 + z / 2 + O(z^2): no division by a subnormal z
        growth = np.where(small, 1.0 + 0.5 * z, np.expm1(z) / np.where(small, 1.0, z))
        x = -growth * z
        xi = -growth * 2.0 * half * (1.0 if q == 0 else ns[j] * ns[j])
        den = 2.0 * (a * Q + P) - xi * (a - b) * (b * Q - P)
        P2, Q2 = (2.0 - x) * P + b * x * Q, xi * P + (2.0 - x) * Q
        if below is not None:
            f = 1.0 if q == 0 else ns[j - 1] / ns[j]
            w = 2.0 * f * np.exp(half * kz[j]) * w * Q * (a * Q2 + P2) / (Q2 * den)
        scale = np.maximum(np.abs(P2), np.abs(Q2))  # Y is their ratio: keep both near 1
        P, Q = P2 / scale, Q2 / scale
    a = _admittance(q, kz[0], ns[0])
    # Y = 0 below (P = 0) reflects r = 1 at every incidence; at exact grazing (a = 0) the
    # quotient is 0/0 and r takes that limit
    zero = P == 0
    with np.errstate(invalid="ignore", divide="ignore"):
        den = np.where(zero, 1.0, a * Q + P)
        r = np.where(zero, 1.0, (a * Q - P) / den)
        one_plus_r = np.where(zero, 2.0, 2.0 * a * Q / den)  # not 1 + r: it cancels near grazing
    return r, w * one_plus_r


def _below(c, n0, sub):
    """``(kz, n)`` of the substrate under the films (:func:`_rouard`; ``None``: a perfect
    conductor)."""
    return None if sub == math.inf else (n0 * _w(c, sub / n0), sub)
