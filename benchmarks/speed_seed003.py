"""Print the measured speed of the seed 003 models, with ratios, and the Monte Carlo
error and cost versus the number of facet pairs.

    python benchmarks/speed_seed003.py

Per-geometry cost over 10^6 geometries (best of 3, numpy on one core) beside
SCATMECH: pySCATMECH's per-call cost measured in the same run (1000 calls)
when it is importable, and the compiled C++ figures of DESIGN.md (quoted, not
measured here).  Then RoughDiffuseBRDF on the paper's CARC preset (exponential
slopes rms 2, n 1.5, g 0.3, rho 0.05, theta_i 60 deg), an in-plane curve of 181
angles: time, mean relative standard error of M00 and the measured RMS error
against a 100000-pair reference, for 50 .. 20000 pairs.  Last, issue 12's case,
``models.RoughDiffuseBRDF().mueller(0.5, tr, phi)`` on 181 in-plane angles with the default
5000 pairs, on the numpy reference path (the implementation before the compiled Monte
Carlo) and on the default compiled one, in this run: a fresh model's first call (which
also estimates the rough R-bar) and the warm call (best of 3), with their ratio.
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

QUOTED_US = {"diffuse": 11.0, "single": 9.5}


def best_of(fn, repeat=3):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def scatmech_us(kind):
    try:
        from pySCATMECH.brdf import BRDF_Model
    except ImportError:  # pragma: no cover
        return None
    if kind == "diffuse":
        m = BRDF_Model("Diffuse_Subsurface_BRDF_Model", substrate="(1.5,0)", **{"reflectance.table": "0.93"})
    else:
        m = BRDF_Model(
            "First_Diffuse_BRDF_Model",
            substrate="(1.5,0)",
            phase_function="Unpolarized_Phase_Function",
            **{"phase_function.phase_function.g": "0.3", "phase_function.log_absorption": "-1000"},
        )
    rng = np.random.default_rng(0)
    g = rng.uniform(0, 1.4, (1000, 3))
    t = time.perf_counter()
    for a, b, c in g:
        m.MuellerBRDF(a, b, c)
    return (time.perf_counter() - t) / 1000 * 1e6


def main():
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    rng = np.random.default_rng(1)
    n = 10**6
    geo = (
        rng.uniform(0, math.radians(85), n),
        rng.uniform(0, math.radians(85), n),
        rng.uniform(-math.pi, math.pi, n),
    )
    print("per-geometry Mueller cost over 10^6 geometries (best of 3):")
    for label, kind, m in (
        ("DiffuseSubsurfaceBRDF", "diffuse", models.DiffuseSubsurfaceBRDF(coating=1.5, rho=0.93)),
        (
            "SingleScatterBRDF depolarizing",
            "single",
            models.SingleScatterBRDF(coating=1.5, phase=models.HenyeyGreenstein(0.3, polarized=False)),
        ),
        (
            "SingleScatterBRDF polarized",
            "single",
            models.SingleScatterBRDF(coating=1.5, phase=models.HenyeyGreenstein(0.3)),
        ),
    ):
        us = best_of(lambda m=m: m.mueller(*geo)) / n * 1e6
        sc = scatmech_us(kind)
        q = QUOTED_US[kind]
        extra = f"; pySCATMECH measured {sc:.2f} us/call (x{sc / us:.0f})" if sc else ""
        print(
            f"  {label:32s} {us:6.3f} us  (target 0.3; compiled SCATMECH quoted {q} us: x{q / us:.0f}{extra})"
        )

    kw = dict(
        slopes=models.ExponentialSlopes(2.0),
        n=1.5,
        phase=models.HenyeyGreenstein(0.3),
        rho=0.05,
        surface=False,
    )
    t = np.radians(np.linspace(-90.0, 90.0, 181))
    tr = np.minimum(np.abs(t), math.radians(89.9))
    pr = np.where(t < 0, math.pi, 0.0)
    ti = math.radians(60.0)
    ref = models.RoughDiffuseBRDF(pairs=100_000, seed=999, **kw).mueller(ti, tr, pr)[:, 0, 0]
    print("\nRoughDiffuseBRDF (CARC preset, volume terms), in-plane curve of 181 angles, theta_i = 60 deg:")
    print("   pairs    time (s)   s per 1000 pairs   mean SE/M00   RMS |M00 - ref|/ref (seed 0)")
    base = None
    for pairs in (50, 500, 5000, 20000):
        m = models.RoughDiffuseBRDF(pairs=pairs, seed=0, **kw)
        sec = best_of(lambda m=m: m.mueller_with_error(ti, tr, pr), repeat=2 if pairs > 5000 else 3)
        M, E = m.mueller_with_error(ti, tr, pr)
        rel_se = float(np.mean(E[:, 0, 0] / M[:, 0, 0]))
        rms = float(np.sqrt(np.mean(((M[:, 0, 0] - ref) / ref) ** 2)))
        base = base or (pairs, rms)
        print(f"  {pairs:6d}   {sec:8.3f}   {sec / pairs * 1000:16.3f}   {rel_se:11.2e}   {rms:.2e}")
    m = models.RoughDiffuseBRDF(pairs=5000, seed=0, **{**kw, "surface": True})
    sec = best_of(lambda: m.mueller_with_error(ti, tr, pr))
    print(f"  5000 pairs with the surface term (the preset): {sec:.3f} s (target <= 2 s)")
    monte_carlo_before_after()


def monte_carlo_before_after():
    """Issue 12's Monte Carlo case on the numpy reference and the compiled path."""
    t = np.radians(np.linspace(-90.0, 90.0, 181))
    tr, phi = np.abs(t), np.where(t < 0, math.pi, 0.0)
    print("\nRoughDiffuseBRDF() defaults (5000 pairs), mueller(0.5, tr, phi), 181 in-plane angles:")
    print("   path                      first call (s)   warm (s, best of 3)")
    rows = {}
    for label, name in (("numpy (reference)", "numpy"), ("compiled (default)", "numba")):
        with models.backend(name):
            m = models.RoughDiffuseBRDF()
            t0 = time.perf_counter()
            m.mueller(0.5, tr, phi)
            first = time.perf_counter() - t0
            rows[name] = (first, best_of(lambda m=m: m.mueller(0.5, tr, phi)))
        print(f"   {label:24s}  {rows[name][0]:14.3f}   {rows[name][1]:8.3f}")
    (f0, w0), (f1, w1) = rows["numpy"], rows["numba"]
    print(
        f"   compiled / numpy: first call x{f0 / f1:.1f} faster, warm x{w0 / w1:.1f} faster (target <= 0.5 s warm)"
    )


if __name__ == "__main__":
    main()
