"""Point-source illumination (seed 001 Eq. 25-30): speed and error of the shift
approximation (Eq. 29-30, FFT correlation) against the exact superposition
(Eq. 28), tabulated against the resolution knob and the source distance.

Run:  python benchmarks/point_source_tradeoff.py [--quick]

Model: the seed's varnished iron plate (VarnishedCookTorranceBRDF, m = 0.03,
n_v = 1.5, iron 2.29+3.37i, energy normalization), central incidence 17 deg,
observation grid theta_r 0..40 deg (0.25 deg) x phi_r -10..10 deg (0.5 deg).
Only d / R matters (sample radius R = 1).  Errors are max |f - f_ref| / max f_ref
with f_ref the exact superposition at a higher resolution (its own convergence
is printed).  Times are single runs (best of 2 for the cheap shift method) on
whatever cores are free: compare columns side by side, not across machines.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

import numpy as np

# Use the models of the checkout this script lives in (not an installed copy).
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from scatterbench import models  # noqa: E402
from scatterbench.validation.checks.seed001 import energy_published  # noqa: E402


def _timed(fn, repeat=1):
    best, out = math.inf, None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return out, best


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer distances and resolutions")
    args = ap.parse_args(argv)
    base = energy_published(models.VarnishedCookTorranceBRDF())
    ti = math.radians(17.0)
    tr = np.radians(np.linspace(0, 40, 161))
    pr = np.radians(np.linspace(-10, 10, 41))
    T, P = np.meshgrid(tr, pr, indexing="ij")
    coll = base.brdf(ti, T, P)
    distances = (1.0, 10.0, 100.0) if args.quick else (1.0, 3.0, 10.0, 30.0, 100.0, 1000.0)
    resolutions = (2, 4, 8) if args.quick else (2, 4, 8, 16, 32)
    ref_res, check_res = (24, 16) if args.quick else (48, 32)
    print(f"grid {T.size} directions; reference: exact at resolution {ref_res}")
    print(
        f"{'d/R':>7} {'res':>4} {'nodes':>6} {'t_exact s':>10} {'t_shift s':>10} {'speed-up':>9} "
        f"{'err_exact':>10} {'err_shift':>10} {'|ref-collimated|':>17}"
    )
    for d in distances:

        def mk(r, meth="exact", d=d):
            return models.PointSourceBRDF(
                model=base, distance=d, sample_radius=1.0, resolution=r, method=meth
            )

        ref = mk(ref_res).brdf_grid(ti, tr, pr)
        conv = np.abs(mk(check_res).brdf_grid(ti, tr, pr) - ref).max() / ref.max()
        dc = np.abs(coll - ref).max() / ref.max()
        for r in resolutions:
            ex, te = _timed(lambda r=r, mk=mk: mk(r).brdf_grid(ti, tr, pr))
            sh, ts = _timed(lambda r=r, mk=mk: mk(r, "shift").brdf_grid(ti, tr, pr), repeat=2)
            ee = np.abs(ex - ref).max() / ref.max()
            es = np.abs(sh - ref).max() / ref.max()
            print(
                f"{d:7g} {r:4d} {2 * r * r:6d} {te:10.4f} {ts:10.4f} {te / ts:9.1f} {ee:10.2e} {es:10.2e} {dc:17.2e}"
            )
        print(f"{'':7} reference converged to {conv:.1e} (resolution {check_res} vs {ref_res})")


if __name__ == "__main__":
    main()
