"""``report``, ``validate`` and ``nightly`` run every study on the executor ``--workers N`` /
``--scheduler ADDRESS`` ask for, and their results do not depend on it.

The whole ``report --quick`` (about 4-9 min on the shared 2-core machine) is compared in-process,
on 2 local workers and on a 2-worker dask ``LocalCluster`` by ``python benchmarks/study_workers.py
--study report``; here the same code path runs on a representative subset of sections: the seed 003
presets (a Monte Carlo model, one task per preset), the stability sweep (a study of the check
context, one task per model instance) and the summary judging the sweep's check."""

import json
import os

import pytest
from spy_executor import Spy

from scatterbench.validation.checks import registry
from scatterbench.validation.checks.registry import CheckContext
from scatterbench.validation.cli import main
from scatterbench.validation.cli import report as report_cli
from scatterbench.validation.cli import validate as validate_cli
from scatterbench.validation.fitting.executors import SerialExecutor, _local_cores
from scatterbench.validation.report import build
from scatterbench.validation.report.sections import summary
from scatterbench.validation.report.timing import results_digest, without_timings
from scatterbench.validation.studies import tradeoff

SUBSET = ("seed003_presets", "stability", "summary", "provenance")
CHECK = "stability.check_stability"


# ----------------------------------------------------------------------------- the flags
def _fake_report(seen):
    def write_report(out, quick=False, executor=None, **kw):
        seen["executor"] = executor
        summary = {"n_checks": 0, "n_pass": 0, "n_finding": 0, "n_fail": 0}
        return {"meta": {"seconds": 0.0}, "summary": summary}

    return write_report


@pytest.mark.parametrize(
    "flags, kind, workers",
    [([], "default", None), (["--workers", "1"], "serial", 1), (["--workers", "3"], "processes", 3)],
)
def test_report_runs_on_the_executor_the_flags_ask_for(flags, kind, workers, monkeypatch, tmp_path):
    seen = {}
    monkeypatch.setattr(report_cli, "write_report", _fake_report(seen))
    assert main(["report", "--quick", "--out", str(tmp_path / "r"), *flags]) == 0
    ex = seen["executor"]
    if kind == "default":  # the cores this process may run on (its affinity mask)
        assert ex.workers == _local_cores() and ex.kind == ("serial" if _local_cores() == 1 else "processes")
    else:
        assert (ex.kind, ex.workers) == (kind, workers)


def test_validate_and_nightly_pass_the_executor_down(monkeypatch, tmp_path):
    seen = {}

    def run(quick=False, json_path=None, executor=None, **kw):
        seen["validate"] = executor
        return 0

    class Run:
        code, regressions, run_dir, notes = 0, [], str(tmp_path / "h" / "runs" / "x"), []

    def nightly(history, quick=False, wait=0, executor=None, **kw):
        seen["nightly"] = executor
        return Run()

    monkeypatch.setattr(validate_cli, "run", run)
    monkeypatch.setattr(report_cli, "nightly", nightly)
    assert main(["validate", "--quick", "--workers", "2"]) == 0
    assert main(["nightly", "--history", str(tmp_path / "h"), "--quick", "--workers", "2"]) == 0
    assert [(seen[c].kind, seen[c].workers) for c in ("validate", "nightly")] == [("processes", 2)] * 2


def test_a_study_runs_on_the_context_s_executor_once_keyed_without_it():
    calls = []

    def study(n, executor=None):
        calls.append(executor)
        return executor.map(abs, [-n, n], tasks=2)

    spy = Spy()
    ctx = CheckContext(quick=True, executor=spy)
    assert ctx.study(study, 3) == [3, 3] and ctx.study(study, 3) == [3, 3]
    assert calls == [spy] and spy.tasks == [2]  # once per context, on its executor
    ctx.executor = SerialExecutor()  # another executor: the same results, not recomputed
    assert ctx.study(study, 3) == [3, 3] and len(calls) == 1
    assert isinstance(CheckContext().runner(), SerialExecutor)  # none given: in-process


def test_the_trade_off_runs_its_knobs_one_task_each_with_the_same_errors():
    names = ["in-plane grid", "precision"]
    spy = Spy()
    serial = tradeoff.study(names=names, quick=True)
    spied = tradeoff.study(names=names, quick=True, executor=spy)
    assert spy.tasks == [2]

    def errors(results):
        return [(r.knob, [(p.setting, p.error, p.evaluations) for p in r.points]) for r in results]

    assert errors(spied) == errors(serial) and len(serial) == 2


def test_the_speed_section_times_the_knobs_and_each_models_throughput_in_one_map(monkeypatch):
    """One task per knob and per model, in one map: the section runs alone, so on many workers
    it takes about its longest task.  The rows name the model and the threads it ran on."""
    from scatterbench import models
    from scatterbench.validation.report.core import Context
    from scatterbench.validation.report.sections import speed

    knob = tradeoff.KNOBS["precision"]
    monkeypatch.setattr(tradeoff, "KNOBS", {"precision": knob})
    few = [models.FacetBRDF.sweep_base(), models.CookTorranceBRDF.sweep_base()]
    monkeypatch.setattr(speed, "default_models", lambda: few)
    spy = Spy()
    data = speed.compute(Context(quick=True, executor=spy))
    assert spy.tasks == [1 + len(few)]
    assert [r.knob for r in data.knobs] == ["precision"]
    assert [r["model"] for r in data.throughput_rows] == ["FacetBRDF", "CookTorranceBRDF"]
    for row in data.throughput_rows:
        assert row["geometries per call"] == data.geometries and row["kernel threads"] >= 1
        assert row["us per geometry (CPU)"] > 0 and row["us per geometry (wall)"] > 0


# ----------------------------------------------------------------------------- the results
def _subset(monkeypatch):
    """The report's sections and checks cut to :data:`SUBSET` and :data:`CHECK`, on the same path."""
    monkeypatch.setattr(build, "SECTIONS", tuple(s for s in build.SECTIONS if s.id in SUBSET))
    everything = registry.registered
    monkeypatch.setattr(
        summary, "registered", lambda quick=False: [s for s in everything(quick) if s.id == CHECK]
    )


def _report(tmp_path, name, flags):
    out = tmp_path / name
    assert main(["report", "--quick", "--out", str(out), *flags]) == 0
    with open(os.path.join(out, "results.json"), encoding="utf-8") as fh:
        return json.load(fh)


def _same(a, b):
    assert set(a["sections"]) == set(SUBSET) and [c["id"] for c in a["checks"]] == [CHECK]
    assert a["sections"]["seed003_presets"]["tracked"]  # the Monte Carlo preset's numbers are there
    assert json.dumps(without_timings(a), sort_keys=True) == json.dumps(without_timings(b), sort_keys=True)
    assert results_digest(a) == results_digest(b)


@pytest.fixture(scope="module")
def in_process(tmp_path_factory):
    with pytest.MonkeyPatch.context() as mp:
        _subset(mp)
        return _report(tmp_path_factory.mktemp("serial"), "r", ["--workers", "1"])


def test_report_sections_identical_on_two_local_workers(in_process, monkeypatch, tmp_path, capsys):
    _subset(monkeypatch)
    _same(in_process, _report(tmp_path, "r", ["--workers", "2"]))
    assert "executor: 2 local processes" in capsys.readouterr().out


def test_report_sections_identical_on_a_dask_cluster(in_process, monkeypatch, tmp_path, capsys):
    """``report --quick --scheduler`` on a 2-worker ``LocalCluster`` (issue 30, part 5)."""
    from dask.distributed import LocalCluster

    _subset(monkeypatch)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as lc:
        _same(in_process, _report(tmp_path, "r", ["--scheduler", lc.scheduler_address]))
    assert "executor: dask.distributed at tcp://127.0.0.1" in capsys.readouterr().out


def test_results_without_timings_differ_when_a_result_does(in_process):
    """The comparison can fail: a moved number shows, a moved time does not."""
    moved = json.loads(json.dumps(in_process))
    moved["meta"]["seconds"] += 1.0
    moved["sections"]["stability"]["seconds"] += 1.0
    assert results_digest(moved) == results_digest(in_process)
    key = next(iter(moved["sections"]["seed003_presets"]["tracked"]))
    moved["sections"]["seed003_presets"]["tracked"][key]["value"] += 1e-12
    assert results_digest(moved) != results_digest(in_process)


def test_results_without_timings_leave_out_the_commit_not_the_rest_of_provenance():
    """Two commits' reports compare equal where their results are: the provenance table's
    commit row is left out (as ``meta``'s ``git_commit``), its other rows stay."""
    rows = [{"item": "numpy", "value": "2.4.6"}, {"item": "git commit", "value": "6e188bcff69c"}]
    a = {"meta": {"git_commit": "6e188bc"}, "sections": {"provenance": {"numbers": {"provenance": rows}}}}
    b = json.loads(json.dumps(a))
    b["meta"]["git_commit"] = "unknown"
    b["sections"]["provenance"]["numbers"]["provenance"][1]["value"] = "unknown"
    assert results_digest(a) == results_digest(b)
    b["sections"]["provenance"]["numbers"]["provenance"][0]["value"] = "2.5.0"
    assert results_digest(a) != results_digest(b)


def test_the_monte_carlo_checks_runs_identical_on_workers():
    """The slow Monte Carlo checks' runs (25 for the error scaling) are tasks of the run's executor."""
    from scatterbench.validation.checks.seed003 import mc_error_scaling
    from scatterbench.validation.fitting.executors import ProcessExecutor

    spy = Spy()
    serial = mc_error_scaling(seeds=2, executor=spy, reference_pairs=5000)
    assert spy.tasks == [1 + 3 * 2]
    with ProcessExecutor(2) as ex:
        assert mc_error_scaling(seeds=2, executor=ex, reference_pairs=5000) == serial
