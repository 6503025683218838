"""Studies of the full report (the model comparison, the stability sweep, the recovery) in-process
and on local worker processes, in one run.

    python benchmarks/study_workers.py [--study comparison|sweep|recovery|tradeoff|presets|report|
                                               comparison-quick|recovery-quick|sweep-quick]
                                      [--workers 1 2 dask2] [--baseline DIR] [--warm]

``comparison`` (the default) runs :func:`scatterbench.validation.fitting.compare.seed003_pairing` with the
full report's settings (:func:`scatterbench.validation.checks.fitting.comparison_settings`: 8 fits, 24
walkers, differential evolution to N >= 50 tau); ``sweep`` runs the full stability sweep
(:func:`scatterbench.validation.studies.edge_sweep.sweep`, energy integrals included: ~300 small tasks);
``recovery`` the full report's injection-recovery study (100 small fits to N >= 50 tau; a
tree whose study cannot be given an executor is refused); ``tradeoff`` the quick trade-off study
(its errors: the costs are timings); ``presets`` the quick seed 003 presets section (its Monte
Carlo preset included); ``report`` the whole ``report --quick``, its results.json without the
run's timings (:func:`scatterbench.validation.report.timing.results_digest`); ``*-quick`` a
study with ``report --quick``'s settings.  ``--workers`` takes ``N`` (local processes; 1 is
in-process) or ``daskN`` (a ``LocalCluster`` of N one-thread worker processes, started before
the clock).
Each ``--workers`` value runs in a fresh process, and prints the seconds and a digest of the
results (every fit's chain and table row; every finding): the digests must be equal (the
results do not depend on the executor), and the command exits 1 when they are not.
``--baseline DIR``: another checkout (e.g. ``git archive <commit> | tar -x -C DIR``) run the
same way, alternating with this one, for before/after figures.  A tree never run before compiles its kernels in its first run (numba's
cache is keyed by the source files' paths): ``--warm`` runs each tree once in-process,
untimed, first.  The machine's load is printed before and after: figures from a shared
machine are noisy.

Measured 2026-11-29 on the shared 2-core machine (load average 4.9-8.4), ``--study report
--workers 1 2 dask2``: 578.3 s in-process, 309.5 s on 2 local workers, 295.8 s on a 2-worker
LocalCluster, the same digest (a0e5d461970ddfe0) for all three.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
from benchmarks.checkouts import environment  # noqa: E402

# run inside the checkout given as argv[1]; a __main__ guard, since workers are spawned
CHILD = r"""
import hashlib, importlib, sys, time

def mod(name):
    try:
        return importlib.import_module("scatterbench." + name)
    except ImportError:  # a checkout from before the one namespace
        return importlib.import_module(name)

def comparison(ex):
    comparison_settings = mod("validation.checks.fitting").comparison_settings
    seed003_pairing = mod("validation.fitting.compare").seed003_pairing

    h = hashlib.sha1()
    for c in seed003_pairing(**comparison_settings(False), executor=ex):
        for f in c["fits"]:
            h.update(f.chain.chain.tobytes())
        h.update(repr(c["rows"]).encode())
    return h

def sweep(ex):
    try:
        sweep = mod("validation.studies.edge_sweep").sweep
    except ImportError:  # a checkout from before the sweep's module was named edge_sweep
        sweep = mod("validation.studies.stability").sweep
    # what each finding says, not its type's repr (which a tree's Finding fields change)
    found = [(f.model, f.params, f.kind, f.value, f.where, f.fields) for f in sweep(energy=True, executor=ex)]
    return hashlib.sha1(repr(found).encode())

def recovery(ex):
    import inspect
    _recovery = mod("validation.checks.fitting")._recovery
    SEED = mod("validation.checks.registry").SEED

    if "executor" not in inspect.signature(_recovery).parameters:
        raise SystemExit("this tree's recovery study runs on its own executor only")
    return hashlib.sha1(repr(_recovery(False, SEED, ex)).encode())

def quick(name):
    # a study with the report --quick's settings (what a report --quick runs)
    fitting = mod("validation.checks.fitting")
    SEED = mod("validation.checks.registry").SEED

    def run(ex):
        if name == "comparison-quick":
            out = mod("validation.fitting.compare").seed003_pairing(**fitting.comparison_settings(True), executor=ex)
            return hashlib.sha1(repr([(c["rows"], [f.chain.chain.tobytes() for f in c["fits"]]) for c in out]).encode())
        if name == "recovery-quick":
            return hashlib.sha1(repr(fitting._recovery(True, SEED, ex)).encode())
        found = mod("validation.studies.edge_sweep").sweep(energy=False, executor=ex)
        return hashlib.sha1(repr([(f.model, f.params, f.kind, f.value, f.where, f.fields) for f in found]).encode())
    return run

def tradeoff(ex):
    # the errors, settings and evaluations of every knob; the costs are timings
    knobs = mod("validation.studies.tradeoff").study(quick=True, executor=ex)
    return hashlib.sha1(repr([(k.knob, [(p.setting, p.error, p.evaluations) for p in k.points]) for k in knobs]).encode())

def presets(ex):
    Context = mod("validation.report.core").Context
    d = mod("validation.report.sections.seed003_presets").compute(Context(quick=True, executor=ex))
    return hashlib.sha1(repr((d.tracked, d.fit_rows, d.table_rows)).encode())

def report(ex):
    # the whole report --quick; its results.json without the run's timings
    build = mod("validation.report.build")
    results, _ = build.build_report(quick=True, executor=ex)
    return hashlib.sha1(mod("validation.report.timing").results_digest(results).encode())

STUDIES = {"comparison": comparison, "sweep": sweep, "recovery": recovery, "tradeoff": tradeoff,
           "presets": presets, "report": report, "comparison-quick": quick("comparison-quick"),
           "recovery-quick": quick("recovery-quick"), "sweep-quick": quick("sweep-quick")}

def executor(spec):
    # N: N local processes (1: in-process); daskN: a LocalCluster of N one-thread workers
    ex = mod("validation.fitting.executors")
    if not spec.startswith("dask"):
        return ex.make_executor(int(spec), None), None
    from dask.distributed import LocalCluster
    lc = LocalCluster(n_workers=int(spec[4:]), threads_per_worker=1, processes=True, dashboard_address=None)
    return ex.DaskExecutor(lc.scheduler_address), lc

def main():
    ex, cluster = executor(sys.argv[2])  # a cluster's start is not the study's; a local pool starts on use
    t = time.perf_counter()
    with ex:
        h = STUDIES[sys.argv[3]](ex)
    print(f"{time.perf_counter() - t:.1f} {h.hexdigest()[:16]}")
    if cluster is not None:
        cluster.close()

if __name__ == "__main__":
    main()
"""


STUDY_NAMES = (
    "comparison",
    "sweep",
    "recovery",
    "tradeoff",
    "presets",
    "report",
    "comparison-quick",
    "recovery-quick",
    "sweep-quick",
)


def timed(checkout, workers, study):
    """``(seconds, digest)`` of ``study`` from ``checkout`` on ``workers`` processes."""
    r = subprocess.run(
        [sys.executable, "-c", CHILD, checkout, str(workers), study],
        env=environment(checkout),
        capture_output=True,
        text=True,
        cwd=checkout,
    )
    if r.returncode != 0:
        raise RuntimeError(f"{checkout}, workers {workers}: exit {r.returncode}\n{r.stderr}")
    seconds, digest = r.stdout.split()[-2:]
    return float(seconds), digest


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", choices=STUDY_NAMES, default="comparison")
    ap.add_argument(
        "--workers", nargs="+", default=["1", "2"], help="N local processes (1: in-process) or daskN"
    )
    ap.add_argument("--baseline", help="another checkout, run the same way for before/after figures")
    ap.add_argument("--warm", action="store_true", help="run each tree once, untimed, first")
    args = ap.parse_args()
    trees = [("this checkout", ROOT)] + ([("baseline", args.baseline)] if args.baseline else [])
    for _, tree in trees if args.warm else ():
        timed(tree, 1, args.study)
    print(f"load before: {os.getloadavg()}")
    digests = set()
    for w in args.workers:
        for name, tree in trees:
            seconds, digest = timed(tree, w, args.study)
            digests.add(digest)
            print(f"{name:<14} workers {w:>5}: {seconds:7.1f} s  digest {digest}")
    print(f"load after: {os.getloadavg()}")
    if len(digests) != 1:
        sys.exit("RESULTS DIFFER between executors or checkouts: the results must not depend on them")
    print("results identical across executors and checkouts")


if __name__ == "__main__":
    main()
