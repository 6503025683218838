"""Studies of the full report (the model comparison, the stability sweep, the recovery) in-process
and on local worker processes, in one run.

    python benchmarks/study_workers.py [--study comparison|sweep|recovery] [--workers 1 2]
                                      [--baseline DIR] [--warm]

``comparison`` (the default) runs :func:`scatterbench.validation.fitting.compare.seed003_pairing` with the
full report's settings (:func:`scatterbench.validation.checks.fitting.comparison_settings`: 8 fits, 24
walkers, differential evolution to N >= 50 tau); ``sweep`` runs the full stability sweep
(:func:`scatterbench.validation.studies.edge_sweep.sweep`, energy integrals included: ~300 small tasks);
``recovery`` the full report's injection-recovery study (100 small fits to N >= 50 tau; a
tree whose study cannot be given an executor is refused).
Each ``--workers`` value runs in a fresh process, and prints the seconds and a digest of the
results (every fit's chain and table row; every finding): the digests must be equal (the
results do not depend on the executor), and the command exits 1 when they are not.
``--baseline DIR``: another checkout (e.g. ``git archive <commit> | tar -x -C DIR``) run the
same way, alternating with this one, for before/after figures.  A tree never run before compiles its kernels in its first run (numba's
cache is keyed by the source files' paths): ``--warm`` runs each tree once in-process,
untimed, first.  The machine's load is printed before and after: figures from a shared
machine are noisy.
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

def main():
    make_executor = mod("validation.fitting.executors").make_executor

    t = time.perf_counter()
    with make_executor(int(sys.argv[2]), None) as ex:
        h = {"comparison": comparison, "sweep": sweep, "recovery": recovery}[sys.argv[3]](ex)
    print(f"{time.perf_counter() - t:.1f} {h.hexdigest()[:16]}")

if __name__ == "__main__":
    main()
"""


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
    ap.add_argument("--study", choices=("comparison", "sweep", "recovery"), default="comparison")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
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
            print(f"{name:<14} workers {w}: {seconds:7.1f} s  digest {digest}")
    print(f"load after: {os.getloadavg()}")
    if len(digests) != 1:
        sys.exit("RESULTS DIFFER between executors or checkouts: the results must not depend on them")
    print("results identical across executors and checkouts")


if __name__ == "__main__":
    main()
