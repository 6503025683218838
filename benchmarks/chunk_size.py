"""Print the numpy path's cost per chunk size (``models.evaluation.CHUNK``).

    python benchmarks/chunk_size.py [--n 200000] [--repeat 3]

FacetBRDF and SubsurfaceFacetBRDF on ``n`` random geometries with ``models.backend("numpy")``,
best wall time (one thread) of ``repeat`` runs at each chunk size from 1024 to 32768, and each as a ratio
to the current ``CHUNK``.
"""

from __future__ import annotations

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import argparse  # noqa: E402

from benchmarks.speed import best_of  # noqa: E402
from scatterbench import models  # noqa: E402
from scatterbench.models import evaluation  # noqa: E402
from scatterbench.validation.numerics.probes import random_geometries  # noqa: E402

SIZES = (1024, 2048, 4096, 8192, 16384, 32768)


def measure(model, g, repeat):
    """``{chunk: best wall seconds}`` of ``model.mueller(*g)`` on the numpy path."""
    current, out = evaluation.CHUNK, {}
    try:
        for c in SIZES:
            evaluation.CHUNK = c
            with models.backend("numpy"):
                out[c] = best_of(lambda: model.mueller(*g), repeat)[0]
    finally:
        evaluation.CHUNK = current
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    g = random_geometries(args.n, seed=1)
    print(
        f"{'model':22} "
        + " ".join(f"{c:>9}" for c in SIZES)
        + f"   (ms; ratio to CHUNK = {evaluation.CHUNK})"
    )
    for m in (models.FacetBRDF(), models.SubsurfaceFacetBRDF()):
        t = measure(m, g, args.repeat)
        ref = t[evaluation.CHUNK]
        print(f"{type(m).__name__:22} " + " ".join(f"{1e3 * t[c]:9.1f}" for c in SIZES))
        print(f"{'':22} " + " ".join(f"{t[c] / ref:9.2f}" for c in SIZES))


if __name__ == "__main__":
    main()
