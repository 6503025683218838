"""Print the per-geometry cost of Smith shadowing, film-stack substrates and the shadowed BTDF (the
paths issue 15 added) beside the existing ones, with ratios.

    python benchmarks/speed_shadowing_films.py

10^5 random geometries (polar angles up to 85 deg, every azimuth), Mueller
matrices, one call each, best of 5 runs in one process, on both backends
(``models.backend``): the numpy reference implementation, and the default
``numba`` backend (the compiled kernels where they cover the path, numpy where
they do not, so a ratio there may set a kernel against numpy): Smith
shadowing (closed forms and the tabulated Lambda) against ``shadowing="none"``,
FilmStack substrates against a plain index, FacetBTDF with and without
shadowing; and the one-off cost of tabulating Lambda for a distribution.
"""

from __future__ import annotations

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import math

import numpy as np

from benchmarks.speed import best_of
from scatterbench import models
from scatterbench.models.shadowing import LambdaTable
from scatterbench.models.thin_film import FilmStack

N = 100_000


def pairs():
    """``(label, reference model, new model)``."""
    al = 1.37 + 7.62j
    tio2_mica = FilmStack(layers=((2.6 + 0j, 140.0),), substrate=1.56, wavelength_nm=550.0)
    three = FilmStack(layers=((2.6 + 0j, 140.0), (1.46 + 0j, 90.0), (2.6 + 0.01j, 60.0)), substrate=al)
    out = []
    for name, sl in (
        ("Gaussian (erf)", models.GaussianSlopes(0.2)),
        ("GGX (closed form)", models.GGXSlopes(0.2)),
        ("exponential (table)", models.ExponentialSlopes(0.2)),
        ("aniso GGX", models.AnisotropicGGXSlopes(0.1, 0.3, 0.4)),
    ):
        base = models.FacetBRDF(slopes=sl, substrate=al)
        out.append((f"FacetBRDF {name}: smith vs none", base, base.replace(shadowing="smith")))
    sub = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.2), coating=1.5, substrate=1.56)
    out.append(("Subsurface exponential: smith vs none", sub, sub.replace(shadowing="smith")))
    out.append(("Subsurface: 1-film stack vs index", sub, sub.replace(substrate=tio2_mica)))
    out.append(("Subsurface: 3-film stack vs index", sub, sub.replace(substrate=three)))
    bt = models.FacetBTDF(slopes=models.GaussianSlopes(0.3), substrate=1.5)
    out.append(("FacetBTDF Gaussian: smith vs none", bt, bt.replace(shadowing="smith")))
    return out


def main():
    rng = np.random.default_rng(0)
    ti, tr = rng.uniform(0, math.radians(85), (2, N))
    pr = rng.uniform(-math.pi, math.pi, N)
    print(f"{N} geometries, Mueller matrix, best of 5; us per geometry")
    print(f"{'':<44}{'numpy backend':^28}{'numba backend (default)':^28}")
    print(f"{'path':<44}" + f"{'existing':>10}{'new':>10}{'ratio':>8}" * 2)
    for label, ref, new in pairs():
        new.mueller(ti[:10], tr[:10], pr[:10])  # build any Lambda table, compile, outside the timing
        ref.mueller(ti[:10], tr[:10], pr[:10])
        cells = ""
        for name in ("numpy", "numba"):
            with models.backend(name):
                a = best_of(lambda m=ref: m.mueller(ti, tr, pr))[0] / N * 1e6
                b = best_of(lambda m=new: m.mueller(ti, tr, pr))[0] / N * 1e6
            cells += f"{a:>10.3f}{b:>10.3f}{b / a:>8.2f}"
        print(f"{label:<44}{cells}")
    t = best_of(lambda: LambdaTable(models.ExponentialSlopes(0.2)), repeat=3)[0]
    print(f"LambdaTable(ExponentialSlopes) construction: {t * 1e3:.1f} ms (once per distribution)")


if __name__ == "__main__":
    main()
