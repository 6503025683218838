"""How the work scales with cores, in one run: the kernels by thread count, each study by worker
count, and the first ``report --quick`` cold and warm.

    python benchmarks/scaling.py [--geometries 1000000] [--threads 1 2 ...] [--workers 1 2 ...]
                                 [--studies sweep-quick presets ...] [--first-run [--pairs N] [--full]]
                                 [--compile]
                                 [--repeat 3]

* **Kernels.** ``FacetBRDF.mueller16`` (Gaussian slopes, aluminium, no shadowing) on ``--geometries``
  random geometries, ``numba.set_num_threads(t)`` for every ``t`` in ``--threads`` (default
  1 .. the cores of this process's affinity mask): the best of ``--repeat`` calls, into a fresh
  result and into ``out=``, in ns per geometry, and the speedup over one thread.
* **Studies.** Each study of ``--studies`` (the names of ``benchmarks/study_workers.py``; default
  the ``report --quick`` studies: comparison, recovery, sweep, trade-off, presets) in a fresh
  process per worker count of ``--workers`` (default 1, 2, 4, ... and the cores): seconds,
  speedup over one worker, and the digest of its results, which must be equal for every
  worker count (the command exits 1 when they are not).
* **First run** (``--first-run``): ``scatterbench report --quick`` (with ``--full``, the
  full ``scatterbench report``) with an empty numba cache (``NUMBA_CACHE_DIR`` a fresh folder:
  every kernel compiles) and then again with that cache (warm), with the default ``--workers``,
  ``--pairs`` times: the seconds of each and their ratio.
* **Compilation** (``--compile``): each compile group of a report
  (``validation.report.build.every_compile_group``: a kernel's loops, or the Monte Carlo, aperture or
  disc entries, grouped by the helpers they share; the last ones compiled beside the sections
  after the others) in a fresh process, as a report's worker
  takes it, its tasks in turn, with one empty numba cache: wall and CPU seconds per task, per
  group, and their sum (what the report's worker processes share on a first run).

The machine's load average is printed before and after each part: figures from a shared
machine are noisy.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
from benchmarks.study_workers import STUDY_NAMES, timed  # noqa: E402

#: the studies a report --quick runs on its executor (study_workers' names)
REPORT_STUDIES = ("comparison-quick", "recovery-quick", "sweep-quick", "tradeoff", "presets")


def cores():
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def _load():
    return "load average " + " ".join(f"{x:.2f}" for x in os.getloadavg())


def _best(fn, repeat):
    best = math.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def kernels(n, threads, repeat):
    """ns per geometry of FacetBRDF's Mueller matrix (``mueller16``: the kernels' element-major
    layout) at each thread count, into a fresh result and into ``out=``."""
    import numba

    from scatterbench import models

    m = models.FacetBRDF(slopes=models.GaussianSlopes(0.2), substrate=1.37 + 7.62j)
    rng = np.random.default_rng(1)
    ti, tr = rng.uniform(0.0, 1.4, (2, n))
    pr = rng.uniform(-math.pi, math.pi, n)
    out = np.empty((16, n))  # element-major, as the kernels write it
    m.mueller16(ti, tr, pr, out=out)  # compiles or loads the kernels, touches out
    print(f"\nkernels: FacetBRDF (Gaussian 0.2, Al), {n} geometries, best of {repeat}; {_load()}")
    print(f"{'threads':>7}  {'fresh ns/geom':>13}  {'speedup':>7}  {'out= ns/geom':>12}  {'speedup':>7}")
    base = None
    for t in threads:
        numba.set_num_threads(min(t, numba.config.NUMBA_NUM_THREADS))
        fresh = _best(lambda: m.mueller16(ti, tr, pr), repeat) / n * 1e9
        into = _best(lambda: m.mueller16(ti, tr, pr, out=out), repeat) / n * 1e9
        base = base or (fresh, into)
        print(f"{t:>7}  {fresh:>13.1f}  {base[0] / fresh:>7.2f}  {into:>12.1f}  {base[1] / into:>7.2f}")


def studies(names, workers):
    """Each study on each worker count, in a fresh process; False when a study's digests differ."""
    ok = True
    for name in names:
        print(f"\nstudy {name}: {_load()}")
        digests, base = set(), None
        for w in workers:
            seconds, digest = timed(ROOT, str(w), name)
            base = base or seconds
            digests.add(digest)
            print(f"  workers {w:>3}: {seconds:8.1f} s  speedup {base / seconds:5.2f}  digest {digest}")
        if len(digests) != 1:
            print(f"  RESULTS DIFFER between worker counts for {name}")
            ok = False
    return ok


def first_run(pairs=1, full=False):
    """``report --quick`` (``report`` where ``full``) with an empty numba cache, then warm, each in
    a fresh process, ``pairs`` times (a fresh cache each): per pair the whole command's seconds,
    ``results.json``'s and the cold run's ratio to the warm one, then the ratios' range (a shared
    host moves them by more than one pair shows). False when a cold run's results differ from
    its warm run's (``results_digest``: the timings left out)."""
    from scatterbench.validation.report.timing import results_digest

    quick = [] if full else ["--quick"]
    name = " ".join(["scatterbench report", *quick])
    print(f"\nfirst run: {name}, {pairs} pair(s); {_load()}")
    ratios, ok = [], True
    for k in range(pairs):
        with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as out:
            env = dict(os.environ, NUMBA_CACHE_DIR=cache)
            walls, seconds, digests = [], [], []
            for label in ("cold (empty numba cache)", "warm"):
                t = time.perf_counter()
                cmd = [sys.executable, "-m", "scatterbench.validation.cli", "report", *quick, "--out", out]
                r = subprocess.run(cmd, env=env, capture_output=True, text=True)
                walls.append(time.perf_counter() - t)
                if r.returncode not in (0, 1):  # 1: a check failed, the report still written
                    sys.exit(f"{name} exited {r.returncode}:\n{r.stderr[-2000:]}")
                with open(os.path.join(out, "results.json"), encoding="utf-8") as f:
                    results = json.load(f)
                seconds.append(results["meta"]["seconds"])
                digests.append(results_digest(results))
                print(
                    f"  pair {k + 1} {label:<25} {walls[-1]:7.1f} s  results.json {seconds[-1]:6.1f} s"
                    f"  exit {r.returncode}  digest {digests[-1]}  {phases(results)}"
                )
            if digests[0] != digests[1]:
                print(f"  pair {k + 1}: RESULTS DIFFER between the cold and the warm run")
                ok = False
            ratios.append(walls[0] / walls[1])
            print(
                f"  pair {k + 1} cold / warm: {ratios[-1]:.2f} of wall, {seconds[0] / seconds[1]:.2f} of results.json"
            )
    print(f"  cold / warm of wall over {pairs} pair(s): {min(ratios):.2f} - {max(ratios):.2f}; {_load()}")
    return ok


def phases(results):
    """Where a report's seconds went (``meta.phase_seconds``): before its sections, its sections
    side by side (what more workers shorten), then one at a time (what they do not)."""
    p = results["meta"].get("phase_seconds")
    return (
        ""
        if p is None
        else f"(start {p['start']:.1f}, beside {p['beside']:.1f}, in turn {p['in turn']:.1f} s)"
    )


_COMPILE = """
import sys, time
from scatterbench.validation.report.build import every_compile_group, warm_task
total = 0.0
for task in every_compile_group()[int(sys.argv[1])]:
    t, c = time.perf_counter(), time.process_time()
    warm_task(task)
    cpu = time.process_time() - c
    total += cpu
    sets = "all" if task[2] is None else len(task[2])
    loops = f"option sets {sets!s:>3}" + (" + scalar" if task[3] else "         ")
    print(f"  {task[0]:<10} {task[1] or '':<8} {loops}  {time.perf_counter() - t:6.1f} s  cpu {cpu:6.1f} s")
print(f"  group {sys.argv[1]}: cpu {total:.1f} s")
"""


def compile_tasks():
    """The report's compile-ahead groups, each in a fresh process as the report's workers take
    them (its tasks one after another), all with one empty cache."""
    print(
        f"\ncompilation: the report's compile-ahead groups, a fresh process each, empty numba cache; {_load()}"
    )
    from scatterbench.validation.report.build import every_compile_group

    total = 0.0
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        for g in range(len(every_compile_group())):
            r = subprocess.run(
                [sys.executable, "-c", _COMPILE, str(g)], env=env, check=True, capture_output=True, text=True
            )
            print(r.stdout, end="")
            total += float(r.stdout.rsplit("cpu", 1)[1].split()[0])
    print(f"  all groups: cpu {total:.1f} s (half of it on each of two cores at best)")


def _powers(top):
    out, k = [], 1
    while k < top:
        out.append(k)
        k *= 2
    return out + [top]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--geometries", type=float, default=1e6)
    ap.add_argument("--threads", type=int, nargs="+", default=None)
    ap.add_argument("--workers", type=int, nargs="+", default=None)
    ap.add_argument("--studies", nargs="*", choices=STUDY_NAMES, default=list(REPORT_STUDIES))
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--first-run", action="store_true", help="also time report --quick cold and warm")
    ap.add_argument("--pairs", type=int, default=1, help="cold and warm pairs of --first-run (default 1)")
    ap.add_argument("--full", action="store_true", help="--first-run times the full report, not --quick")
    ap.add_argument("--compile", action="store_true", help="also time each compile-ahead task, empty cache")
    args = ap.parse_args()
    c = cores()
    print(f"{c} cores in this process's affinity mask; {_load()}")
    kernels(int(args.geometries), args.threads or list(range(1, c + 1)), args.repeat)
    ok = studies(args.studies, args.workers or _powers(c))
    if args.compile:
        compile_tasks()
    if args.first_run:
        ok = first_run(args.pairs, args.full) and ok
    print(f"\nend; {_load()}")
    if not ok:
        sys.exit("RESULTS DIFFER: the results must not depend on the worker count or the numba cache")


if __name__ == "__main__":
    main()
