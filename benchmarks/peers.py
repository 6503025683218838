"""scatterbench beside its peers, pySCATMECH and Mitsuba 3: same geometries, one run, ratios.

    python benchmarks/peers.py [--n 100000] [--loop 1000] [--out FILE | --no-save]

Pairs (DESIGN.md's mapping):

* SCATMECH (pySCATMECH, C++ in double precision, one geometry per call):
  ``FacetBRDF`` = ``Facet_BRDF_Model``, ``SubsurfaceFacetBRDF`` =
  ``Subsurface_Facet_BRDF_Model``, ``DiffuseSubsurfaceBRDF`` =
  ``Diffuse_Subsurface_BRDF_Model``, ``SingleScatterBRDF`` (depolarizing
  Henyey-Greenstein) = ``First_Diffuse_BRDF_Model`` with ``Unpolarized_Phase_Function``.
* Mitsuba 3 ``roughconductor`` (``ggx``; float32) = ``FacetBRDF(GGXSlopes, shadowing="smith")``:
  the scalar variants one direction per call (``scalar_rgb`` against ``brdf``,
  ``scalar_spectral_polarized`` against ``mueller``), and the LLVM JIT variants on
  arrays (``llvm_ad_rgb``, ``llvm_ad_mono_polarized``) on one thread, when Dr.Jit finds
  an LLVM it can use (``DRJIT_LIBLLVM_PATH``; set here to Debian's ``libLLVM-19.so``
  when that exists and the variable is unset).  Beside each, ours per geometry without the
  Smith term (``shadowing="none"``): issue 30 asks float64 within 2x of Mitsuba's float32
  per geometry with and without it; the last lines print both ratios.

Every side runs on one thread: Dr.Jit is set to one (``dr.set_thread_count(1)``),
scatterbench's compiled kernels (which run on threads over every core from 1024
geometries) are pinned to one around its timed calls (``numba.set_num_threads(1)``),
and numpy's elementwise arithmetic is single-threaded; the JSON records the counts
(``machine.threads``).

For every pair two figures on each side: *per call*, one geometry per call
(``m.mueller(0.5, 0.6, 0.1)``-style, what a ported SCATMECH loop pays), and *per
geometry*, ``--n`` geometries in one call for the array implementations (scatterbench,
Mitsuba's LLVM variants) or a Python loop over ``--loop`` of them for the one-geometry
APIs.  Each is the best CPU time over short batches after a warm-up call
(:func:`scatterbench.validation.studies.tradeoff.time_call`, >= 0.2 s of work), with the best wall
time beside it; scatterbench evaluates in float64, SCATMECH in double, Mitsuba in
float32.  Mitsuba is timed from direction vectors already in its arrays (its input),
scatterbench from angles.  Every row also states how far the two implementations'
values differ on the timed geometries, so the timings are of the same quantity.
A peer that is not installed is skipped, saying so.

The table is written (``--out``, default ``references/data/peer_timings.json``) with the
machine, the versions, the date and the load average: measured figures, to be shown as
measured, on this machine.
"""

from __future__ import annotations

import os
import sys

# the checkout's packages, not an installed copy, when run as ``python benchmarks/...``
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import argparse
import datetime
import math
import platform
import subprocess
from dataclasses import asdict, dataclass, field
from importlib import metadata

import numba
import numpy as np

from scatterbench import models
from scatterbench.models.geometry import incident_direction, scattered_direction
from scatterbench.validation.numerics.probes import random_geometries
from scatterbench.validation.studies.tradeoff import time_call

DEFAULT_OUT = os.path.join(
    os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "references", "data", "peer_timings.json"
)
AL = 1.37 + 7.62j
RBAR_NOTE = (
    "SCATMECH integrates the diffuse R-bar on a 0.2-deg grid, we exactly: the values differ by "
    "that (validation.checks.seed003 allows 2e-3 for this pair)"
)
#: Debian's LLVM for Dr.Jit's JIT variants (the older default LLVM fails with "Cannot select fmaximum")
LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
#: threads of every timed side (scatterbench's kernels, Dr.Jit's JIT variants)
THREADS = 1


@dataclass
class Row:
    """One pair: per-call and per-geometry microseconds (CPU, wall) on each side."""

    model: str
    peer: str
    variant: str
    ours_precision: str
    peer_precision: str
    ours_call_us: float
    ours_call_wall_us: float
    ours_geometry_us: float
    ours_geometry_wall_us: float
    peer_call_us: float
    peer_call_wall_us: float
    peer_geometry_us: float
    peer_geometry_wall_us: float
    max_rel_diff: float
    compared: str
    notes: list = field(default_factory=list)
    #: Mitsuba's pairs: ours per geometry without the Smith term (``shadowing="none"``, the rest
    #: the same), CPU and wall; Mitsuba's ``roughconductor`` always applies its ``G``
    ours_unshadowed_geometry_us: float | None = None
    ours_unshadowed_geometry_wall_us: float | None = None


def geometries(n, seed=2024):
    """``(ti, tr, pr)``: polar angles uniform in [0, 80] deg, azimuth in [-pi, pi)."""
    return random_geometries(n, seed, max_deg=80.0)


def _us(fn, per=1):
    """``(output, CPU us, wall us)`` per item of ``fn()`` doing ``per`` items."""
    out, t = time_call(fn)
    return out, t.seconds / per * 1e6, t.wall_seconds / per * 1e6


def time_ours(evaluate, g, loop):
    """scatterbench: one geometry per call, and all of ``g`` in one call; the values
    at the first ``loop`` geometries (for the comparison)."""
    ti, tr, pr = g
    threads = numba.get_num_threads()
    numba.set_num_threads(THREADS)  # the kernels would use a thread per core from 1024 geometries
    try:
        _, call, call_wall = _us(lambda: evaluate(float(ti[0]), float(tr[0]), float(pr[0])))
        out, geom, geom_wall = _us(lambda: evaluate(ti, tr, pr), per=ti.size)
    finally:
        numba.set_num_threads(threads)
    return out[:loop], (call, call_wall, geom, geom_wall)


def _loop_peer(one, g, loop):
    """A one-geometry API: one call, and a Python loop over ``loop`` geometries."""
    ti, tr, pr = (a[:loop] for a in g)
    _, call, call_wall = _us(lambda: one(ti[0], tr[0], pr[0]))
    out, geom, geom_wall = _us(lambda: [one(a, b, c) for a, b, c in zip(ti, tr, pr, strict=True)], per=loop)
    return np.array(out), (call, call_wall, geom, geom_wall)


def _rel_diff(ours, theirs, floor=1e-250):
    """max |ours - theirs| / max(|theirs M00|, floor) over the geometries (every element)."""
    ours, theirs = np.asarray(ours, float), np.asarray(theirs, float)
    m00 = theirs[:, 0, 0] if theirs.ndim == 3 else theirs
    diff = np.abs(ours - theirs).reshape(len(m00), -1).max(axis=1)
    return float(np.max(diff / np.maximum(np.abs(m00), floor)))


# ----------------------------------------------------------------------------- SCATMECH
def scatmech_pairs():
    """``(name, our model, SCATMECH model name, its parameters)`` for the four pairs."""
    exp = {"sdf": "Exponential_Slope_Distribution_Function", "sdf.s": "0.1"}
    hg = {
        "phase_function": "Unpolarized_Phase_Function",
        "phase_function.phase_function": "Henyey_Greenstein_Phase_Function",
        "phase_function.phase_function.g": "0.3",
        "phase_function.log_absorption": "-1000",
    }
    return [
        ("FacetBRDF", models.FacetBRDF(slopes=models.ExponentialSlopes(0.1), substrate=AL),
         "Facet_BRDF_Model", {"substrate": "(1.37,7.62)", **exp}),
        ("SubsurfaceFacetBRDF",
         models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.1), coating=1.5, substrate=AL),
         "Subsurface_Facet_BRDF_Model", {"substrate": "(1.37,7.62)", "overcoat": "(1.5,0)", **exp}),
        ("DiffuseSubsurfaceBRDF", models.DiffuseSubsurfaceBRDF(coating=1.5, rho=0.93),
         "Diffuse_Subsurface_BRDF_Model", {"substrate": "(1.5,0)", "reflectance.table": "0.93"}),
        ("SingleScatterBRDF",
         models.SingleScatterBRDF(coating=1.5, phase=models.HenyeyGreenstein(g=0.3, polarized=False)),
         "First_Diffuse_BRDF_Model", {"substrate": "(1.5,0)", **hg}),
    ]  # fmt: skip


def scatmech_rows(g, loop):
    """One :class:`Row` per SCATMECH pair; ``(rows, None)`` or ``([], reason)``."""
    try:
        from pySCATMECH.brdf import BRDF_Model
    except ImportError as exc:
        return (
            [],
            f"pySCATMECH not installed ({exc}): pip install pyscatmech (compiles SCATMECH, several minutes)",
        )
    rows = []
    for name, ours, sc_name, params in scatmech_pairs():
        ref = BRDF_Model(sc_name, **params)
        theirs, peer = _loop_peer(lambda a, b, c, ref=ref: np.array(ref.MuellerBRDF(a, b, c)), g, loop)
        mine, me = time_ours(ours.mueller, g, loop)
        rows.append(
            Row(name, "pySCATMECH", sc_name, "float64", "double (C++)", *me, *peer,
                _rel_diff(mine, theirs), "every Mueller element, relative to SCATMECH's M00",
                [RBAR_NOTE] if name == "DiffuseSubsurfaceBRDF" else [])
        )  # fmt: skip
    return rows, None


# ----------------------------------------------------------------------------- Mitsuba 3
def _directions(mi, ti, tr, pr):
    """Mitsuba's ``(si.wi, wo)`` for our geometry: ``si.wi`` our reflected direction, ``wo``
    the reverse of our incident ray (towards the light)."""
    wi = scattered_direction(tr, pr)
    wo = -incident_direction(ti)
    return mi.Vector3f(*np.moveaxis(wi, -1, 0)), mi.Vector3f(*np.moveaxis(wo, -1, 0))


def _interaction(mi, polarized):
    si = mi.SurfaceInteraction3f()
    si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
    si.n = mi.Normal3f(0.0, 0.0, 1.0)
    if polarized and mi.variant().startswith("scalar_spectral"):
        si.wavelengths = [550.0] * 4
    return si


def _scalar_one(mi, bsdf, polarized):
    """One direction per call: Mitsuba's BRDF (M00 for the polarized variant, in 1/sr)."""
    ctx, si = mi.BSDFContext(), _interaction(mi, polarized)

    def one(ti, tr, pr):
        si.wi, wo = _directions(mi, ti, tr, pr)
        v = bsdf.eval(ctx, si, wo)
        m00 = np.array(v, dtype=float)[0, 0, 0] if polarized else float(v[0])
        return m00 / math.cos(ti)  # eval is f cos(theta_i)

    return one


def _llvm_timed(mi, dr, bsdf, polarized, g):
    """Dr.Jit arrays: one geometry per call and all of ``g`` in one call (evaluated and
    synchronized: the kernel has run when the clock stops); M00 of every geometry."""
    ctx = mi.BSDFContext()

    def run(ti, tr, pr):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
        si.n = mi.Normal3f(0.0, 0.0, 1.0)
        si.wi, wo = _directions(mi, ti, tr, pr)
        dr.eval(si.wi, wo)

        def call():
            v = bsdf.eval(ctx, si, wo)
            dr.eval(v)
            dr.sync_thread()
            return v

        return call

    ti, tr, pr = g
    _, call, call_wall = _us(run(ti[:1], tr[:1], pr[:1]))
    v, geom, geom_wall = _us(run(ti, tr, pr), per=ti.size)
    m00 = np.array(v[0][0] if polarized else v[0], dtype=float).reshape(-1)
    return m00 / np.cos(ti), (call, call_wall, geom, geom_wall)


#: one evaluation of a JIT variant, run in a child process first (:func:`_jit_unusable`)
_JIT_PROBE = """
import drjit as dr, mitsuba as mi
mi.set_variant({variant!r})
b = mi.load_dict({{"type": "roughconductor", "distribution": "ggx", "alpha": 0.2, "eta": 1.37, "k": 7.62}})
si = dr.zeros(mi.SurfaceInteraction3f)
si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
si.wi = mi.Vector3f(0.0, 0.0, 1.0)
dr.eval(b.eval(mi.BSDFContext(), si, mi.Vector3f(0.0, 0.0, 1.0)))
"""


def _jit_unusable(variant):
    """``None`` when Mitsuba's JIT ``variant`` evaluates a BSDF in a child process, else why
    not: an LLVM that Dr.Jit cannot use aborts the process inside LLVM ("Cannot select
    fmaximum"), which no ``except`` in this one could catch."""
    res = subprocess.run(
        [sys.executable, "-c", _JIT_PROBE.format(variant=variant)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    if res.returncode == 0:
        return None
    tail = (res.stderr.strip().splitlines() or [f"exit status {res.returncode}"])[-1]
    return f"its probe process failed ({tail[:200]}); Dr.Jit needs Debian's libllvm19 (DRJIT_LIBLLVM_PATH={LLVM})"


def mitsuba_rows(g, loop):
    """One :class:`Row` per Mitsuba variant that runs; ``(rows, notes)``."""
    try:
        import drjit as dr
        import mitsuba as mi
    except ImportError as exc:
        return [], [f"Mitsuba 3 not installed ({exc}): pip install mitsuba"]
    ours = models.FacetBRDF(slopes=models.GGXSlopes(alpha=0.2), substrate=AL, shadowing="smith")
    bare = models.FacetBRDF(slopes=models.GGXSlopes(alpha=0.2), substrate=AL)
    rows, notes = [], []
    for variant in ("scalar_rgb", "scalar_spectral_polarized", "llvm_ad_rgb", "llvm_ad_mono_polarized"):
        polarized = variant.endswith("polarized")
        why = None if variant.startswith("scalar") else _jit_unusable(variant)
        if why:
            notes.append(f"Mitsuba {variant} skipped: {why}")
            continue
        try:
            mi.set_variant(variant)
            dr.set_thread_count(THREADS)
            bsdf = mi.load_dict(
                {"type": "roughconductor", "distribution": "ggx", "alpha": 0.2, "eta": 1.37, "k": 7.62}
            )
            if variant.startswith("scalar"):
                theirs, peer = _loop_peer(_scalar_one(mi, bsdf, polarized), g, loop)
            else:
                theirs, peer = _llvm_timed(mi, dr, bsdf, polarized, g)
                theirs = theirs[:loop]
        except Exception as exc:  # noqa: BLE001 - a JIT variant without a usable LLVM says why
            notes.append(f"Mitsuba {variant} skipped: {type(exc).__name__}: {exc}")
            continue
        what = "mueller" if polarized else "brdf"
        mine, me = time_ours(getattr(ours, what), g, loop)
        _, unshadowed = time_ours(getattr(bare, what), g, loop)
        m00 = mine[:, 0, 0] if polarized else mine
        rows.append(
            Row("FacetBRDF(GGX 0.2, smith)", "Mitsuba 3", f"roughconductor ggx, {variant}", "float64", "float32",
                *me, *peer, _rel_diff(m00, theirs, floor=1e-20), "BRDF (M00), relative; float32 on Mitsuba's side",
                [] if variant.startswith("scalar") else [f"Dr.Jit on {THREADS} thread, from direction arrays"],
                *unshadowed[2:])
        )  # fmt: skip
    return rows, notes


# ----------------------------------------------------------------------------- output
def _versions():
    out = {"python": platform.python_version(), "numpy": np.__version__}
    for pkg in ("pyscatmech", "mitsuba", "drjit", "numba"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = None
    return out


def _machine():
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next((ln.split(":", 1)[1].strip() for ln in fh if ln.startswith("model name")), cpu)
    except OSError:
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "platform": platform.platform(),
        "load_average_at_start": os.getloadavg(),
        "threads": {"scatterbench (numba kernels)": THREADS, "Dr.Jit (Mitsuba LLVM variants)": THREADS},
    }


def print_table(rows):
    print(
        f"{'model':<26} {'peer / variant':<46} {'per call (us)':>22} {'per geometry (us)':>24} {'max diff':>9}"
    )
    print(f"{'':<26} {'':<46} {'ours':>7} {'peer':>7} {'ratio':>6} {'ours':>7} {'peer':>8} {'ratio':>7}")
    for r in rows:
        print(
            f"{r.model:<26} {(r.peer + ' ' + r.variant)[:46]:<46} {r.ours_call_us:>7.2f} {r.peer_call_us:>7.2f} "
            f"{r.peer_call_us / r.ours_call_us:>6.2f} {r.ours_geometry_us:>7.3f} {r.peer_geometry_us:>8.4f} "
            f"{r.peer_geometry_us / r.ours_geometry_us:>7.2f} {r.max_rel_diff:>9.1e}"
        )
    print(
        f"ratio = peer / scatterbench (> 1: scatterbench is faster); CPU time, best of batches, {THREADS} thread"
    )
    for r in (r for r in rows if r.ours_unshadowed_geometry_us is not None and "llvm" in r.variant):
        print(
            f"{r.variant}: ours per geometry {r.ours_geometry_us:.4f} us with Smith's G, "
            f"{r.ours_unshadowed_geometry_us:.4f} without; Mitsuba (always with its G) {r.peer_geometry_us:.4f}: "
            f"ours / Mitsuba {r.ours_geometry_us / r.peer_geometry_us:.2f}x, "
            f"{r.ours_unshadowed_geometry_us / r.peer_geometry_us:.2f}x"
        )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=100_000, help="geometries per array call")
    ap.add_argument("--loop", type=int, default=1000, help="geometries of a one-geometry-per-call loop")
    ap.add_argument("--out", default=DEFAULT_OUT, help="JSON file of the measured table")
    ap.add_argument("--no-save", action="store_true", help="print only")
    args = ap.parse_args(argv)
    if args.n < 1 or not 1 <= args.loop <= args.n:
        ap.error(f"--n must be >= 1 and --loop in [1, --n]; got --n {args.n}, --loop {args.loop}")
    if "DRJIT_LIBLLVM_PATH" not in os.environ and os.path.exists(LLVM):
        os.environ["DRJIT_LIBLLVM_PATH"] = LLVM  # read when Dr.Jit starts its LLVM backend
    machine, g = _machine(), geometries(args.n)
    sc_rows, sc_skip = scatmech_rows(g, args.loop)
    mi_rows, mi_notes = mitsuba_rows(g, args.loop)
    skipped = ([sc_skip] if sc_skip else []) + mi_notes
    print_table(sc_rows + mi_rows)
    for s in skipped:
        print(f"skipped: {s}")
    if not args.no_save:
        from scatterbench.validation.atomic import atomic_write_json

        machine["load_average_at_end"] = os.getloadavg()
        atomic_write_json(args.out, {
            "what": "per-call and per-geometry times of scatterbench and its peers, measured in one run "
                    f"by benchmarks/peers.py (CPU time, best of batches, {THREADS} thread on every side; wall time beside it)",
            "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
            "machine": machine, "versions": _versions(), "geometries": {"array": args.n, "loop": args.loop},
            "rows": [asdict(r) for r in sc_rows + mi_rows], "skipped": skipped,
        })  # fmt: skip
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
