"""Throughput and memory of every model from 10^3 to 10^7 geometries.

    python benchmarks/throughput.py [--max-exp 7]

Each size runs in a fresh subprocess so its peak resident memory (ru_maxrss)
is its own.  Geometries are a hemispherical scan, ``theta_r (k, 1) x phi_r
(1, m)`` at a fixed ``theta_i``: the inputs are tiny and broadcast, so the
memory is what the evaluation itself holds.  ``brdf`` returns N values
(8 bytes each); the full Mueller matrix at 10^7 would be 1.28 GB of output
alone, so at every size it is *streamed* with ``iter_mueller`` and reduced,
which shows the working memory is bounded by the chunk size.
"""

from __future__ import annotations

import os
import sys

# the checkout's packages, not an installed copy, when run as ``python benchmarks/...``
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import argparse
import json
import subprocess

CHILD = r"""
import json, math, resource, sys, time
import numpy as np
import models
name, n, what = sys.argv[1], int(sys.argv[2]), sys.argv[3]
from validation.studies.stability import _BASES
cls = next(c for c in models.Model.registry if c.__name__ == name)
m = _BASES[name]() if name in _BASES else cls()
k = int(round(math.sqrt(n / 4)))
tr = np.linspace(0, 1.5, k)[:, None]
pr = np.linspace(-math.pi, math.pi, n // k)[None, :]
N = tr.size * pr.size
m.brdf(0.5, tr[:2], pr[:, :2])  # warm up
t = time.perf_counter()
if what == "brdf":
    out = m.brdf(0.5, tr, pr)
    check = float(out.sum())
else:
    check = 0.0
    for _, block in m.iter_mueller(0.5, tr, pr):
        check += float(block[:, 0, 0].sum())
dt = time.perf_counter() - t
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
print(json.dumps({"n": N, "seconds": dt, "us": dt / N * 1e6, "rss_mb": rss}))
"""


def run(name, n, what):
    env = dict(
        os.environ,
        PYTHONPATH=os.pathsep.join(
            [os.path.dirname(os.path.dirname(os.path.abspath(__file__))), os.environ.get("PYTHONPATH", "")]
        ),
    )
    r = subprocess.run(
        [sys.executable, "-c", CHILD, name, str(n), what], capture_output=True, text=True, env=env
    )
    if r.returncode != 0:
        raise RuntimeError(r.stderr)
    return json.loads(r.stdout)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--max-exp", type=int, default=7)
    ap.add_argument("--models", nargs="*", default=None)
    args = ap.parse_args()
    import models

    names = args.models or [c.__name__ for c in models.Model.registry if c is not models.Sum]
    # Monte Carlo (200 pairs per geometry here) and the point-source wrapper (512 inner
    # evaluations per geometry) cost 2-3 orders more per geometry: sizes up to 10^5.
    heavy = {"RoughDiffuseBRDF", "PointSourceBRDF", "DetectorAperture"}  # 10-100 us per geometry
    print(f"{'model':<22} {'what':<12} {'N':>9} {'us/geom':>9} {'peak RSS MB':>12}")
    for name in names:
        for what in ("brdf", "iter_mueller"):
            for e in range(3, (min(args.max_exp, 5) if name in heavy else args.max_exp) + 1):
                r = run(name, 10**e, what)
                print(f"{name:<22} {what:<12} {r['n']:>9} {r['us']:>9.3f} {r['rss_mb']:>12.0f}")


if __name__ == "__main__":
    main()
