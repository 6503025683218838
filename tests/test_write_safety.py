"""Issue 31, the command line's side: nothing lost on a failed or concurrent write, no false
success, a one-parameter fit's corner plot, and the environment (NUMBA_DISABLE_JIT, a latin-1
stdout).

Output folders are built beside the old one and swapped in whole under one lock
(``validation/atomic.py``): a write that fails half way (the disk fills) leaves the old
folder byte for byte, and a second run on a folder being written is refused (exit 2).
"""

from __future__ import annotations

import errno
import importlib
import importlib.metadata
import json
import os
import subprocess
import sys
import textwrap

import pytest

from scatterbench import references
from scatterbench.validation import atomic
from scatterbench.validation.checks.table1 import Table1Row
from scatterbench.validation.cli import fit as cli_fit
from scatterbench.validation.cli import main
from scatterbench.validation.cli import table1 as cli_table1
from scatterbench.validation.report import build

COATED = references.scene_path("aluminium_flakes_clearcoat.toml")
DATA = references.data_path("scatmech_flake_measurement.csv")  # its sidecar records the truth
CLI = [sys.executable, "-m", "scatterbench.validation.cli"]


def _fit_args(out, *extra, data=DATA):
    # one free parameter (the sidecar has its truth): the corner plot is a single Axes
    return [
        "fit", str(data), "--scene", COATED, "--free", "sigma:0.01:1:log", "--noise", "brdf=0.05",
        "--walkers", "4", "--max-steps", "20", "--check-every", "10", "--starts", "1", "--no-progress",
        "--out", str(out), *extra,
    ]  # fmt: skip


def _snapshot(folder):
    """Every file of ``folder`` by name, with its bytes."""
    return {n: open(os.path.join(folder, n), "rb").read() for n in sorted(os.listdir(folder))}


def _disk_full_at(monkeypatch, name):
    """Every atomic write goes through ``_temp_beside``: the one that writes ``name`` fails
    as a full disk does (after the files written before it)."""
    real = atomic._temp_beside

    def failing(path, suffix=""):
        if os.path.basename(path) == name:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), path)
        return real(path, suffix)

    monkeypatch.setattr(atomic, "_temp_beside", failing)


@pytest.fixture(scope="module")
def complete_fit(tmp_path_factory):
    """A complete one-parameter fit with plots, written through the command line."""
    out = tmp_path_factory.mktemp("fits") / "fit"
    assert main(_fit_args(out)) == 0
    return out


# ----------------------------------------------------------------------------- class 7
def test_a_one_parameter_fit_with_a_truth_sidecar_draws_its_corner_plot(complete_fit, capsys):
    files = _snapshot(complete_fit)
    assert set(files) == {"posterior.json", "chain.npz", "corner.png", "predictive.png", "residuals.png"}
    assert files["corner.png"].startswith(b"\x89PNG") and len(files["corner.png"]) > 1000
    # nothing of the build, the old folder or the checkpoint is left beside it
    assert sorted(os.listdir(complete_fit.parent)) == [".fit.lock", "fit"]


# ----------------------------------------------------------------------------- class 1
def test_a_fit_that_fails_writing_leaves_the_previous_fit_byte_identical(complete_fit, monkeypatch, capsys):
    before = _snapshot(complete_fit)
    _disk_full_at(monkeypatch, "predictive.png")  # posterior.json and corner.png are written first
    assert main(_fit_args(complete_fit, "--force", "--seed", "7")) == 3
    assert "No space left on device" in capsys.readouterr().err
    assert _snapshot(complete_fit) == before
    # the new chain is kept beside it for --resume; no half-built folder is
    left = sorted(os.listdir(complete_fit.parent))
    assert left == [".fit.lock", ".fit.partial", "fit"], left
    assert os.listdir(complete_fit.parent / ".fit.partial") == ["chain.partial.npz"]
    # and --resume finishes that run from its chain (no new sampling: the budget is spent)
    monkeypatch.undo()
    assert main(_fit_args(complete_fit, "--resume", "--seed", "7")) == 0
    post = json.loads((complete_fit / "posterior.json").read_text())
    assert post["settings"]["seed"] == 7 and post["sampling"]["steps"] == 20
    assert sorted(os.listdir(complete_fit.parent)) == [".fit.lock", "fit"]
    assert set(os.listdir(complete_fit)) == set(before)


def test_the_swap_puts_the_old_folder_back_when_the_new_one_cannot_be_renamed_in(tmp_path, monkeypatch):
    out, new = tmp_path / "out", tmp_path / "new"
    out.mkdir()
    (out / "a").write_text("old")
    new.mkdir()
    (new / "a").write_text("new")
    real, calls = os.rename, []

    def rename(src, dst):
        calls.append((src, dst))
        if len(calls) == 2:  # new -> out: the moment the old folder is aside
            raise OSError(errno.EIO, "simulated", str(dst))
        real(src, dst)

    monkeypatch.setattr(atomic.os, "rename", rename)
    with pytest.raises(OSError, match="simulated"):
        atomic.swap_folder(str(new), str(out))
    assert (out / "a").read_text() == "old" and (new / "a").read_text() == "new"
    assert sorted(os.listdir(tmp_path)) == ["new", "out"]  # the old folder is back, nothing aside


def test_a_second_fit_into_a_folder_being_written_is_refused(tmp_path, capsys):
    out = tmp_path / "fit"
    with atomic.folder_lock(str(out)):  # a run in progress holds it (flock: per open file)
        assert main(_fit_args(out)) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {out} is being written by pid {os.getpid()} on "), err
    assert not out.exists() and not (tmp_path / ".fit.partial").exists()


_HOLD = "import sys, time\nfrom scatterbench.validation import atomic\nwith atomic.folder_lock(sys.argv[1]):\n    print('held', flush=True)\n    time.sleep(60)\n"


def test_a_fit_refused_while_another_process_holds_the_folder(tmp_path):
    out = tmp_path / "fit"
    holder = subprocess.Popen([sys.executable, "-c", _HOLD, str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        r = subprocess.run([*CLI, *_fit_args(out, "--no-plots")], capture_output=True, text=True, timeout=600)
    finally:
        holder.kill()
        holder.wait()
    assert r.returncode == 2, r.stderr
    assert f"is being written by pid {holder.pid} on" in r.stderr and "Traceback" not in r.stderr


def test_force_never_deletes_files_the_command_does_not_write(tmp_path, capsys):
    out = tmp_path / "fit"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    assert main(_fit_args(out, "--force")) == 2
    assert "holds files this command does not write (notes.txt)" in capsys.readouterr().err
    assert (out / "notes.txt").read_text() == "mine"


def _stub_report(tag):
    return lambda **kw: ({"meta": {"run": tag}, "summary": {}, "checks": []}, f"<html>{tag}</html>")


def test_a_report_that_fails_writing_keeps_results_and_page_together(tmp_path, monkeypatch):
    out = tmp_path / "r"
    monkeypatch.setattr(build, "build_report", _stub_report("old"))
    build.write_report(str(out))
    before = _snapshot(out)
    assert set(before) == {"report.html", "results.json"} and b"old" in before["report.html"]
    monkeypatch.setattr(build, "build_report", _stub_report("new"))
    _disk_full_at(monkeypatch, "report.html")  # results.json is written first
    with pytest.raises(OSError, match="No space left"):
        build.write_report(str(out))
    assert _snapshot(out) == before
    assert sorted(os.listdir(tmp_path)) == [".r.lock", "r"]  # the failed build is removed
    with atomic.folder_lock(str(out)), pytest.raises(atomic.FolderBusy, match="is being written by pid"):
        build.write_report(str(out))


def test_a_nightly_stopped_by_user_code_leaves_no_half_run(tmp_path, monkeypatch, capsys):
    nightly_mod = importlib.import_module("scatterbench.validation.report.nightly")  # the package's
    # ``nightly`` attribute is the function

    def exits(**kw):
        sys.exit(0)

    monkeypatch.setattr(nightly_mod, "build_report", exits)
    hist = tmp_path / "h"
    assert main(["nightly", "--history", str(hist), "--quick"]) == 3
    err = capsys.readouterr().err
    assert err.startswith("error: user code called sys.exit(0) in ") and "(exits)" in err
    assert sorted(os.listdir(hist)) == [".lock", "runs"] and os.listdir(hist / "runs") == []


# ----------------------------------------------------------------------------- class 2
def _module(tmp_path, monkeypatch, name, text):
    (tmp_path / f"{name}.py").write_text(textwrap.dedent(text))
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))


def test_sys_exit_in_a_module_given_to_check_is_not_success(tmp_path, monkeypatch, capsys):
    _module(tmp_path, monkeypatch, "exits_on_import", "import sys\nsys.exit(0)\n")
    assert main(["check", "exits_on_import:Model"]) == 3
    err = capsys.readouterr().err
    assert err.startswith("error: user code called sys.exit(0) in ") and "exits_on_import.py:2" in err


def test_sys_exit_in_a_models_mueller_is_not_success(tmp_path, monkeypatch, capsys):
    _module(
        tmp_path,
        monkeypatch,
        "exits_in_mueller",
        """
        import sys

        class Model:
            def mueller(self, theta_i, theta_r, phi_r):
                sys.exit(0)
        """,
    )
    assert main(["check", "exits_in_mueller:Model", "--quick"]) == 3
    err = capsys.readouterr().err
    assert "user code called sys.exit(0) in " in err and "exits_in_mueller.py" in err and "(mueller)" in err


def test_a_plug_in_that_exits_on_import_is_listed_as_broken(tmp_path, monkeypatch, capsys):
    _module(tmp_path, monkeypatch, "plugin_exits", "import sys\nsys.exit(0)\n")
    group = "scatterbench.models"
    eps = [
        importlib.metadata.EntryPoint("exits", "plugin_exits:Model", group),
        importlib.metadata.EntryPoint("gone", "no_such_module_xyz:Model", group),
    ]
    monkeypatch.setattr(
        importlib.metadata, "entry_points", lambda group=None: eps if group == "scatterbench.models" else []
    )
    assert main(["models"]) == 0
    out = capsys.readouterr().out
    assert "Contributed models (entry-point group scatterbench.models): 2" in out
    assert "not loaded: its module called sys.exit(0) while loading" in out
    assert "gone = no_such_module_xyz:Model" in out  # listed after it: not cut short


@pytest.mark.parametrize("names", [",", "", " , "])
def test_check_with_an_empty_list_of_checks_is_refused(names, capsys):
    assert main(["check", "scatterbench.models:FacetBRDF", "--checks", names]) == 2
    assert capsys.readouterr().err.startswith(f"error: --checks {names!r}: no check name given")


def _row(error):
    return Table1Row(
        "Al", 1.5, 0.1, 0.1, 0.1, error, 10, "adaptive integral", 0.1, "x", 0.0, True, True, "ok"
    )


def test_table1_says_when_its_tolerance_is_not_met(monkeypatch, capsys):
    monkeypatch.setattr(cli_table1, "compute_table1", lambda tol: ([_row(0.0), _row(1e-13)], 1.0))
    assert main(["table1", "--tol", "1e-300"]) == 1
    out = capsys.readouterr().out
    assert "tolerance NOT met: 1 of 2 entries have an error estimate above --tol 1e-300 (largest 1e-13" in out
    assert main(["table1", "--tol", "1e-12"]) == 0
    assert "NOT met" not in capsys.readouterr().out


def test_a_fit_whose_likelihood_is_minus_infinity_is_refused_before_sampling(tmp_path, capsys):
    lines = open(DATA, encoding="utf-8").read().splitlines()
    head = next(i for i, ln in enumerate(lines) if ln.startswith("theta_i_deg"))
    rows = [ln + (",1e308" if i == 0 else ",1e-9") for i, ln in enumerate(lines[head + 1 :])]
    data = tmp_path / "bad.csv"
    data.write_text("\n".join([*lines[:head], lines[head] + ",brdf_err", *rows]) + "\n")
    (tmp_path / "bad.json").write_bytes(open(DATA[:-4] + ".json", "rb").read())
    out = tmp_path / "fit"
    assert main(_fit_args(out, "--no-plots", data=data)) == 2
    err = capsys.readouterr().err
    assert err.startswith(
        f"error: {data}: ln L is not finite (-inf) at the best of the fit's starts: 1 row(s)"
    )
    assert f"(line {head + 2})" in err  # the first data row, counted from 1
    assert not out.exists() and sorted(os.listdir(tmp_path)) == [".fit.lock", "bad.csv", "bad.json"]


def test_a_chain_that_never_moved_is_not_reported_as_a_posterior():
    ok = {"sampling": {"acceptance_mean": 0.4, "tau_steps": [2.0]}}
    assert cli_fit._chain_problem(ok) is None
    short = {"sampling": {"acceptance_mean": 0.3, "tau_steps": [None]}}  # too short for tau: not converged
    assert cli_fit._chain_problem(short) is None
    stuck = {"sampling": {"acceptance_mean": 0.0, "tau_steps": [None]}}
    assert "never moved" in cli_fit._chain_problem(stuck)


# ----------------------------------------------------------------------------- class 9
def _small_scene(tmp_path):
    """The clear-coat scene without its detector aperture: few kernel evaluations."""
    text = open(COATED, encoding="utf-8").read().replace("aperture_deg = 0.7", "aperture_deg = 0.0")
    path = tmp_path / "small.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_numba_disable_jit_runs_the_kernels_and_gives_the_same_numbers(tmp_path):
    scene = _small_scene(tmp_path)
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    r = subprocess.run(
        [*CLI, "scene", str(scene), "--out", str(tmp_path / "nojit")],
        capture_output=True,
        text=True,
        env=env,
        timeout=900,
    )
    assert r.returncode == 0, r.stderr
    assert main(["scene", str(scene), "--out", str(tmp_path / "jit")]) == 0
    nojit = (tmp_path / "nojit" / "small.csv").read_text(encoding="utf-8")
    assert nojit == (tmp_path / "jit" / "small.csv").read_text(encoding="utf-8")


def test_a_latin_1_stdout_does_not_stop_a_command(tmp_path):
    env = {**os.environ, "PYTHONIOENCODING": "latin-1"}
    scene = _small_scene(tmp_path)
    r = subprocess.run(
        [*CLI, "scene", str(scene), "--out", str(tmp_path / "s")], capture_output=True, env=env, timeout=900
    )
    assert r.returncode == 0, r.stderr
    assert b"SubsurfaceFacetBRDF \\u2014 facets" in r.stdout  # the em dash, escaped
    assert len((tmp_path / "s" / "small.csv").read_bytes().decode("utf-8").splitlines()) > 100


def test_a_report_folder_given_as_a_symlink_keeps_the_link(tmp_path, monkeypatch):
    """The folder the link names is replaced (built beside it), not the link."""
    target = tmp_path / "real"
    target.mkdir()
    link = tmp_path / "link"
    link.symlink_to(target)
    monkeypatch.setattr(build, "build_report", _stub_report("new"))
    build.write_report(str(link))
    assert link.is_symlink() and os.path.realpath(link) == str(target)
    assert (target / "report.html").read_text() == "<html>new</html>"
    assert sorted(os.listdir(tmp_path)) == [".real.lock", "link", "real"]
