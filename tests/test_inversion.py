"""Slope-distribution inversion (seed 000 Fig. 4): noise-free round trip, normalization, bootstrap."""

import copy
import math
import os

import numpy as np
import pytest

from scatterbench import models, references
from scatterbench.models import scene
from scatterbench.validation.cli import main
from scatterbench.validation.fitting.datafile import Dataset, load_data
from scatterbench.validation.fitting.inversion import UnitSlopes, bootstrap, fit_curve, invert, probed_slopes
from scatterbench.validation.fitting.likelihood import scene_for_data

DATA = references.data_path("scatmech_flake_measurement.csv")
COATED = references.scene_path("aluminium_flakes_clearcoat.toml")


def _synthetic(model):
    """Noise-free BRDF for linear:45 incidence: in-plane scans at 60 and 45 deg, out-of-plane at 45."""
    rows = []
    for ti in (60.0, 45.0):
        s = np.linspace(-89.0, 89.0, 357)
        rows += [(ti, abs(x), 180.0 if x < 0 else 0.0) for x in s]
    rows += [(45.0, 45.0, p) for p in np.linspace(0.0, 180.0, 91)]
    g = np.radians(np.array(rows))
    inc = np.tile([1.0, 0.0, 1.0, 0.0], (len(g), 1))
    b = np.einsum("nij,nj->ni", model.mueller(g[:, 0], g[:, 1], g[:, 2]), inc)[:, 0]
    keep = b > 0
    return Dataset("synthetic", g[keep, 0], g[keep, 1], g[keep, 2], b[keep], inc[keep])


@pytest.mark.parametrize(
    "slopes",
    [
        models.ExponentialSlopes(0.1),
        models.GaussianSlopes(0.15, coverage=0.8),
        models.ExponentialSlopes(0.05, coverage=0.6),
    ],
    ids=repr,
)
@pytest.mark.parametrize("coating", [1.0, 1.5])
def test_noise_free_inversion_returns_p3_and_its_normalization(slopes, coating):
    if coating == 1.0:
        m = models.FacetBRDF(slopes=slopes, substrate=1.37 + 7.62j)
    else:
        m = models.SubsurfaceFacetBRDF(slopes=slopes, coating=coating, substrate=1.37 + 7.62j)
    inv = invert(m, _synthetic(m))
    true = slopes.p3(inv.zeta_x, inv.zeta_y)
    assert np.max(np.abs(inv.p3 / true - 1)) < 1e-6
    curve = fit_curve(inv)
    assert inv.zeta.min() == pytest.approx(0.0, abs=1e-12)  # the specular geometry probes zeta = 0
    # the part beyond the largest probed slope is reported separately; here it is < 1e-6
    assert curve.tail < 1e-6
    assert abs(curve.normalization - slopes.coverage) < 1e-6
    assert curve.interpolation_error < 1e-5


def test_probed_slope_is_the_facet_bisector():
    m = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.1), coating=1.5)
    ti, tr, pr = 0.9, 0.4, 2.0
    zx, zy = probed_slopes(m, ti, tr, pr)
    si, sr = math.sin(ti) / 1.5, math.sin(tr) / 1.5
    ki = np.array([si, 0, -math.sqrt(1 - si * si)])
    kr = np.array([sr * math.cos(pr), sr * math.sin(pr), math.sqrt(1 - sr * sr)])
    h = kr - ki
    assert (zx, zy) == pytest.approx((h[0] / h[2], h[1] / h[2]), abs=1e-15)
    assert UnitSlopes().p3(0.3, -2.0) == 1.0


def test_binned_curve_and_bootstrap_are_calibrated_on_noisy_data():
    """Log-normal 5% noise: the binned estimator is unbiased over realizations and the
    bootstrap's spread matches the spread across realizations."""
    data = load_data(DATA)
    m = scene_for_data(scene.load(COATED), data).build()  # point detector: the data's sidecar
    inv = invert(m, data)
    true = m.slopes.p3(inv.zeta_x, inv.zeta_y)
    rng = np.random.default_rng(0)
    norms = []
    for _ in range(60):
        v = copy.copy(inv)
        v.p3 = true * np.exp(0.05 * rng.standard_normal(len(true)))
        norms.append(fit_curve(v, bins=30).normalization)
    spread = np.std(norms, ddof=1)
    assert abs(np.mean(norms) - 1.0) < 3 * spread / math.sqrt(len(norms))
    b = bootstrap(v, bins=30, n=100, seed=1)
    lo, _, hi = b["normalization_p16_p50_p84"]
    assert 0.6 * spread < 0.5 * (hi - lo) < 1.5 * spread


def test_inversion_command(tmp_path, capsys):
    out = str(tmp_path / "inv")
    assert (
        main(
            ["study", "inversion", DATA, "--scene", COATED, "--bins", "30", "--bootstrap", "30", "--out", out]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert "normalization over the probed range" in text and "rms ln(P3 / common curve)" in text
    assert os.path.getsize(os.path.join(out, "inversion.png")) > 0
    assert main(["study", "inversion", DATA, "--scene", COATED, "--out", out]) == 2
