"""The speed/accuracy trade, measured (issue 5 item 3).

A *knob* is a setting that trades cost for accuracy.  For each knob the study
evaluates a quantity at every setting, times it, and measures its error against
an independent higher-accuracy reference (never an extrapolation):

* ``integration tolerance``: the integrated reflectance at ``tol`` in
  1e-2 .. 1e-8, against the slope-space prediction of
  :mod:`validation.numerics.energy` (an exposed facet surface) — a different algorithm,
  not the same integrator at a tighter tolerance;
* ``in-plane grid``: an in-plane BRDF curve sampled on ``k`` points and linearly
  interpolated, against the model evaluated on a 20001-point grid (max relative
  error over the curve);
* knobs that other modules register with :func:`register_knob` (Monte Carlo
  pairs, point-source resolution, ...).

``pareto`` keeps the settings no other setting beats on both cost and error;
``choose(knob, tol)`` returns the cheapest setting whose *measured* error meets
``tol`` (or says none does).
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np

import models
from models.geometry import signed_inplane
from validation.numerics.energy import exposed_reflectance
from validation.numerics.integrate import integrated_reflectance

__all__ = ["Point", "KnobResult", "register_knob", "KNOBS", "study", "pareto", "choose"]


@dataclass(frozen=True)
class Point:
    setting: float
    error: float
    seconds: float
    evaluations: int


@dataclass(frozen=True)
class KnobResult:
    knob: str
    quantity: str
    reference: str
    points: list = field(default_factory=list)

    def as_dict(self):
        return {**asdict(self), "pareto": [asdict(p) for p in pareto(self.points)]}


KNOBS = {}


def register_knob(name):
    def deco(fn):
        KNOBS[name] = fn
        return fn

    return deco


def _timed(fn, repeat=3):
    best = math.inf
    out = None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return out, best


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
        r, sec = _timed(lambda tol=tol: integrated_reflectance(model, theta_i, tol=tol))
        points.append(Point(tol, abs(r.value - truth), sec, r.evaluations))
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
        vals, sec = _timed(lambda x=x: curve(x))
        interp = np.interp(fine, x, vals)
        err = float(np.max(np.abs(interp - ref)) / np.max(ref))
        points.append(Point(k, err, sec, k))
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
        errs, secs = [], []
        for seed in seeds:
            m = mc(pairs, seed)
            m.brdf(theta_i, tr[:1], 0.0)  # exclude one-time set-up (the rough-interface R-bar) from the cost
            vals, sec = _timed(lambda m=m: m.brdf(theta_i, tr, 0.0), repeat=1)
            errs.append(np.mean(((vals - ref) / ref) ** 2))
            secs.append(sec)
        points.append(Point(pairs, float(np.sqrt(np.mean(errs))), float(np.median(secs)), pairs * tr.size))
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
        vals, sec = _timed(lambda m=m: m.brdf(theta_i, tr, 0.0))
        points.append(
            Point(res, float(np.max(np.abs(vals - ref)) / np.max(ref)), sec, res * 2 * res * tr.size)
        )
    return KnobResult(
        "point-source resolution",
        "PointSourceBRDF(exact) around CookTorranceBRDF(m 0.03, iron), d/R = 10, in-plane 30-60 deg at 45 deg",
        "the same superposition at resolution 96; max |f - f_ref| / max f_ref",
        points,
    )


def pareto(points):
    """Settings not dominated in (cost, error)."""
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
    """Cheapest setting whose measured error is <= tol, or None."""
    ok = [p for p in result.points if p.error <= tol]
    return min(ok, key=lambda p: p.seconds) if ok else None


def study(names=None, quick=False):
    return [KNOBS[n](quick=quick) for n in (names or KNOBS)]
