"""Fits to Mueller-matrix BRDF data: the [fit.mueller] spec, the likelihood (basis, offset,
calibration, wavelengths) and the injection test on NIST's PTFE geometries."""

from __future__ import annotations

import math
from dataclasses import replace

import numba
import numpy as np
import pytest

from scatterbench.models import scene as scene_mod
from scatterbench.references import nist_ptfe_path
from scatterbench.validation.fitting.fit import run_fit
from scatterbench.validation.fitting.fitspec import FitSpecError
from scatterbench.validation.fitting.mueller_data import fold_negative_polar, load_mueller_data, to_basis
from scatterbench.validation.fitting.mueller_likelihood import MuellerLikelihood
from scatterbench.validation.fitting.mueller_spec import material_index, mueller_spec_from
from scatterbench.validation.fitting.settings import ChainSettings

SCENE = """
name = "PTFE test: facets + diffuse subsurface"
[illumination]
theta_i_deg = 45.0
wavelength_nm = 532.0
[coating]
index = 1.35
[coating.roughness]
distribution = "gaussian"
sigma = 0.25
[volume]
rho = 0.95
single = false
interface = "smooth"
[fit]
free = ["coating.roughness.sigma:0.05:0.8:log", "volume.rho:0.5:1", "coating.index:1.2:1.6"]
[fit.mueller]
calibration_width = 0.05
theta_i_offset_deg = "-2:2"
{extra}
[fit.mueller.noise]
m11 = "0.005:0.5:log"
normalized = "0.001:0.2:log"
"""


def _scene(extra=""):
    return scene_mod.loads(SCENE.replace("{extra}", extra), "<test>")


@pytest.fixture(scope="module")
def nist():
    return load_mueller_data(nist_ptfe_path())


@pytest.fixture
def one_thread():
    """One numba thread: on a shared two-core machine the kernels' threads contend (measured
    16 ms against 81 ms per batch of 24 walkers x 304 rows under load)."""
    n = numba.get_num_threads()
    numba.set_num_threads(1)
    yield
    numba.set_num_threads(n)


def _subset(data, wavelengths=(532.0,), step=6):
    return data.subset(np.flatnonzero(np.isin(data.wavelength_nm, wavelengths))[::step])


def test_spec_names_per_wavelength_nuisance_and_noise(nist):
    spec = mueller_spec_from(_scene('per_wavelength = ["coating.index"]'), nist.wavelength_nm)
    assert spec.names == [
        "coating.roughness.sigma",
        "volume.rho",
        "coating.index@351",
        "coating.index@532",
        "coating.index@633",
        "coating.index@1064",
        "calibration.m11",
        "theta_i_offset_deg",
        "noise.m11",
        "noise.normalized",
    ]
    cal = spec.free[spec.names.index("calibration.m11")]
    assert cal.sd == 0.05 and cal.prior == "log"
    # the log-normal prior: ln c = 0.05 is one width, -0.5 below the centre
    u = np.array([p.to_u(p.start if p.start is not None else 0.5 * (p.low + p.high)) for p in spec.free])
    u1 = u.copy()
    u1[spec.names.index("calibration.m11")] = 0.05
    assert spec.log_prior(u1) - spec.log_prior(u) == pytest.approx(-0.5)


@pytest.mark.parametrize(
    "extra, fragment",
    [
        ('elements = ["m11", "m55"]', "unknown 'm55'"),
        ("wavelengths_nm = [500]", "500 nm is not in the data"),
        ('per_wavelength = ["volume.g"]', "per_wavelength: unknown 'volume.g'"),
        ("calibration_width = 2", None),
        ('theta_i_offset_deg = "-20:2"', "theta_i_offset_deg"),
        ('materials = {"coating.index" = "main/NoSuch/Thing"}', "not a refractiveindex.info material"),
        ("colour = 1", "unknown key(s) ['colour']"),
    ],
)
def test_spec_refuses_bad_entries_naming_them(nist, extra, fragment):
    key = extra.split(" =")[0]
    if key in ("calibration_width", "theta_i_offset_deg"):  # replace the scene's own entry
        text = "\n".join(extra if line.startswith(key) else line for line in SCENE.splitlines())
        sc, fragment = scene_mod.loads(text.replace("{extra}", ""), "<test>"), key
    else:
        sc = _scene(extra)
    with pytest.raises(FitSpecError) as exc:
        mueller_spec_from(sc, nist.wavelength_nm)
    assert fragment in str(exc.value)
    assert "<test>" in str(exc.value)


def test_batch_equals_positions_one_at_a_time(nist, one_thread):
    d = _subset(nist, (532.0, 633.0), step=20)
    spec = mueller_spec_from(_scene('per_wavelength = ["coating.index"]'), d.wavelength_nm)
    lik = MuellerLikelihood(_scene('per_wavelength = ["coating.index"]'), spec, d)
    b = spec.u_bounds()
    U = np.random.default_rng(3).uniform(b[:, 0], b[:, 1], (5, len(b)))
    assert np.array_equal(lik.batch(U), [lik(u) for u in U])
    assert np.all(np.isfinite(lik.batch(U)))


def test_prediction_is_the_model_restated_in_the_data_basis(nist, one_thread):
    """Element by element, the likelihood's prediction equals the scene's model at the folded
    incidence |theta_i + offset| and relative azimuth, restated psps -> xyxy by to_basis."""
    d = _subset(nist, (633.0,), step=10)
    assert np.any(d.theta_i < math.radians(1.5))  # rows where the negative offset turns the incidence over
    sc = _scene()
    spec = mueller_spec_from(sc, d.wavelength_nm)
    lik = MuellerLikelihood(sc, spec, d)
    vals = {"coating.roughness.sigma": 0.3, "volume.rho": 0.9, "coating.index": 1.4}
    u = np.array(
        [
            p.to_u({**vals, "calibration.m11": 1.0, "theta_i_offset_deg": -1.5}.get(p.key, 0.01))
            for p in spec.free
        ]
    )
    P = lik.predict(u[None])
    ti, tr, phi = d.relative_geometry()
    t, phi_i = fold_negative_polar(ti - math.radians(1.5), d.phi_i)
    turned = phi_i != fold_negative_polar(ti, d.phi_i)[1]
    assert turned.any()
    phi = np.where(turned, phi + math.pi, phi)
    M = sc.with_values(vals).build().mueller(t, tr, phi)
    want = to_basis(M, d.phi_i, d.phi_r, "psps", "xyxy")
    for e in range(16):
        np.testing.assert_allclose(
            P[e][0], want[:, e // 4, e % 4], rtol=1e-12, atol=1e-14 * np.max(want[:, 0, 0])
        )
    # the data are in xyxy: out of the plane the bases differ, so the restatement matters
    assert np.max(np.abs(want[:, 1, 0] - M[:, 1, 0])) > 1e-3 * np.max(M[:, 0, 0])


def test_calibration_scales_m11_only(nist, one_thread):
    d = _subset(nist, (532.0,), step=30)
    sc = _scene('elements = ["m12", "m33"]')
    spec = mueller_spec_from(sc, d.wavelength_nm)
    lik = MuellerLikelihood(sc, spec, d)
    u = np.array([p.to_u(p.start if p.start is not None else 0.5 * (p.low + p.high)) for p in spec.free])
    i = spec.names.index("calibration.m11")
    u2 = u.copy()
    u2[i] = 0.1
    # without m11 among the elements the scale cannot change the likelihood, only its prior
    assert lik.loglike(u) == lik.loglike(u2)
    sc = _scene()
    lik = MuellerLikelihood(sc, mueller_spec_from(sc, d.wavelength_nm), d)
    assert lik.loglike(u) != lik.loglike(u2)


def test_dispersion_and_material_indices_per_row(nist):
    d = _subset(nist, (351.0, 1064.0), step=40)
    text = SCENE.replace(', "coating.index:1.2:1.6"', "")
    sc = scene_mod.loads(
        text.replace(
            "{extra}", 'dispersion = {"coating.index" = {law = "cauchy", A = "1.3:1.4", B = "0:0.01"}}'
        ),
        "<t>",
    )
    spec = mueller_spec_from(sc, d.wavelength_nm)
    assert "coating.index.cauchy_A" in spec.names and "coating.index.cauchy_B" in spec.names
    lik = MuellerLikelihood(sc, spec, d)
    U = np.array(
        [
            [
                p.to_u(
                    {"coating.index.cauchy_A": 1.35, "coating.index.cauchy_B": 0.005}.get(
                        p.key, p.low * 1.01 if p.low > 0 else 0.1
                    )
                )
                for p in spec.free
            ]
        ]
    )
    n = lik.scene_values(U, lik.rows)["coating.index"][0]
    lam = d.wavelength_nm / 1000
    np.testing.assert_allclose(n, 1.35 + 0.005 / lam**2, rtol=1e-14)
    silica = material_index("main/SiO2/Malitson", [532.0, 1064.0])
    assert silica[532.0].real == pytest.approx(1.4607, abs=1e-4) and silica[532.0].imag == 0
    assert material_index("main/Au/Johnson", [532.0])[532.0].imag > 2  # k >= 0: absorbing


def _synthetic(lik, spec, truth, seed):
    """Mueller data made by the likelihood's own model at ``truth``, with its noise model."""
    d = lik.data
    u = np.array([p.to_u(truth[p.key]) for p in spec.free])
    P = lik.predict(u[None])
    rng = np.random.default_rng(seed)
    m11 = truth["calibration.m11"] * P[0][0] * np.exp(truth["noise.m11"] * rng.standard_normal(len(d)))
    N = np.stack([P[e][0] / P[0][0] for e in range(16)], -1).reshape(-1, 4, 4)
    N = N + truth["noise.normalized"] * rng.standard_normal(N.shape)
    N[:, 0, 0] = 1.0
    return replace(d, mueller=m11[:, None, None] * N, meta={"truth": truth})


def test_injection_recovers_the_truth_at_nist_geometries(nist, one_thread):
    """Synthetic data by the facets + diffuse-subsurface model at 304 of NIST's 532 nm
    geometries (every 12th: 152 rows), all 16 elements, calibration 1.03, incidence offset 0.7 deg,
    noise 3% on M11 and 0.01 on the normalized elements (seed 0): every true value lies inside
    its 95% posterior interval."""
    truth = {
        "coating.roughness.sigma": 0.25,
        "volume.rho": 0.95,
        "coating.index": 1.38,
        "calibration.m11": 1.03,
        "theta_i_offset_deg": 0.7,
        "noise.m11": 0.03,
        "noise.normalized": 0.01,
    }
    sc = _scene()
    d = _subset(nist, (532.0,), step=12)
    spec = mueller_spec_from(sc, d.wavelength_nm)
    syn = _synthetic(MuellerLikelihood(sc, spec, d), spec, truth, seed=0)
    lik = MuellerLikelihood(sc, spec, syn)
    fit = run_fit(
        lik, ChainSettings(walkers=24, max_steps=600, check_every=100, tau_factor=50, starts=1, seed=1)
    )
    outside = {}
    for key, p in fit.summary["parameters"].items():
        print(
            f"{key:24s} true {truth[key]:<6g} 95% [{p['p2.5']:.5g}, {p['p97.5']:.5g}] median {p['p50']:.5g}"
        )
        if not p["p2.5"] <= truth[key] <= p["p97.5"]:
            outside[key] = (truth[key], p["p2.5"], p["p97.5"])
    assert not outside, outside
    # and the posterior is informative: M11 noise to 20%, sigma to 5%
    par = fit.summary["parameters"]
    assert par["noise.m11"]["p97.5"] - par["noise.m11"]["p2.5"] < 0.2 * truth["noise.m11"] * 2
    assert par["coating.roughness.sigma"]["std"] < 0.05 * truth["coating.roughness.sigma"]


# ------------------------------------------------------------------ the CLI: fit and predict
def _write_mueller_file(path, data, rows):
    """Rows of ``data`` as a scatterbench-mueller/1 file (normalized elements, its basis)."""
    from scatterbench.validation.fitting.mueller_data import ELEMENTS as EL

    N = data.normalized()
    head = "theta_i_deg,phi_i_deg,theta_r_deg,phi_r_deg,wavelength_nm,m11," + ",".join(
        f"{e}/m11" for e in EL[1:]
    )
    lines = ["# format: scatterbench-mueller/1", f"# basis: {data.basis}", head]
    for r in rows:
        geo = np.degrees([data.theta_i[r], data.phi_i[r], data.theta_r[r], data.phi_r[r]])
        vals = [*geo, data.wavelength_nm[r], data.mueller[r, 0, 0], *N[r].reshape(16)[1:]]
        lines.append(",".join(repr(float(v)) for v in vals))
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def lambertian_fit(tmp_path_factory):
    """``scatterbench fit`` of the Lambertian PTFE scene on NIST's file as published (a short chain)."""
    from scatterbench.validation.cli import main

    out = tmp_path_factory.mktemp("fit") / "lambertian"
    n = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        rc = main(
            [
                "fit",
                nist_ptfe_path(),
                "--scene",
                "references/scenes/ptfe_lambertian_joint.toml",
                "--out",
                str(out),
                "--walkers",
                "16",
                "--max-steps",
                "20",
                "--check-every",
                "10",
                "--starts",
                "1",
                "--no-progress",
            ]
        )
    finally:
        numba.set_num_threads(n)
    assert rc == 0
    return out


def test_fit_cli_takes_the_nist_file_as_published(lambertian_fit):
    import json

    post = json.loads((lambertian_fit / "posterior.json").read_text())
    assert post["kind"] == "mueller" and post["data"]["rows"] == 7296 and post["data"]["basis"] == "xyxy"
    assert post["data"]["wavelengths_nm"] == [351.0, 532.0, 633.0, 1064.0]
    assert set(post["parameters"]) >= {"volume.rho@351", "volume.rho@1064", "calibration.m11", "noise.m11"}
    assert (lambertian_fit / "posterior_samples.npz").exists() and (lambertian_fit / "chain.npz").exists()
    # PTFE is a near-perfect diffuser: a Lambertian albedo near 1 at 633 nm
    assert 0.8 < post["parameters"]["volume.rho@633"]["median"] <= 1.0


def test_predict_writes_one_row_per_input_row_in_order(lambertian_fit, nist, tmp_path, capsys):
    from scatterbench.validation.cli import main

    rows = [4000, 5, 2500, 7000, 5]  # out of order, one repeated: the output follows the input
    data = _write_mueller_file(tmp_path / "held_out.csv", nist, rows)
    out = tmp_path / "pred.csv"
    assert (
        main(["predict", str(data), "--posterior", str(lambertian_fit), "--out", str(out), "--draws", "50"])
        == 0
    )
    text = out.read_text().splitlines()
    assert any("measurement noise" in line for line in text if line.startswith("#"))
    body = [line for line in text if not line.startswith("#")]
    head, table = body[0].split(","), np.array([[float(x) for x in line.split(",")] for line in body[1:]])
    assert len(table) == len(rows)
    assert head[:7] == [
        "line",
        "theta_i_deg",
        "phi_i_deg",
        "theta_r_deg",
        "phi_r_deg",
        "wavelength_nm",
        "m11_median",
    ]
    assert len(head) == 6 + 16 * 5
    np.testing.assert_allclose(table[:, 5], nist.wavelength_nm[rows])
    np.testing.assert_array_equal(table[:, 0], [4, 5, 6, 7, 8])  # each input line, in order
    np.testing.assert_array_equal(table[1, 1:6], table[4, 1:6])  # the repeated row's geometry
    for k in range(16):
        q = table[:, 6 + 5 * k : 11 + 5 * k]  # median, 2.5, 16, 84, 97.5
        assert np.all(q[:, 1] <= q[:, 2]) and np.all(q[:, 2] <= q[:, 0]) and np.all(q[:, 0] <= q[:, 3])
        assert np.all(q[:, 3] <= q[:, 4])
    # the NIST file as published: every row, in order
    out2 = tmp_path / "all.csv"
    assert (
        main(
            [
                "predict",
                nist_ptfe_path(),
                "--posterior",
                str(lambertian_fit),
                "--out",
                str(out2),
                "--draws",
                "20",
            ]
        )
        == 0
    )
    assert sum(1 for line in out2.read_text().splitlines() if not line.startswith("#")) == 7296 + 1


def test_predict_refuses_bad_input_with_the_path(lambertian_fit, tmp_path, capsys):
    from scatterbench.validation.cli import main

    out = tmp_path / "p.csv"
    assert main(["predict", nist_ptfe_path(), "--posterior", str(tmp_path / "none"), "--out", str(out)]) == 2
    assert "error: --posterior" in capsys.readouterr().err
    bad = tmp_path / "bad.csv"
    bad.write_text("# basis: xyxy\ntheta_i_deg,phi_i_deg\n1,2\n")
    assert main(["predict", str(bad), "--posterior", str(lambertian_fit), "--out", str(out)]) == 2
    assert f"error: {bad}:2" in capsys.readouterr().err
    not_fit = tmp_path / "notfit"
    not_fit.mkdir()
    (not_fit / "posterior.json").write_text('{"kind": "brdf"}')
    assert main(["predict", nist_ptfe_path(), "--posterior", str(not_fit), "--out", str(out)]) == 2
    assert "posterior.json: kind" in capsys.readouterr().err
    assert not out.exists()  # nothing written on an error


@pytest.mark.parametrize("path", sorted(__import__("glob").glob("references/scenes/ptfe_*.toml")))
def test_ptfe_scenes_fit_the_published_file(path, nist, one_thread):
    """Every shipped PTFE scene gives a Mueller fit spec on NIST's file and, at its start, a
    finite log posterior (the Monte Carlo rough-interface scenes are only specified here:
    one evaluation rebuilds the scene per walker and wavelength)."""
    from scatterbench.validation.fitting.mueller_fit import mueller_likelihood
    from scatterbench.validation.fitting.sampling import _default_start

    d = nist.subset(np.arange(0, len(nist), 40))
    lik = mueller_likelihood(scene_mod.load(path), d)
    assert lik.spec.wavelengths == (351.0, 532.0, 633.0, 1064.0)
    assert "calibration.m11" in lik.spec.names and "theta_i_offset_deg" in lik.spec.names
    if "rough" not in path:
        assert np.isfinite(lik(_default_start(lik, lik.spec.u_bounds())))


def test_fused_kernel_equals_the_numpy_reference(nist, one_thread):
    """The per-row log-likelihood of the fused kernel and of the numpy residuals agree to 1e-11
    relative, on random positions, with per-wavelength, dispersion and offset parameters and
    with error columns (the kernel's second branch)."""
    d = nist.subset(np.arange(0, len(nist), 29))
    sc = scene_mod.load("references/scenes/ptfe_smooth_diffuse_joint.toml")
    from scatterbench.validation.fitting.mueller_fit import mueller_likelihood

    for data in (d, replace(d, err=np.full(d.mueller.shape, 0.004), err_normalized=True)):
        lik = mueller_likelihood(sc, data)
        b = lik.spec.u_bounds()
        U = np.random.default_rng(5).uniform(b[:, 0], b[:, 1], (7, len(b)))
        a, r = lik.pointwise_batch(U), lik.pointwise_reference(U)
        assert np.all(np.isfinite(a))
        np.testing.assert_allclose(a, r, rtol=1e-11)


def test_compile_ahead_warms_the_fused_likelihood_for_the_types_a_fit_passes(nist, one_thread):
    """The report's compile-ahead task ``"likelihood"`` compiles the fused kernel for exactly the
    argument types a fit's batch passes: the batch, with and without error columns, adds no
    specialization (a type apart compiled it again on the report's main process, ~2.4 s cold)."""
    from scatterbench.validation.fitting import mueller_kernel
    from scatterbench.validation.fitting.mueller_fit import mueller_likelihood
    from scatterbench.validation.report.build import COMPILE_GROUPS, warm_task

    assert ("likelihood", None, None, False) in [task for group in COMPILE_GROUPS for task in group]
    assert warm_task(("likelihood", None, None, False)) == "likelihood"
    assert not mueller_kernel.cold()
    before = len(mueller_kernel._rows.signatures)
    d = nist.subset(np.arange(0, len(nist), 97))
    sc = scene_mod.load("references/scenes/ptfe_lambertian_per_wavelength.toml")
    for data in (d, replace(d, err=np.full(d.mueller.shape, 0.004), err_normalized=True)):
        lik = mueller_likelihood(sc, data)
        u0 = lik.spec.u_bounds().mean(axis=1)
        assert np.all(np.isfinite(lik.batch(np.array([u0, u0]))))
    assert len(mueller_kernel._rows.signatures) == before, mueller_kernel._rows.signatures


def test_a_scene_with_films_fits_its_own_wavelength_only(nist):
    """Films are built at the scene's wavelength: fitting such a scene to other wavelengths
    would use the wrong film phases, so it is refused, naming the table and the remedy."""
    text = SCENE.replace("{extra}", "").replace(
        "[volume]", "[coating.film]\nlayers = [{index = 1.25, thickness_nm = 100.0}]\n\n[volume]"
    )
    sc = scene_mod.loads(text, "<films>")
    d = _subset(nist, (532.0, 633.0), step=50)
    with pytest.raises(FitSpecError, match=r"\[coating.film\].*wavelengths_nm = \[532.0\]"):
        MuellerLikelihood(sc, mueller_spec_from(sc, d.wavelength_nm), d)
    only = scene_mod.loads(text.replace("[fit.mueller]", "[fit.mueller]\nwavelengths_nm = [532]"), "<films>")
    lik = MuellerLikelihood(only, mueller_spec_from(only, d.wavelength_nm), d)
    assert set(lik.data.wavelength_nm) == {532.0}


def test_a_refused_walker_is_minus_inf_alone(nist, one_thread):
    """A position the scene refuses (an albedo above 1 at one wavelength) gives -inf for its
    walker only; the others keep their own values, and the refusal names the parameter."""
    from scatterbench.validation.fitting.mueller_fit import mueller_likelihood

    d = nist.subset(np.arange(0, len(nist), 37))
    lik = mueller_likelihood(scene_mod.load("references/scenes/ptfe_smooth_diffuse_joint.toml"), d)
    b = lik.spec.u_bounds()
    U = np.random.default_rng(2).uniform(b[:, 0], b[:, 1], (3, len(b)))
    k = lik.spec.names.index("volume.rho@532")
    U[1, k] = b[k, 1] + 10 * (b[k, 1] - b[k, 0])
    assert lik.spec.free[k].from_u(U[1:2, k])[0] > 1
    got = lik.pointwise_batch(U)
    assert np.all(got[1] == -np.inf) and np.all(np.isfinite(got[[0, 2]]))
    for w in (0, 2):
        assert np.array_equal(got[w], lik.pointwise_batch(U[w : w + 1])[0])
    with pytest.raises(ValueError, match="rho"):
        lik.predict(U[1:2])


def _gathered_indexed(self, index, ti, tr, pr, out, add=False):
    """``Model.flat_mueller16_indexed`` as it was before the kernels read parameter columns
    through an index: the kernel rows gathered per chunk of geometries, a sum's later term
    computed whole and then added."""
    from scatterbench.models import evaluation, modelset
    from scatterbench.models.kernels import Compiled

    if add:
        out += _gathered_indexed(self, index, ti, tr, pr, np.empty(out.shape))
        return out
    if not evaluation.kernel_path(self):
        leaves = self._sets
        out[...] = evaluation.flat(
            modelset.with_leaves(self, {p: a.reshape(-1)[index] for p, a in leaves.items()}), ti, tr, pr
        )
        return out
    code, rows, options = self._kernel_spec()
    g = math.prod(self.param_shape)
    for start in range(0, out.shape[1], evaluation.KERNEL_CHUNK):
        sl = slice(start, min(start + evaluation.KERNEL_CHUNK, out.shape[1]))
        part = [np.asarray(r).reshape(-1)[index[sl]] if np.size(r) == g and np.ndim(r) else r for r in rows]
        angles = [a if a.shape[0] == 1 else a[sl] for a in (ti, tr, pr)]
        Compiled(self, code, part, options).write(out, sl, *angles, "float64")
    return out


@pytest.mark.parametrize("name", ["ptfe_smooth_diffuse_joint", "ptfe_smooth_diffuse_per_wavelength"])
def test_batch_at_new_positions_gives_the_bits_of_the_gathered_route(name, nist, monkeypatch):
    """A/B of the batch's speed-ups (issue 29 part 6): 24 walkers at new positions over all of
    NIST's rows (several kernel chunks) give the same log posteriors, bit for bit, as the route
    before them: the model's elements for all walkers and rows first, kernel rows gathered per
    chunk, a sum's terms added whole, and R-bar by ``quad`` with the Python integrand (every
    position new, so every R-bar computed again)."""
    from scatterbench.models import base, smooth_interface
    from scatterbench.validation.fitting.mueller_fit import mueller_likelihood
    from scatterbench.validation.fitting.sampling import _default_start

    lik = mueller_likelihood(scene_mod.load(f"references/scenes/{name}.toml"), nist)
    u0 = _default_start(lik, lik.spec.u_bounds())
    U = u0 + 1e-3 * np.random.default_rng(4).standard_normal((24, len(u0)))
    smooth_interface._rbar.cache_clear()
    assert lik._unit_terms(U) is not None  # the fast route: range by range through the cache
    fast = lik.batch(U)
    with monkeypatch.context() as mp:
        mp.setattr(MuellerLikelihood, "_unit_terms", lambda self, U: None)  # the whole (16, W, N) first
        mp.setattr(base.Model, "flat_mueller16_indexed", _gathered_indexed)
        mp.setattr(smooth_interface, "_compiled_integrand", lambda: None)
        smooth_interface._rbar.cache_clear()
        slow = lik.batch(U)
    smooth_interface._rbar.cache_clear()
    assert np.all(np.isfinite(fast)) and np.array_equal(fast, slow)
