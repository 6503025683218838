"""Distributed studies: the recovery study's members, the model-comparison fits and the
stability sweep give the same results, in the same order, on a dask.distributed cluster
(two worker processes, so everything crosses a process boundary pickled), on local
processes and in-process."""

import functools
import json
import time
from dataclasses import dataclass

import command_files
import numpy as np
import pytest
import worker_probe

from scatterbench import models, references
from scatterbench.models import scene
from scatterbench.models.base import Model
from scatterbench.models.constraints import Interval
from scatterbench.models.params import param
from scatterbench.validation.cli import main
from scatterbench.validation.fitting.compare import compare_fits
from scatterbench.validation.fitting.datafile import load_data
from scatterbench.validation.fitting.executors import (
    DaskExecutor,
    ProcessExecutor,
    SerialExecutor,
    _chunks,
    _dask_kernel_threads,
    _local_cores,
    kernel_threads,
)
from scatterbench.validation.fitting.fitspec import fitspec_from
from scatterbench.validation.fitting.likelihood import Likelihood
from scatterbench.validation.fitting.recovery import recovery_study, subsample
from scatterbench.validation.fitting.settings import ChainSettings
from scatterbench.validation.studies.edge_sweep import classify, sweep

COATED = references.scene_path("aluminium_flakes_clearcoat.toml")
DATA = references.data_path("scatmech_flake_measurement.csv")


@pytest.fixture(scope="module")
def cluster():
    """Two single-threaded worker processes; the executor the ``--scheduler`` path builds."""
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as lc:
        with DaskExecutor(lc.scheduler_address) as ex:
            assert ex.workers == 2
            yield ex


@pytest.fixture(scope="module")
def setup():
    return scene.load(COATED), load_data(DATA)


def test_chunks_keep_order_and_cover_every_item():
    items = list(range(7))
    for n in (1, 2, 3, 7, 10):
        parts = _chunks(items, n)
        assert [x for p in parts for x in p] == items and len(parts) == min(n, 7)
        assert max(map(len, parts)) - min(map(len, parts)) <= 1


def test_map_one_task_per_item_keeps_order(cluster):
    assert cluster.map(abs, [-3, 1, -2, 5, -8], tasks=5) == [3, 1, 2, 5, 8]
    assert SerialExecutor().map(abs, [-1, 2], tasks=2) == [1, 2]


def _kernel_threads_here(_):
    import numba

    return numba.get_num_threads()


def _blas_threads_here(_):
    from threadpoolctl import threadpool_info

    return sorted({p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"})


def test_local_workers_start_with_the_executor_and_import_the_fitting_machinery():
    """A pool's workers start when it is made, not at its first map, and each imports the
    preload (the fitting machinery) as it starts: a task that imports nothing of scatterbench
    finds it loaded there, and not in a worker without the preload."""
    fit = "scatterbench.validation.fitting.fit"
    with ProcessExecutor(2) as ex:
        assert len(ex._pool._processes) == 2  # before any map
        assert ex.map(worker_probe.imported, [fit] * 2, tasks=2) == [True, True]
    with ProcessExecutor(1, preload=()) as ex:
        assert ex.map(worker_probe.imported, [fit]) == [False]


def _stamped(seconds):
    """A task: sleeps ``seconds``, then returns the time it ends."""
    time.sleep(seconds)
    return time.time()


def _interrupt():
    raise KeyboardInterrupt


def test_a_map_runs_meanwhile_here_while_its_tasks_run(cluster):
    """``meanwhile`` runs once in the calling thread after the tasks are sent, before they end
    (local processes, a cluster), and the map returns the tasks' results alone; in-process it
    runs before the items.  An error it raises propagates once the tasks have ended, an
    interrupt at once."""
    with ProcessExecutor(1) as local:
        for ex in (local, cluster):
            ran = []
            ends = ex.map(_stamped, [0.5], meanwhile=lambda ran=ran: ran.append(time.time()))
            assert len(ran) == 1 and len(ends) == 1 and ran[0] < ends[0]
            t = time.time()
            with pytest.raises(ValueError, match="meanwhile"):
                ex.map(_stamped, [0.5], meanwhile=functools.partial(int, "meanwhile"))
            assert time.time() - t >= 0.5  # the task was waited for
        t = time.time()
        with pytest.raises(KeyboardInterrupt):
            local.map(_stamped, [2.0], meanwhile=_interrupt)
        assert time.time() - t < 1.5  # an interrupt is not held back by the task
    order = []
    SerialExecutor().map(order.append, ["item"], meanwhile=lambda: order.append("meanwhile"))
    assert order == ["meanwhile", "item"]


def test_local_workers_share_the_cores_among_their_threads(monkeypatch):
    """Each local worker runs the compiled kernels and BLAS on its share of its machine's cores:
    left at numba's default (a thread per core), two workers on two cores ran the full
    report's model comparison 3.8x slower than with one thread each; left at BLAS's, the
    stability sweep on two workers took 25.2 s against 10.1 s in-process
    (benchmarks/study_workers.py)."""
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        monkeypatch.delenv(var, raising=False)  # the workers' own limits, not inherited ones
    share = max(1, _local_cores() // 2)
    with ProcessExecutor(2) as ex:
        assert ex.map(_kernel_threads_here, [0, 1], tasks=2) == [kernel_threads(2)] * 2 == [share] * 2
        assert ex.map(_blas_threads_here, [0, 1], tasks=2) == [[share]] * 2  # numpy's and scipy's
    assert kernel_threads(1) == _local_cores() and kernel_threads(10**6) == 1


def test_dask_workers_share_their_host_s_cores_among_their_kernel_threads(cluster):
    """The cluster: two single-threaded workers on this machine, a share of its cores each."""
    assert cluster.map(_kernel_threads_here, [0, 1], tasks=2) == [max(1, _local_cores() // 2)] * 2


def test_dask_workers_split_their_host_s_cores():
    """Per host, its cores over all the task threads of its workers there; at least one."""
    info = {
        "a": {"host": "h1", "nthreads": 2},
        "b": {"host": "h1", "nthreads": 2},
        "c": {"host": "h2", "nthreads": 1},
        "d": {"host": "h3", "nthreads": 8},
    }
    cores = {"a": 16, "b": 16, "c": 6, "d": 4}
    assert _dask_kernel_threads(info, cores) == {"a": 4, "b": 4, "c": 6, "d": 1}


def test_recovery_members_identical_on_a_cluster(setup, cluster):
    sc, data = setup
    spec = fitspec_from(sc, ["sigma:0.01:1:log"], ["brdf=0.1"])
    st = ChainSettings(walkers=4, seed=2, max_steps=30, check_every=30, starts=1)
    kw = dict(noise_levels=(0.05, 0.2), n_geometries=(6,), injections=3)
    serial = recovery_study(sc, spec, data, st, **kw)
    dist = recovery_study(sc, spec, data, st, executor=cluster, **kw)
    assert json.dumps(serial, sort_keys=True) == json.dumps(dist, sort_keys=True)
    # members differ from one another (seeded per member), so a reordering would show
    medians = [m["params"]["substrate.sigma"]["median"] for c in serial for m in c["members"]]
    assert len(set(medians)) == len(medians)


def test_comparison_fits_identical_on_a_cluster(setup, cluster):
    sc, data = setup
    d = subsample(data, 20)
    gauss = sc.with_values({"substrate.distribution": "gaussian"})
    liks = [Likelihood(s, fitspec_from(s, ["sigma:0.01:1:log"], ["brdf=0.1"]), d) for s in (sc, gauss)]
    st = ChainSettings(walkers=4, seed=5, max_steps=30, check_every=30, starts=1)
    rows, fits = compare_fits(liks, ["exponential", "gaussian"], st)
    rows_d, fits_d = compare_fits(liks, ["exponential", "gaussian"], st, executor=cluster)
    assert json.dumps(rows, sort_keys=True) == json.dumps(rows_d, sort_keys=True)
    assert [r["scene"] for r in rows_d] == ["exponential", "gaussian"]
    for a, b in zip(fits, fits_d, strict=True):
        assert np.array_equal(a.chain.chain, b.chain.chain)
        assert np.array_equal(a.chain.log_prob, b.chain.log_prob)
    assert not np.array_equal(fits[0].chain.chain, fits[1].chain.chain)


@dataclass(frozen=True)
class Brittle(Model):
    """Deliberately broken where ``k`` > 1.5: a division by zero at phi = 1e-12 (a warning
    and an inf), negative below it; a finding of each kind."""

    depolarizing = True
    k: float = param(1.0, "breakage", Interval(0.0, 2.0))

    def _mueller16(self, ti, tr, pr):
        out = np.zeros((16, ti.size))
        out[0] = 1.0 / (pr - 1e-12) if self.k > 1.5 else 1.0
        return out


def _as_tuples(findings):
    return [(f.model, f.params, f.kind, repr(f.value), f.where, repr(f.fields)) for f in findings]


def test_stability_sweep_identical_on_a_cluster_and_processes(cluster):
    classes = [Brittle, models.DiffuseSubsurfaceBRDF, models.FacetBTDF]
    serial = sweep(classes=classes, energy=False)
    assert {"non-finite", "negative-M00", "fp-warning"} <= {f.kind for f in serial}
    assert {f.params for f in serial} == {"Brittle(k=2.0)"}  # only the broken instance
    dist = sweep(classes=classes, energy=False, executor=cluster)
    assert _as_tuples(dist) == _as_tuples(serial)
    with ProcessExecutor(2) as ex:
        assert _as_tuples(sweep(classes=classes, energy=False, executor=ex)) == _as_tuples(serial)
    # the energy check too, on a class that passes it quickly
    energy = sweep(classes=[models.DiffuseSubsurfaceBRDF], executor=cluster)
    assert _as_tuples(energy) == _as_tuples(sweep(classes=[models.DiffuseSubsurfaceBRDF]))
    assert classify(energy)[1] == []


def test_stability_command_rejects_a_bad_worker_count(capsys):
    assert main(["stability", "--no-energy", "--workers", "0"]) == 2
    # refused by the flag's type, before anything runs
    assert "error: argument --workers: must be an integer >= 1; got 0" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["fit", "stability"])
def test_an_unreachable_scheduler_is_an_input_error(command, monkeypatch, tmp_path, capsys):
    """No scheduler at the address: ``error: scheduler: ...``, exit 2 (not an internal error)."""
    from scatterbench.validation.fitting import executors

    monkeypatch.setattr(executors, "SCHEDULER_TIMEOUT", 2)
    flags = ["--scheduler", "tcp://127.0.0.1:1"]
    if command == "fit":
        (tmp_path / "s.toml").write_text(command_files.SCENE)
        (tmp_path / "d.csv").write_text(command_files.DATA)
        argv = ["fit", str(tmp_path / "d.csv"), "--scene", str(tmp_path / "s.toml")]
        argv += ["--out", str(tmp_path / "o"), *command_files.FAST, *flags]
    else:
        argv = ["stability", "--no-energy", *flags]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "error: --scheduler 'tcp://127.0.0.1:1': port 1 is a privileged port" in err
    assert "internal" not in err
