"""PointSourceBRDF and DetectorAperture before and after (issues 12 and 13), in one run.

    python benchmarks/wrappers.py [--n 200] [--repeat 3]
    python benchmarks/wrappers.py --blocks     # DetectorAperture's block size, 2^12 to 2^16

"Before" is the code of commit a0b9da6 (``models/point_source.py`` and ``models/aperture.py``
read with ``git show`` and loaded beside the current modules, on the same inner models and
kernels); "after" is this checkout.  Every figure is per geometry: the best of ``--repeat``
timings, each on a fresh instance (nothing cached from an earlier repeat).

PointSourceBRDF (exact method), at 4 incidences (0, 0.3, 0.6, 0.9 rad) x random observations
(polar 0-1.4 rad, any azimuth), three inner models at d/R = 3: a broad lobe (the brief's
SubsurfaceFacetBRDF, Gaussian slopes 0.2), issue 13's narrow lobe (Cook-Torrance m = 0.01) and
a cusp (exponential slopes 0.05).  The error is max |M - M_ref| over the elements and the
geometries over the peak M00_ref of the set, ``M_ref`` the new quadrature at ``tol = 1e-8``
(its own estimate is printed); the M00 column is the same for M00 alone.  Rows: the old
default (``resolution="auto"``, N = max(16, ceil(10 spread / width)) radial nodes); the new
default (``tol = 1e-4``); its floor, the inner model's own cost for as many evaluations
(what any quadrature spending them costs at least: the old default over it bounds the
speed-up the new default can reach at its accuracy); the new at the old default's error as tolerance (at least 1e-7, ten
times the reference's); the old at the smallest fixed resolution that matches the new
default's error (hand-tuned, no estimate), or 256.  The broad lobe is also shown at one
incidence, 0.6 rad, where the source's foot lies off the sample (at 0 it is the sample's
centre, at 0.3 near its rim: the incident basis turns around it, which the old rule, centred
on the sample, resolves slowly in the polarization elements).

DetectorAperture around the same broad-lobe model, seed 000's 0.7 deg aperture, resolution 4
(32 nodes): old and new, their largest difference relative to M00, and the floor: the inner
model's own cost for the 32 evaluations.

The machine's load is printed before and after: absolute figures from a shared machine are
noisy, the ratios within one run less so.
"""

from __future__ import annotations

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import argparse
import math
import subprocess
import types
import warnings

import numpy as np

from benchmarks.speed import best_of
from scatterbench import models

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BASE = "a0b9da6"
DISTANCE = 3.0
INNERS = {
    "broad lobe": models.SubsurfaceFacetBRDF(slopes=models.GaussianSlopes(0.2)),
    "narrow lobe": models.CookTorranceBRDF(slopes=models.GaussianSlopes(0.01)),
    "cusp": models.FacetBRDF(slopes=models.ExponentialSlopes(0.05)),
}


def baseline(name):
    """The module ``models/<name>.py`` as it was at :data:`BASE`, loaded as ``models._before_<name>``."""
    src = subprocess.run(
        ["git", "-C", ROOT, "show", f"{BASE}:models/{name}.py"], capture_output=True, text=True, check=True
    ).stdout
    # the baseline's code calls its inner models by the entry's old name (flat_mueller16 now)
    models.Model._m16 = models.Model.flat_mueller16
    mod = types.ModuleType(f"scatterbench.models._before_{name}")
    mod.__package__ = "scatterbench.models"
    sys.modules[mod.__name__] = mod
    exec(compile(src, f"{BASE}:models/{name}.py", "exec"), mod.__dict__)
    return mod


def geometries(n, seed=0):
    rng = np.random.default_rng(seed)
    ti = np.repeat([0.0, 0.3, 0.6, 0.9], -(-n // 4))[:n]
    return ti, rng.uniform(0.0, 1.4, n), rng.uniform(-math.pi, math.pi, n)


def timed(make, geo, repeat):
    """``(M, us per geometry)``: ``make()`` builds a fresh instance per repeat."""
    out = {}

    def run():
        out["M"] = make().mueller(*geo)

    t = best_of(run, repeat)[0]
    return out["M"], t / geo[0].size * 1e6


def point_source_rows(old, inner, geo, repeat):
    """The rows of one inner model: ``[(label, us, evaluations, error, M00 error)]``, and the
    reference's largest estimate and capped count."""
    ref = models.PointSourceBRDF(model=inner, distance=DISTANCE, tol=1e-8).accuracy(*geo)
    peak = np.max(ref.mueller[..., 0, 0])

    def err(M):
        d = np.abs(M - ref.mueller)
        return float(np.max(d) / peak), float(np.max(d[..., 0, 0]) / peak)

    res = [
        old.PointSourceBRDF(model=inner, distance=DISTANCE).resolution_at(float(t)) for t in np.unique(geo[0])
    ]
    M, t_old = timed(lambda: old.PointSourceBRDF(model=inner, distance=DISTANCE), geo, repeat)
    rows = [("old default (auto)", t_old, f"{2 * min(res) ** 2}-{2 * max(res) ** 2}", *err(M))]
    new = models.PointSourceBRDF(model=inner, distance=DISTANCE)
    for tol, label in ((1e-4, "new default (tol 1e-4)"), (None, "new at the old default's error")):
        tol = tol or min(0.1, max(1e-7, rows[0][3]))
        M, t = timed(lambda tol=tol: new.replace(tol=tol), geo, repeat)
        acc = new.replace(tol=tol).accuracy(*geo)
        capped = f", {int(acc.capped.sum())} capped" if acc.capped.any() else ""
        rows.append((f"{label}: tol {tol:.1e}{capped}", t, f"{acc.evaluations.mean():.0f}", *err(M)))
    rows.insert(2, floor(inner, geo, int(round(float(rows[1][2]))), repeat))
    target = rows[1][3]
    for N in (2, 4, 8, 16, 32, 64, 128, 256):
        M, t = timed(lambda N=N: old.PointSourceBRDF(model=inner, distance=DISTANCE, resolution=N), geo, 1)
        if err(M)[0] <= target or N == 256:
            note = "matches the new default" if err(M)[0] <= target else "short of the new default"
            rows.append((f"old fixed N={N} ({note})", t, f"{2 * N * N}", *err(M)))
            break
    return rows, float(np.max(ref.error)), int(ref.capped.sum())


def floor(inner, geo, evaluations, repeat):
    """The row of the floor under the new default: the inner model's own cost for its
    ``evaluations`` per geometry (one call on that many random geometries at the same
    incidences), what any quadrature spending them costs at least."""
    n = geo[0].size
    rng = np.random.default_rng(2)
    big = (
        np.repeat(geo[0], evaluations),
        rng.uniform(0.0, 1.4, n * evaluations),
        rng.uniform(-3, 3, n * evaluations),
    )
    t = best_of(lambda: inner.flat_mueller16(*big), repeat)[0] / n * 1e6
    return (
        f"floor: the new default's {evaluations} inner evaluations alone",
        t,
        f"{evaluations}",
        math.nan,
        math.nan,
    )


def print_point_source(old, n, repeat):
    print(f"PointSourceBRDF exact, d/R = {DISTANCE:g}; error: max over elements and geometries / peak M00")
    head = f"  {'':58} {'us/geom':>9} {'evaluations':>12} {'error':>8} {'M00 err':>8} {'old/this':>9}"
    cases = [
        (name, inner, geometries(n if name == "broad lobe" else max(8, n // 4)))
        for name, inner in INNERS.items()
    ]
    one = geometries(n)  # the broad lobe at one incidence whose source foot is off the sample
    cases.insert(1, ("broad lobe, theta_i = 0.6 only", INNERS["broad lobe"], (np.full(n, 0.6), *one[1:])))
    for name, inner, geo in cases:  # (the old default is slow on narrow lobes: fewer geometries)
        rows, ref_est, ref_capped = point_source_rows(old, inner, geo, repeat)
        print(f" {name}: {inner!r}")
        print(
            f"  {geo[0].size} geometries; reference (tol 1e-8): largest estimate {ref_est:.1e}, capped {ref_capped}"
        )
        print(head)
        for label, t, evals, e, e00 in rows:
            errs = "" if math.isnan(e) else f"{e:8.1e} {e00:8.1e}"
            print(f"  {label:58} {t:9.1f} {evals:>12} {errs:>17} {rows[0][1] / t:9.2f}")


def print_aperture(old, n, repeat):
    inner = INNERS["broad lobe"]
    ti, tr, pr = geometries(n, seed=1)
    geo = (ti, tr, pr)
    kw = dict(model=inner, aperture=math.radians(0.7), resolution=4)
    M_old, t_old = timed(lambda: old.DetectorAperture(**kw), geo, repeat)
    M_new, t_new = timed(lambda: models.DetectorAperture(**kw), geo, repeat)
    diff = np.max(np.abs(M_new - M_old) / M_old[..., :1, :1])
    K = 32
    big = (np.repeat(ti, K), np.repeat(tr, K), np.repeat(pr, K))
    t_in = best_of(lambda: inner.flat_mueller16(*big), repeat)[0] / n * 1e6
    print(f"DetectorAperture, 0.7 deg, resolution 4 ({K} nodes), {n} geometries, around {inner!r}")
    print(f"  old {t_old:8.2f} us/geom   new {t_new:8.2f} us/geom   old/new {t_old / t_new:6.2f}")
    print(f"  floor: the inner model's {K} evaluations {t_in:8.2f} us/geom (old/floor {t_old / t_in:5.2f})")
    print(f"  max |new - old| / M00 = {diff:.1e}")


def print_aperture_blocks(repeat):
    """DetectorAperture's compiled route per geometry at each block size
    (``models.aperture._BLOCK``, inner-model evaluations per call) from 2^12 to 2^16, at 800,
    8000 and 80,000 geometries: the evidence for the block size chosen."""
    import scatterbench.models.aperture as aperture

    kw = dict(model=INNERS["broad lobe"], aperture=math.radians(0.7), resolution=4)
    chosen = aperture._BLOCK
    sizes = (800, 8000, 80000)
    geos = [geometries(n, seed=1) for n in sizes]
    print(f"DetectorAperture per geometry (us) by block size; the module's: 2^{chosen.bit_length() - 1}")
    try:
        for b in range(12, 17):
            aperture._BLOCK = 1 << b
            cells = []
            for geo in geos:
                models.DetectorAperture(**kw).mueller(*geo)
                t = best_of(lambda geo=geo: models.DetectorAperture(**kw).mueller(*geo), max(5, 10 * repeat))[
                    0
                ]
                cells.append(f"{1e6 * t / geo[0].size:7.3f}")
            print(f"  2^{b}: " + "  ".join(f"n={n} {c}" for n, c in zip(sizes, cells, strict=True)))
    finally:
        aperture._BLOCK = chosen


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200, help="geometries per case (default 200)")
    ap.add_argument("--repeat", type=int, default=3, help="timings per figure; the best is kept")
    ap.add_argument("--blocks", action="store_true", help="DetectorAperture's block sizes only")
    args = ap.parse_args(argv)
    if args.blocks:
        print_aperture_blocks(args.repeat)
        return
    old_ps, old_ap = baseline("point_source"), baseline("aperture")
    warnings.simplefilter("ignore", models.point_source.AccuracyWarning)  # capped counts are printed
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    models.PointSourceBRDF(model=INNERS["cusp"], distance=DISTANCE).mueller(
        *geometries(8)
    )  # compile/load kernels
    print_aperture(old_ap, 4 * args.n, args.repeat)
    print_point_source(old_ps, args.n, args.repeat)
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
