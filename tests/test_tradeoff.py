"""Speed/accuracy knobs: errors measured against independent references; --tol picks honestly."""

import json
import math
import os
import types
from dataclasses import dataclass

import numpy as np
import pytest

from scatterbench import models
from scatterbench.validation.atomic import atomic_write_json
from scatterbench.validation.cli import main
from scatterbench.validation.studies import tradeoff
from scatterbench.validation.studies.tradeoff import (
    MIN_BATCHES,
    MIN_WORK,
    KnobResult,
    KnobUnavailable,
    Point,
    at_precision,
    choose,
    knob_precision,
    pareto,
    precision_option,
    study,
    time_call,
)


@pytest.fixture(scope="module")
def results():
    return {r.knob: r for r in study(quick=True)}


def test_integration_errors_fall_with_tolerance(results):
    r = results["integration tolerance"]
    errs = [p.error for p in r.points]
    assert errs[-1] < errs[0] / 10
    for p in r.points:
        assert p.error <= p.setting  # each tolerance met, checked against the slope-space reference


def test_choose_meets_tolerance_against_reference(results):
    for r in results.values():
        for tol in (1e-2, 1e-4, 1e-6):
            pick = choose(r, tol)
            if pick is not None:
                assert pick.error <= tol
                for p in r.points:
                    if p.error <= tol and p is not pick:
                        # costs at least as much, or ties with it (same error) and loses the tie;
                        # a point whose error another point reaches with fewer evaluations, or
                        # with as many from a coarser setting (listed earlier), is that point's
                        # duplicate (the same work: its CPU time differs by noise)
                        tie = p.error == pick.error and p.evaluations >= pick.evaluations
                        duplicate = any(
                            q.error == p.error
                            and (q.evaluations, r.points.index(q)) < (p.evaluations, r.points.index(p))
                            for q in r.points
                        )
                        assert p.seconds >= pick.seconds or tie or duplicate
                        if tie and p.evaluations == pick.evaluations:
                            assert r.points.index(p) > r.points.index(pick)  # pick is the coarser


def test_pareto():
    pts = [Point(1, 1e-2, 1.0, 1), Point(2, 1e-3, 2.0, 1), Point(3, 1e-2, 3.0, 1)]
    assert [p.setting for p in pareto(pts)] == [1, 2]


@pytest.mark.parametrize("noise", [(1.02, 1.0, 1.01), (1.0, 1.02, 1.01), (1.01, 1.02, 1.0)])
def test_ties_are_broken_by_evaluations_then_the_coarser_setting_not_by_noise(noise):
    """Integration tolerances 1e-2, 1e-3, 1e-4 stop at the same evaluations with the same
    error: whichever CPU time the noise makes smallest, --tol picks the coarsest, 1e-2."""
    tied = [Point(tol, 6.43e-5, s * 1e-3, 15750) for tol, s in zip((1e-2, 1e-3, 1e-4), noise, strict=True)]
    finer = Point(1e-5, 2e-7, 3e-3, 40000)
    r = KnobResult("integration tolerance", "q", "ref", [*tied, finer])
    assert choose(r, 1e-4) is tied[0]
    assert [p.setting for p in pareto(r.points)] == [1e-2, 1e-5]
    # equal error, fewer evaluations wins even when listed later and timed slower
    fewer = Point(1e-6, 6.43e-5, 2e-3, 15000)
    r = KnobResult("integration tolerance", "q", "ref", [*tied, fewer])
    assert choose(r, 1e-4) is fewer and pareto(r.points) == [fewer]


def test_cli_writes_json_and_png(tmp_path, capsys):
    out = tmp_path / "t"
    assert main(["tradeoff", "--quick", "--out", str(out), "--tol", "1e-4"]) == 0
    data = json.loads((out / "tradeoff.json").read_text())
    assert {d["knob"] for d in data} >= {"integration tolerance", "in-plane grid", "precision"}
    for d in data:  # measured, or skipped with its reason
        assert d.get("skipped") or all(
            {"seconds", "spread", "calls", "wall_seconds"} <= set(p) for p in d["points"]
        )
    assert (out / "tradeoff.png").stat().st_size > 1000
    printed = capsys.readouterr().out
    assert "chose" in printed and "cost: CPU seconds per call" in printed


def test_atomic_write_keeps_previous_on_failure(tmp_path):
    p = tmp_path / "r.json"
    atomic_write_json(p, {"a": 1})
    with pytest.raises(TypeError):
        atomic_write_json(p, {"a": object()})  # not serializable
    from scatterbench.validation.atomic import _temp_beside

    with pytest.raises(RuntimeError):
        with _temp_beside(p) as tmp:
            with open(tmp, "w") as fh:
                fh.write('{"a": 2, "trunc')  # interrupted midway
            raise RuntimeError("killed")
    assert json.loads(p.read_text()) == {"a": 1}
    assert oct(p.stat().st_mode & 0o777) != "0o600"
    assert [f for f in os.listdir(tmp_path) if f.startswith(".tmp-")] == []


def test_every_knob_has_an_independent_reference_and_improves(results):
    assert {"integration tolerance", "in-plane grid", "Monte Carlo pairs", "point-source resolution"} <= set(
        results
    )
    for r in results.values():
        assert r.reference and r.points
        errs = [p.error for p in r.points]
        assert min(errs[1:]) < errs[0]  # more cost buys accuracy on every knob


def test_scene_tol_picks_settings_that_meet_it(tmp_path, capsys):
    from scatterbench import references

    path = [p for p in references.scene_paths() if "point_source" in p][0]
    assert main(["scene", path, "--out", str(tmp_path), "--tol", "1e-6"]) == 0
    out = capsys.readouterr().out
    assert "point-source resolution: chose" in out
    # the grid knob cannot reach 1e-6 with the measured settings: said, not hidden
    assert "in-plane grid: no measured setting reaches" in out


def test_costs_are_resolved_best_of_batches(results):
    """Every setting is timed over >= MIN_WORK s of CPU time in >= MIN_BATCHES batches, so
    the sub-millisecond grid settings are resolved: the curve's cost rises with the
    number of points instead of running backwards."""
    for r in results.values():
        for p in r.points:
            assert p.cpu_total >= MIN_WORK and p.wall_seconds > 0
    grid = results["in-plane grid"].points
    assert grid[0].calls > 100  # a ~0.1 ms call: batched, not timed once
    assert grid[-1].seconds > grid[0].seconds  # 361 points cost more than 19


class _Clock:
    """time_call's two clocks, moved only by the work: a call of ``cost`` adds ``cost`` of CPU
    time and twice that of wall time (a loaded machine). Powers of two keep the sums exact."""

    def __init__(self):
        self.cpu = self.wall = 0.0

    def work(self, cost):
        self.cpu += cost
        self.wall += 2 * cost
        return cost


def test_time_call_measures_the_work_of_one_call(monkeypatch):

    clock = _Clock()
    fake = types.SimpleNamespace(perf_counter=lambda: clock.wall, process_time=lambda: clock.cpu)
    monkeypatch.setattr(tradeoff, "time", fake)
    c = 2.0**-13
    out, small = time_call(lambda: clock.work(c))
    _, large = time_call(lambda: clock.work(8 * c))
    assert out == c
    for t, cost in ((small, c), (large, 8 * c)):
        # the cost is the CPU time of one call, the wall time beside it
        assert (t.seconds, t.wall_seconds, t.spread) == (cost, 2 * cost, 0.0)
        # batches of ceil(BATCH / warm-up wall time) calls, until MIN_WORK and MIN_BATCHES
        number = math.ceil(tradeoff.BATCH / (2 * cost))
        batches, rest = divmod(t.calls, number)
        assert rest == 0 and batches >= MIN_BATCHES and t.cpu_total == t.calls * cost >= MIN_WORK
        assert batches == MIN_BATCHES or (batches - 1) * number * cost < MIN_WORK  # and no more
    assert large.seconds == 8 * small.seconds  # 8 x the work, per call
    assert small.calls > large.calls >= MIN_BATCHES


@dataclass(frozen=True)
class RoundedFacet(models.FacetBRDF):
    """A stand-in for a model with float32 kernels: ``precision="float32"`` rounds the
    angles and the result to float32 (the numpy path itself computes in float64)."""

    def mueller(self, theta_i, theta_r, phi_r=0.0, out=None, precision="float64"):
        if precision == "float64":
            return super().mueller(theta_i, theta_r, phi_r, out)
        f32 = [np.asarray(a, dtype=np.float32) for a in (theta_i, theta_r, phi_r)]
        return super().mueller(*f32).astype(np.float32)


class Plain:
    """A model without a float32 kernel (not a models.Model: its mueller takes no
    ``precision``)."""

    depolarizing = True

    def mueller(self, theta_i, theta_r, phi_r=0.0):
        return np.broadcast_to(np.diag([1 / math.pi, 0, 0, 0]), np.shape(theta_i) + (4, 4))


#: models whose mueller takes precision= (every models.Model) but that no float32 kernel
#: evaluates: Monte Carlo and the point-source wrapper (float64, rounded, at the same cost)
NO_KERNEL = [
    models.RoughDiffuseBRDF(pairs=200),
    models.PointSourceBRDF(model=models.CookTorranceBRDF(convention="corrected"), distance=100.0),
]


def test_precision_option_is_a_real_float32_kernel():
    assert precision_option(RoundedFacet()) == "keyword"
    assert precision_option(models.SubsurfaceFacetBRDF()) == "keyword"
    assert precision_option(Plain()) is None
    for m in NO_KERNEL:
        assert precision_option(m) is None, m
    with models.backend("numpy"):  # the reference path: float64, rounded
        assert precision_option(models.SubsurfaceFacetBRDF()) is None
    assert at_precision(RoundedFacet(), "float32")(0.1, 0.2, 0.3).dtype == np.float32
    with pytest.raises(ValueError, match="precision must be 'float64' or 'float32'; got 'half'"):
        at_precision(RoundedFacet(), "half")
    with pytest.raises(ValueError, match="precision: Plain has no float32 kernel"):
        at_precision(Plain(), "float32")
    with pytest.raises(ValueError, match="precision: RoughDiffuseBRDF has no float32 kernel"):
        at_precision(NO_KERNEL[0], "float32")


def test_precision_knob_measures_float32_against_float64():
    r = knob_precision(model=RoundedFacet(slopes=models.ExponentialSlopes(0.1)))
    by = {p.setting: p for p in r.points}
    assert set(by) == {64, 32} and by[64].error == 0.0  # the reference itself
    assert 1e-9 < by[32].error < 1e-4  # float32 rounding, resolved and small
    assert choose(r, 1e-12) is by[64]  # float32 does not meet 1e-12
    pick = choose(r, 1e-3)  # both meet it: the cheaper measured one
    assert pick is min(r.points, key=lambda p: p.seconds)


def test_precision_knob_is_unavailable_with_its_reason_without_a_float32_kernel():
    with pytest.raises(KnobUnavailable, match="Plain has no float32 kernel"):
        knob_precision(quick=True, model=Plain())
    for m in NO_KERNEL:
        with pytest.raises(KnobUnavailable, match=f"{type(m).__name__} has no float32 kernel"):
            knob_precision(quick=True, model=m)


def test_scene_precision_is_decided_and_measured_on_the_scenes_model(monkeypatch):
    from scatterbench.validation.studies import scenes

    notes = []
    assert scenes._choose_precision(NO_KERNEL[0], 1e-3, notes) == "float64"
    assert notes == ["precision: float64 (RoughDiffuseBRDF has no float32 kernel)"]
    seen = []
    real = tradeoff.KNOBS["precision"]
    monkeypatch.setitem(tradeoff.KNOBS, "precision", lambda **kw: seen.append(kw) or real(**kw))
    model = models.FacetBRDF(slopes=models.GaussianSlopes(0.3))
    notes = []
    assert scenes._choose_precision(model, 1e-3, notes) in ("float32", "float64")
    assert seen == [{"quick": True, "model": model}] and notes[0].startswith("precision: chose")
