"""Independent chains per fit of a model comparison (issue 30, part 2): seeded from the run's
seed and the chain's index, so the rows do not depend on the executor, and compared by the
rank-normalized split R-hat (ArviZ's, through validation/fitting/diagnostics.py)."""

import json
import math

import numpy as np
import pytest

from scatterbench import references
from scatterbench.models import scene
from scatterbench.validation.fitting.compare import compare_fits
from scatterbench.validation.fitting.datafile import load_data
from scatterbench.validation.fitting.diagnostics import chain_seed, rhat
from scatterbench.validation.fitting.executors import ProcessExecutor
from scatterbench.validation.fitting.fitspec import fitspec_from
from scatterbench.validation.fitting.likelihood import Likelihood
from scatterbench.validation.fitting.recovery import subsample
from scatterbench.validation.fitting.settings import ChainSettings


def test_rhat_sees_chains_that_disagree_and_not_chains_that_agree():
    rng = np.random.default_rng(0)
    agree = rng.standard_normal((4, 2000))
    assert rhat(agree) < 1.01
    apart = agree + np.array([[0.0], [0.0], [0.0], [1.0]])  # one chain stuck elsewhere
    assert rhat(apart) > 1.1
    drift = agree + np.linspace(0, 3, 2000)  # every chain drifting: split halves disagree
    assert rhat(drift) > 1.1
    wide = agree * np.array([[1.0], [1.0], [1.0], [4.0]])  # same centre, one chain far wider: the tail
    assert rhat(wide) > 1.05
    assert math.isnan(rhat(agree[:, :3])) and math.isnan(rhat(np.full((2, 10), np.nan)))
    with pytest.raises(ValueError, match="draws must be"):
        rhat(agree[0])


def test_chain_seeds_keep_chain_0_s_seed_and_differ_from_each_other():
    assert chain_seed(7, 0) == 7
    seeds = [chain_seed(7, c) for c in range(8)]
    assert len(set(seeds)) == 8 and seeds == [chain_seed(7, c) for c in range(8)]
    assert chain_seed(8, 1) != chain_seed(7, 1)


@pytest.fixture(scope="module")
def liks():
    sc = scene.load(references.scene_path("aluminium_flakes_clearcoat.toml"))
    d = subsample(load_data(references.data_path("scatmech_flake_measurement.csv")), 20)
    gauss = sc.with_values({"substrate.distribution": "gaussian"})
    return [Likelihood(s, fitspec_from(s, ["sigma:0.01:1:log"], ["brdf=0.1"]), d) for s in (sc, gauss)]


ST = ChainSettings(walkers=4, seed=5, max_steps=60, check_every=30, starts=1)
NAMES = ["exponential", "gaussian"]


def test_several_chains_per_fit_identical_in_process_and_on_workers(liks):
    rows, fits = compare_fits(liks, NAMES, ST, chains=3)
    with ProcessExecutor(2) as ex:
        rows_p, fits_p = compare_fits(liks, NAMES, ST, chains=3, executor=ex)
    assert json.dumps(rows, sort_keys=True) == json.dumps(rows_p, sort_keys=True)
    for a, b in zip(fits, fits_p, strict=True):
        assert np.array_equal(a.chain.chain, b.chain.chain)
    for r in rows:
        assert r["chains"] == 3 and set(r["rhat"]) == {"substrate.sigma"}
        assert math.isfinite(r["rhat_max"]) and r["rhat_max"] == max(r["rhat"].values())
        assert "of 3 chains converged" in r["stop_reason"]


def test_one_chain_is_the_fit_it_always_was_and_more_chains_add_to_it(liks):
    one, fits1 = compare_fits(liks, NAMES, ST)
    three, fits3 = compare_fits(liks, NAMES, ST, chains=3)
    for a, b in zip(fits1, fits3, strict=True):  # chain 0 keeps the run's seed
        assert np.array_equal(a.chain.chain, b.chain.chain)
    assert all("rhat" not in r and "chains" not in r for r in one)
    for r1, r3 in zip(one, three, strict=True):  # the best ln L over more chains is no worse
        assert r3["max_log_likelihood"] >= r1["max_log_likelihood"]
        assert r3["WAIC"] != r1["WAIC"]  # pooled over the three chains
