"""The report computes its ``beside`` sections (the studies on the executor) at once, on
threads of their own, when its workers run one task at a time; everything else one after
another, before them (the other sections of stage 0) or after them (those that time code, the
later stages).  Every section is rendered on the calling thread, those computed before the
beside ones and each beside one as it is done while the others compute; what later stages read
(the failures, the seconds) follows the order sections run.

Equal results on every executor are ``tests/test_report_executors.py``'s (its subset, the
seed 003 presets and the stability sweep, are both ``beside``)."""

import functools
import importlib
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import pytest

from scatterbench.validation.checks.registry import CheckContext
from scatterbench.validation.fitting import executors
from scatterbench.validation.report import build, sections
from scatterbench.validation.report.core import SectionSpec


class Workers(executors.SerialExecutor):
    """In-process, but claiming two one-task workers: what makes a report compute side by side."""

    workers = 2
    kind = "processes"
    one_task_per_process = True


def _report(monkeypatch, specs, executor):
    summary, provenance = sections.SECTIONS[0], sections.SECTIONS[-1]
    monkeypatch.setattr(build, "SECTIONS", [summary, *specs, provenance])
    return build.build_report(quick=True, checks=[], executor=executor)[0]


def _meeting(n, timeout=20.0):
    """``n`` sections' compute that return only once all ``n`` run at the same time (a barrier
    that breaks after ``timeout`` s: computed one after another, each raises)."""
    barrier = threading.Barrier(n, timeout=timeout)
    seen = []

    def compute(ctx):
        barrier.wait()
        seen.append(threading.current_thread().name)
        return len(seen)

    return compute, seen


def _rendering(log):
    def render(sec, data):
        log.append((sec.id, threading.current_thread() is threading.main_thread()))
        sec.numbers["data"] = 1.0

    return render


def test_beside_sections_are_computed_at_once_and_rendered_on_the_main_thread(monkeypatch):
    compute, seen = _meeting(3)
    log = []
    specs = [SectionSpec(f"s{i}", f"S{i}", compute, _rendering(log), beside=True) for i in range(3)]
    results = _report(monkeypatch, specs, Workers())
    assert [s["error"] for s in results["sections"].values()] == [None] * 5
    assert len(set(seen)) == 3 and all(name.startswith("scatterbench-section") for name in seen)
    assert sorted(log) == [("s0", True), ("s1", True), ("s2", True)]  # on the main thread
    assert list(results["sections"]) == ["summary", "s0", "s1", "s2", "provenance"]  # page order
    assert results["summary"]["n_fail"] == 0


def _waiting_for(event, then=None, timeout=10.0):
    """A compute that waits for ``event`` (raising after ``timeout`` s), then returns
    ``then``."""

    def compute(ctx):
        if not event.wait(timeout):
            raise TimeoutError("not rendered meanwhile")
        return then

    return compute


def _rendering_sets(log, event):
    def render(sec, data):
        log.append(sec.id)
        event.set()

    return render


def test_sections_are_rendered_as_they_are_done_while_the_beside_ones_compute(monkeypatch):
    """This thread renders the sections computed before the beside ones, then each beside one
    as it is done, while the others still compute: each compute below waits for the render
    before it (its event), and fails after 10 s if the renders wait for every compute."""
    events = [threading.Event() for _ in range(3)]
    log = []
    specs = [
        SectionSpec(
            "b0", "B0", _waiting_for(events[2]), _rendering_sets(log, threading.Event()), beside=True
        ),
        SectionSpec("b1", "B1", _waiting_for(events[1]), _rendering_sets(log, events[2]), beside=True),
        SectionSpec("b2", "B2", _waiting_for(events[0]), _rendering_sets(log, events[1]), beside=True),
        SectionSpec("first", "First", lambda ctx: 0, _rendering_sets(log, events[0])),
    ]
    results = _report(monkeypatch, specs, Workers())
    assert [s["error"] for s in results["sections"].values()] == [None] * 6
    assert log == ["first", "b2", "b1", "b0"]
    assert list(results["sections"]) == ["summary", "b0", "b1", "b2", "first", "provenance"]


def test_what_later_stages_read_is_in_page_order_whatever_order_sections_are_done(monkeypatch):
    """The summary's check list (and so the results' digest) has the failed sections, and the
    provenance section's table their seconds, in the order sections run, although the beside
    ones are rendered as they are done (here the last first)."""
    events = [threading.Event() for _ in range(2)]

    def failing_after(event):
        def compute(ctx):
            assert event.wait(10.0)
            raise RuntimeError("broken")

        return compute

    def broken_now(ctx):
        raise RuntimeError("broken")

    specs = [
        SectionSpec("b0", "B0", failing_after(events[1]), _rendering([]), beside=True),
        SectionSpec("b1", "B1", failing_after(events[0]), _rendering([]), beside=True),
        SectionSpec("b2", "B2", lambda ctx: 0, _rendering_sets([], events[0]), beside=True),
        SectionSpec("first", "First", broken_now, _rendering([])),
        SectionSpec("alone", "Alone", broken_now, _rendering([]), alone=True),
    ]
    # b1 fails once b2 is rendered, b0 once b1 has failed (its event set here)
    monkeypatch.setattr(build, "_section_failure", _failure_noting(events[1]))
    results = _report(monkeypatch, specs, Workers())
    failed = ["report.section_b0", "report.section_b1", "report.section_first", "report.section_alone"]
    assert [c["id"] for c in results["checks"]] == failed
    times = results["sections"]["provenance"]["numbers"]["section_times"]
    assert [row["section"] for row in times] == ["b0", "b1", "b2", "first", "alone"]


def _failure_noting(event):
    real = build._section_failure

    def failure(name):
        if name == "b1":
            event.set()
        return real(name)

    return failure


def test_a_section_that_times_code_is_computed_with_nothing_else_running(monkeypatch):
    """An ``alone`` section is computed after the beside ones, no section thread left; any
    other section of stage 0 before them, so that this process only renders while they run."""
    log = []

    def noting(name):
        def compute(ctx):
            threads = [t.name for t in threading.enumerate() if t.name.startswith("scatterbench-section")]
            log.append((name, threading.current_thread() is threading.main_thread(), bool(threads)))
            return 0

        return compute

    specs = [
        SectionSpec("timed", "Timed", noting("timed"), _rendering([]), alone=True),
        SectionSpec("b0", "B0", lambda ctx: time.sleep(0.3), _rendering([]), beside=True),
        SectionSpec("b1", "B1", noting("b1"), _rendering([]), beside=True),
        SectionSpec("other", "Other", noting("other"), _rendering([])),
    ]
    results = _report(monkeypatch, specs, Workers())
    assert results["summary"]["n_fail"] == 0
    assert log[0] == ("other", True, False) and log[2] == ("timed", True, False)
    assert log[1] == ("b1", False, True)
    # the report's one such section: the speed section times the kernels
    assert [sp.id for sp in sections.SECTIONS if sp.alone] == ["speed"]


def test_on_one_process_or_many_task_threads_the_sections_run_one_after_another(monkeypatch):
    class Threads(Workers):
        one_task_per_process = False  # a Dask worker with several task threads

    for executor in (executors.SerialExecutor(), Threads()):
        compute, _ = _meeting(2, timeout=1.0)
        specs = [SectionSpec(f"s{i}", f"S{i}", compute, _rendering([]), beside=True) for i in range(2)]
        results = _report(monkeypatch, specs, executor)
        # one after another, the first waits at the barrier alone until it breaks
        assert results["sections"]["s0"]["error"] == "BrokenBarrierError: "
        assert results["summary"]["n_fail"] == 2


def test_a_beside_section_that_raises_fails_alone(monkeypatch):
    def broken(ctx):
        raise RuntimeError("the study failed")

    log = []
    specs = [
        SectionSpec("bad", "Bad", broken, _rendering(log), beside=True),
        SectionSpec("good", "Good", lambda ctx: 1, _rendering(log), beside=True),
        SectionSpec("after", "After", lambda ctx: 2, _rendering(log)),
    ]
    results = _report(monkeypatch, specs, Workers())
    assert results["sections"]["bad"]["error"] == "RuntimeError: the study failed"
    assert results["sections"]["good"]["numbers"] == {"data": 1.0}
    assert [c["id"] for c in results["checks"]] == ["report.section_bad"]
    assert log == [("after", True), ("good", True)]  # computed before the beside ones


def _sleeping(seconds):
    def compute(ctx):
        time.sleep(seconds)
        return seconds

    return compute


def test_the_report_says_where_its_seconds_went(monkeypatch):
    """``meta.phase_seconds``: before the sections, the sections side by side (the preloads
    among them), then the rest one at a time; left out of the results' digest, as every time
    is."""
    from scatterbench.validation.report.core import render_html
    from scatterbench.validation.report.timing import results_digest

    specs = [
        SectionSpec(
            "s0", "S0", _sleeping(0.6), _rendering([]), beside=True, preloads=(lambda: time.sleep(0.3),)
        ),
        SectionSpec("s1", "S1", _sleeping(0.6), _rendering([]), beside=True),
        SectionSpec("later", "Later", _sleeping(0.2), _rendering([])),
    ]
    results = _report(monkeypatch, specs, Workers())
    phases = results["meta"]["phase_seconds"]
    assert phases["start"] < 0.3 and phases["beside"] >= 0.6 and 0.2 <= phases["in turn"] < phases["beside"]
    assert sum(phases.values()) <= results["meta"]["seconds"]
    header = render_html(results["meta"], [], results["summary"])
    assert f"{phases['beside']:.1f} s of studies side by side" in header
    moved = {**results, "meta": {**results["meta"], "phase_seconds": {"start": 0.0}}}
    assert results_digest(moved) == results_digest(results)


def test_what_sections_import_on_first_use_is_imported_on_the_main_thread_once_they_started(
    monkeypatch, tmp_path
):
    """A section's ``preloads`` run on the report's main thread, once each, after every
    side-by-side section has started (their tasks run meanwhile): the preload below waits for
    both sections to start (10 s, then the one that needs it fails), and they wait for it."""
    (tmp_path / "preload_probe.py").write_text(
        "import threading\nTHREADS = [threading.current_thread().name]\n", encoding="utf-8"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "preload_probe", raising=False)
    calls, loaded = [], threading.Event()
    started = {"needs": threading.Event(), "free": threading.Event()}

    def load():
        calls.append(threading.current_thread().name)
        if not all(ev.wait(10.0) for ev in started.values()):
            raise TimeoutError("the sections did not start before the preload")
        importlib.import_module("preload_probe")
        loaded.set()

    def waiting(sid):
        def compute(ctx):
            started[sid].set()
            if not loaded.wait(10.0):
                raise TimeoutError("the preload did not run meanwhile")
            return list(sys.modules["preload_probe"].THREADS)

        return compute

    specs = [
        SectionSpec("needs", "Needs", waiting("needs"), _rendering([]), beside=True, preloads=(load,)),
        SectionSpec("free", "Free", waiting("free"), _rendering([]), beside=True),
    ]
    results = _report(monkeypatch, specs, Workers())
    assert [s["error"] for s in results["sections"].values()] == [None] * 4
    assert sys.modules["preload_probe"].THREADS == calls == ["MainThread"]  # once, shared


def test_a_preload_that_fails_to_import_fails_its_sections_alone(monkeypatch, tmp_path):
    """A preload that raises (an import that fails) does not stop the report: the sections that
    import the module fail with its error, the others are computed."""
    (tmp_path / "broken_probe.py").write_text("raise RuntimeError('broken on import')\n", encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    specs = [
        SectionSpec(
            "needs", "Needs", lambda ctx: importlib.import_module("broken_probe"), _rendering([]), beside=True,
            preloads=(functools.partial(importlib.import_module, "broken_probe"),),
        ),
        SectionSpec("other", "Other", lambda ctx: 1, _rendering([]), beside=True),
    ]  # fmt: skip
    results = _report(monkeypatch, specs, Workers())
    assert results["sections"]["needs"]["error"] == "RuntimeError: broken on import"
    assert results["sections"]["other"]["error"] is None
    assert [c["id"] for c in results["checks"]] == ["report.section_needs"]


def test_the_dask_executor_says_whether_its_workers_run_one_task_at_a_time():
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    ) as lc:
        with distributed.Client(lc) as client:
            ex = executors.DaskExecutor(client)
            assert not ex.one_task_per_process and not build.side_by_side(ex)
    assert build.side_by_side(Workers()) and not build.side_by_side(executors.SerialExecutor())


def test_two_sections_asking_for_one_study_share_one_run_of_it():
    ctx = CheckContext()
    calls, started = [], threading.Event()

    def study(x, executor=None):
        calls.append(x)
        started.set()
        threading.Event().wait(0.3)  # long enough that the other thread asks meanwhile
        return x * 2

    def ask(out):
        out.append(ctx.study(study, 21))

    got = []
    first = threading.Thread(target=ask, args=(got,))
    first.start()
    started.wait(5)
    ask(got)
    first.join()
    assert got == [42, 42] and calls == [21]


def test_a_worker_keeps_the_functions_of_sections_that_alternate(monkeypatch):
    loads = []
    real = executors.pickle.loads

    def counting(blob):
        loads.append(blob)
        return real(blob)

    monkeypatch.setattr(executors, "_WORKER_FNS", {})
    monkeypatch.setattr(executors.pickle, "loads", counting)
    blobs = {k: executors.pickle.dumps(fn) for k, fn in (("a", abs), ("b", round))}
    for _ in range(3):  # two studies' chunks alternating on one worker
        assert executors._run_pickled_chunk("a", blobs["a"], [-1]) == [1]
        assert executors._run_pickled_chunk("b", blobs["b"], [1.4]) == [1]
    assert len(loads) == 2


def _late_compile(monkeypatch, fail=False):
    """A first run's compile of loop ``("facet", "float32")`` that only a later section uses:
    ``warm_group`` logs, waits until the section before that one has started (so it fails,
    after 20 s, unless the two overlap) and then raises if ``fail``."""
    task = ("facet", "float32", None, True)
    log, started = [], threading.Event()

    def warm_group(group):
        log.append(("compile", tuple(group)))
        assert started.wait(20.0), "the sections before did not run during the compile"
        time.sleep(0.2)  # a section that did not wait would log first
        log.append("compiled")
        if fail:
            raise RuntimeError("LLVM ran out of memory")
        return [t[0] for t in group]

    def before(ctx):
        log.append("before")
        started.set()
        return 1

    def needs(ctx):
        log.append("needs")
        return 2

    monkeypatch.setattr(build, "warm_group", warm_group)
    monkeypatch.setattr(build, "cold_task", lambda t: t == task)
    specs = [
        *(
            SectionSpec(f"b{i}", "B", lambda ctx: log.append("beside") or 0, _rendering([]), beside=True)
            for i in range(2)
        ),
        SectionSpec("before", "Before", before, _rendering([])),
        SectionSpec("needs", "Needs", needs, _rendering([]), compiles=(task,), alone=True),
    ]
    return log, task, _report(monkeypatch, specs, Workers())


def test_a_sections_own_loops_compile_on_the_workers_while_this_process_computes_the_first_sections(
    monkeypatch,
):
    """A section's own loops (``SectionSpec.compiles``; here a section that times code, as the
    speed section) compile on the workers as the sections start, while this process computes
    those before the beside ones, and that section starts only when they are compiled (it
    loads them rather than compiling them again).  Fails when they compile ahead of every
    section (the compile then waits 20 s for a section that has not started), or the section
    does not wait."""
    log, task, results = _late_compile(monkeypatch)
    assert sorted(log[:2], key=str) == [("compile", (task,)), "before"]  # at once: either first
    assert log.count("beside") == 2 and log.index("beside") > log.index("before")
    assert log.index("compiled") < log.index("needs") == len(log) - 1
    assert results["summary"]["n_fail"] == 0


def test_a_failed_late_compile_leaves_the_section_to_compile_its_own(monkeypatch):
    log, _, results = _late_compile(monkeypatch, fail=True)
    assert log[-2:] == ["compiled", "needs"]
    assert results["sections"]["needs"]["error"] is None and results["summary"]["n_fail"] == 0


class _Stop(Exception):
    """Raised by a stand-in example fit, carrying what it saw."""


class _Submitting(Workers):
    """Runs a map's tasks on threads while the caller does its ``meanwhile``, as worker
    processes do."""

    def map(self, fn, items, tasks=None, meanwhile=None):
        with ThreadPoolExecutor(len(items)) as pool:
            futs = [pool.submit(fn, x) for x in items]
            if meanwhile is not None:
                meanwhile()
            return [f.result() for f in futs]


def test_the_recovery_study_runs_while_the_example_fit_runs_on_the_workers(monkeypatch):
    """The uncertainty section's example fit is a task, and the recovery study's tasks go to the
    workers while it runs, not after it (on many cores the fit was the report's longest path):
    the stand-in fit waits for the recovery to start, and sees it start only then."""
    from scatterbench.validation.report.sections import uncertainty

    started = threading.Event()
    monkeypatch.setattr(uncertainty, "recovery_cells", lambda ctx: started.set())

    def fit(job):
        raise _Stop(started.wait(10.0), threading.current_thread() is threading.main_thread())

    monkeypatch.setattr(uncertainty, "fit_task", fit)
    with pytest.raises(_Stop) as stop:
        uncertainty.compute(CheckContext(quick=True, executor=_Submitting()))
    assert stop.value.args == (True, False)  # the recovery started meanwhile; the fit a task
