"""Fit spec, likelihood, emcee sampling with resume, executors, recovery of the SCATMECH data set, CLI."""

import json
import math
import os

import numpy as np
import pytest

from scatterbench import models, references
from scatterbench.models import scene
from scatterbench.validation.checks.fitting import InterruptAfter
from scatterbench.validation.cli import main
from scatterbench.validation.fitting import likelihood
from scatterbench.validation.fitting.datafile import load_data
from scatterbench.validation.fitting.executors import DaskExecutor, ProcessExecutor, SerialExecutor
from scatterbench.validation.fitting.fit import fingerprint, run_fit
from scatterbench.validation.fitting.fitspec import FitSpecError, fitspec_from, parse_free
from scatterbench.validation.fitting.likelihood import Likelihood
from scatterbench.validation.fitting.recovery import subsample
from scatterbench.validation.fitting.sampling import (
    ChainSettings,
    CheckpointBackend,
    CheckpointError,
    _converged,
    _unsettled,
    at_bounds,
    initial_ball,
    optimize,
    run_chain,
)

COATED = references.scene_path("aluminium_flakes_clearcoat.toml")
FITSCENE = references.scene_path("aluminium_flakes_fit.toml")
DATA = references.data_path("scatmech_flake_measurement.csv")


@pytest.fixture(scope="module")
def coated():
    return scene.load(COATED)


@pytest.fixture(scope="module")
def data():
    return load_data(DATA)


# ----------------------------------------------------------------------------- spec
def test_free_entries_aliases_priors_and_bounds(coated):
    p = parse_free("sigma:0.01:1:log")
    assert (p.key, p.low, p.high, p.prior) == ("substrate.sigma", 0.01, 1.0, "log")
    assert parse_free("k:3:12").key == "substrate.index[1]" and parse_free("k:3:12").prior == "uniform"
    with pytest.raises(FitSpecError, match="log-uniform prior needs low > 0"):
        parse_free("sigma:0:1:log")
    with pytest.raises(FitSpecError, match="low < high"):
        parse_free("sigma:1:0.5")
    with pytest.raises(FitSpecError, match="prior must be"):
        parse_free("sigma:0.1:1:gauss")
    with pytest.raises(FitSpecError, match=r"coating\.index: bound 0\.5 gives an invalid scene"):
        fitspec_from(coated, ["coating:0.5:2"], ["brdf=0.1"])
    with pytest.raises(FitSpecError, match="substrate.roughness: not set"):
        fitspec_from(coated, ["substrate.roughness:0.1:1"], ["brdf=0.1"])
    with pytest.raises(FitSpecError, match="unknown noise term"):
        fitspec_from(coated, ["sigma:0.01:1"], ["speckle=0.1"])


def test_scene_fit_table_and_log_prior_bounds():
    sc = scene.load(FITSCENE)
    spec = fitspec_from(sc)
    assert spec.names == [
        "substrate.sigma",
        "coating.index",
        "substrate.index[0]",
        "substrate.index[1]",
        "noise.brdf",
    ]
    assert spec.noise == {"eta_deg": 1.0, "P": 0.02, "P_C": 0.02}
    u = np.array([math.log(0.1), 1.5, 1.37, 7.62, math.log(0.05)])
    assert spec.log_prior(u) == 0.0
    assert spec.log_prior(u + np.array([0, 0.6, 0, 0, 0])) == -math.inf  # coating 2.1 > 2
    # vectorized over walkers (what Likelihood.batch uses): out of bounds or not finite: -inf
    U = np.array([u, u + [0, 0.6, 0, 0, 0], u + [0, 0, 0, 0, math.nan], u - [0, 0, 0, 8, 0]])
    np.testing.assert_array_equal(spec.log_prior(U), [0.0, -math.inf, -math.inf, -math.inf])
    assert spec.physical(u)["substrate.sigma"] == pytest.approx(0.1)
    # the command line replaces the scene's free list
    assert fitspec_from(sc, ["sigma:0.05:0.2:log"]).names == ["substrate.sigma", "noise.brdf"]


def test_masks_near_specular_and_boxes(coated, data):
    spec = fitspec_from(coated, ["sigma:0.01:1:log"], ["brdf=0.05"], near_specular_deg=5.0)
    keep = spec.mask(data)
    from scatterbench.validation.fitting.fitspec import specular_distance

    d = np.degrees(specular_distance(data.theta_i, data.theta_r, data.phi_r))
    assert np.array_equal(keep, d > 5.0) and 0 < (~keep).sum() < 40
    spec = fitspec_from(
        coated, ["sigma:0.01:1:log"], ["brdf=0.05"], exclude=["theta_r_deg=53:67,phi_r_deg=180:180"]
    )
    gone = ~spec.mask(data)
    tr, pr = np.degrees(data.theta_r), np.degrees(data.phi_r)
    assert np.array_equal(gone, (tr >= 53 - 1e-9) & (tr <= 67 + 1e-9) & np.isclose(pr, 180.0))
    assert gone.sum() > 5


# ----------------------------------------------------------------------------- likelihood
def test_likelihood_prefers_the_truth_and_uses_declared_terms(coated, data):
    spec = fitspec_from(
        coated, ["sigma:0.01:1:log", "coating:1.2:2"], ["brdf=0.05", "eta_deg=1", "P=0.02", "P_C=0.02"]
    )
    lik = Likelihood(coated, spec, data)
    assert lik.terms == ("brdf", "eta", "P", "P_C")
    at_truth = lik([math.log(0.1), 1.5])
    assert at_truth > lik([math.log(0.11), 1.5]) + 50
    assert at_truth > lik([math.log(0.1), 1.55]) + 50
    assert lik([math.log(0.1), 2.5]) == -math.inf  # outside the bounds
    # whitened residuals at the truth are unit-variance noise (what the data were made with)
    w = lik.whitened([math.log(0.1), 1.5])
    assert len(w) == 4 * len(data) and 0.85 < np.std(w) < 1.15
    spec = fitspec_from(coated, ["sigma:0.01:1:log"], ["eta_deg=1"])
    with pytest.raises(ValueError, match="noise.brdf"):
        Likelihood(coated, spec, data)
    # "off" drops a term the scene's [fit.noise] declares (a BRDF-only fit of polarimetric data)
    sc = scene.load(FITSCENE)
    assert Likelihood(sc, fitspec_from(sc), data).terms == ("brdf", "eta", "P", "P_C")
    off = fitspec_from(sc, None, ["eta_deg=off", "P=off"])
    assert off.off == ("eta_deg", "P") and "eta_deg" not in off.noise
    assert Likelihood(sc, off, data).terms == ("brdf", "P_C")
    with pytest.raises(ValueError, match="brdf: the BRDF term cannot be off"):
        fitspec_from(sc, None, ["brdf=off"])


def test_a_brdf_only_fit_predicts_from_the_first_row_alone(coated, data):
    """With BRDF the only fitted term the likelihood skips eta, P and P_C (the Mueller matrix's
    first row against each row's incident Stokes vector): the same BRDF as :meth:`predict`
    to rounding, whatever the rows' incident polarizations, and the same ln L."""
    spec = fitspec_from(coated, ["sigma:0.01:1:log", "coating:1.2:2"], ["brdf=0.05"])
    lik = Likelihood(coated, spec, data)
    assert lik.terms == ("brdf",) and len(np.unique(data.incident, axis=0)) > 1
    v = lik.spec.values(np.array([[math.log(0.1), 1.5], [math.log(0.2), 1.3]]))
    model = lik.model(v.scene)
    fast, full = lik.predict(model, terms=lik.terms), lik.predict(model)
    assert set(fast) == {"brdf"}
    np.testing.assert_allclose(fast["brdf"], full["brdf"], rtol=1e-14, atol=0)
    ll_fast = lik._pointwise_rows(v.noise, fast)
    ll_full = lik._pointwise_rows(v.noise, full)
    assert np.max(np.abs(ll_fast - ll_full)) <= 1e-12 * np.max(np.abs(ll_full))


@pytest.mark.parametrize(
    "scene_file, data_file",
    [
        ("aluminium_flakes_fit.toml", "scatmech_flake_measurement.csv"),
        ("red_paint_fit.toml", "scatmech_paint_measurement.csv"),
        ("maxwell_beard_fit.toml", "scatmech_mb_measurement.csv"),
    ],
)
@pytest.mark.parametrize("walkers", [None, 1, 7])
def test_the_likelihood_s_kernel_route_gives_the_models_bits(scene_file, data_file, walkers):
    """The likelihood calls a compiled model's kernel at the fitted rows directly
    (models.evaluation.FixedAngles: their angles validated and broadcast once per walker
    count): the Mueller matrices of
    ``model.mueller16``, bit for bit, for a single model and for model sets of 1 and 7
    walkers, on the first call and on the cached angles; a sum of models (the paint), which
    has no kernel of its own, the same way through numpy's sum of its terms' kernels."""
    sc = scene.load(references.scene_path(scene_file))
    lik = Likelihood(sc, fitspec_from(sc), subsample(load_data(references.data_path(data_file)), 60))
    rng = np.random.default_rng(3)
    b = lik.spec.u_bounds()
    d = lik.data
    for _ in range(2):
        u = rng.uniform(b[:, 0], b[:, 1], (walkers or 1, len(b)))
        if walkers is None:
            model = lik.model(lik.spec.physical(u[0]))
        else:
            model = lik.model(lik.spec.values(u).scene)
        # a sum of models (the paint) has no kernel of its own
        assert models.evaluation.kernel_path(model) == (scene_file != "red_paint_fit.toml")
        shape, M = lik._rows.mueller16(model)
        ref_shape, ref = model.mueller16(d.theta_i, d.theta_r, d.phi_r)
        assert shape == ref_shape and np.array_equal(M, ref)


def test_stokes_of_the_rows_are_einsum_s_bits():
    """The likelihood's Stokes vectors (each row's Mueller matrix on its incident Stokes
    vector, products added in the incident elements' order) are numpy's einsum's, bit for bit,
    over magnitudes 1e-5..1e5, several walker counts and row counts, a zero V included; one
    incident vector for all rows gives the same, and skips its zero element."""
    rng = np.random.default_rng(11)
    for walkers, rows in [(1, 1), (1, 200), (12, 200), (7, 33), (24, 5)]:
        M = rng.standard_normal((4, 4, walkers, rows)) * 10.0 ** rng.uniform(-5, 5, (4, 4, walkers, rows))
        inc = rng.standard_normal((rows, 4))
        inc[::2, 3] = 0.0
        S = likelihood._stokes(M, np.ascontiguousarray(inc.T))
        assert np.array_equal(S, np.einsum("ab...n,nb->a...n", M, inc))
        # one incident vector for every row: the same sums, its zero element skipped, so that
        # an infinite element it multiplies gives no NaN
        one = np.ascontiguousarray(np.tile(inc[0], (rows, 1)).T)
        assert np.array_equal(likelihood._stokes(M, inc[0]), likelihood._stokes(M, one))
        M[:, 3] = np.inf
        assert np.all(np.isfinite(likelihood._stokes(M, inc[0])))


@pytest.mark.parametrize(
    "scene_file, data_file",
    [
        ("aluminium_flakes_fit.toml", "scatmech_flake_measurement.csv"),
        ("red_paint_fit.toml", "scatmech_paint_measurement.csv"),
        ("maxwell_beard_fit.toml", "scatmech_mb_measurement.csv"),
    ],
)
def test_batched_likelihood_equals_the_scene_rebuilt_per_walker(scene_file, data_file):
    """All walkers in one call (a model set bound to the scene's keys) give the ln L of the
    scene rebuilt and validated per walker, to 1e-12; a single position is a batch of one,
    so the two agree bit for bit whatever the batch."""
    sc = scene.load(references.scene_path(scene_file))
    lik = Likelihood(sc, fitspec_from(sc), subsample(load_data(references.data_path(data_file)), 60))
    assert lik.binding is not None
    b = lik.spec.u_bounds()
    U = np.random.default_rng(5).uniform(b[:, 0], b[:, 1], (12, len(b)))
    L = lik.batch(U)
    ref = np.array([lik.loglike_rebuilt(u) for u in U])
    assert np.all(np.isfinite(ref))
    assert np.max(np.abs(L - ref) / np.abs(ref)) <= 1e-12
    assert np.array_equal(L, [lik(u) for u in U])
    assert np.array_equal(L[3:5], lik.batch(U[3:5]))
    outside = U[:2].copy()
    outside[0, 0] = b[0, 1] + 1.0
    outside[1, -1] = np.nan
    assert np.all(lik.batch(outside) == -math.inf)


def test_walkers_the_scene_refuses_get_minus_inf_and_leave_the_others_unchanged(coated, data):
    """A walker inside the bounds that the scene refuses (here: a refusal patched in above a
    sigma) gets -inf; the others keep the values they have in any batch, bit for bit."""
    lik = _small(coated, data, 20)
    key, limit = lik.spec.free[0].key, 0.3
    model, rebuilt = lik.model, lik.model_rebuilt

    def refusing(build):
        def build_or_refuse(values):
            if np.any(np.asarray(values[key]) > limit):
                raise ValueError(f"{key} refused above {limit}")
            return build(values)

        return build_or_refuse

    lik.model, lik.model_rebuilt = refusing(model), refusing(rebuilt)
    b = lik.spec.u_bounds()
    U = np.random.default_rng(7).uniform(b[:, 0], b[:, 1], (10, len(b)))
    refused = np.exp(U[:, 0]) > limit
    assert 0 < refused.sum() < len(U)
    L = lik.batch(U)
    assert np.all(L[refused] == -math.inf) and np.all(np.isfinite(L[~refused]))
    assert np.array_equal(L, np.concatenate([lik.batch(U[:3]), lik.batch(U[3:])]))
    assert np.array_equal(L, [lik(u) for u in U])
    ref = np.array([lik.loglike_rebuilt(u) for u in U[~refused]])
    assert np.max(np.abs(L[~refused] - ref) / np.abs(ref)) <= 1e-12


def test_vectorized_sampler_equals_the_per_walker_one(coated, data):
    """emcee with vectorize=True (the likelihood's batch) runs the chain a per-walker
    log-probability runs, bit for bit."""
    from scatterbench.validation.fitting.sampling import vectorized

    lik = _small(coated, data, 20)

    def per_walker(u):
        return lik(u)

    assert vectorized(lik) and not vectorized(per_walker)
    p0 = initial_ball(np.array([math.log(0.1), 1.5]), 8, 2, lik.spec.u_bounds())
    st = ChainSettings(walkers=8, seed=2, max_steps=20, check_every=10)
    a = run_chain(lik, st, p0=p0)
    b = run_chain(per_walker, st, p0=p0)
    assert np.array_equal(a.chain, b.chain) and np.array_equal(a.log_prob, b.log_prob)


# ----------------------------------------------------------------------------- sampling
def _small(coated, data, n=30):
    spec = fitspec_from(coated, ["sigma:0.01:1:log", "coating:1.2:2"], ["brdf=0.05", "eta_deg=1"])
    return Likelihood(coated, spec, subsample(data, n))


def test_resume_after_interruption_gives_the_same_chain_bit_for_bit(coated, data, tmp_path):
    lik = _small(coated, data)
    u0, _, _ = optimize(lik, 7, n_starts=1)
    p0 = initial_ball(u0, 8, 7, lik.spec.u_bounds())
    st = ChainSettings(walkers=8, seed=7, max_steps=60, check_every=20, tau_factor=50)
    full = run_chain(lik, st, p0=p0, backend=CheckpointBackend(str(tmp_path / "a.npz"), "f"))
    ck = str(tmp_path / "b.npz")
    with pytest.raises(KeyboardInterrupt):  # dies in step ~35
        run_chain(InterruptAfter(lik, 8 + 8 * 35), st, p0=p0, backend=CheckpointBackend(ck, "f"))
    with np.load(ck) as z:
        assert z["chain"].shape[0] == 20  # the last complete segment survived
    resumed = run_chain(lik, st, backend=CheckpointBackend.load(ck, "f"))
    assert np.array_equal(resumed.chain, full.chain)
    assert np.array_equal(resumed.log_prob, full.log_prob)
    assert np.array_equal(resumed.accepted, full.accepted)
    assert [s for s, _ in resumed.tau_history] == [s for s, _ in full.tau_history] == [20, 40, 60]
    for (_, a), (_, b) in zip(resumed.tau_history, full.tau_history, strict=True):
        assert np.array_equal(a, b, equal_nan=True)
    assert resumed.evaluations == full.evaluations == 8 * 61
    # stopping early on a budget and continuing with a larger one is the same too
    c = str(tmp_path / "c.npz")
    part = run_chain(lik, st.replace(max_steps=40), p0=p0, backend=CheckpointBackend(c, "f"))
    assert part.steps == 40 and not part.converged and "step budget" in part.stop_reason
    more = run_chain(lik, st, backend=CheckpointBackend.load(c, "f"))
    assert np.array_equal(more.chain, full.chain)
    with pytest.raises(CheckpointError, match="other data"):
        CheckpointBackend.load(ck, "other")
    with pytest.raises(CheckpointError, match="has 8 walkers, the settings 10"):
        run_chain(lik, st.replace(walkers=10), backend=CheckpointBackend.load(ck, "f"))


def test_the_checkpoint_is_an_emcee_backend_kept_in_memory(coated, data):
    """Without a path the backend is emcee's in-memory one; the sampler stores into it."""
    import emcee

    lik = _small(coated, data, 20)
    p0 = initial_ball(np.array([math.log(0.1), 1.5]), 6, 1, lik.spec.u_bounds())
    backend = CheckpointBackend()
    res = run_chain(
        lik, ChainSettings(walkers=6, seed=1, max_steps=25, check_every=10), p0=p0, backend=backend
    )
    assert isinstance(backend, emcee.backends.Backend)
    assert backend.iteration == 25 and np.array_equal(backend.get_chain(), res.chain)
    assert [s for s, _ in backend.tau_history] == [
        10,
        20,
        25,
    ]  # checks on multiples of check_every, then the end


def _old_format_checkpoint(path):
    """A checkpoint as scatterbench wrote it before the emcee backend (no format entry)."""
    rs = np.random.RandomState(0).get_state()
    np.savez(
        path,
        chain=np.zeros((3, 4, 1)),
        log_prob=np.zeros((3, 4)),
        accepted=np.zeros(4),
        coords=np.zeros((4, 1)),
        last_log_prob=np.zeros(4),
        rs_name=np.array(rs[0]),
        rs_keys=rs[1],
        rs_pos=np.array(rs[2]),
        rs_has_gauss=np.array(rs[3]),
        rs_cached=np.array(rs[4]),
        fingerprint=np.array("f"),
        tau_history="[]",
        seconds=np.array(1.0),
        evaluations=np.array(16),
    )


@pytest.mark.parametrize(
    "kind", ["old format", "not a zip", "truncated", "missing entry", "bad shapes", "missing"]
)
def test_unusable_checkpoints_are_refused_naming_the_file(coated, data, tmp_path, kind):
    lik = _small(coated, data, 20)
    st = ChainSettings(walkers=4, seed=1, max_steps=20, check_every=10)
    good = str(tmp_path / "good.npz")
    run_chain(lik, st, p0=initial_ball(np.array([math.log(0.1), 1.5]), 4, 1, lik.spec.u_bounds()),
              backend=CheckpointBackend(good, "f"))  # fmt: skip
    path = str(tmp_path / "chain.npz")
    if kind == "old format":
        _old_format_checkpoint(path)
    elif kind == "not a zip":
        open(path, "w").write("not a checkpoint\n")
    elif kind == "truncated":
        open(path, "wb").write(open(good, "rb").read()[:500])
    elif kind in ("missing entry", "bad shapes"):
        with np.load(good) as z:
            e = {k: z[k] for k in z.files}
        if kind == "missing entry":
            del e["rs_keys"]
        else:
            e["accepted"] = np.zeros(3)
        np.savez(path, **e)
    words = {"old format": "older scatterbench", "missing": "no checkpoint"}.get(kind, "")
    with pytest.raises(CheckpointError, match=f"^{path}: .*{words}"):
        CheckpointBackend.load(path, "f")


def test_chain_settings_name_the_field_and_its_range():
    for field, bad, words in [
        ("walkers", 7, "even"),
        ("walkers", 0, ">= 2"),
        ("walkers", 8.0, "integer"),
        ("seed", -1, ">= 0"),
        ("max_steps", 0, ">= 1"),
        ("check_every", 0, ">= 1"),
        ("tau_factor", math.inf, "finite number > 0"),
        ("tau_factor", 0.0, "> 0"),
        ("tau_rtol", -0.1, "> 0"),
        ("starts", 0, ">= 1"),
        ("starts", True, "integer"),
        ("moves", "gibbs", "one of stretch, de"),
        ("moves", None, "one of stretch, de"),
    ]:
        with pytest.raises(ValueError, match=f"^{field} must be .*{words}"):
            ChainSettings(**{field: bad})
    st = ChainSettings(walkers=np.int64(6), tau_factor=np.float32(40))
    assert type(st.walkers) is int and type(st.tau_factor) is float
    assert st.require_walkers(3) is st
    with pytest.raises(ValueError, match=r"walkers must be even and >= 2 x free parameters \(8\); got 6"):
        st.require_walkers(4)
    with pytest.raises(ValueError, match="max_steps"):
        st.replace(max_steps=-5)
    with pytest.raises(AttributeError):
        st.walkers = 8  # frozen


def test_de_moves_are_seeded_resumable_and_executor_independent(coated, data, tmp_path):
    """The differential-evolution moves draw from the sampler's seeded random state like the
    stretch move: a resumed chain equals the uninterrupted one, the process executor the serial
    one, and the chain is not the stretch move's."""
    lik = _small(coated, data, 20)
    p0 = initial_ball(np.array([math.log(0.1), 1.5]), 8, 5, lik.spec.u_bounds())
    st = ChainSettings(walkers=8, seed=5, max_steps=40, check_every=20, moves="de")
    full = run_chain(lik, st, p0=p0, backend=CheckpointBackend(str(tmp_path / "a.npz"), "f"))
    ck = str(tmp_path / "b.npz")
    with pytest.raises(KeyboardInterrupt):  # dies in step ~30, after the step-20 checkpoint
        run_chain(InterruptAfter(lik, 8 + 8 * 30), st, p0=p0, backend=CheckpointBackend(ck, "f"))
    resumed = run_chain(lik, st, backend=CheckpointBackend.load(ck, "f"))
    assert np.array_equal(resumed.chain, full.chain)
    with ProcessExecutor(2) as ex:
        assert np.array_equal(run_chain(lik, st, p0=p0, executor=ex).chain, full.chain)
    stretch = run_chain(lik, st.replace(moves="stretch"), p0=p0)
    assert not np.array_equal(stretch.chain, full.chain)
    # a checkpoint of one move is not resumed with the other: the fit's fingerprint differs
    assert fingerprint(lik, st) != fingerprint(lik, st.replace(moves="stretch"))


def test_same_seed_same_chain_whatever_the_executor(coated, data):
    from dask.distributed import Client, LocalCluster

    lik = _small(coated, data, 20)
    st = ChainSettings(walkers=8, seed=3, max_steps=30, check_every=15, starts=1)
    ref = run_fit(lik, st, executor=SerialExecutor())
    with ProcessExecutor(2) as ex:
        procs = run_fit(lik, st, executor=ex)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with Client(cluster) as client, DaskExecutor(client) as ex:
            assert ex.workers == 2
            dask = run_fit(lik, st, executor=ex)
        with DaskExecutor(cluster.scheduler_address) as ex:  # the --scheduler ADDRESS path
            assert ex.map(abs, [-3, 1, -2]) == [3, 1, 2]
    assert np.array_equal(ref.chain.chain, procs.chain.chain)
    assert np.array_equal(ref.chain.chain, dask.chain.chain)
    assert np.array_equal(ref.chain.log_prob, dask.chain.log_prob)
    other = run_fit(lik, st.replace(seed=4), executor=SerialExecutor())
    assert not np.array_equal(ref.chain.chain, other.chain.chain)


def test_a_burned_chain_continues_the_burn_in_bit_for_bit(coated, data):
    """``ChainSettings.burn``: the kept chain is the tail of the chain the burn-in began (its
    ensemble and random state continued), for either move; the burned steps and their time
    are reported, and the setting refuses a negative count, naming itself."""
    lik = _small(coated, data, 20)
    for moves in ("stretch", "de"):
        st = ChainSettings(walkers=8, seed=3, max_steps=20, check_every=10, starts=1, moves=moves)
        whole = run_fit(lik, st.replace(max_steps=32))
        burned = run_fit(lik, st.replace(burn=12))
        assert burned.chain.steps == 20
        assert np.array_equal(burned.chain.chain, whole.chain.chain[12:])
        assert np.array_equal(burned.chain.log_prob, whole.chain.log_prob[12:])
        b = burned.summary["sampling"]["burned_before_chain"]
        assert b["steps"] == 12 and b["seconds"] > 0
        assert whole.summary["sampling"]["burned_before_chain"] == {"steps": 0, "seconds": 0.0}
    assert fingerprint(lik, st) != fingerprint(lik, st.replace(burn=12))
    with pytest.raises(ValueError, match="burn must be an integer >= 0"):
        ChainSettings(burn=-1)


def test_recovers_the_scatmech_sample_within_95_percent(coated, data):
    """Held-out SCATMECH data: sigma, coating index, n and k inside their 95% intervals.

    A short chain (the full convergent run is the CLI run in the report); noise
    levels fixed at the values the data were made with.
    """
    spec = fitspec_from(
        coated,
        ["sigma:0.01:1:log", "coating:1.2:2", "n:0.3:4", "k:3:12"],
        ["brdf=0.05", "eta_deg=1", "P=0.02", "P_C=0.02"],
    )
    res = run_fit(
        Likelihood(coated, spec, data),
        ChainSettings(walkers=16, seed=11, max_steps=500, check_every=100, starts=2),
    )
    truth = data.meta["truth"]
    for key, v in truth.items():
        p = res.summary["parameters"][key]
        assert p["p2.5"] <= v <= p["p97.5"], (key, p)
        lo, hi = p["bounds"]
        assert p["p97.5"] - p["p2.5"] < 0.25 * (hi - lo)  # the data, not the prior, set the interval
    s = res.summary["sampling"]
    assert 0.2 < s["acceptance_mean"] < 0.8 and np.all(np.isfinite(s["tau_steps"]))


# ----------------------------------------------------------------------------- CLI
def test_fit_command_writes_results_refuses_overwrite_and_resumes(tmp_path, capsys):
    out = str(tmp_path / "fit")
    args = [
        "fit", DATA, "--scene", COATED, "--free", "sigma:0.01:1:log", "--noise", "brdf:0.01:0.5:log",
        "--walkers", "8", "--max-steps", "40", "--check-every", "20", "--starts", "1", "--no-progress",
        "--out", out,
    ]  # fmt: skip
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "step budget reached" in text and "evaluations/s" in text and "acceptance" in text
    for f in ("posterior.json", "chain.npz", "corner.png", "predictive.png", "residuals.png"):
        assert os.path.getsize(os.path.join(out, f)) > 0
    post = json.load(open(os.path.join(out, "posterior.json")))
    p = post["parameters"]["substrate.sigma"]
    assert p["p2.5"] <= p["p16"] <= p["median"] <= p["p84"] <= p["p97.5"]
    assert post["sampling"]["steps"] == 40 and post["sampling"]["converged"] is False
    assert set(post["posterior_predictive"]) == {"brdf"}
    assert main(args) == 2
    assert "exists" in capsys.readouterr().err
    args[args.index("40")] = "60"
    assert main(args + ["--resume", "--no-plots"]) == 0
    post = json.load(open(os.path.join(out, "posterior.json")))
    assert post["sampling"]["steps"] == 60
    assert (
        main(["fit", DATA, "--scene", COATED, "--free", "sigma:0.01:1:log", "--out", str(tmp_path / "x")])
        == 2
    )
    assert "noise.brdf" in capsys.readouterr().err


def test_fit_and_studies_refuse_bad_settings_and_unusable_checkpoints_without_a_traceback(tmp_path, capsys):
    out = tmp_path / "fit"
    out.mkdir()
    ck = out / "chain.npz"
    _old_format_checkpoint(str(ck))
    args = [
        "fit", DATA, "--scene", COATED, "--free", "sigma:0.01:1:log", "--noise", "brdf=0.05", "--walkers", "4",
        "--max-steps", "20", "--starts", "1", "--no-progress", "--no-plots", "--out", str(out), "--resume",
    ]  # fmt: skip
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {ck}: a checkpoint of an older scatterbench") and "Traceback" not in err
    ck.write_bytes(b"garbage")
    assert main(args) == 2
    assert capsys.readouterr().err.startswith(f"error: {ck}: not a readable checkpoint")
    assert main(args[:-1] + ["--force", "--max-steps", "0"]) == 2
    assert capsys.readouterr().err == "error: max_steps must be an integer >= 1; got 0\n"
    two = ["--free", "coating:1.2:2", "--walkers", "2"]
    assert main(args[:-1] + ["--force"] + two) == 2
    assert "walkers must be even and >= 2 x free parameters (4); got 2" in capsys.readouterr().err
    study = ["study", "recovery", DATA, "--scene", COATED, "--free", "sigma:0.01:1:log", "--noise", "brdf=0.1",
             "--injections", "1", "--out", str(tmp_path / "rec")]  # fmt: skip
    assert main(study + two) == 2
    assert "walkers must be even and >= 2 x free parameters (4); got 2" in capsys.readouterr().err
    assert main(study[:-4] + ["--injections", "0"] + study[-2:]) == 2
    assert capsys.readouterr().err == "error: injections must be an integer >= 1; got 0\n"
    assert main(study + ["--check-every", "0"]) == 2
    assert capsys.readouterr().err == "error: check_every must be an integer >= 1; got 0\n"


def test_the_data_sidecar_sets_the_aperture_and_the_choice_is_fixed_for_the_fit(coated, data):
    """SCATMECH's data record a point detector (aperture_deg = 0): the 0.7 deg of the scene is not
    applied.  A sidecar that records 0.7 deg gets the averaged model with the quadrature chosen at
    the scene's values at every parameter value, though a scene built at a wider lobe alone
    would choose a coarser one, so ln L is smooth."""
    import dataclasses

    from scatterbench import models

    spec = fitspec_from(coated, ["sigma:0.01:1:log"], ["brdf=0.05"])
    d = subsample(data, 20)
    lik = Likelihood(coated, spec, d)
    assert lik.scene.aperture_deg == 0.0 and not isinstance(
        lik.model({"substrate.sigma": 0.1}), models.DetectorAperture
    )
    d7 = dataclasses.replace(d, meta={**d.meta, "aperture_deg": 0.7})
    lik7 = Likelihood(coated, spec, d7)
    for sigma in (0.1, 1.0):
        m = lik7.model({"substrate.sigma": sigma})
        assert isinstance(m, models.DetectorAperture) and m.resolution == 8
    assert lik7.decisions == {"point_source": False, "aperture_resolution": 8}
    assert "resolution 4 " in coated.with_values({"substrate.sigma": 1.0}).aperture_decision()
    # the averaged peak is lower than the point detector's (the exponential cusp is smoothed)
    assert (
        lik7.predict(lik7.model({"substrate.sigma": 0.1}))["brdf"].max()
        < lik.predict(lik.model({"substrate.sigma": 0.1}))["brdf"].max()
    )


def test_at_bounds_says_when_a_posterior_is_pressed_against_its_prior_box(capsys):
    """``at_bounds``: samples spread over the box put about 2% within 1% of the range of its
    two bounds; samples piled at a bound put there nearly all; the fit's printout names such a
    parameter (the PTFE joint fit's Cauchy A sat at 1.25001 on its bound 1.25), and only
    such a one.  Fails when the band or the threshold changes what a flat posterior shows."""
    from scatterbench.validation.cli.fit import _print_posterior

    rng = np.random.default_rng(1)
    bounds = np.array([[0.0, 1.0], [1.25, 1.45]])
    u = np.column_stack([rng.uniform(0.0, 1.0, 20000), 1.25 + rng.exponential(5e-4, 20000)])
    near = at_bounds(u, bounds)
    assert 0.015 < near[0] < 0.025 and near[1] > 0.95, near
    stats = {"p2.5": 0.0, "p16": 0.0, "p50": 0.0, "p84": 0.0, "p97.5": 0.0}
    post = {
        "parameters": {"flat": {**stats, "at_bound": near[0]}, "pressed": {**stats, "at_bound": near[1]}},
        "information_criteria": {"max_log_likelihood": 0.0, "AIC": 0.0, "BIC": 0.0},
        "posterior_predictive": {},
    }
    _print_posterior(post)
    line = next(ln for ln in capsys.readouterr().out.splitlines() if "pressed against" in ln)
    assert "pressed 0.9" in line and "flat" not in line, line


def test_a_chain_past_50_tau_says_why_it_is_not_converged():
    """The N >= 50 tau rule needs two autocorrelation estimates with max(tau) stable: a chain
    past 50 tau at its only check, or with tau still moving, says which (the PTFE study's
    chains, checked once at the end, each read "NOT converged" without saying why)."""
    s = ChainSettings(max_steps=1000, check_every=1000)
    tau = np.array([5.0, 10.0])
    assert _unsettled([(1000, tau)], s).startswith(" (N is, but tau was estimated once")
    assert "moved by 50%" in _unsettled([(500, tau / 2), (1000, tau)], s)
    assert _unsettled([(1000, tau * 30)], s) == ""  # N < 50 tau: the rule's first half says it
    assert _converged([(500, tau), (1000, tau)], s) and _unsettled([(500, tau), (1000, tau)], s) == ""
