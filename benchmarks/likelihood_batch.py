"""What one batch of walkers costs each likelihood of the report's two fit studies, this
checkout against another in one run, and whether the two give the same bits.

    python benchmarks/likelihood_batch.py [--baseline DIR] [--walkers W] [--batches 300]
                                          [--rounds 3]

The model comparison (:func:`scatterbench.validation.checks.fitting.comparison_settings`)
samples seed 003's two hypotheses on two data sets, with every term and with the BRDF alone:
8 likelihoods of 200 rows, each called by emcee with half its 24 walkers at a time (the moves
update one half of the ensemble against the other), 2400 geometries a call; the recovery study
(:func:`~scatterbench.validation.checks.fitting.recovery_settings`) fits 8 rows with 16
walkers, 64 geometries a call.  A chain's time is mostly these calls, and a call's mostly the
Python and numpy around its kernels (about a tenth of a comparison call, less of a recovery
one).  For each likelihood, on one thread, this prints the best of ``--rounds`` mean times of
``--batches`` calls at fixed positions near the middle of the prior (``--walkers`` of them;
default half the study's walkers), the trees alternating round by round in processes of
their own, and a digest of the values at 64 positions: the digests must be equal (the change
kept the bits), else the command exits 1; with ``--rtol R`` a change that moves the values
(another order of operations, another libm function) passes where the largest difference, relative
to the values', is at most ``R`` and prints it.  ``--baseline DIR``: another checkout (e.g. ``git
archive <commit> | tar -x -C DIR``).
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
from benchmarks.checkouts import environment  # noqa: E402

CHILD = r"""
import hashlib, sys, time
import numba
import numpy as np
from scatterbench import references
from scatterbench.models import scene as scene_mod
from scatterbench.validation.checks import fitting
from scatterbench.validation.fitting.compare import _pairing_cases
from scatterbench.validation.fitting.datafile import load_data
from scatterbench.validation.fitting.fitspec import fitspec_from
from scatterbench.validation.fitting.likelihood import Likelihood
from scatterbench.validation.fitting.recovery import subsample

numba.set_num_threads(1)
walkers, batches = int(sys.argv[1]), int(sys.argv[2])
cfg = fitting.comparison_settings(False)
cases, groups = _pairing_cases(cfg["rows"], ("all", "brdf"))
todo = [
    ((case["generator"], case["terms"], name), lik, walkers or cfg["settings"].walkers // 2)
    for case, (liks, names) in zip(cases, groups)
    for lik, name in zip(liks, names)
]
rs = fitting.recovery_settings(False)
sc = scene_mod.load(references.scene_path(fitting.RECOVERY_SCENE))
data = subsample(load_data(references.data_path(fitting.RECOVERY_DATA)), rs["n_geometries"][0])
rec = Likelihood(sc, fitspec_from(sc, rs["free"], rs["noise"]), data)
todo.append((("recovery", "brdf", "flakes"), rec, walkers or rs["chain"].walkers // 2))
for key, lik, w in todo:
    b = lik.spec.u_bounds()
    rng = np.random.default_rng(7)
    mid, width = b.mean(axis=1), b[:, 1] - b[:, 0]
    probe = mid + 0.02 * width * rng.standard_normal((64, len(mid)))
    values = lik.batch(probe)
    digest = hashlib.sha1(values.tobytes()).hexdigest()[:16]
    U = probe[:w]
    lik.batch(U)
    t = time.perf_counter()
    for _ in range(batches):
        lik.batch(U)
    us = (time.perf_counter() - t) / batches * 1e6
    print(*key, w, f"{us:.1f}", digest, ",".join(map(float.hex, values.tolist())))
"""


def run(tree, walkers, batches):
    r = subprocess.run(
        [sys.executable, "-c", CHILD, str(walkers), str(batches)],
        env=dict(environment(tree), NUMBA_NUM_THREADS="1"),
        capture_output=True,
        text=True,
        cwd=tree,
    )
    if r.returncode != 0:
        raise SystemExit(f"{tree}: exit {r.returncode}\n{r.stderr[-3000:]}")
    return {
        tuple(f[:4]): (float(f[4]), f[5], [float.fromhex(x) for x in f[6].split(",")])
        for f in (ln.split() for ln in r.stdout.splitlines())
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", help="another checkout, run the same way, alternating")
    ap.add_argument(
        "--walkers", type=int, default=0, help="positions a call (default: half the study's walkers)"
    )
    ap.add_argument("--batches", type=int, default=300, help="calls a round (default 300)")
    ap.add_argument("--rounds", type=int, default=3, help="rounds, each tree in a fresh process (default 3)")
    ap.add_argument(
        "--rtol",
        type=float,
        default=0.0,
        help="largest relative difference of the values allowed (default 0: the same bits)",
    )
    args = ap.parse_args()
    trees = [("this", ROOT)] + ([("baseline", args.baseline)] if args.baseline else [])
    best = {name: {} for name, _ in trees}
    for _ in range(args.rounds):
        for name, tree in trees:
            for key, (us, digest, values) in run(tree, args.walkers, args.batches).items():
                old = best[name].get(key, (float("inf"),))
                best[name][key] = (min(old[0], us), digest, values)
    print(f"us a call, best of {args.rounds} rounds of {args.batches} calls, one thread")
    head = f"{'data':<14}{'terms':<6}{'hypothesis':<15}{'walkers':>8}{'this':>9}"
    print(head + (f"{'baseline':>10}{'ratio':>8}  bits" if args.baseline else "  digest"))
    worst = 0.0
    for key, (us, digest, values) in best["this"].items():
        line = f"{key[0]:<14}{key[1]:<6}{key[2]:<15}{key[3]:>8}{us:9.1f}"
        if args.baseline:
            bus, bdigest, bvalues = best["baseline"][key]
            diff = _relative(values, bvalues)
            worst = max(worst, diff)
            bits = "same" if bdigest == digest else f"DIFFER by {diff:.1e}"
            line += f"{bus:10.1f}{bus / us:7.2f}x  {bits}"
        else:
            line += f"  {digest}"
        print(line)
    if worst > args.rtol:
        sys.exit(
            f"the likelihoods' values differ between the trees by {worst:.1e} (relative), more than --rtol {args.rtol:g}"
        )


def _relative(a, b):
    """The largest difference of two lists of values relative to their magnitude (infinite where
    one is finite and the other not, 0 where both are the same infinity)."""
    a, b = (np.asarray(x, dtype=float) for x in (a, b))
    same = a == b
    if not np.array_equal(np.isfinite(a), np.isfinite(b)) or not np.all(same | np.isfinite(a)):
        return math.inf
    return float(np.max(np.where(same, 0.0, np.abs(a - b) / np.maximum(np.abs(a), np.abs(b)))))


if __name__ == "__main__":
    main()
