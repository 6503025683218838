"""The compiled kernels against the numpy reference path, measured in one run.

    python benchmarks/kernel_speed.py [--n 1000000] [--repeat 5]

Prints, for every closed-form model: the per-geometry cost of the full float64 Mueller
matrix from angles at ``--n`` geometries with the numpy path and with the kernels on one
thread and on every core (best of ``--repeat``), and the ratios, each call allocating its
result and again writing into one allocated before (``out=``: the first touch of a fresh
128 MB result, the operating system zeroing its pages, is part of the former); the small calls (one
geometry, 100 geometries); float32 against float64 (cost, and the error as the trade-off
study's precision knob defines it: max |M32 - M64| over every element / max M64_00); and
the import + first-call time of a fresh process with an empty kernel cache (cold: the
kernels compile) and again with that cache filled (warm).  The machine's load is printed
before and after: figures from a shared machine are noisy, the ratios within one run less so.
"""

from __future__ import annotations

import os
import sys

# the checkout's benchmarks (``benchmarks.speed``) when run as ``python benchmarks/...``
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import argparse
import math
import subprocess
import tempfile
import time

import numba
import numpy as np

from benchmarks.speed import best_of

try:
    from scatterbench import models
    from scatterbench.validation.numerics.probes import random_geometries
    from scatterbench.validation.studies.tradeoff import precision_error
except ImportError:  # benchmarks/kernel_ab.py runs this file in a checkout from before the namespace
    import models
    from validation.checks.common import random_geometries
    from validation.studies.tradeoff import precision_error

AL = 1.37 + 7.62j
MODELS = {
    "FacetBRDF": lambda: models.FacetBRDF(slopes=models.ExponentialSlopes(0.1), substrate=AL),
    "FacetBRDF GGX smith": lambda: models.FacetBRDF(
        slopes=models.GGXSlopes(0.2), substrate=AL, shadowing="smith"
    ),
    "FacetBRDF Gaussian smith": lambda: models.FacetBRDF(
        slopes=models.GaussianSlopes(0.2), substrate=AL, shadowing="smith"
    ),
    "SubsurfaceFacetBRDF": lambda: models.SubsurfaceFacetBRDF(),
    "FacetBTDF": lambda: models.FacetBTDF(slopes=models.GaussianSlopes(0.2), substrate=1.5),
    "SingleScatterBRDF": lambda: models.SingleScatterBRDF(phase=models.HenyeyGreenstein(0.3, True)),
    "DiffuseSubsurfaceBRDF": lambda: models.DiffuseSubsurfaceBRDF(),
    "CookTorranceBRDF": lambda: models.CookTorranceBRDF(),
    "CookTorranceBRDF smith": lambda: models.CookTorranceBRDF(shadowing="smith"),
    "CookTorranceBRDF strokes smith": lambda: models.CookTorranceBRDF(
        slopes=models.StrokeSlopes(0.05, 0.2, 0.7), shadowing="smith"
    ),
    "VarnishedCookTorranceBRDF": lambda: models.VarnishedCookTorranceBRDF(),
    "MaxwellBeardBRDF": lambda: models.MaxwellBeardBRDF(polarized=True),
}
FIRST_CALL = (
    "import time; t = time.perf_counter()\n"
    f"{'from scatterbench import models' if models.__name__.startswith('scatterbench') else 'import models'}\n"
    "models.SubsurfaceFacetBRDF().mueller(0.5, 0.6, 0.1); print(time.perf_counter() - t)"
)


def geometries(n):
    """``(ti, tr, pr)``: polar angles uniform in [0, 1.5] rad, azimuth in [-pi, pi) (seed 0)."""
    return random_geometries(n, 0, max_deg=math.degrees(1.5))


#: the kernel columns of :func:`per_geometry`
COLUMNS = ("1 thread", "all threads", "1 thread, out=", "all threads, out=")


def per_geometry(n, repeat):
    """``{model: (numpy us, one thread us, all threads us, one thread out= us, all out= us)}``
    per geometry at ``n``: each call allocates its ``(16, n)`` result, whose fresh pages
    the operating system zeroes on first touch, except in the ``out=`` columns, which
    write into one array allocated before (``m.mueller(..., out=out)``)."""
    ti, tr, pr = geometries(n)
    out = {}
    buf = np.empty((16, n))
    for name, make in MODELS.items():
        m = make()
        m.mueller(ti[:10], tr[:10], pr[:10])  # compiled (or loaded) before timing
        with models.backend("numpy"):
            t_np = best_of(lambda m=m: m.mueller(ti, tr, pr), max(1, repeat // 2))[0]
        times = []
        for threads in (1, numba.config.NUMBA_NUM_THREADS):
            numba.set_num_threads(threads)
            times.append(best_of(lambda m=m: m.mueller(ti, tr, pr), repeat)[0])
            times.append(best_of(lambda m=m: m.mueller(ti, tr, pr, out=buf), repeat)[0])
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        t_1, t_1o, t_all, t_allo = times
        out[name] = tuple(1e6 * t / n for t in (t_np, t_1, t_all, t_1o, t_allo))
    return out


def small_calls(repeat):
    """``{"model, case": (numpy us, kernel us)}`` per call of every closed-form model: one
    geometry as three floats (``m.mueller(0.5, 0.6, 0.1)``) and 100 geometries (two float64
    arrays and a float); then, for SubsurfaceFacetBRDF, the other forms users pass (ints,
    numpy scalars, lists, a broadcast grid, ``out=``, float32).  Each figure is the best over
    ``10 * repeat`` batches of about 2 ms (on a shared machine short batches miss the other
    processes' time slices)."""
    x = np.linspace(0.1, 1.4, 100)
    y = x[::-1].copy()
    cases = {}
    for name, make in MODELS.items():
        m = make()
        cases[f"{name}, one geometry"] = lambda m=m: m.mueller(0.5, 0.6, 0.1)
        cases[f"{name}, 100 geometries"] = lambda m=m: m.mueller(x, y, 0.3)
    m = MODELS["SubsurfaceFacetBRDF"]()
    f, out = np.float64, np.empty((16, 100))
    forms = {
        "ints (0, 1, 0)": lambda: m.mueller(0, 1, 0),
        "numpy scalars": lambda: m.mueller(f(0.5), f(0.6), f(0.1)),
        "lists of 3": lambda: m.mueller([0.5, 0.6, 0.7], [0.6, 0.5, 0.4], [0.1, 0.2, 0.3]),
        "10 x 10 grid": lambda: m.mueller(x[:10, None], y[None, :10], 0.3),
        "100 into out=": lambda: m.mueller(x, y, 0.3, out=out),
        "brdf, 100": lambda: m.brdf(x, y, 0.3),
        "float32, one geometry": lambda: m.mueller(0.5, 0.6, 0.1, precision="float32"),
        "float32, 100": lambda: m.mueller(x, y, 0.3, precision="float32"),
    }
    cases.update({f"SubsurfaceFacetBRDF, {k}": fn for k, fn in forms.items()})
    result = {}
    for case, fn in cases.items():
        fn()
        with models.backend("numpy"):
            fn()
            t_np = _per_call(fn, repeat)
        result[case] = (1e6 * t_np, 1e6 * _per_call(fn, repeat))
    return result


def wrapper_calls(repeat):
    """``{"wrapper, case": (nan, us per geometry)}``: PointSourceBRDF at its default (``tol =
    1e-4``, d/R = 3) around a broad lobe, a narrow lobe and a cusp (``benchmarks/wrappers.py``'s
    three inner models) at 50, 200 and 1000 geometries, and DetectorAperture (0.7 deg, 32
    nodes) at 1, 50 and 800, each call on a fresh instance (nothing cached), the best of ``repeat``.
    The models are restated here, not imported: ``kernel_ab.py`` runs this file inside the
    older checkout, whose ``benchmarks/wrappers.py`` may differ or be absent."""
    inners = {
        "broad lobe": models.SubsurfaceFacetBRDF(slopes=models.GaussianSlopes(0.2)),
        "narrow lobe": models.CookTorranceBRDF(slopes=models.GaussianSlopes(0.01)),
        "cusp": models.FacetBRDF(slopes=models.ExponentialSlopes(0.05)),
    }
    rng = np.random.default_rng(0)
    result = {}

    def case(label, make, n):
        ti = np.repeat([0.0, 0.3, 0.6, 0.9], -(-n // 4))[:n]
        geo = (ti, rng.uniform(0.0, 1.4, n), rng.uniform(-math.pi, math.pi, n))
        make().mueller(*geo)
        result[label] = (math.nan, 1e6 * best_of(lambda: make().mueller(*geo), repeat)[0] / n)

    for name, inner in inners.items():
        for n in (50, 200, 1000):
            case(
                f"PointSourceBRDF {name}, {n}",
                lambda m=inner: models.PointSourceBRDF(model=m, distance=3.0),
                n,
            )
    ap = dict(model=inners["broad lobe"], aperture=math.radians(0.7), resolution=4)
    for n in (1, 50, 800):  # a fit's fresh aperture per evaluation: the small calls show its set-up
        case(f"DetectorAperture, {n}", lambda: models.DetectorAperture(**ap), n)
    return result


def _per_call(fn, repeat):
    t = time.perf_counter()
    fn()
    k = max(1, int(2e-3 / max(time.perf_counter() - t, 1e-7)))
    return best_of(lambda: [fn() for _ in range(k)], 10 * repeat)[0] / k


def float32(n, repeat):
    """``(float64 us, float32 us, error)`` per geometry, SubsurfaceFacetBRDF; the error is
    the precision knob's (:func:`scatterbench.validation.studies.tradeoff.precision_error`)."""
    m = models.SubsurfaceFacetBRDF()
    ti, tr, pr = geometries(n)
    m.mueller(ti[:10], tr[:10], pr[:10], precision="float32")
    t64 = best_of(lambda: m.mueller(ti, tr, pr), repeat)[0]
    t32 = best_of(lambda: m.mueller(ti, tr, pr, precision="float32"), repeat)[0]
    err = precision_error(m.mueller(ti, tr, pr, precision="float32"), m.mueller(ti, tr, pr))
    return 1e6 * t64 / n, 1e6 * t32 / n, err


def first_call():
    """``(cold s, warm s)``: a fresh interpreter's import + first call, cache empty then filled."""
    with tempfile.TemporaryDirectory() as cache:
        # the same package as this process's (sys.path[0] is a checkout from before the namespace)
        env = dict(os.environ, NUMBA_CACHE_DIR=cache, PYTHONPATH=os.pathsep.join(sys.path))
        runs = [
            subprocess.run([sys.executable, "-c", FIRST_CALL], env=env, capture_output=True, text=True)
            for _ in "cw"
        ]
    return tuple(float(r.stdout.strip()) for r in runs)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    print(
        f"load {os.getloadavg()}; {numba.config.NUMBA_NUM_THREADS} threads; {args.n} geometries, full Mueller"
    )
    print(f"{'':<36} fresh result{'':<28} into out=")
    print(
        f"{'model':<26} {'numpy us':>9} {'1 thread':>9} {'all':>9} {'np/1thr':>8} {'1thr/all':>9}"
        f" {'1 thread':>9} {'all':>9} {'1thr/all':>9}"
    )
    for name, (t_np, t_1, t_all, t_1o, t_allo) in per_geometry(args.n, args.repeat).items():
        print(
            f"{name:<26} {t_np:9.4f} {t_1:9.4f} {t_all:9.4f} {t_np / t_1:7.1f}x {t_1 / t_all:8.2f}x"
            f" {t_1o:9.4f} {t_allo:9.4f} {t_1o / t_allo:8.2f}x"
        )
    for name, (t_np, t_k) in small_calls(args.repeat).items():
        print(f"small call, {name:<42} numpy {t_np:8.1f} us, kernel {t_k:6.1f} us ({t_np / t_k:.1f}x)")
    t64, t32, err = float32(args.n, args.repeat)
    print(
        f"float32: {t32:.4f} us vs float64 {t64:.4f} us per geometry; error {err:.1e} (max |M32 - M64| / max M00)"
    )
    cold, warm = first_call()
    print(f"import + first call, fresh process: cold cache {cold:.1f} s, warm cache {warm:.2f} s")
    print(f"load after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
