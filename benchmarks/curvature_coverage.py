"""Coverage of the optimum's curvature intervals over many injections: is the estimator's own
distribution Gaussian enough for nominal coverage, independent of any sampler?

For each cell (number of geometries x speckle level) this simulates ``--injections`` data sets
from the coated-flake scene at its values (seeded), finds the least-squares optimum of sigma and
the coating index (:func:`scatterbench.validation.fitting.sampling.optimize`) and counts how often the truth lies
within 1 and 2 Gauss-Newton standard deviations (sampling coordinates).  Cheap (~10 ms an
injection), so thousands of injections pin coverage to a few tenths of a percent, far tighter
than the 50-injection MCMC recovery study can; the study's own ``curvature`` columns are the same
check on its data sets.

    python benchmarks/curvature_coverage.py [--injections 3000] [--seed 7]
"""

from __future__ import annotations

import os
import sys

# the checkout's packages, not an installed copy, when run as ``python benchmarks/...``
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import argparse
import math
import time

import numpy as np

from scatterbench import references
from scatterbench.models import scene
from scatterbench.validation.fitting.datafile import load_data
from scatterbench.validation.fitting.fitspec import fitspec_from
from scatterbench.validation.fitting.likelihood import Likelihood
from scatterbench.validation.fitting.recovery import simulate, subsample
from scatterbench.validation.fitting.sampling import optimize


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--injections", type=int, default=3000)
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args(argv)
    sc = scene.load(references.scene_path("aluminium_flakes_clearcoat.toml"))
    data = load_data(references.data_path("scatmech_flake_measurement.csv"))
    n = args.injections
    se68, se95 = math.sqrt(0.6827 * 0.3173 / n), math.sqrt(0.9545 * 0.0455 / n)
    print(
        f"{'geoms':>5} {'noise':>5} {'parameter':<16} {'cov68':>6} {'z68':>6} {'cov95':>6} {'z95':>6} {'sd(z)':>6}"
    )
    for ng in (8, 32):
        for lvl in (0.05, 0.1):
            spec = fitspec_from(sc, ["sigma:0.01:1:log", "coating:1.2:2"], [f"brdf={lvl}"])
            d = subsample(data, ng)
            truth = {p.key: float(sc.get_value(p.key)) for p in spec.free}
            tu = np.array([float(p.to_u(truth[p.key])) for p in spec.free])
            t0 = time.perf_counter()
            z = []
            for j in range(n):
                sim = simulate(
                    sc,
                    spec,
                    d,
                    truth,
                    {"brdf": lvl},
                    np.random.default_rng([args.seed, ng, round(1000 * lvl), j]),
                )
                u, _, info = optimize(Likelihood(sc, spec, sim), j, n_starts=1)
                z.append((u - tu) / info["sd_u"])
            z = np.abs(np.array(z))
            for i, p in enumerate(spec.free):
                c68, c95 = np.mean(z[:, i] <= 1), np.mean(z[:, i] <= 2)
                print(
                    f"{len(d):>5} {lvl:>5g} {p.key:<16} {c68:>6.3f} {(c68 - 0.6827) / se68:>+6.2f} "
                    f"{c95:>6.3f} {(c95 - 0.9545) / se95:>+6.2f} {np.sqrt(np.mean(z[:, i] ** 2)):>6.3f}"
                )
            print(f"      ({n} injections in {time.perf_counter() - t0:.1f} s)")
    print(f"binomial standard errors over {n} injections: 68%: {se68:.4f}, 95%: {se95:.4f}")


if __name__ == "__main__":
    main()
