"""What a model's first calls cost on a cold numba cache: compilation, per call kind.

    python benchmarks/first_call.py [--models FacetBRDF SingleScatterBRDF ...]

For each model (default: one per compiled kernel), a fresh process with an empty
``NUMBA_CACHE_DIR`` calls it at one geometry (the scalar entry), 100 geometries (the small
vector path), 5000 (the parallel loop) and 5000 in float32, then a second process does the same
with that cache (warm).  It prints the CPU seconds of each call (process time: less sensitive
to a shared machine's load than wall time), their total cold and warm, and the load average.
Public API only, so the same script measures any earlier commit too.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile

MODELS = {
    "FacetBRDF": "models.FacetBRDF(slopes=models.GaussianSlopes(sigma=0.2), substrate=1.5)",
    "FacetBTDF": "models.FacetBTDF()",
    "SingleScatterBRDF": "models.SingleScatterBRDF()",
    "DiffuseSubsurfaceBRDF": "models.DiffuseSubsurfaceBRDF()",
    "CookTorranceBRDF": "models.CookTorranceBRDF()",
    "MaxwellBeardBRDF": "models.MaxwellBeardBRDF()",
}

_PROBE = """
import json, sys, time
import numpy as np
from scatterbench import models
m = {model}
tr = lambda n: np.linspace(0.0, 1.2, n)
calls = [("1", lambda: m.mueller(0.3, 0.4, 0.5)), ("100", lambda: m.mueller(0.3, tr(100), 0.5)),
         ("5000", lambda: m.mueller(0.3, tr(5000), 0.5)),
         ("5000 float32", lambda: m.mueller(0.3, tr(5000), 0.5, precision="float32"))]
out = {{}}
for name, f in calls:
    t = time.process_time()
    f()
    out[name] = time.process_time() - t
print(json.dumps(out))
"""


def probe(model, cache):
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    code = _PROBE.format(model=MODELS[model])
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", nargs="+", default=list(MODELS), choices=list(MODELS))
    args = ap.parse_args()
    print("load average " + " ".join(f"{x:.2f}" for x in os.getloadavg()))
    print(f"{'model':24s} {'call':>14s} {'cold s':>8s} {'warm s':>8s}")
    totals = [0.0, 0.0]
    for model in args.models:
        with tempfile.TemporaryDirectory() as cache:
            cold, warm = probe(model, cache), probe(model, cache)
        for call in cold:
            print(f"{model:24s} {call:>14s} {cold[call]:8.2f} {warm[call]:8.2f}")
        totals[0] += sum(cold.values())
        totals[1] += sum(warm.values())
    print(f"{'total':24s} {'':>14s} {totals[0]:8.2f} {totals[1]:8.2f}")
    print("load average " + " ".join(f"{x:.2f}" for x in os.getloadavg()))


if __name__ == "__main__":
    main()
