"""Exit codes, tracebacks and Ctrl-C as a user (or cron) sees them: real subprocesses.

0 ok, 1 a failed check or regression, 2 usage/input error, 3 internal error, 130
interrupted; no traceback on stderr unless ``SCATTERBENCH_TRACEBACK=1``.  Also two
nightly runs started together into one history folder.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from scatterbench import references

COATED = references.scene_path("aluminium_flakes_clearcoat.toml")
DATA = references.data_path("scatmech_flake_measurement.csv")
CLI = [sys.executable, "-m", "scatterbench.validation.cli"]


def _run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=600, **kw)


def test_input_error_exits_2_with_one_error_line(tmp_path):
    r = _run([*CLI, "scene", str(tmp_path / "missing.toml"), "--out", str(tmp_path / "o")])
    assert r.returncode == 2
    assert (
        r.stderr
        == f"error: {tmp_path / 'missing.toml'}: cannot read the scene file (No such file or directory)\n"
    )


def test_usage_error_exits_2():
    r = _run([*CLI, "fit"])
    assert r.returncode == 2 and "error: the following arguments are required" in r.stderr
    assert "Traceback" not in r.stderr


_BUG = (
    "import sys, scatterbench.validation.cli.models as m\n"
    "m._cmd_models = lambda args: 1 / 0\n"
    "from scatterbench.validation.cli import main\n"
    "sys.exit(main(['models']))\n"
)


def test_a_bug_exits_3_without_a_traceback_unless_asked():
    r = _run([sys.executable, "-c", _BUG])
    assert r.returncode == 3
    assert r.stderr.startswith("error: internal: ZeroDivisionError: division by zero\n")
    assert "Traceback" not in r.stderr and "SCATTERBENCH_TRACEBACK=1" in r.stderr
    r = _run([sys.executable, "-c", _BUG], env={**os.environ, "SCATTERBENCH_TRACEBACK": "1"})
    assert r.returncode == 1 and "Traceback" in r.stderr and "ZeroDivisionError" in r.stderr


def _fit_args(out, *extra):
    return [
        *CLI, "fit", DATA, "--scene", COATED, "--free", "sigma:0.01:1:log", "--noise", "brdf:0.01:0.5:log",
        "--walkers", "8", "--check-every", "5", "--starts", "1", "--no-progress", "--no-plots",
        "--out", str(out), *extra,
    ]  # fmt: skip


def _sigint_default():
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.parametrize("workers", ["1", "2"])
def test_ctrl_c_during_a_fit_says_how_to_resume_in_one_line(tmp_path, workers):
    """SIGINT to the whole process group, as a terminal's Ctrl-C sends it (workers included).
    ``--tau-factor 1e6``: the chain cannot converge before the interrupt (with 50 it converged
    about a second after its first checkpoint on a warm cache, and the test raced it: exit 0)."""
    out = tmp_path / "fit"
    p = subprocess.Popen(
        _fit_args(out, "--max-steps", "1000000", "--tau-factor", "1e6", "--workers", workers),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        # as a terminal's foreground job: a suite run in the background (``pytest &``, nohup)
        # ignores SIGINT, its children inherit that (POSIX), and the fit never saw the Ctrl-C
        preexec_fn=_sigint_default,
    )
    try:
        deadline = time.monotonic() + 300
        # the running checkpoint lives in the build beside the folder (swapped in when done)
        while not (tmp_path / ".fit.partial" / "chain.partial.npz").exists():
            assert p.poll() is None and time.monotonic() < deadline, p.communicate()
            time.sleep(0.2)
        time.sleep(0.5)
        os.killpg(p.pid, signal.SIGINT)
        _, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
    assert p.returncode == 130, err
    # a cold cache's compile notices ("  compiling the ... kernel loop") are progress, not the message
    lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith("  compiling the ")]
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith("interrupted: the chain (") and ".fit.partial/chain.partial.npz" in lines[0]
    assert not out.exists()  # nothing half-written where the results go
    assert "--resume" in lines[0]
    # and the line's advice works: the same command with --resume continues the chain
    r = _run(_fit_args(out, "--max-steps", "60", "--tau-factor", "1e6", "--workers", workers, "--resume"))
    assert r.returncode == 0, r.stderr
    post = json.loads((out / "posterior.json").read_text())
    assert post["sampling"]["steps"] >= 60


_NIGHTLY = (
    "import sys, time\n"
    "from scatterbench.validation.report import nightly\n"
    "run = nightly(sys.argv[1], quick=True, only=[], checks=[], _after_build=lambda tmp: time.sleep(2))\n"
    "print(run.run_dir)\n"
    "sys.exit(run.code)\n"
)


def test_two_nightlies_into_one_history_take_turns(tmp_path):
    """Started together: both exit cleanly, each run is complete, ``latest`` points to a
    complete run, nothing half-built is left (the runs take turns on the history's lock)."""
    hist = str(tmp_path / "hist")
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", _NIGHTLY, hist], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        for _ in range(2)
    ]
    outs = [p.communicate(timeout=600) for p in procs]
    for p, (_, err) in zip(procs, outs, strict=True):
        assert p.returncode == 0, err
        assert "Traceback" not in err
    run_dirs = {out.strip().splitlines()[-1] for out, _ in outs}
    runs = sorted(os.listdir(os.path.join(hist, "runs")))
    assert len(run_dirs) == 2 and len(runs) == 2
    for name in runs:
        assert sorted(os.listdir(os.path.join(hist, "runs", name))) == ["report.html", "results.json"]
    latest = os.path.realpath(os.path.join(hist, "latest"))
    assert os.path.basename(latest) in runs
    with open(os.path.join(latest, "results.json")) as fh:
        assert json.load(fh)["history_notes"] == []
    assert sorted(os.listdir(hist)) == [".lock", "latest", "runs"]  # nothing half-built


def test_readme_documents_every_exit_code():
    """Cron users read the codes in the README: the table there lists exactly main()'s codes."""
    import re

    import scatterbench.validation.cli as cli

    readme = open(
        os.path.join(os.path.dirname(os.path.dirname(__file__)), "README.md"), encoding="utf-8"
    ).read()
    table = readme.split("Exit codes, the same for every command", 1)[1].split("\n\n", 2)[1]
    documented = [int(m) for m in re.findall(r"^\| (\d+) \|", table, re.M)]
    codes = [cli.EXIT_OK, cli.EXIT_FAILED, cli.EXIT_USAGE, cli.EXIT_INTERNAL, cli.EXIT_INTERRUPTED]
    assert documented == codes == [0, 1, 2, 3, 130]
