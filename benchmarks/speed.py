"""Print the measured speed of the facet models and of Table I, with ratios.

    python benchmarks/speed.py

Per-geometry cost over 10^3 .. 10^6 geometries (best of 5 runs, one process,
numpy on one core), the Table I time, and ratios to SCATMECH.  When pySCATMECH
is importable its per-call cost is measured here in the same run; the compiled
C++ figures of DESIGN.md (measured on this kind of machine, not in this run)
are printed beside them, labelled as quoted.
"""

from __future__ import annotations

import os
import sys

# the checkout's packages, not an installed copy, when run as ``python benchmarks/...``
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import math
import time

import numpy as np

from scatterbench import models
from scatterbench.validation.checks.table1 import compute_table1

QUOTED_US = {"Facet (compiled SCATMECH, quoted)": 0.5, "Subsurface facet (compiled SCATMECH, quoted)": 5.2}


def best_of(fn, repeat=5):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times), float(np.median(times))


def main():
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    rng = np.random.default_rng(1)
    sub = models.SubsurfaceFacetBRDF(
        slopes=models.ExponentialSlopes(0.2), coating=1.5, substrate=1.37 + 7.62j
    )
    fac = models.FacetBRDF(slopes=models.ExponentialSlopes(0.2), substrate=1.37 + 7.62j)
    print("per-geometry cost of mueller() (us; best / median of 5)")
    print(f"{'N':>9} {'SubsurfaceFacetBRDF':>24} {'FacetBRDF':>20}")
    per = {}
    for n in (10**3, 10**4, 10**5, 10**6):
        ti, tr = rng.uniform(0, math.radians(85), (2, n))
        pr = rng.uniform(-math.pi, math.pi, n)
        a = best_of(lambda m=sub, ti=ti, tr=tr, pr=pr: m.mueller(ti, tr, pr))
        b = best_of(lambda m=fac, ti=ti, tr=tr, pr=pr: m.mueller(ti, tr, pr))
        per[n] = (a[0] / n * 1e6, b[0] / n * 1e6)
        print(
            f"{n:>9} {a[0] / n * 1e6:>12.3f} / {a[1] / n * 1e6:<9.3f} {b[0] / n * 1e6:>9.3f} / {b[1] / n * 1e6:<9.3f}"
        )
    sub_us, fac_us = per[10**6]
    print()
    try:
        from pySCATMECH.brdf import BRDF_Model

        ref = BRDF_Model(
            "Subsurface_Facet_BRDF_Model",
            substrate="(1.37,7.62)",
            overcoat="(1.5,0)",
            sdf="Exponential_Slope_Distribution_Function",
            **{"sdf.s": 0.2},
        )
        ti, tr = rng.uniform(0, 1.4, (2, 3000))
        pr = rng.uniform(-3, 3, 3000)
        t, _ = best_of(lambda: [ref.MuellerBRDF(a, b, c) for a, b, c in zip(ti, tr, pr, strict=True)], 3)
        live = t / 3000 * 1e6
        print(f"pySCATMECH Subsurface_Facet_BRDF_Model, measured now: {live:.2f} us per call")
        print(f"  speed-up of SubsurfaceFacetBRDF at 10^6 geometries: {live / sub_us:.0f}x")
    except ImportError:
        print("pySCATMECH not installed: no live SCATMECH measurement in this run")
    for label, us in QUOTED_US.items():
        mine = sub_us if "Subsurface" in label else fac_us
        print(f"{label}: {us} us per geometry -> ratio {us / mine:.1f}x")
    print()
    t, med = best_of(lambda: compute_table1(tol=1e-4), 3)
    print(f"Table I, 27 entries at tol 1e-4: {t:.3f} s (median {med:.3f} s)")


if __name__ == "__main__":
    main()
