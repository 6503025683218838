"""Injection-recovery: coverage over >= 50 injections within binomial error; determinism; compare."""

import json
import os

import numpy as np
import pytest
from spy_executor import Spy

from scatterbench import references
from scatterbench.models import scene
from scatterbench.validation.cli import main
from scatterbench.validation.fitting.compare import compare_fits, seed003_pairing
from scatterbench.validation.fitting.datafile import load_data
from scatterbench.validation.fitting.executors import ProcessExecutor
from scatterbench.validation.fitting.fitspec import fitspec_from
from scatterbench.validation.fitting.likelihood import Likelihood
from scatterbench.validation.fitting.recovery import recovery_study, subsample
from scatterbench.validation.fitting.settings import ChainSettings

COATED = references.scene_path("aluminium_flakes_clearcoat.toml")
DATA = references.data_path("scatmech_flake_measurement.csv")


@pytest.fixture(scope="module")
def setup():
    sc = scene.load(COATED)
    return sc, load_data(DATA)


def test_coverage_over_50_injections_is_within_binomial_error(setup):
    """A cheap but real study: 50 independent noisy data sets (8 geometries, 10% speckle),
    each fitted by emcee (4 walkers, 150 steps, checked >= 8 autocorrelation times); the
    fraction of 68% / 95% intervals containing the truth must be within 2 binomial
    standard errors of nominal."""
    sc, data = setup
    spec = fitspec_from(sc, ["sigma:0.01:1:log"], ["brdf=0.1"])
    (cell,) = recovery_study(
        sc, spec, data, ChainSettings(walkers=4, seed=5, max_steps=150, check_every=150, starts=1),
        noise_levels=(0.1,), n_geometries=(8,), injections=50,
    )  # fmt: skip
    s = cell["summary"]["substrate.sigma"]
    assert s["injections"] == 50 and cell["steps_over_tau_min"] > 8
    for level in ("68", "95"):
        c = s["coverage"][level]
        assert abs(c["z"]) <= 2.0, (level, c)
    assert abs(s["bias"]) < 3 * s["bias_se"]


def test_study_members_are_identical_on_any_executor(setup):
    sc, data = setup
    spec = fitspec_from(sc, ["sigma:0.01:1:log"], ["brdf=0.1"])
    st = ChainSettings(walkers=4, seed=1, max_steps=40, check_every=40)
    kw = dict(noise_levels=(0.05, 0.2), n_geometries=(6,), injections=2)
    a = recovery_study(sc, spec, data, st, **kw)
    with ProcessExecutor(2) as ex:
        b = recovery_study(sc, spec, data, st, executor=ex, **kw)
    assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)
    # widths grow with the noise level
    w = [c["summary"]["substrate.sigma"]["width68_mean"] for c in a]
    assert w[1] > w[0]


def test_a_study_without_a_progress_bar_maps_every_member_at_once(setup):
    """Without a progress bar no cell waits for the previous one: one map, a task per member;
    with one, a map per cell (the bar moves); the same results either way."""
    sc, data = setup
    spec = fitspec_from(sc, ["sigma:0.01:1:log"], ["brdf=0.1"])
    st = ChainSettings(walkers=4, seed=1, max_steps=40, check_every=40)
    kw = dict(noise_levels=(0.05, 0.2), n_geometries=(6,), injections=2)
    once, by_cell = Spy(), Spy()
    a = recovery_study(sc, spec, data, st, executor=once, **kw)
    b = recovery_study(sc, spec, data, st, executor=by_cell, progress=True, **kw)
    assert once.tasks == [4] and by_cell.tasks == [2, 2]
    assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def test_recovery_command(tmp_path, capsys):
    out = str(tmp_path / "rec")
    args = [
        "study", "recovery", DATA, "--scene", COATED, "--free", "sigma:0.01:1:log", "--noise", "brdf=0.1",
        "--noise-levels", "0.05,0.1", "--n-geometries", "6,12", "--injections", "3", "--walkers", "4",
        "--max-steps", "40", "--check-every", "40", "--starts", "1", "--out", out,
    ]  # fmt: skip
    assert main(args) == 0
    res = json.load(open(os.path.join(out, "recovery.json")))
    assert [(c["noise_brdf"], c["geometries"]) for c in res["cells"]] == [
        (0.05, 6),
        (0.05, 12),
        (0.1, 6),
        (0.1, 12),
    ]
    assert os.path.getsize(os.path.join(out, "recovery.png")) > 0
    assert "binomial standard errors" in capsys.readouterr().out


def test_compare_prefers_the_generating_slope_family(setup):
    """SCATMECH data made with exponential slopes: the exponential scene wins on every criterion."""
    sc, data = setup
    d = subsample(data, 60)
    gauss = sc.with_values({"substrate.distribution": "gaussian"})
    liks = [Likelihood(s, fitspec_from(s, ["sigma:0.01:1:log"], ["brdf:0.01:1:log"]), d) for s in (sc, gauss)]
    rows, _ = compare_fits(
        liks,
        ["exponential", "gaussian"],
        ChainSettings(walkers=8, seed=2, max_steps=200, check_every=100, starts=2),
    )
    e, g = rows
    assert e["max_log_likelihood"] > g["max_log_likelihood"] + 10
    assert e["dBIC"] == 0 and e["dAIC"] == 0 and e["dWAIC"] == 0 and g["dWAIC"] > 10
    assert (
        np.isfinite(e["p_waic"])
        and e["predictive"]["brdf"]["inside_95"] > g["predictive"]["brdf"]["inside_95"]
    )


@pytest.fixture(scope="module")
def pairing():
    """Seed 003's pairing on 40 rows of each SCATMECH data set, all likelihood terms and the BRDF alone."""
    return seed003_pairing(
        ChainSettings(walkers=16, seed=3, max_steps=200, check_every=100, starts=3), rows=40, chains=2
    )


@pytest.mark.parametrize("terms", ["all", "brdf"])
def test_seed003_pairing_each_hypothesis_wins_on_its_own_data(pairing, terms):
    """Seed 003 Sec. 4: the facet + single + diffuse combination against Maxwell-Beard, each
    fitted to SCATMECH data made by its own generator and by the other's.  The generating
    hypothesis must win on the BIC and the WAIC by a wide margin, and the data's truth must lie
    inside its fitted 95% intervals."""
    for case in (c for c in pairing if c["terms"] == terms):
        by = {r["scene"]: r for r in case["rows"]}
        win = by[case["generator"]]
        lose = by[next(h for h in by if h != case["generator"])]
        assert win["dBIC"] == 0 and lose["dBIC"] > 50 and lose["dWAIC"] > 50, (case["data"], terms)
        fit = case["fits"][[r["scene"] for r in case["rows"]].index(case["generator"])]
        truth = fit.lik.data_all.meta["truth"]
        checked = 0
        for k, p in fit.summary["parameters"].items():
            if k in truth:
                assert p["p2.5"] <= truth[k] <= p["p97.5"], (case["data"], terms, k, p, truth[k])
                checked += 1
        assert checked == len(fit.spec.free) - 1  # every free parameter but the speckle level
