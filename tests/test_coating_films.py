"""Thin films on the coating's top surface (``coating_films``, models.Films): the stack's
transmission both ways (against tmm, reciprocity relation, energy), the filmed models against
the bare ones, their Helmholtz reciprocity and energy, the quarter-wave anti-reflection film,
and [coating.film] in scene files."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate
from test_thin_film import TMM_TOL, _absorbed

from scatterbench import models, references
from scatterbench.models import scene
from scatterbench.models.cubature import AccuracyWarning
from scatterbench.models.smooth_interface import (
    film_hemispherical_reflectance,
    film_transmission,
    internal_hemispherical_reflectance,
)
from scatterbench.models.thin_film import Films, FilmStack
from scatterbench.validation.numerics.integrate import integrated_reflectance
from scatterbench.validation.numerics.probes import random_geometries
from scatterbench.validation.numerics.reciprocity import reciprocity_error

N = 1.5  # the clear coat
LAM = 550.0
ABSORBING = Films(layers=((1.8 + 0.3j, 120.0), (2.4, 60.0)), wavelength_nm=LAM)
LOSSLESS = Films(layers=((2.3, 95.0), (1.38, 140.0)), wavelength_nm=LAM)
NF = math.sqrt(N)  # the quarter-wave anti-reflection film: n_f^2 = n_coating
AR = Films(layers=((NF, LAM / (4 * NF)),), wavelength_nm=LAM)

MODELS = {
    "subsurface": models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.2), coating=N),
    "single-polarized": models.SingleScatterBRDF(coating=N, phase=models.HenyeyGreenstein(0.6)),
    "single-depolarizing": models.SingleScatterBRDF(
        coating=N, phase=models.HenyeyGreenstein(-0.4, polarized=False)
    ),
    "diffuse": models.DiffuseSubsurfaceBRDF(coating=N, rho=0.8),
}


def _random_stack(rng):
    """A random stack of 1-4 films (some absorbing, some of zero thickness) on a coating."""
    films = []
    for _ in range(int(rng.integers(1, 5))):
        d = 0.0 if rng.random() < 0.1 else float(rng.uniform(0.0, 500.0))
        k = rng.uniform(0.0, 2.0) if rng.random() < 0.3 else 0.0
        films.append((complex(rng.uniform(1.1, 3.0), k), d))
    n = float(rng.uniform(1.0, 2.5))
    return FilmStack(layers=tuple(films), substrate=n, wavelength_nm=float(rng.uniform(380.0, 780.0)))


# ------------------------------------------------------------------ the stack, both ways
def test_transmission_both_ways_against_tmm():
    """Down (ambient -> films -> coating) and up (coating -> films -> ambient) against
    tmm.coh_tmm with the layers reversed, committed (references.tmm_both_ways: 300 random
    stacks of 1-4 films, some absorbing or of zero thickness, on coatings 1-2.5,
    references/scripts/make_tmm_reference.py; no tmm at test time), both polarizations: the
    amplitudes t, and the transmitted power fractions T with the kz ratios the models use
    (F3 of models.smooth_interface: kz_s / kz_0 |t_01|^2, kz_0 / kz_s |t_10|^2) against tmm's
    own T.  Measured worst 2.1e-14 (t), 3.2e-14 (T); TMM_TOL = 1e-12 as for the stacks' r and t
    (tests/test_thin_film.py; a wrong phase, sign or flux factor is O(1))."""
    pairs = references.tmm_both_ways()
    assert len(pairs) == 300
    worst = 0.0
    for down, up in pairs:
        st = FilmStack(
            layers=tuple(down["films"]), substrate=down["substrate"], wavelength_nm=down["wavelength_nm"]
        )
        assert up["films"] == down["films"][::-1] and up["n0"] == st.indices[1].real
        th, th_sub, n = down["theta0"], up["theta0"], up["n0"]
        (ts, tp), (us, u_p) = st.transmission(math.cos(th))
        ratio = n * math.cos(th_sub) / math.cos(th)  # kz_s / kz_0
        for pol, t_down, t_up in (("s", ts, us), ("p", tp, u_p)):
            worst = max(worst, abs(t_down - down[f"t{pol}"]), abs(t_up - up[f"t{pol}"]))
            worst = max(worst, abs(ratio * abs(t_down) ** 2 - down[f"T_{pol}"]))
            worst = max(worst, abs(abs(t_up) ** 2 / ratio - up[f"T_{pol}"]))
    assert worst <= TMM_TOL


def _reciprocity_sides(rng, c, stacks):
    """``(t_10 kz_0, t_01 kz_s)`` of (R), s and p, for ``stacks`` random stacks at cosines ``c``."""
    for _ in range(stacks):
        st = _random_stack(rng)
        n = st.indices[1].real
        kz_s = n * np.sqrt(1.0 - (1.0 - c * c) / (n * n))
        (ts, tp), (us, up) = st.transmission(c)
        yield from ((us * c, ts * kz_s), (up * c, tp * kz_s))


def test_the_stack_is_reciprocal():
    """(R) of models.thin_film: t_10 kz_0 = t_01 kz_s for s and p, absorbing films included,
    every angle to grazing.  Measured worst 8.7e-16 absolute (|t kz| <= ~5): 1e-14."""
    c = np.cos(np.linspace(0.0, math.pi / 2, 91))
    sides = _reciprocity_sides(np.random.default_rng(11), c, 100)
    assert max(np.max(np.abs(a - b)) for a, b in sides) <= 1e-14


def test_the_stack_is_reciprocal_relative_to_its_amplitude_near_grazing():
    """(R) again, relative: near grazing both sides of (R) vanish as cos, and the absolute
    bound above cannot see an error of their ratio (the top transmission written as
    w (1 + r), with r -> -1, erred by 1e-7 of it at cos 1e-9; the stability sweep found it)."""
    sides = _reciprocity_sides(np.random.default_rng(12), np.geomspace(1e-12, 1e-2, 41), 30)
    assert max(np.max(np.abs(a - b) / np.abs(b)) for a, b in sides) <= 1e-12


@pytest.mark.parametrize("films", [LOSSLESS, ABSORBING], ids=["lossless", "absorbing"])
def test_energy_of_the_crossings(films):
    """Each crossing's R + T + A = 1: R = |r|^2, T the flux into the far medium (the kz ratios
    the models use), A integrated from the fields inside the films (test_thin_film's path);
    from below, the stack seen from the coating (FilmStack.upward).  A lossless film has A = 0.
    Measured worst 1.5e-14 (lossless), 4.1e-15 (absorbing); 1e-13."""
    st = films.on(N)
    c = np.linspace(0.0, 1.0, 41)[1:]  # the top cosine; c = 0 carries no flux
    c_int = np.sqrt(N * N - 1.0 + c * c) / N
    (ts, tp), (us, up) = st.transmission(c)
    rs, rp, _, _ = st.coefficients(c, 1.0)
    qs, qp, _, _ = st.upward().coefficients(c_int, N)
    worst, lost = 0.0, 0.0
    for k in range(c.size):
        for pol, r_down, t_down, r_up, t_up in (("s", rs, ts, qs, us), ("p", rp, tp, qp, up)):
            a_down = _absorbed(st, c[k], 1.0, pol)
            a_up = _absorbed(st.upward(), c_int[k], N, pol)
            down = abs(r_down[k]) ** 2 + N * c_int[k] / c[k] * abs(t_down[k]) ** 2 + a_down
            upw = abs(r_up[k]) ** 2 + c[k] / (N * c_int[k]) * abs(t_up[k]) ** 2 + a_up
            worst = max(worst, abs(down - 1.0), abs(upw - 1.0))
            lost = max(lost, a_down, a_up)
    assert worst <= 1e-13
    assert (lost == 0.0) if films is LOSSLESS else (lost > 0.1)


def test_hemispherical_reflectance_of_the_stack():
    """R-bar (F5) with no films or a zero-thickness film is the bare interface's closed form
    (measured 1.1e-16); with films it equals an independent adaptive quadrature over
    u = sin^2 theta' (scipy quad, a breakpoint at the critical angle; measured 1.7e-16).
    1e-13 both."""
    for n in (1.0, 1.2, 1.5, 3.0):
        for films in (Films(layers=()), Films(layers=((2.0 + 0.5j, 0.0),))):
            got = film_hemispherical_reflectance(films.on(n))
            assert abs(got - internal_hemispherical_reflectance(n)) <= 1e-13
    for films in (LOSSLESS, ABSORBING, AR):
        st = films.on(N)
        up = st.upward()

        def r10(u, up=up):
            rs, rp, _, _ = up.coefficients(np.array([math.sqrt(1.0 - u)]), N)
            return 0.5 * (abs(rs[0]) ** 2 + abs(rp[0]) ** 2)

        want, _ = integrate.quad(r10, 0.0, 1.0, points=[1 / N**2], epsabs=1e-14, epsrel=1e-13, limit=500)
        assert abs(film_hemispherical_reflectance(st) - want) <= 1e-13


def test_hemispherical_reflectance_warns_at_its_panel_cap():
    """A tolerance no doubling can meet stops at 2^14 panels with an AccuracyWarning (the last
    estimate still returned, within 1e-13 of the converged one), not silently."""
    st = ABSORBING.on(N)
    with pytest.warns(AccuracyWarning, match="16384 panels"):
        got = film_hemispherical_reflectance(st, tol=-1.0)  # never met
    assert abs(got - film_hemispherical_reflectance(st)) <= 1e-13


# ------------------------------------------------------------------ the models
def _geometries():
    ti, tr, pr = random_geometries(2000, seed=9, max_deg=89.9)
    ti[:5], tr[:5], pr[:5] = 0.7, 0.7, math.pi  # retroreflection
    ti[5:10], tr[5:10], pr[5:10] = 0.3, 0.3, 0.0  # specular
    ti[10:15], tr[10:15] = 0.0, math.pi / 2 - 1e-9  # normal in, grazing out
    return ti, tr, pr


@pytest.mark.parametrize("name", list(MODELS))
@pytest.mark.parametrize(
    "films",
    [
        Films(layers=((2.4 + 0.2j, 0.0),), wavelength_nm=LAM),  # zero thickness
        Films(layers=((N, 200.0),), wavelength_nm=LAM),  # the coating's index
        Films(layers=((1.0, 200.0),), wavelength_nm=LAM),  # the ambient's index
        Films(layers=(), wavelength_nm=LAM),  # no layer at all
    ],
    ids=["zero-thickness", "coating-index", "ambient-index", "empty"],
)
def test_films_that_are_not_there_give_the_bare_model(name, films):
    """Measured worst 2.0e-15 relative to M00 (Jones: 1.4e-15 relative to sqrt(M00); the film
    path's algebra differs from the bare Fresnel formulas in rounding only); 1e-13 as the brief
    asks.  The bare model is evaluated
    on its numpy path: the kernel is held to that at 1e-12 by test_kernels."""
    bare = MODELS[name]
    ti, tr, pr = _geometries()
    with models.backend("numpy"):
        want = bare.mueller(ti, tr, pr)
    got = bare.replace(coating_films=films).mueller(ti, tr, pr)
    assert np.all(np.isfinite(got))
    assert np.max(np.abs(got - want) / np.maximum(want[..., :1, :1], 1e-300)) <= 1e-13
    if not bare.depolarizing:
        # a film of the coating's or the ambient's index adds its propagation phase to both
        # crossings alike: the Jones matrices agree up to that overall phase
        jw, jg = bare.jones(ti, tr, pr), bare.replace(coating_films=films).jones(ti, tr, pr)
        overlap = np.sum(jg * np.conj(jw), axis=(-1, -2))[:, None, None]
        jg = jg * np.conj(overlap) / np.maximum(np.abs(overlap), 1e-300)
        assert np.max(np.abs(jg - jw) / np.sqrt(np.maximum(want[..., :1, :1], 1e-300))) <= 1e-13


@pytest.mark.parametrize("name", list(MODELS))
def test_default_is_the_bare_model_with_its_kernel(name):
    bare = MODELS[name]
    assert bare.coating_films is None and bare._kernel_spec() is not None
    assert bare.replace(coating_films=ABSORBING)._kernel_spec() is None  # films: numpy


# the bare models' reciprocity tolerances: seed 000's facet models 1e-10 (check_reciprocity),
# seed 003's 1e-12 (check_reciprocity_seed003).  Measured with the films: 4.0e-15 (facet;
# anisotropic slopes 9.8e-15), 2.0e-15 (seed 003 models).
RECIPROCITY_TOL = {
    "subsurface": 1e-10,
    "single-polarized": 1e-12,
    "single-depolarizing": 1e-12,
    "diffuse": 1e-12,
}


@pytest.mark.parametrize("name", list(MODELS))
@pytest.mark.parametrize("films", [ABSORBING, AR], ids=["absorbing", "ar"])
def test_filmed_models_are_reciprocal(name, films):
    ti, tr, pr = random_geometries(400, seed=3, max_deg=88.0)
    m = MODELS[name].replace(coating_films=films)
    r = reciprocity_error(m, ti, tr, pr)
    assert r.n > 0
    assert max(r.scalar, r.mueller, r.jones or 0.0) <= RECIPROCITY_TOL[name]


def test_anisotropic_filmed_model_is_reciprocal():
    """The reversed path rotates the sample (model.rotated keeps the films)."""
    ti, tr, pr = random_geometries(60, seed=4, max_deg=80.0)
    s = models.AnisotropicExponentialSlopes(0.05, 0.6, 0.4)
    m = models.SubsurfaceFacetBRDF(slopes=s, coating=N, coating_films=ABSORBING)
    assert m.rotated(0.3).coating_films == ABSORBING
    assert reciprocity_error(m, ti, tr, pr).mueller <= 1e-10


def test_jones_through_films_is_the_complex_product():
    """At the specular geometry the facet normal is z, so the facet's s and p are the rays':
    J_ss / J_pp of the filmed model is the bare one's times (t_s,out t_s,in / t_s^2) /
    (t_p,out t_p,in / t_p^2), complex, phase included (t the bare Fresnel amplitudes)."""
    sl = models.GaussianSlopes(0.05)
    ti = np.radians([10.0, 35.0, 60.0])
    bare = models.SubsurfaceFacetBRDF(slopes=sl, coating=N, substrate=1.37 + 7.62j)
    film = bare.replace(coating_films=ABSORBING)
    jb, jf = bare.jones(ti, ti, 0.0), film.jones(ti, ti, 0.0)
    (ts_in, tp_in), (ts_out, tp_out) = film_transmission(np.cos(ti), np.cos(ti), ABSORBING.on(N))
    _, _, ts, tp = models.fresnel_coefficients(np.cos(ti), 1.0, N)
    want = (jb[:, 0, 0] / jb[:, 1, 1]) * (ts_in * ts_out / ts**2) / (tp_in * tp_out / tp**2)
    got = jf[:, 0, 0] / jf[:, 1, 1]
    assert np.max(np.abs(got / want - 1.0)) <= 1e-12
    # the films shift the s/p phase difference (measured 0.0034, 0.046, 0.12 rad at 10, 35, 60 deg)
    assert np.max(np.abs(np.angle(got / (jb[:, 0, 0] / jb[:, 1, 1])))) > 0.1


def test_quarter_wave_anti_reflection_film():
    """n_f = sqrt(n), d = lambda / (4 n_f): at normal incidence the coating reflects nothing
    (R = ((n - n_f^2)/(n + n_f^2))^2 = 0; measured 1e-32), every crossing transmits all,
    T = n |t_01|^2 = 1, where the bare interface transmits T = 4 n / (n + 1)^2.  Seed 000's
    BRDF carries |t_in|^2 |t_out|^2 (the rest of Eq. 49 is unchanged by the film), so at
    normal incidence and exit it rises by (T_AR / T_bare)^2 = ((n + 1)^2 / (4 n))^2 = 1.0851
    for n = 1.5 (measured to 1.5e-15).  The diffuse model's rises by the same factor times
    (1 - rho R-bar) / (1 - rho R-bar_AR) (Eq. 27's prefactor; R-bar of each interface;
    measured to 1.4e-15)."""
    Rs, Rp, Ts, Tp = AR.on(N).reflectance_transmittance(1.0, 1.0)
    assert max(Rs, Rp) <= 1e-28 and abs(Ts - 1.0) <= 1e-14 and abs(Tp - 1.0) <= 1e-14
    factor = ((N + 1) ** 2 / (4 * N)) ** 2
    bare = models.SubsurfaceFacetBRDF(coating=N)
    got, want = bare.replace(coating_films=AR).mueller(0.0, 0.0, 0.0), bare.mueller(0.0, 0.0, 0.0)
    assert np.max(np.abs(got - factor * want)) <= 1e-13 * factor * want[0, 0]  # every element
    # near normal the rise stays this factor to O(theta^2): measured 6e-10 at 1 deg, 4.9e-8 at 3
    t = np.radians([1.0, 3.0])
    near = bare.replace(coating_films=AR).brdf(t, t, math.pi) / bare.brdf(t, t, math.pi)
    assert np.max(np.abs(near / factor - 1.0)) <= 1e-6
    d = models.DiffuseSubsurfaceBRDF(coating=N, rho=0.8)
    da = d.replace(coating_films=AR)
    want = factor * (1 - 0.8 * d.rbar) / (1 - 0.8 * da.rbar)
    assert abs(da.brdf(0.0, 0.0, 0.0) / d.brdf(0.0, 0.0, 0.0) / want - 1.0) <= 1e-13


def _round_trip(stack, c):
    """Unpolarized T_01(theta) T_10(theta): in through the films and straight back out."""
    (ts, tp), (us, up) = stack.transmission(c)
    n = stack.indices[1].real
    kz_s = n * math.sqrt(1.0 - (1.0 - c * c) / (n * n))
    t_in = [kz_s / c * abs(t) ** 2 for t in (ts, tp)]
    t_out = [c / kz_s * abs(u) ** 2 for u in (us, up)]
    return 0.5 * (t_in[0] * t_out[0] + t_in[1] * t_out[1])


@pytest.mark.parametrize("deg", [0.0, 30.0])
def test_mirror_flakes_return_the_round_trip_transmittance(deg):
    """Perfect-conductor flakes (|r| = 1, no cross-polarization at facet normal z) under the
    absorbing films: as sigma -> 0 the integrated reflectance tends to T_01 T_10 of the stack,
    with an O(sigma^2) remainder (measured relative 3.2e-5, 7.9e-5 at sigma = 0.01 and 9x
    that at 0.03).  Richardson's (9 R(0.01) - R(0.03)) / 8 removes it; measured 3.1e-7 and
    2.5e-6 from the limit (the O(sigma^4) rest).  1e-5; the integrals' own errors are 1e-9."""
    ti = math.radians(deg)
    r = {}
    for sigma in (0.01, 0.03):
        m = models.SubsurfaceFacetBRDF(
            slopes=models.GaussianSlopes(sigma), coating=N, substrate=math.inf, coating_films=ABSORBING
        )
        res = integrated_reflectance(m, ti, tol=1e-8)
        assert res.converged and res.value <= 1.0 + res.error
        r[sigma] = res.value
    limit = (9 * r[0.01] - r[0.03]) / 8
    want = _round_trip(ABSORBING.on(N), math.cos(ti))
    assert abs(limit / want - 1.0) <= 1e-5
    assert want < 0.2  # the absorbing films matter: the bare coat returns ~0.9


@pytest.mark.parametrize("deg", [0.0, 60.0, 85.0])
def test_filmed_mirror_flakes_conserve_energy(deg):
    """Rough perfect-conductor flakes (Smith-shadowed, so the facets alone return at most 1)
    under a lossless film: integrated reflectance <= 1 + integration error (measured 0.78,
    0.52, 0.21 at 0, 60, 85 deg), and above the bare coat's at normal incidence, where the
    film transmits all."""
    m = models.SubsurfaceFacetBRDF(
        slopes=models.GaussianSlopes(0.3), coating=N, substrate=math.inf, shadowing="smith", coating_films=AR
    )
    r = integrated_reflectance(m, math.radians(deg), tol=1e-5)
    assert r.converged and r.value <= 1.0 + r.error
    if deg == 0.0:
        bare = integrated_reflectance(m.replace(coating_films=None), 0.0, tol=1e-5)
        assert r.value > bare.value + r.error + bare.error


@pytest.mark.parametrize("films", [LOSSLESS, ABSORBING], ids=["lossless", "absorbing"])
@pytest.mark.parametrize("deg", [0.0, 40.0, 75.0])
def test_diffuse_model_energy_through_films(films, deg):
    """Eq. 27 at rho = 1 through films: the diffuse term integrates to T_01(ti) <T_10> /
    (1 - R-bar), <T_10> = int_0^1 T_10 du the exit transmittance averaged like R-bar (an
    independent quadrature of FilmStack.reflectance_transmittance seen from the coating).
    Lossless films: <T_10> = 1 - R-bar, so the stack's reflectance plus the diffuse term is 1.
    Measured within 5.8e-10 of both, against the integrator's error estimates of 7.9e-9 to
    9.9e-9, which the test allows."""
    st = films.on(N)
    ti = math.radians(deg)
    m = models.DiffuseSubsurfaceBRDF(coating=N, rho=1.0, coating_films=films)
    r = integrated_reflectance(m, ti, tol=1e-8)
    assert r.converged
    Rs, Rp, Ts, Tp = st.reflectance_transmittance(math.cos(ti), 1.0)
    up = st.upward()

    def t10(u):
        _, _, a, b = up.reflectance_transmittance(math.sqrt(1.0 - u), N)
        return 0.5 * float(a + b)

    exit_mean, _ = integrate.quad(t10, 0.0, 1 / N**2, epsabs=1e-13, epsrel=1e-12, limit=200)
    want = 0.5 * (Ts + Tp) * exit_mean / (1.0 - m.rbar)
    assert abs(r.value - want) <= r.error
    if films is LOSSLESS:
        assert abs(r.value + 0.5 * (Rs + Rp) - 1.0) <= r.error
    else:
        assert r.value + 0.5 * (Rs + Rp) < 0.5  # absorbed in the films


def test_model_set_over_the_coating_with_films():
    """A model set over the coating index places the films on each element's coating."""
    coat = np.array([[1.3], [1.7]])
    m = models.SubsurfaceFacetBRDF(coating=coat, coating_films=ABSORBING)
    tr = np.array([0.2, 0.5, 0.9])
    got = m.mueller(0.4, tr, 0.3)
    for i, n in enumerate((1.3, 1.7)):
        assert np.array_equal(
            got[i], models.SubsurfaceFacetBRDF(coating=n, coating_films=ABSORBING).mueller(0.4, tr, 0.3)
        )


@pytest.mark.parametrize(
    "cls", [models.SubsurfaceFacetBRDF, models.SingleScatterBRDF, models.DiffuseSubsurfaceBRDF]
)
def test_coating_films_is_declared_checked_and_listed(cls):
    assert "coating_films" in {p.name for p in cls.parameters()}
    assert "coating_films" in cls.info()
    with pytest.raises(ValueError, match=r"^coating_films must be None or a models.Films .*FilmStack states"):
        cls(coating_films=FilmStack(layers=((1.2, 100.0),), substrate=N))
    with pytest.raises(ValueError, match=r"^coating_films must be None or a models.Films"):
        cls(coating_films=((1.2, 100.0),))
    assert "coating_films" in models.list_models()


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(layers=((2.0, -1.0),)), r"layers\[0\] thickness_nm"),
        (dict(layers=((2.0 - 0.1j, 10.0),)), r"layers\[0\] index"),
        (dict(layers=((math.inf, 10.0),)), r"layers\[0\] index"),
        (dict(layers=(2.0,)), "layers"),
        (dict(wavelength_nm=-5.0), "wavelength_nm"),
    ],
)
def test_films_bad_input_names_the_parameter(kwargs, name):
    with pytest.raises(ValueError, match=name):
        Films(**kwargs)


def test_transmission_needs_a_real_substrate_at_least_the_ambient():
    for sub in (1.37 + 7.62j, math.inf, 0.9):
        with pytest.raises(ValueError, match=r"substrate must be a real index >= 1 \(the ambient's\)"):
            FilmStack(layers=((2.0, 10.0),), substrate=sub).transmission(0.5)


# ------------------------------------------------------------------ scenes
AR_SCENE = references.scene_path("aluminium_flakes_ar_clearcoat.toml")

SMOOTH = """name = "t"
[illumination]
theta_i_deg = 30.0
wavelength_nm = 550.0
[coating]
index = 1.5
"""
FILM = "[coating.film]\nlayers = [{index = 1.2247, thickness_nm = 112.3}]\n"


def test_example_scene_builds_the_filmed_model():
    sc = scene.load(AR_SCENE)
    m = sc.build()
    assert isinstance(m, models.SubsurfaceFacetBRDF)
    assert m.coating == 1.5 and m.substrate == 1.37 + 7.62j
    assert m.coating_films == Films(layers=((1.2247, 129.2),), wavelength_nm=632.8)
    (mech,) = sc.mechanisms()
    assert "films on the coating" in mech.why
    bare = m.replace(coating_films=None)
    assert m.brdf(0.0, 0.0, 0.0) / bare.brdf(0.0, 0.0, 0.0) > 1.08  # ~((n+1)^2/(4n))^2 = 1.085


def test_coating_film_reaches_the_volume_and_the_rough_top():
    text = SMOOTH + FILM + "[coating.roughness]\ndistribution = 'gaussian'\nsigma = 0.05\n"
    text += "[volume]\nrho = 0.5\ninterface = 'smooth'\n"
    sc = scene.loads(text, "v.toml")
    films = sc.coating["films"]
    kinds = {type(m).__name__: m for _, m in sc.build().terms}
    assert kinds["SingleScatterBRDF"].coating_films == films
    assert kinds["DiffuseSubsurfaceBRDF"].coating_films == films
    rough = kinds["FacetBRDF"]  # the rough top surface reflects as the filmed coating
    assert rough.substrate == films.on(1.5)


def test_coating_film_thickness_is_a_fit_key():
    sc = scene.load(AR_SCENE)
    m = sc.with_values({"coating.film.layers[0].thickness_nm": 140.0}).build()
    assert m.coating_films.layers[0][1] == 140.0


@pytest.mark.parametrize(
    "extra, message",
    [
        (
            FILM.replace("112.3", "-1.0"),
            r"v.toml: \[coating.film\] layers\[0\].thickness_nm: layers\[0\] thickness_nm must be",
        ),
        (
            FILM.replace("1.2247", "[1.2, -0.1]"),
            r"v.toml: \[coating.film\] layers\[0\].index: layers\[0\] index must be",
        ),
        (
            FILM.replace("thickness_nm", "depth_nm"),
            r"v.toml: \[coating.film\] layers\[0\].depth_nm: unknown key",
        ),
        ("[coating.film]\nlayers = []\n", r"v.toml: \[coating.film\] layers: required: a non-empty array"),
        ("[coating.film]\nlayer = 1\n", r"v.toml: \[coating.film\] layer: unknown key; allowed: layers"),
        (
            FILM + "[substrate]\nmodel = 'cook-torrance'\nindex = [2.29, 3.37]\nm = 0.1\n",
            r"v.toml: \[coating.film\]: not with \[substrate\] model = 'cook-torrance'",
        ),
        (
            FILM + "[coating.roughness]\ndistribution = 'gaussian'\nsigma = 0.05\n[volume]\nrho = 0.5\n",
            r"v.toml: \[coating.film\]: not with a \[volume\] under the rough coating",
        ),
    ],
)
def test_coating_film_errors_name_the_file_and_key(extra, message):
    with pytest.raises(scene.SceneError, match=message):
        scene.loads(SMOOTH + extra, "v.toml")


def test_coating_film_needs_the_wavelength():
    text = SMOOTH.replace("wavelength_nm = 550.0\n", "") + FILM
    with pytest.raises(
        scene.SceneError, match=r"v.toml: \[illumination\] wavelength_nm: required with \[coating.film\]"
    ):
        scene.loads(text, "v.toml")
