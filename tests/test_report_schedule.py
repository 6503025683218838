"""benchmarks/report_schedule.py: a recorded report's schedule replayed on more workers (the
16-core estimate of docs/guide/scaling.md), checked here on a schedule worked out by hand."""

import importlib.util
import os

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture(scope="module")
def schedule():
    spec = importlib.util.spec_from_file_location(
        "report_schedule", os.path.join(ROOT, "benchmarks", "report_schedule.py")
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _record():
    """0.5 s before the sections; ``a`` computed first (0.2 s, rendered in 0.1 s); ``b`` and
    ``c`` side by side: ``b`` works 0.1 s, maps two 1-s tasks, works 0.1 s; ``c`` maps one 3-s
    task; then ``z`` (0.5 s)."""
    main = "MainThread"
    events = [
        (main, "start", "a", 0.0, None), (main, "end", "a", 0.2, None),
        ("T1", "start", "b", 0.2, None), ("T2", "start", "c", 0.2, None),
        ("T2", "map", 2, 0.2, None), ("T1", "map", 1, 0.3, None),
        (main, "render", "a", 0.3, 0.1),
        ("T1", "wait", 1, 2.3, [1.0, 1.0]), ("T1", "end", "b", 2.4, None), (main, "render", "b", 2.4, 0.0),
        ("T2", "wait", 2, 3.2, [3.0]), ("T2", "end", "c", 3.2, None), (main, "render", "c", 3.2, 0.0),
        (main, "start", "z", 3.5, None), (main, "end", "z", 4.0, None), (main, "render", "z", 4.0, 0.0),
    ]  # fmt: skip
    return {"workers": 2, "quick": True, "seconds": 4.6, "phase_seconds": {"start": 0.5}, "events": events}


def test_the_record_is_cut_into_each_sections_steps(schedule):
    sections, renders, before, beside, after, lead = schedule.phases(_record())
    assert (before, beside, after, lead) == (["a"], ["b", "c"], ["z"], 0.0)
    steps = sections["b"]
    assert [st[0] for st in steps] == ["work", "work", "map", "wait", "work"]
    assert [st[1] for st in steps if st[0] == "work"] == pytest.approx([0.0, 0.1, 0.1])
    assert steps[2] == ("map", 1, [1.0, 1.0]) and steps[3] == ("wait", 1)
    assert renders == {"a": 0.1, "b": 0.0, "c": 0.0, "z": 0.0}


@pytest.mark.parametrize(
    "workers, slower, total, ends",
    [
        # one worker: c's task (submitted first) 0.7-3.7, then b's two 3.7-5.7; b ends at 5.8
        (1, 1.0, 6.3, {"b": 5.1, "c": 3.0}),
        # two: c's task 0.7-3.7 on one, b's 0.8-1.8 and 1.8-2.8 on the other
        (2, 1.0, 4.2, {"b": 2.2, "c": 3.0}),
        # twice as slow: c's 0.7-6.7, b's 0.8-2.8 and 2.8-4.8
        (2, 2.0, 7.2, {"b": 4.2, "c": 6.0}),
    ],
)
def test_the_replay_runs_tasks_first_submitted_first_on_the_first_free_worker(
    schedule, workers, slower, total, ends
):
    got, got_ends = schedule.estimate(_record(), workers, slower)
    assert got == pytest.approx(total)
    assert got_ends == pytest.approx(ends)


def test_a_section_started_later_than_the_first_waits_that_long_and_so_do_the_renders(schedule):
    """A side-by-side section started after the others (after the preloads) starts that much
    later in the replay; the report's thread renders once it has done what it did first (here
    1.5 s: the first render, 0.1 s long, ends at 1.8 s)."""
    rec = _record()
    later = {"c", 2}
    rec["events"] = [
        (th, k, key, t + 1.0 if key in later else t + 1.5 if (k, key) == ("render", "a") else t, x)
        for th, k, key, t, x in rec["events"]
    ]
    sections, *_, lead = schedule.phases(rec)
    assert sections["c"][0] == ("work", pytest.approx(1.0)) and lead == pytest.approx(1.5)
    # two workers: b's tasks first now, 0.8-1.8 on both (b ends 1.9); c's 1.8-4.8; the renders
    # from 2.2 (0.7 + 1.5), c's last at 4.8, then z
    total, ends = schedule.estimate(rec, 2, 1.0)
    assert ends == pytest.approx({"b": 1.2, "c": 4.1}) and total == pytest.approx(5.3)
