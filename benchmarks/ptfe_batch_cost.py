"""What one batch of walkers costs each PTFE model, and where a batch's time goes.

    python benchmarks/ptfe_batch_cost.py [--models rough_diffuse,smooth_diffuse] [--wavelength 532]
                                         [--row-step 24] [--walkers W] [--top 4]

For each model's per-wavelength scene (``references/scenes/ptfe_<model>_per_wavelength.toml``)
on every ``--row-step``-th row of NIST's file at ``--wavelength`` (the study's own selection,
:func:`scatterbench.validation.studies.ptfe.select_rows`), on one thread: the best of three
batches of log-likelihoods at new positions (``--walkers``, default twice the free parameters,
emcee's least), then one more under cProfile, whose ``--top`` functions by own time are printed
with their share of it.  The study's cost per step is about one such batch.
"""

from __future__ import annotations

import argparse
import cProfile
import os
import pstats
import sys
import time

import numba
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from scatterbench.models import scene as scene_mod  # noqa: E402
from scatterbench.references import nist_ptfe_path  # noqa: E402
from scatterbench.validation.fitting.mueller_data import load_mueller_data  # noqa: E402
from scatterbench.validation.fitting.mueller_fit import mueller_likelihood  # noqa: E402
from scatterbench.validation.fitting.sampling import _default_start  # noqa: E402
from scatterbench.validation.studies import ptfe  # noqa: E402


def batch_cost(name, data, walkers, top):
    """``(walkers, best seconds, [(function, own seconds)])`` of one batch of model ``name``."""
    lik = mueller_likelihood(scene_mod.load(ptfe.scene_path(ptfe.scene_file(name))), data)
    u0 = _default_start(lik, lik.spec.u_bounds())
    rng = np.random.default_rng(0)
    W = walkers or 2 * len(u0)
    U = u0 + 1e-3 * rng.standard_normal((W, len(u0)))
    lik.batch(U)  # compile or load the kernels
    best = float("inf")
    for _ in range(3):
        V = U + 1e-6 * rng.standard_normal(U.shape)
        t = time.perf_counter()
        lik.batch(V)
        best = min(best, time.perf_counter() - t)
    prof = cProfile.Profile()
    prof.enable()
    lik.batch(U + 1e-6 * rng.standard_normal(U.shape))
    prof.disable()
    stats = pstats.Stats(prof).stats
    total = sum(v[2] for v in stats.values())
    own = sorted(((v[2], f"{os.path.basename(k[0])}:{k[2]}") for k, v in stats.items()), reverse=True)
    return W, best, [(fn, s, s / total) for s, fn in own[:top]]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--models", default="rough_diffuse,smooth_diffuse")
    ap.add_argument("--wavelength", type=float, default=532.0)
    ap.add_argument("--row-step", type=int, default=24)
    ap.add_argument("--walkers", type=int, default=0)
    ap.add_argument("--top", type=int, default=4)
    args = ap.parse_args(argv)
    numba.set_num_threads(1)
    data = load_mueller_data(nist_ptfe_path())
    data = data.subset(ptfe.select_rows(data, args.wavelength, args.row_step))
    print(f"{len(data)} rows at {args.wavelength:g} nm, one thread; load average {os.getloadavg()}")
    for name in args.models.split(","):
        W, best, top = batch_cost(name, data, args.walkers, args.top)
        print(f"{name}: {best:.3f} s per batch of {W} walkers ({best / W * 1e3:.1f} ms a walker)")
        for fn, s, share in top:
            print(f"    {fn:<40} {s:.3f} s ({share:.0%} of the profiled batch)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
