"""Steps to convergence of the model comparison's chains under each ensemble move.

    python benchmarks/fit_moves.py [--max-steps 12000]

Runs the report's full seed 003 model comparison
(:func:`scatterbench.validation.checks.fitting.comparison_settings`) once with emcee's stretch move and
once with the differential-evolution mixture (``ChainSettings.moves``), the same seed and
step budget, and prints per fit the final ``max tau``, the steps run, whether ``N >= 50
tau`` was reached, and each run's time.  It is why the report's comparison uses ``"de"``.

The figures cited in :func:`scatterbench.validation.checks.fitting.comparison_settings` come from::

    python benchmarks/fit_moves.py --max-steps 2000

(the default budget is the report's, 12000 steps).  Measured 2026-11-24 on 2 shared cores:
stretch 0/8 converged at 2000 steps (max tau 43.8-156.4, 491 s), "de" 5/8 (converged at
800-1900 steps; the other three at max tau 52.2-151.7, 262 s).
"""

from __future__ import annotations

import os
import sys

# the checkout's packages, not an installed copy, when run as ``python benchmarks/...``
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import argparse
import time

from scatterbench.validation.checks.fitting import comparison_settings
from scatterbench.validation.fitting.compare import seed003_pairing


def run(moves, max_steps):
    s = comparison_settings(False)
    settings = s["settings"].replace(moves=moves, max_steps=max_steps)
    t = time.perf_counter()
    cases = seed003_pairing(settings, rows=s["rows"])
    seconds = time.perf_counter() - t
    rows = [
        (c["generator"], c["terms"], r["scene"], f.chain.tau.max(), f.chain.chain.shape[0], f.chain.converged)
        for c in cases
        for r, f in zip(c["rows"], c["fits"], strict=True)
    ]
    return rows, seconds


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max-steps", type=int, default=comparison_settings(False)["settings"].max_steps)
    args = ap.parse_args()
    print(f"{'data':<14}{'terms':<7}{'hypothesis':<15}{'moves':<9}{'max tau':>9}{'steps':>7}  N >= 50 tau")
    for moves in ("stretch", "de"):
        rows, seconds = run(moves, args.max_steps)
        for g, t, h, tau, steps, ok in rows:
            print(f"{g:<14}{t:<7}{h:<15}{moves:<9}{tau:9.1f}{steps:7d}  {'yes' if ok else 'NO'}")
        print(f"{moves}: {sum(r[5] for r in rows)}/{len(rows)} converged, {seconds:.1f} s\n")


if __name__ == "__main__":
    main()
