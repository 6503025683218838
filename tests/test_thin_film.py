"""Thin-film stacks (models/thin_film.py): against tmm (committed data, no tmm at test
time: references/scripts/make_tmm_reference.py), energy R + T + A = 1 with the
absorption integrated from the fields inside the films, the bare-interface limits,
the quarter-wave closed form, and stacks as facet-model substrates."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scatterbench import models, references
from scatterbench.models.fresnel import fresnel_coefficients
from scatterbench.models.thin_film import FilmStack, TabulatedIndex
from scatterbench.validation.numerics.probes import random_geometries

# Ours and tmm are both float64 transfer-matrix products over at most 4 films with |r|, |t|
# <= 2.11 in the 400 cases: they differ by round-off, measured worst 6.2e-14 (~280 eps, a
# 4-film case; the next 1.9e-14) by evaluating each case's coefficients against the CSV.
# 1e-12 (~4500 eps) leaves 16x for other platforms' complex exp/sqrt; a wrong phase or sign
# is far above it (thicknesses scaled by 1 + 1e-11 already give 1.8e-9).
TMM_TOL = 1e-12

# R + T + A = 1 by an independent path: A integrates the fields propagated down from the
# top's (1, r), which carries r's round-off through the films, growing as the field decays
# across them: measured |R + T + A - 1| <= 13 eps e^(G/2), G = sum k0 |Im q| d over the films.
# The data's largest G, 23.8 (four absorbing films, T ~ 1e-21), gives eps e^(G/2) = 3.2e-11 and
# the worst measured 3.4e-11 (the next case 5.9e-12, all others <= 6.4e-13): 1e-10 is 3x that.
ENERGY_TOL = 1e-10


def _stack(case):
    return FilmStack(
        layers=tuple(case["films"]), substrate=case["substrate"], wavelength_nm=case["wavelength_nm"]
    )


@pytest.fixture(scope="module")
def cases():
    return references.tmm_reference()


def test_coefficients_agree_with_tmm(cases):
    """tmm's conventions are Born & Wolf's, as ours: r, t compared as they are, TMM_TOL."""
    worst = 0.0
    for c in cases:
        got = _stack(c).coefficients(math.cos(c["theta0"]), c["n0"])
        worst = max(worst, *(abs(g - c[k]) for g, k in zip(got, ("rs", "rp", "ts", "tp"), strict=True)))
    assert worst <= TMM_TOL


def test_tmm_data_cover_the_hard_cases(cases):
    """Absorbing films, metals, total internal reflection and zero thicknesses are all in."""
    n_abs = sum(any(n.imag > 0 for n, _ in c["films"]) for c in cases)
    n_metal = sum(c["substrate"].imag > 1 for c in cases)
    n_tir = sum(
        c["n0"] * math.sin(c["theta0"]) > c["substrate"].real and c["substrate"].imag == 0 for c in cases
    )
    n_zero = sum(any(d == 0 for _, d in c["films"]) for c in cases)
    assert min(n_abs, n_metal, n_tir, n_zero) >= 10


def _layer_integrals(a, b, kappa, d):
    """``int_0^d |a e^{i kappa z} +- b e^{-i kappa z}|^2 dz`` (``+``, ``-``), in closed form."""

    def f(c):
        return d if c == 0 else (np.exp(c * d) - 1.0) / c

    base = abs(a) ** 2 * f(-2 * kappa.imag) + abs(b) ** 2 * f(2 * kappa.imag)
    cross = 2.0 * (a * np.conj(b) * f(2j * kappa.real)).real
    return base + cross, base - cross


def _absorbed(stack, cos0, n0, pol):
    """Fraction of the incident flux absorbed in the films, ``k0 Im(n^2) int |E|^2 dz / (n0 cos)``,
    from the fields propagated down from the top (incident 1, reflected r): for s the
    continuous pair ``(E_y, q (A - B))``, for p ``(H_y, q/n^2 (A - B))`` with ``|E|^2 =
    |E_x|^2 + |E_z|^2``; ``q = n cos theta``, ``xi = n0 sin theta0``."""
    rs, rp, _, _ = stack.coefficients(cos0, n0)
    lam = stack.wavelength_nm
    k0 = 2 * math.pi / lam
    xi = n0 * math.sqrt(1 - cos0 * cos0)
    q0 = n0 * cos0
    if pol == "s":
        u, v = 1 + rs, q0 * (1 - rs)
    else:
        u, v = n0 * (1 + rp), q0 / n0 * (1 - rp)
    total = 0.0
    for (n, d), _ in zip(stack.layers, stack.indices[0], strict=True):
        n = complex(n)
        q = np.sqrt(n * n - xi * xi + 0j)
        w = q if pol == "s" else q / (n * n)
        a, b = (u + v / w) / 2, (u - v / w) / 2
        plus, minus = _layer_integrals(a, b, k0 * q, d)
        e2 = plus if pol == "s" else abs(w) ** 2 * minus + abs(xi / (n * n)) ** 2 * plus
        total += k0 * (n * n).imag * e2 / q0
        ph = np.exp(1j * k0 * q * d)
        u, v = a * ph + b / ph, w * (a * ph - b / ph)
    return total


def test_energy_r_plus_t_plus_a(cases):
    """R + T + A = 1: R, T from the amplitude coefficients (T the Poynting flux into the
    substrate), A from the volume absorption in the films, an independent path."""
    worst = 0.0
    count = 0
    for c in cases:
        st = _stack(c)
        cos0 = math.cos(c["theta0"])
        Rs, Rp, Ts, Tp = st.reflectance_transmittance(cos0, c["n0"])
        for pol, R, T in (("s", Rs, Ts), ("p", Rp, Tp)):
            A = _absorbed(st, cos0, c["n0"], pol)
            worst = max(worst, abs(R + T + A - 1.0))
            count += A > 1e-3
    assert count > 50  # the absorption term matters in many cases
    assert worst <= ENERGY_TOL


def test_energy_on_a_perfect_conductor():
    st = FilmStack(layers=((1.8 + 0.1j, 130.0), (2.3 + 0j, 60.0)), substrate=math.inf, wavelength_nm=520.0)
    for cos0 in (1.0, 0.6, 0.05):
        Rs, Rp, Ts, Tp = st.reflectance_transmittance(cos0, 1.0)
        assert Ts == Tp == 0.0
        assert abs(Rs + _absorbed(st, cos0, 1.0, "s") - 1) < 1e-12
        assert abs(Rp + _absorbed(st, cos0, 1.0, "p") - 1) < 1e-12


@pytest.mark.parametrize(
    "n0, film, sub", [(1.0, 2.5, 1.56), (1.5, 1.3 + 0.4j, 1.37 + 7.62j), (1.5, 2.0, 1.2)]
)
def test_zero_thickness_film_is_the_bare_interface(n0, film, sub):
    """Both polarizations, phases included (TIR beyond 53 deg for 1.5 -> 1.2): the stack
    (which leaves zero-thickness films out) and the recursion summing such a film, which
    must give the same by the identity (r01 + r12) / (1 + r01 r12) = r02 (exact grazing
    included: in the admittance form the step of a zero-thickness film is no 0/0)."""
    from scatterbench.models.thin_film import _below, _rouard, _w

    c = np.cos(np.linspace(0, math.pi / 2, 181))
    got = FilmStack(layers=((film, 0.0),), substrate=sub, wavelength_nm=600.0).coefficients(c, n0)
    kz = [n0 * c + 0j, n0 * _w(c, film / n0)]
    summed = _rouard(kz, [complex(n0), film], (0.0,), 600.0, _below(c, n0, sub))
    want = fresnel_coefficients(c, n0, sub)
    for g, s, w in zip(got, summed, want, strict=True):
        assert np.array_equal(g, w)
        assert np.max(np.abs(s - w)) <= 1e-14 * max(1.0, np.max(np.abs(w)))


@pytest.mark.parametrize(
    "layers, sub",
    [
        (((2.0, 0.0),), 1.0),  # zero-thickness film between two media of one index
        (((2.0, 0.0),), math.inf),  # ... on a perfect conductor (r_p = 1 below)
        (((1.0, 100.0),), 1.5),  # a film of the ambient's index
        (((1.0, 100.0), (2.0, 0.0), (1.3 + 0.1j, 80.0)), 1.0),
        (((1.5, 100.0), (1.5, 40.0)), 1.5),  # films of the substrate's index
    ],
)
def test_exact_grazing_is_the_limit_not_nan(layers, sub):
    """At cos = 0 the coefficients are finite and continue those at cos = 1e-12 (they move
    by O(cos)); the first four stacks made the recursion 0/0 there (NaN) before
    zero-thickness films were left out and same-index interfaces set to r = 0, t = 1 (the
    last has same-index interfaces away from grazing).  Both ways where the substrate allows."""
    st = FilmStack(layers=layers, substrate=sub, wavelength_nm=550.0)
    c = np.array([0.0, 1e-12])
    with np.errstate(divide="raise", invalid="raise"):  # no 0/0 on the way either
        pairs = [st.coefficients(c)]
        if sub != math.inf:
            pairs += list(st.transmission(c))
    for coeffs in pairs:
        for x in coeffs:
            assert np.all(np.isfinite(x)) and abs(x[0] - x[1]) <= 1e-9


def test_a_filmed_coating_of_the_ambients_index_at_grazing_is_finite():
    """The model-level case that gave NaN: ``coating=1.0`` under a zero-thickness film at
    exact grazing incidence."""
    films = models.Films(layers=((2.0, 0.0),), wavelength_nm=550.0)
    m = models.DiffuseSubsurfaceBRDF(coating=1.0, coating_films=films)
    bare = models.DiffuseSubsurfaceBRDF(coating=1.0)
    ti = np.array([math.pi / 2, 1.0])
    got = m.mueller(ti, 0.3, 0.0)
    assert np.all(np.isfinite(got)) and np.array_equal(got, bare.mueller(ti, 0.3, 0.0))


def test_empty_stack_is_fresnel_bit_for_bit():
    c = np.cos(np.linspace(0, math.pi / 2, 91))
    got = FilmStack(layers=(), substrate=1.37 + 7.62j).coefficients(c, 1.5)
    for g, w in zip(got, fresnel_coefficients(c, 1.5, 1.37 + 7.62j), strict=True):
        assert np.array_equal(g, w)


def test_quarter_wave_film_closed_form():
    """A quarter-wave film (n d = lambda / 4) at normal incidence: R = ((n0 ns - n^2)/(n0 ns + n^2))^2."""
    n, ns, lam = 2.5, 1.56, 550.0
    st = FilmStack(layers=((n, lam / (4 * n)),), substrate=ns, wavelength_nm=lam)
    Rs, Rp, _, _ = st.reflectance_transmittance(1.0, 1.0)
    want = ((ns - n * n) / (ns + n * n)) ** 2
    assert abs(Rs - want) < 1e-14 and abs(Rp - want) < 1e-14
    # half-wave: the film is absent
    st2 = st.replace(layers=((n, lam / (2 * n)),))
    assert abs(st2.reflectance_transmittance(1.0, 1.0)[0] - ((ns - 1) / (ns + 1)) ** 2) < 1e-14


def test_dispersive_indices():
    tio2 = TabulatedIndex(wavelength_nm=(400.0, 700.0), n=(2.9, 2.5), k=(0.02, 0.0))
    assert tio2(550.0) == pytest.approx(2.7 + 0.01j, abs=1e-15)
    st = FilmStack(layers=((tio2, 120.0),), substrate=lambda lam: 1.56 + 0j, wavelength_nm=400.0)
    assert st.indices[0][0] == pytest.approx(2.9 + 0.02j)
    assert st.at(700.0).indices[0][0] == pytest.approx(2.5 + 0j)
    fixed = FilmStack(layers=((2.5 + 0j, 120.0),), substrate=1.56, wavelength_nm=700.0)
    a, b = st.at(700.0).coefficients(0.8), fixed.coefficients(0.8)
    assert all(abs(x - y) < 1e-15 for x, y in zip(a, b, strict=True))
    with pytest.raises(ValueError, match="wavelength_nm"):
        st.at(800.0)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(layers=((2.0, -1.0),)), "thickness_nm"),
        (dict(layers=((2.0 - 0.1j, 10.0),)), r"layers\[0\] index"),
        (dict(layers=((math.inf, 10.0),)), r"layers\[0\] index"),
        (dict(layers=(2.0,)), "layers"),
        (dict(substrate=1 - 1j), "substrate"),
        (dict(wavelength_nm=0.0), "wavelength_nm"),
    ],
)
def test_bad_input_names_the_parameter(kwargs, name):
    with pytest.raises(ValueError, match=name):
        FilmStack(**kwargs)


# ------------------------------------------------------------------ stacks in the facet models
def _angles():
    ti, tr, pr = random_geometries(4000, seed=5, max_deg=math.degrees(1.45))
    # exact retroreflection and specular, where K = (r_s + r_p)/sin^2 is 0/0
    ti[:10], tr[:10], pr[:10] = 0.7, 0.7, math.pi
    ti[10:20], tr[10:20], pr[10:20] = 0.3, 0.3, 0.0
    return ti, tr, pr


@pytest.mark.parametrize("coating", [1.0, 1.5])
def test_facet_with_zero_thickness_film_is_the_bare_substrate(coating):
    sl = models.ExponentialSlopes(0.2)
    sub = 1.37 + 7.62j
    st = FilmStack(layers=((2.4 + 0.01j, 0.0),), substrate=sub, wavelength_nm=500.0)
    ti, tr, pr = _angles()
    bare = models.SubsurfaceFacetBRDF(slopes=sl, coating=coating, substrate=sub).mueller(ti, tr, pr)
    film = models.SubsurfaceFacetBRDF(slopes=sl, coating=coating, substrate=st).mueller(ti, tr, pr)
    assert np.all(np.isfinite(film))
    assert np.max(np.abs(film - bare) / np.maximum(bare[..., :1, :1], 1e-300)) < 1e-12


def test_facet_with_empty_stack_is_bit_identical():
    """On the numpy path (a film stack has no compiled kernel; the bare interface's kernel is
    held to the numpy path at 1e-12 in test_kernels)."""
    ti, tr, pr = _angles()
    for sub in (1.5, math.inf):
        with models.backend("numpy"):
            a = models.FacetBRDF(substrate=sub).mueller(ti, tr, pr)
        b = models.FacetBRDF(substrate=FilmStack(layers=(), substrate=sub)).mueller(ti, tr, pr)
        assert np.array_equal(a, b)


def test_interference_flakes_follow_the_stack_reflectance():
    """Mica flakes with a TiO2 film under a clear coat: at the specular geometry (facet
    normal along z, so the facet's s and p are the rays'), |J_ss|^2 and |J_pp|^2 change
    from the bare flakes exactly by the stack's R_s and R_p ratios seen from the coating."""
    sl = models.GaussianSlopes(0.05)
    n, mica = 1.5, 1.56
    st = FilmStack(layers=((2.6 + 0j, 140.0),), substrate=mica, wavelength_nm=550.0)
    ti = np.radians([10.0, 30.0, 50.0])
    film = models.SubsurfaceFacetBRDF(slopes=sl, coating=n, substrate=st).jones(ti, ti, 0.0)
    bare = models.SubsurfaceFacetBRDF(slopes=sl, coating=n, substrate=mica).jones(ti, ti, 0.0)
    ci = np.sqrt(1 - (np.sin(ti) / n) ** 2)
    r_film = st.reflectance_transmittance(ci, n)[:2]
    r_bare = FilmStack(layers=(), substrate=mica).reflectance_transmittance(ci, n)[:2]
    for k in (0, 1):
        got = np.abs(film[:, k, k]) ** 2 / np.abs(bare[:, k, k]) ** 2
        assert np.max(np.abs(got / (r_film[k] / r_bare[k]) - 1)) < 1e-12
        assert np.min(r_film[k] / r_bare[k]) > 3  # the film matters: an interference peak


@pytest.mark.parametrize("thickness", [True, False, "5", -1.0, math.nan])
def test_film_thickness_must_be_a_number_not_a_bool_or_text(thickness):
    with pytest.raises(ValueError, match=r"layers\[0\] thickness_nm must be a finite real number"):
        FilmStack(layers=((2.6, thickness),), substrate=1.5, wavelength_nm=550.0)


@pytest.mark.parametrize("film", [1e-12 * (1 + 1j), 5.6e-17, 1e-8 + 0j, 1.7e16 + 0j, 0.05 + 3j])
@pytest.mark.parametrize("sub", [1.5, 0.2 + 3j, math.inf])
def test_a_vanishing_film_of_extreme_index_is_the_bare_interface(film, sub):
    """A film 1e-300 nm thick changes nothing at any index in range (its phase and its
    admittance step are ~1e-280): r and t equal the bare interface's to 1e-14, both
    polarizations, exact grazing included.  The printed recursion divided by 1 + r01 r12 e,
    which rounds to 0 when both reflections are near +-1 with opposite signs: at 1e-12(1 + i)
    it gave NaN, and r_p wrong by 9e-2 at 1e-8."""
    c = np.cos(np.linspace(0.0, math.pi / 2, 37))
    got = FilmStack(layers=((film, 1e-300),), substrate=sub, wavelength_nm=500.0).coefficients(c, 1.0)
    want = fresnel_coefficients(c, 1.0, sub)
    for g, w in zip(got, want, strict=True):
        assert np.all(np.isfinite(g))
        assert np.max(np.abs(g - w)) <= 1e-14 * max(1.0, np.max(np.abs(w)))
