"""The polarized BRDF likelihood's fused kernel (validation/fitting/polarized_kernel.py) against
its numpy reference (Likelihood.predict, residuals and _pointwise_rows): the same rows of
-inf, and each finite row within 1e-12 of the scale of its own terms."""

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest

from scatterbench import references
from scatterbench.models import scene
from scatterbench.validation.fitting import polarized_kernel
from scatterbench.validation.fitting.compare import SEED003_PAIRING
from scatterbench.validation.fitting.datafile import load_data
from scatterbench.validation.fitting.fitspec import fitspec_from
from scatterbench.validation.fitting.likelihood import Likelihood, term_variances
from scatterbench.validation.fitting.recovery import subsample

#: the fused rows' error, relative to the sum of the magnitudes of each row's terms
#: (r^2 / v, ln v, ln 2 pi): the reference computes the same expression with numpy's logarithm
#: and arctangent and another wrap of the angle, each within an ulp or two, and a row's
#: log-density can cancel to near 0, so its own value is no scale
RTOL = 1e-12

_POLARIZATION_OFF = ["eta_deg=off", "P=off", "P_C=off"]


def _likelihoods(rows=60):
    """Seed 003's pairing: both scenes on both data sets, every term and the BRDF alone."""
    for fname in SEED003_PAIRING["data"].values():
        data = subsample(load_data(references.data_path(fname)), rows)
        for sfile in SEED003_PAIRING["scenes"].values():
            sc = scene.load(references.scene_path(sfile))
            for noise in (None, _POLARIZATION_OFF):
                yield (
                    f"{sfile} on {fname}, {'BRDF alone' if noise else 'every term'}",
                    Likelihood(sc, fitspec_from(sc, None, noise), data),
                )


def _scale(lik, noise, model):
    """Per row, the sum of its terms' magnitudes in the reference."""
    res = lik.residuals(lik.predict(model, terms=lik.terms))
    var = term_variances(noise, lik.data, lik.terms)
    with np.errstate(all="ignore"):
        return sum(
            np.abs(res[t] ** 2 / var[t]) + np.abs(np.log(var[t])) + math.log(2 * math.pi) for t in lik.terms
        )


def _check(lik, noise, model):
    fused = lik._fused_rows(noise, model)
    ref = lik._pointwise_rows(noise, lik.predict(model, terms=lik.terms))
    assert fused.shape == ref.shape
    assert np.array_equal(np.isfinite(fused), np.isfinite(ref))
    assert np.all(fused[~np.isfinite(ref)] == -math.inf)
    fin = np.isfinite(ref)
    err = np.abs(fused[fin] - ref[fin]) / _scale(lik, noise, model)[fin]
    assert err.size == 0 or err.max() <= RTOL, err.max()
    return fused, ref


@pytest.mark.parametrize("walkers", [1, 12])
def test_fused_rows_hold_to_the_numpy_reference(walkers):
    rng = np.random.default_rng(17)
    for name, lik in _likelihoods():
        b = lik.spec.u_bounds()
        v = lik.spec.values(rng.uniform(b[:, 0], b[:, 1], (walkers, len(b))))
        fused, ref = _check(lik, v.noise, lik.model(v.scene))
        assert np.all(np.isfinite(ref)), name  # the committed data: every row lit


def _crafted(lik, walkers, rng):
    """``lik`` evaluating crafted Mueller elements at its rows: ``(noise, model, M)``, the
    elements ``M`` ``(16, walkers * rows)`` returned by its rows' evaluation."""
    b = lik.spec.u_bounds()
    v = lik.spec.values(rng.uniform(b[:, 0], b[:, 1], (walkers, len(b))))
    model = lik.model(v.scene)
    shape, M = lik._rows.mueller16(model)
    M = M.reshape(16, -1).copy()
    lik._rows = SimpleNamespace(mueller16=lambda m: (shape, M))
    return v.noise, model, M


def test_dark_and_unpolarized_rows_as_the_reference():
    """A row of no light, or negative light, is -inf in both; a row with no linear
    polarization (Q = U = 0: eta is atan2(0, 0) / 2 = 0 in both) is finite in both."""
    sc = scene.load(references.scene_path(SEED003_PAIRING["scenes"]["maxwell-beard"]))
    data = subsample(load_data(references.data_path(SEED003_PAIRING["data"]["combination"])), 40)
    lik = Likelihood(sc, fitspec_from(sc), data)
    assert lik.terms == ("brdf", "eta", "P", "P_C")
    noise, model, M = _crafted(lik, 3, np.random.default_rng(2))
    M[:, 0] = 0.0  # walker 0, row 0: no light
    M[0, 1] = -abs(M[0, 1]) - 1.0  # row 1: M00 negative (with any incident light, I < 0 here)
    M[1:4, 1] = 0.0
    M[4:12, 2] = 0.0  # row 2: no linear polarization
    fused, ref = _check(lik, noise, model)
    assert fused[0, 0] == -math.inf and fused[0, 1] == -math.inf and math.isfinite(fused[0, 2])


def test_one_incident_vector_skips_its_zero_elements_as_the_reference():
    """Data whose rows share one incident Stokes vector: its zero elements are skipped, so an
    infinite element they would multiply gives a finite row in both, not NaN."""
    sc = scene.load(references.scene_path(SEED003_PAIRING["scenes"]["maxwell-beard"]))
    data = subsample(load_data(references.data_path(SEED003_PAIRING["data"]["combination"])), 40)
    one = np.tile([1.0, 1.0, 0.0, 0.0], (len(data), 1))
    lik = Likelihood(sc, fitspec_from(sc), dataclasses.replace(data, incident=one))
    assert lik._same_incident
    noise, model, M = _crafted(lik, 4, np.random.default_rng(3))
    M[[2, 6, 10, 14], :] = np.inf  # the third column: the vector's zero U
    fused, ref = _check(lik, noise, model)
    assert np.all(np.isfinite(fused))


def test_compile_ahead_warms_the_kernel_for_the_types_a_fit_passes():
    """The report's compile-ahead task ``"likelihood"`` compiles the fused kernel for exactly the
    argument types a fit's batch passes: a batch of each term set adds no specialization (one
    apart would compile on the report's main process)."""
    from scatterbench.validation.report.build import warm_task

    warm_task(("likelihood", None, None, False))
    assert not polarized_kernel.cold()
    before = len(polarized_kernel._rows.signatures)
    for _, lik in _likelihoods(rows=20):
        u0 = lik.spec.u_bounds().mean(axis=1)
        assert np.all(np.isfinite(lik.batch(np.array([u0, u0]))))
    assert len(polarized_kernel._rows.signatures) == before, polarized_kernel._rows.signatures
