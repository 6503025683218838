"""The kit verifies a model's claims instead of trusting them, and hands models read-only
copies of its geometry inputs (issue 31, class 3)."""

import math

import kit_models as km
import numpy as np

from scatterbench import models
from scatterbench.validation.testing import check_model


class ClaimsMirrorCreatesEnergy(km.Lambertian):
    """Claims mirror symmetry, but all its light goes to negative azimuths, at twice a
    rho = 1.2 Lambertian's level: albedo 1.2, and zero on the half an integrator that trusted
    the claim would integrate."""

    mirror_symmetric = True

    def brdf(self, theta_i, theta_r, phi_r):
        f = super().brdf(theta_i, theta_r, phi_r)
        return np.where(np.asarray(phi_r, dtype=float) < 0.0, 2.4 / math.pi, 0.0) + 0.0 * f


class ClaimsNoiseCreatesEnergy(km.CreatesEnergy):
    """Claims to be a Monte Carlo model (a seed and ``stochastic = True``) but its numbers do
    not depend on the seed: were the claim trusted, the energy check would be skipped."""

    stochastic = True
    seed = 3


class WritesIntoInputs(km.Lambertian):
    """Zeroes the incidence angles it is given (a user's in-place 'normalization')."""

    def mueller(self, theta_i, theta_r, phi_r):
        if isinstance(theta_i, np.ndarray) and theta_i.ndim:
            theta_i[...] = 0.0
        return super().mueller(theta_i, theta_r, phi_r)


def test_a_false_mirror_claim_that_creates_energy_fails_quick():
    report = check_model(ClaimsMirrorCreatesEnergy(), quick=True)
    status = {r.name: r for r in report.results}
    assert not report.passed
    assert status["mirror symmetry"].status == "fail"
    energy = status["energy"]
    assert energy.status == "fail" and energy.measured > 1.1, energy.message


def test_a_true_mirror_claim_passes_and_halves_the_integral():
    lam = km.Lambertian()
    lam.mirror_symmetric = True
    report = check_model(lam, checks=["mirror_symmetry", "energy"], quick=True)
    assert [r.status for r in report.results] == ["pass", "pass"]


def test_a_declared_bound_above_one_is_a_finding_not_a_pass():
    hot = km.CreatesEnergy()
    hot.energy_bound = 1.25
    r = check_model(hot, checks=["energy"], quick=True).results[0]
    assert r.status == "finding" and "1.25" in r.fails_if
    hot.energy_bound = 1.1
    assert check_model(hot, checks=["energy"], quick=True).results[0].status == "fail"


def test_a_model_writing_into_its_inputs_fails_clearly_and_corrupts_nothing():
    bad = check_model(WritesIntoInputs(), checks=["finite", "broadcasting"], quick=True)
    assert not bad.passed
    assert any("writes into its input arrays" in r.detail for r in bad.failures), bad.format()
    # the kit's grids are intact for the next model in the same process
    good = check_model(models.FacetBRDF(), checks=["finite", "broadcasting", "reciprocity"], quick=True)
    assert good.passed, good.format()


def test_a_false_stochastic_claim_fails_and_the_exact_checks_run():
    report = check_model(ClaimsNoiseCreatesEnergy(), checks=["stochastic_claim", "energy"], quick=True)
    claim, energy = report.results
    assert claim.status == "fail" and claim.measured == 0.0 and "deterministic" in claim.detail
    assert energy.status == "fail", energy.detail  # run, not skipped: it creates energy


def test_a_true_stochastic_claim_passes_and_skips_the_exact_checks():
    m = models.RoughDiffuseBRDF(pairs=64)
    report = check_model(m, checks=["stochastic_claim", "reciprocity"], quick=True)
    claim, recip = report.results
    assert claim.status == "pass" and claim.measured > 0.0, claim.detail
    assert recip.status == "skip" and "stochastic" in recip.detail
