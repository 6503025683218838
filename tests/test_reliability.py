"""Reliability beyond refusals: reproducible posterior.json, strict JSON, scene plots and CSVs
that show what is there, the history lock, a corrupt previous night, settings that are
meaningful after all (zero noise beside an error column)."""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import os
import re
import threading

import numpy as np
import pytest

from scatterbench import references
from scatterbench.models import scene
from scatterbench.validation.atomic import LockHeld, atomic_write_json, file_lock, strict_json
from scatterbench.validation.cli import main
from scatterbench.validation.fitting.datafile import load_data, write_data
from scatterbench.validation.fitting.fitspec import FitSpecError, fitspec_from
from scatterbench.validation.fitting.likelihood import Likelihood
from scatterbench.validation.report import nightly
from scatterbench.validation.studies.scenes import P_FLOOR, _plot_scan, scan, scene_csv

COATED = references.scene_path("aluminium_flakes_clearcoat.toml")
DATA = references.data_path("scatmech_flake_measurement.csv")


# ----------------------------------------------------------------------------- posterior.json
def _timing_removed(text):
    """posterior.json without its ``timing`` object (strict_json writes it as one indented block)."""
    out, n = re.subn(r'\n  "timing": \{\n(    .*\n)*?  \},?', "", text)
    assert n == 1
    return out


def test_same_seed_same_posterior_json_but_the_timing(tmp_path, capsys):
    texts = []
    for run in ("a", "b"):
        args = [
            "fit", DATA, "--scene", COATED, "--free", "sigma:0.01:1:log", "--noise", "brdf:0.01:0.5:log",
            "--walkers", "8", "--max-steps", "30", "--check-every", "10", "--starts", "1", "--no-progress",
            "--no-plots", "--out", str(tmp_path / run),
        ]  # fmt: skip
        assert main(args) == 0
        texts.append((tmp_path / run / "posterior.json").read_text())
    capsys.readouterr()
    post = json.loads(texts[0])
    assert set(post["timing"]) == {"sampling_seconds", "evaluations_per_second", "note"}
    assert "seconds" not in post["sampling"] and "evaluations_per_second" not in post["sampling"]
    a, b = (_timing_removed(t.replace(str(tmp_path / "b"), str(tmp_path / "a"))) for t in texts)
    assert a == b
    assert "NaN" not in texts[0] and "Infinity" not in texts[0]


# ----------------------------------------------------------------------------- strict JSON
def test_strict_json_writes_null_for_non_finite_numbers(tmp_path):
    obj = {"a": math.nan, "b": [np.float64(np.inf), -math.inf, np.int64(3)], "c": (np.bool_(True), 1.5)}
    path = tmp_path / "x.json"
    atomic_write_json(str(path), obj)
    text = path.read_text()
    assert json.loads(text) == {"a": None, "b": [None, None, 3], "c": [True, 1.5]}
    assert "NaN" not in text and "Infinity" not in text
    with pytest.raises(TypeError):
        strict_json({"x": object()})


# ----------------------------------------------------------------------------- meaningful settings
def test_zero_noise_is_meaningful_beside_an_error_column(tmp_path):
    """A fixed level of 0 leaves the instrument's own errors: a proper likelihood."""
    sc = scene.load(COATED)
    d = load_data(DATA)
    cols = {
        "theta_i_deg": np.degrees(d.theta_i),
        "theta_r_deg": np.degrees(d.theta_r),
        "phi_r_deg": np.degrees(d.phi_r),
        "brdf": d.brdf,
        "brdf_err": 0.05 * d.brdf,
    }
    p = str(tmp_path / "e.csv")
    write_data(p, cols, {"incident_polarization": "linear:45"})
    with_err = load_data(p)
    assert Likelihood(sc, fitspec_from(sc, ["sigma:0.01:1:log"], ["brdf=0"]), with_err).terms == ("brdf",)
    with pytest.raises(FitSpecError, match="zero variance"):
        Likelihood(sc, fitspec_from(sc, ["sigma:0.01:1:log"], ["brdf=0"]), d)


def test_data_comments_stay_comments(tmp_path):
    p = str(tmp_path / "c.csv")
    write_data(p, {"theta_i_deg": [10.0], "theta_r_deg": [5.0], "phi_r_deg": [0.0], "brdf": [1.0]}, None,
               ["made by\n10,5,0,2,s", "ok"])  # fmt: skip
    lines = open(p).read().splitlines()
    assert lines[:2] == ["# made by 10,5,0,2,s", "# ok"] and len(lines) == 4


# ----------------------------------------------------------------------------- scene outputs
def _axes(n=4):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(n, 1)
    return fig, axes


def test_zero_brdf_is_a_gap_not_a_line_at_the_floor():
    """A narrow Gaussian lobe is exactly 0 far from specular: nothing is drawn there."""
    sc = scene.loads(
        'name = "narrow"\n[illumination]\ntheta_i_deg = 30\n[substrate]\nindex = 1.5\n'
        'distribution = "gaussian"\nsigma = 0.01\n',
        "n.toml",
    )
    _, rows = scan(sc)
    r = rows["in-plane"]
    zero = r["brdf"] == 0
    assert zero.any() and (~zero).any()
    fig, axes = _axes()
    _plot_scan(axes, "in-plane", r, 30.0)
    y = axes[0].lines[0].get_ydata()
    assert np.all(np.isnan(y[zero])) and np.all(y[~zero] == r["brdf"][~zero])
    for ax in axes[1:]:  # eta, P and P_C are undefined without light: gaps too
        assert np.all(np.isnan(ax.lines[0].get_ydata()[zero]))
    fig.clf()


def test_unpolarized_light_says_so_instead_of_flat_zero_panels():
    """An unpolarized source on a depolarizing model (Maxwell-Beard's published scalar form)."""
    text = (
        'name = "mb"\n[illumination]\ntheta_i_deg = 30\n[substrate]\nmodel = "maxwell-beard"\n'
        'index = 1.5\ndistribution = "gaussian"\nsigma = 0.1\nrho_d = 0.02\n'
    )
    _, rows = scan(scene.loads(text + "polarized = false\n", "mb.toml"))
    for label, r in rows.items():
        assert np.nanmax(np.abs(r["P"])) < P_FLOOR
        fig, axes = _axes()
        _plot_scan(axes, label, r, 30.0)
        assert len(axes[0].lines) == 1
        for ax in axes[1:]:
            assert not ax.lines and "unpolarized" in ax.texts[0].get_text()
        fig.clf()
    # s-polarized light on the polarizing form of the same model is drawn (polarized light
    # on the depolarizing form leaves unpolarized light too: that is the note again)
    polarizing = scene.loads(
        text.replace("theta_i_deg = 30", 'theta_i_deg = 30\npolarization = "s"'), "mb.toml"
    )
    _, rows = scan(polarizing)
    fig, axes = _axes()
    _plot_scan(axes, "in-plane", rows["in-plane"], 30.0)
    assert all(len(ax.lines) == 1 for ax in axes) and not axes[1].texts
    fig.clf()


def test_scene_csv_treats_names_and_paths_as_data():
    sc = scene.loads('name = "x"\n[illumination]\ntheta_i_deg = 30\n[substrate]\nindex = 1.5\n'
                     'distribution = "gaussian"\nsigma = 0.2\n', "s.toml")  # fmt: skip
    evil = dataclasses.replace(sc, name="a\nin-plane,1,2,3,4,5,6,7", path="p\r\nout-of-plane,9,9,9,9,9,9,9")
    model, rows = scan(evil, n_inplane=5, n_azimuth=3)
    text = scene_csv(evil, model, rows)
    data = [r for r in csv.reader(text.splitlines()) if r and not r[0].startswith("#")]
    assert len(data) == 1 + 5 + 3 and all(len(r) == 8 for r in data)
    assert text.startswith('# scene: "a\\nin-plane,1,2,3,4,5,6,7"\n# file: "p\\r\\nout-of-plane')


# ----------------------------------------------------------------------------- history
def test_file_lock_waits_then_refuses_naming_the_holder(tmp_path):
    path = str(tmp_path / ".lock")
    seen = []
    with file_lock(path):
        with pytest.raises(LockHeld) as exc:
            with file_lock(path, wait=0.3, on_wait=seen.append):
                pass
    assert f"pid {os.getpid()}" in exc.value.holder and seen == [exc.value.holder]
    assert exc.value.waited >= 0.3
    # released at the end of the block: the next holder gets it at once
    acquired, release = threading.Event(), threading.Event()

    def hold():
        with file_lock(path):
            acquired.set()
            release.wait(5)

    t = threading.Thread(target=hold)
    t.start()
    assert acquired.wait(5)
    try:
        with pytest.raises(LockHeld):
            with file_lock(path, wait=0.2):
                pass
    finally:
        release.set()
        t.join()
    with file_lock(path, wait=0):
        pass


def test_a_corrupt_previous_night_is_said_and_the_one_before_is_compared(tmp_path):
    hist = str(tmp_path / "h")
    kw = dict(quick=True, only=[], checks=[])
    first = nightly(hist, stamp="2026-01-01T000000Z", **kw)
    second = nightly(hist, stamp="2026-01-02T000000Z", **kw)
    assert first.code == second.code == 0 and second.notes == []
    with open(os.path.join(second.run_dir, "results.json"), "w") as fh:
        fh.write("{")  # truncated by a full disk, say
    third = nightly(hist, stamp="2026-01-03T000000Z", **kw)
    assert third.code == 1 and len(third.notes) == 1
    note = third.notes[0]
    assert "latest/results.json: not valid JSON" in note and "compared with runs/2026-01-01T000000Z" in note
    with open(os.path.join(third.run_dir, "results.json")) as fh:
        assert json.load(fh)["history_notes"] == third.notes
    assert nightly(hist, stamp="2026-01-04T000000Z", **kw).code == 0  # the next night is clean again


def test_report_says_when_its_previous_results_cannot_be_read(tmp_path, capsys, monkeypatch):
    import scatterbench.validation.report.build as build

    out = tmp_path / "r"
    out.mkdir()
    (out / "results.json").write_text("[]")
    monkeypatch.setattr(
        build, "build_report", lambda **kw: ({"meta": {}, "summary": {}, "checks": []}, "<html>")
    )
    res = build.write_report(str(out), quick=True)
    assert "not a report's results" in res["meta"]["previous_problem"]
