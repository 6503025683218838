"""The speed/accuracy trade, measured (issue 5 item 3, issue 12 item 5).

A *knob* is a setting that trades cost for accuracy.  For each knob the study
evaluates a quantity at every setting, times it, and measures its error against
an independent higher-accuracy reference (never an extrapolation):

* ``integration tolerance``: the integrated reflectance at ``tol`` in
  1e-2 .. 1e-8, against the slope-space prediction of
  :mod:`scatterbench.validation.numerics.energy` (an exposed facet surface) — a different algorithm,
  not the same integrator at a tighter tolerance;
* ``in-plane grid``: an in-plane BRDF curve sampled on ``k`` points and linearly
  interpolated, against the model evaluated on a 20001-point grid (max relative
  error over the curve);
* ``precision``: the Mueller matrix evaluated in float32 against float64, where a
  float32 kernel evaluates the model (:func:`precision_option`); skipped, saying why,
  where none does or where the model's parameters send float32 to the float64 fallback;
* knobs that other modules register with :func:`register_knob` (Monte Carlo
  pairs, point-source resolution, ...).

Costs are per call, the best over repeated short batches (:func:`time_call`): a
setting is called in batches of about :data:`BATCH` seconds until at least
:data:`MIN_WORK` seconds of work have accumulated over at least :data:`MIN_BATCHES`
batches, after one untimed warm-up call.  A single timing of a sub-millisecond call
measures the machine's noise, not the setting.  Each point keeps the spread of its
batches beside the best.

``pareto`` keeps the settings no other setting beats on both cost and error;
``choose(knob, tol)`` returns the cheapest setting whose *measured* error meets
``tol`` (or says none does).  Settings with the same error are a tie that CPU-time
noise must not break: both keep the one with the fewest evaluations, then the coarser
setting (listed first: every knob lists its settings coarser first).
"""

from __future__ import annotations

import functools
import inspect
import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from scatterbench import models
from scatterbench.models import evaluation
from scatterbench.models.geometry import signed_inplane
from scatterbench.validation.fitting.executors import SerialExecutor
from scatterbench.validation.numerics.energy import exposed_reflectance
from scatterbench.validation.numerics.integrate import integrated_reflectance
from scatterbench.validation.numerics.probes import (
    random_geometries,  # not at import: it loads every check
)

__all__ = [
    "Point",
    "KnobResult",
    "KnobUnavailable",
    "precision_error",
    "register_knob",
    "KNOBS",
    "MIN_WORK",
    "MIN_BATCHES",
    "BATCH",
    "Timing",
    "time_call",
    "precision_option",
    "float32_unavailable",
    "at_precision",
    "study",
    "run",
    "measure_knob",
    "knob_tasks",
    "collected",
    "throughput",
    "pareto",
    "choose",
]

#: Seconds of work accumulated per setting before its cost is taken.
MIN_WORK = 0.2
#: The fewest timed batches per setting.
MIN_BATCHES = 3
#: Target length of one timed batch (s): far above the clocks' resolution (perf_counter and
#: process_time: 1e-9 s on Linux, ``time.get_clock_info``), and short enough that on a busy
#: machine some batches run undisturbed (the cost is the best batch).
BATCH = 2e-3


@dataclass(frozen=True)
class Point:
    """One setting of a knob: its error against the reference and its cost.

    ``seconds`` is the best CPU time per call over ``calls`` timed calls in batches
    (:func:`time_call`); ``spread`` is ``(median - best) / best`` over those batches;
    ``wall_seconds`` the best wall-clock time per call (``nan``: not measured);
    ``cpu_total`` the CPU seconds of all the timed batches (``nan``: not measured).
    """

    setting: float
    error: float
    seconds: float
    evaluations: int
    spread: float = 0.0
    calls: int = 1
    wall_seconds: float = math.nan
    cpu_total: float = math.nan


@dataclass(frozen=True)
class KnobResult:
    knob: str
    quantity: str
    reference: str
    points: list = field(default_factory=list)

    def as_dict(self):
        return {**asdict(self), "pareto": [asdict(p) for p in pareto(self.points)]}


class KnobUnavailable(Exception):
    """A knob that cannot be measured here; the message says why."""


KNOBS = {}


def register_knob(name):
    def deco(fn):
        KNOBS[name] = fn
        return fn

    return deco


@dataclass(frozen=True)
class Timing:
    """The cost of a call (:func:`time_call`): best CPU seconds per call, spread of the
    batches, calls timed, best wall-clock seconds per call, CPU seconds of all the timed
    batches."""

    seconds: float
    spread: float
    calls: int
    wall_seconds: float
    cpu_total: float


def time_call(fn, min_work=MIN_WORK, min_batches=MIN_BATCHES, batch=BATCH):
    """``(output, Timing)`` of ``fn()``.

    One untimed warm-up call (first-call set-up, caches) gives the output and the
    batch size, ``ceil(batch / warm-up time)`` calls (one for calls longer than
    ``batch``).  Batches repeat until ``min_work`` seconds of CPU time have
    accumulated and at least ``min_batches`` ran.  Each batch is timed on two clocks:
    the process's CPU time (every thread of this process, and only this process: the
    cost, which other work on the machine does not inflate) and the wall clock (what a
    user waits, on this machine as loaded).  The cost is the best batch's CPU time per
    call; the spread is ``(median - best) / best`` over the batches.
    """
    t = time.perf_counter()
    out = fn()
    first = time.perf_counter() - t
    number = max(1, math.ceil(batch / max(first, 1e-9)))
    cpu, wall = [], []
    while len(cpu) < min_batches or sum(cpu) * number < min_work:
        t, c = time.perf_counter(), time.process_time()
        for _ in range(number):
            fn()
        cpu.append((time.process_time() - c) / number)
        wall.append((time.perf_counter() - t) / number)
    best = min(cpu)
    spread = float(np.median(cpu)) / best - 1.0 if best > 0 else 0.0
    return out, Timing(best, spread, number * len(cpu), min(wall), sum(cpu) * number)


def _point(setting, error, timing: Timing, evaluations):
    t = timing
    return Point(
        setting, float(error), t.seconds, int(evaluations), t.spread, t.calls, t.wall_seconds, t.cpu_total
    )


@register_knob("integration tolerance")
def knob_integration(quick=False):
    slopes = models.ExponentialSlopes(0.1)
    substrate = 1.37 + 7.62j
    theta_i = math.radians(60)
    model = models.FacetBRDF(slopes=slopes, substrate=substrate)
    truth = exposed_reflectance(slopes, theta_i, substrate)
    points = []
    tols = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6) if quick else (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)
    for tol in tols:
        r, cost = time_call(functools.partial(integrated_reflectance, model, theta_i, tol=tol))
        points.append(_point(tol, abs(r.value - truth), cost, r.evaluations))
    return KnobResult(
        "integration tolerance",
        "integrated reflectance, FacetBRDF(exponential sigma 0.1, aluminium), 60 deg",
        "slope-space integral (validation.numerics.energy.exposed_reflectance)",
        points,
    )


@register_knob("in-plane grid")
def knob_grid(quick=False):
    model = models.SubsurfaceFacetBRDF(
        slopes=models.ExponentialSlopes(0.1), coating=1.5, substrate=1.37 + 7.62j
    )
    theta_i = math.radians(60)
    # in-plane curve: theta_r in [0, 89 deg] at phi = 0 and pi (signed angle x)
    fine = np.linspace(-math.radians(89), math.radians(89), 20001)

    def curve(x):
        return model.brdf(theta_i, *signed_inplane(x))

    ref = curve(fine)
    points = []
    ks = (19, 37, 91, 181, 361) if quick else (19, 37, 91, 181, 361, 721, 1441, 2881)
    for k in ks:
        x = np.linspace(fine[0], fine[-1], k)
        vals, cost = time_call(functools.partial(curve, x))
        err = np.max(np.abs(np.interp(fine, x, vals) - ref)) / np.max(ref)
        points.append(_point(k, err, cost, k))
    return KnobResult(
        "in-plane grid",
        "in-plane BRDF curve of SubsurfaceFacetBRDF at 60 deg (linear interpolation)",
        "the model on a 20001-point grid; error = max |interp - ref| / max ref",
        points,
    )


@register_knob("Monte Carlo pairs")
def knob_mc_pairs(quick=False):
    """RoughDiffuseBRDF (volume terms, no surface term; exponential slopes rms 0.5)
    against an independent run with many more pairs and another seed; the
    reference's own standard error is measured and reported."""
    n, g, rho = 1.5, 0.3, 0.3
    phase = models.HenyeyGreenstein(g=g, polarized=False)
    slopes = models.ExponentialSlopes(0.5)
    theta_i = math.radians(45)
    tr = np.radians(np.linspace(0, 80, 17))

    def mc(pairs, seed):
        return models.RoughDiffuseBRDF(
            slopes=slopes, coating=n, phase=phase, rho=rho, pairs=pairs, seed=seed, surface=False
        )

    ref_pairs = 20_000 if quick else 60_000
    ref_m, ref_se = mc(ref_pairs, 12345).mueller_with_error(theta_i, tr, 0.0)
    ref = ref_m[:, 0, 0]
    ref_rel = float(np.sqrt(np.mean((ref_se[:, 0, 0] / ref) ** 2)))
    points = []
    seeds = (7, 8, 9)  # the error of one run is one random draw: average its square over seeds
    for pairs in (50, 200, 1000) if quick else (50, 200, 1000, 5000):
        # the cost does not depend on the seed: one seed's calls are timed (the untimed
        # warm-up call takes the one-time set-up, the rough interface's R-bar, out of it)
        first, cost = time_call(functools.partial(mc(pairs, seeds[0]).brdf, theta_i, tr, 0.0))
        vals = [first] + [mc(pairs, seed).brdf(theta_i, tr, 0.0) for seed in seeds[1:]]
        err = math.sqrt(np.mean([np.mean(((v - ref) / ref) ** 2) for v in vals]))
        points.append(_point(pairs, err, cost, pairs * tr.size))
    return KnobResult(
        "Monte Carlo pairs",
        "RoughDiffuseBRDF (surface off, exponential rms slope 0.5, n 1.5, g 0.3, rho 0.3), 17 in-plane angles at 45 deg",
        f"independent run with {ref_pairs} pairs (another seed), rms relative SE {ref_rel:.2g}; "
        "rms relative error over angles and 3 seeds",
        points,
    )


@register_knob("point-source resolution")
def knob_point_source(quick=False):
    """Exact superposition (seed 001 Eq. 28) at increasing quadrature resolution against a
    resolution-96 evaluation (converged to ~1e-12), iron plate, d/R = 10."""
    inner = models.CookTorranceBRDF(
        slopes=models.GaussianSlopes(0.03), substrate=2.29 + 3.37j, convention="corrected"
    )
    theta_i = math.radians(45)
    tr = np.radians(np.linspace(30, 60, 61))
    ref = models.PointSourceBRDF(model=inner, distance=10.0, sample_radius=1.0, resolution=96).brdf(
        theta_i, tr, 0.0
    )
    points = []
    for res in (2, 4, 8, 16) if quick else (2, 4, 8, 16, 24, 32, 48):
        m = models.PointSourceBRDF(model=inner, distance=10.0, sample_radius=1.0, resolution=res)
        vals, cost = time_call(functools.partial(m.brdf, theta_i, tr, 0.0))
        err = np.max(np.abs(vals - ref)) / np.max(ref)
        points.append(_point(res, err, cost, res * 2 * res * tr.size))
    return KnobResult(
        "point-source resolution",
        "PointSourceBRDF(exact) around CookTorranceBRDF(m 0.03, iron), d/R = 10, in-plane 30-60 deg at 45 deg",
        "the same superposition at resolution 96; max |f - f_ref| / max f_ref",
        points,
    )


def float32_unavailable(model):
    """Why ``model`` has no float32 evaluation to measure (a sentence naming it), or ``None``.

    Every :class:`scatterbench.models.Model`'s ``mueller`` takes ``precision="float32"``, but only a
    model a compiled kernel evaluates (``_kernel_spec()`` not ``None``, numba backend)
    computes in float32, and only inside the kernels' float32-safe domain
    (:mod:`scatterbench.models.float32_domain`): elsewhere (Monte Carlo, wrappers such as the point
    source; parameters outside the domain) it evaluates in float64 and rounds, at float64's
    cost.  An object that is not a :class:`scatterbench.models.Model` is taken at its word when its
    ``mueller`` takes the keyword.
    """
    name = type(model).__name__
    if "precision" not in inspect.signature(model.mueller).parameters:
        return f"{name} has no float32 kernel"
    if isinstance(model, models.Model):
        if not evaluation.kernel_path(model):
            return f"{name} has no float32 kernel"
        if model.float32_fallback is not None:
            return f"{name} falls back to float64 for float32 requests ({model.float32_fallback})"
    return None


def precision_option(model):
    """``"keyword"`` when ``model`` really evaluates in float32 through its ``mueller``'s
    ``precision="float32"`` keyword, else ``None`` (:func:`float32_unavailable` says why)."""
    return None if float32_unavailable(model) else "keyword"


def at_precision(model, precision):
    """``model.mueller`` evaluating at ``precision`` (``"float64"`` or ``"float32"``)
    through the model's own option; ``ValueError`` if it has none."""
    if precision not in ("float64", "float32"):
        raise ValueError(f"precision must be 'float64' or 'float32'; got {precision!r}")
    reason = float32_unavailable(model)
    if reason is not None:
        raise ValueError(f"precision: {reason}")
    return functools.partial(model.mueller, precision=precision)


def precision_error(mueller, reference):
    """The precision knob's error: max ``|M - M_ref|`` over every element and geometry, divided
    by max ``M00_ref`` (``reference``: the float64 evaluation)."""
    return float(np.max(np.abs(mueller.astype(np.float64) - reference)) / np.max(reference[..., 0, 0]))


@register_knob("precision")
def knob_precision(quick=False, model=None):
    """The Mueller matrix in float32 and float64 on 4096 random geometries, against the
    float64 evaluation (so the float64 point has error 0 by construction); ``model``
    defaults to seed 000's coated flake model.  :class:`KnobUnavailable` when no float32
    kernel evaluates the model, or its parameters send float32 requests to float64
    (:func:`float32_unavailable`): a fallback is reported, never timed as float32."""
    if model is None:
        model = models.SubsurfaceFacetBRDF(
            slopes=models.ExponentialSlopes(0.1), coating=1.5, substrate=1.37 + 7.62j
        )
    reason = float32_unavailable(model)
    if reason is not None:
        raise KnobUnavailable(
            f"{reason}: it evaluates in float64 (and rounds a float32 request), so there is no "
            "float32 cost to measure"
        )

    ti, tr, pr = random_geometries(4096, seed=12, max_deg=85.0)
    measured = {
        bits: time_call(functools.partial(at_precision(model, f"float{bits}"), ti, tr, pr))
        for bits in (32, 64)  # cheaper and coarser first, as on every knob
    }
    ref = measured[64][0]
    points = [_point(bits, precision_error(M, ref), cost, ti.size) for bits, (M, cost) in measured.items()]
    return KnobResult(
        "precision",
        f"Mueller matrix of {model!r} on 4096 random geometries (theta < 85 deg); "
        "setting = bits of the evaluation (64: float64, 32: float32)",
        "the float64 evaluation; error = max |M - M_ref| (every element) / max M00_ref",
        points,
    )


def _untied(points):
    """One point per distinct error, in the points' order: of those with the same error
    the fewest evaluations, then the first listed (the coarser setting).  Equal error and
    evaluations mean the same work (e.g. integration tolerances 1e-2..1e-4 stopping at
    the same 15750 evaluations): their CPU times differ by noise only."""
    best = {}
    for i, p in enumerate(points):
        if p.error not in best or p.evaluations < best[p.error][1].evaluations:
            best[p.error] = (i, p)
    return [p for _, p in sorted(best.values(), key=lambda t: t[0])]


def pareto(points):
    """Settings not dominated in (cost, error), ties in error broken as :func:`_untied`."""
    points = _untied(points)
    keep = []
    for p in points:
        dominated = any(
            (q.seconds <= p.seconds and q.error <= p.error) and (q.seconds < p.seconds or q.error < p.error)
            for q in points
        )
        if not dominated:
            keep.append(p)
    return sorted(keep, key=lambda p: p.seconds)


def choose(result: KnobResult, tol: float):
    """Cheapest setting whose measured error is <= tol, or None; ties in error broken
    deterministically (fewest evaluations, then the coarser setting: :func:`_untied`)."""
    ok = [p for p in _untied(result.points) if p.error <= tol]
    return min(ok, key=lambda p: p.seconds) if ok else None


def run(task):
    """``task()``: what :func:`study` maps, so that one map can carry tasks of different
    functions (each a ``functools.partial``: the report's speed section sends the knobs and
    the models' :func:`throughput` together)."""
    return task()


def measure_knob(knob, quick=False):
    """Registered knob function ``knob`` measured: ``(KnobResult, None)``, or ``(None, why)``
    when it cannot be here (:class:`KnobUnavailable`).  A task of :func:`study` (the function
    itself travels, so a worker imports the module that registered it)."""
    try:
        return knob(quick=quick), None
    except KnobUnavailable as exc:
        return None, str(exc)


def knob_tasks(names=None, quick=False):
    """``(names, tasks)``: the knobs ``names`` (default every one) and a :func:`measure_knob`
    task (for :func:`run`) for each."""
    names = list(names or KNOBS)
    return names, [functools.partial(measure_knob, KNOBS[n], quick) for n in names]


def collected(names, done, skipped=None):
    """The :class:`KnobResult` of each measured knob of ``names`` (``done``: their
    :func:`measure_knob` results, in order); a knob that could not be measured is left out,
    its reason put in the dict ``skipped`` when one is given."""
    out = []
    for n, (result, why) in zip(names, done, strict=True):
        if result is not None:
            out.append(result)
        elif skipped is not None:
            skipped[n] = why
    return out


def study(names=None, quick=False, skipped=None, executor=None):
    """Every knob's :class:`KnobResult` (``names``: these knobs only; ``quick``: fewer settings).

    A knob that cannot be measured here (:class:`KnobUnavailable`) is left out; its
    reason goes into the dict ``skipped`` when one is given.  ``executor``: where the knobs
    run, one task each (:mod:`scatterbench.validation.fitting.executors`; default in-process).
    The errors do not depend on it; each cost is timed where its knob runs, on that worker's
    share of the cores, beside the other knobs' work.
    """
    names, tasks = knob_tasks(names, quick)
    return collected(names, (executor or SerialExecutor()).map(run, tasks, tasks=len(tasks)), skipped)


def throughput(model, n, seed):
    """``(Timing, threads)``: the cost of one ``model.mueller`` call (:func:`time_call`) on
    ``n`` random geometries drawn with ``seed`` (:func:`random_geometries`, polar angles up to
    83 deg), and the threads its compiled kernels may run on where it was timed
    (``numba.get_num_threads``: a worker's share of the cores)."""
    import numba  # numba (heavy): loaded where the kernels run anyway

    ti, tr, pr = random_geometries(n, seed=seed, max_deg=83.0)
    _, timing = time_call(functools.partial(model.mueller, ti, tr, pr))
    return timing, numba.get_num_threads()
