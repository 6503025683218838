"""Every chain of the report's full model comparison, one after another on one thread, under
each burn-in: what bounds the comparison on many workers.

    python benchmarks/comparison_chains.py [--burn 0 1000] [--walkers 24 48] [--threads 1]

The comparison (:func:`scatterbench.validation.checks.fitting.comparison_settings`, seed 003's
pairing: 8 fits of two chains each) runs its 16 chains as 16 tasks, so on enough workers it
takes as long as its longest chain, and in-process as long as all of them.  For each burn-in
(``ChainSettings.burn``: steps run before the kept chain, not kept) this prints each chain's
seconds (burn-in included) and their split (the optimum its chain starts from, the burn-in,
the kept chain), kept steps, max tau and whether it reached N >= 50 tau, then the sum, the
longest, and their ratio: the most any number of workers can speed the comparison up over one
process.  ``--walkers`` runs them again with each other ensemble size (default: the
comparison's own), to see whether more walkers shorten the longest chain's steps (its tau) by
more than they lengthen each step.
"""

from __future__ import annotations

import os
import sys

# the checkout's packages, not an installed copy, when run as ``python benchmarks/...``
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import argparse
import time

from scatterbench.validation.checks.fitting import comparison_settings
from scatterbench.validation.fitting.compare import _pairing_cases
from scatterbench.validation.fitting.diagnostics import chain_seed
from scatterbench.validation.fitting.fit import run_fit


def chains(burn, walkers=None):
    """``[(data, terms, hypothesis, chain, seconds, steps, max tau, converged, (optimum, burn-in,
    kept chain seconds))]`` under ``burn`` (and ``walkers``, default the comparison's)."""
    cfg = comparison_settings(False)
    settings = cfg["settings"].replace(walkers=walkers or cfg["settings"].walkers)
    cases, groups = _pairing_cases(cfg["rows"], ("all", "brdf"))
    out = []
    for case, (liks, names) in zip(cases, groups, strict=True):
        for lik, name in zip(liks, names, strict=True):
            # untimed: its kernels loaded (or compiled), so that a hypothesis's first chain is
            # timed as the later ones are (before 2026-12-07 the first paid ~0.5 s for that on a
            # warm cache, and a later --walkers run in the same process would not have)
            lik(lik.spec.u_bounds().mean(axis=1))
            for c in range(cfg["chains"]):
                s = settings.replace(seed=chain_seed(settings.seed, c), burn=burn)
                t = time.perf_counter()
                fit = run_fit(lik, s)
                total, ch = time.perf_counter() - t, fit.chain
                burned = fit.summary["sampling"]["burned_before_chain"]["seconds"]
                split = (total - burned - ch.seconds, burned, ch.seconds)
                row = (case["generator"], case["terms"], name, c, total)
                out.append(row + (ch.steps, float(ch.tau.max()), ch.converged, split))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--burn", type=int, nargs="+", default=[0, comparison_settings(False)["settings"].burn])
    ap.add_argument(
        "--walkers", type=int, nargs="+", default=[None], help="ensemble sizes (default: the comparison's)"
    )
    ap.add_argument("--threads", type=int, default=1, help="numba threads (default 1: a worker's share)")
    args = ap.parse_args()
    import numba

    numba.set_num_threads(min(args.threads, numba.config.NUMBA_NUM_THREADS))
    print(
        f"{'data':<14}{'terms':<6}{'hypothesis':<15}{'chain':>5}{'burn':>6}{'seconds':>9}"
        f"{'optimum':>9}{'burn-in':>9}{'kept':>7}{'steps':>7}{'max tau':>9}  N >= 50 tau"
    )
    for walkers in args.walkers:
        for burn in args.burn:
            report(chains(burn, walkers), burn, walkers)


def report(rows, burn, walkers):
    for g, t, h, c, sec, steps, tau, ok, (opt, burned, kept) in rows:
        print(
            f"{g:<14}{t:<6}{h:<15}{c:>5}{burn:>6}{sec:9.1f}{opt:9.1f}{burned:9.1f}{kept:7.1f}"
            f"{steps:7d}{tau:9.1f}  {'yes' if ok else 'NO'}"
        )
    total, longest = sum(r[4] for r in rows), max(r[4] for r in rows)
    size = f"{walkers} walkers" if walkers else "the comparison's walkers"
    print(
        f"burn {burn}, {size}: {sum(r[7] for r in rows)}/{len(rows)} chains converged; {total:.1f} s in all, "
        f"the longest {longest:.1f} s: at most {total / longest:.1f}x on any number of workers\n",
        flush=True,
    )


if __name__ == "__main__":
    main()
