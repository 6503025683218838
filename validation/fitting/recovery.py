"""Injection-recovery study: does the fit's posterior cover the truth as often as it claims?

Each *injection* simulates a data set from a known scene (the truth: the
scene's values of the free parameters) at the given geometries with the
likelihood's own noise model (log-normal speckle of fractional level
``noise.brdf``; Gaussian eta / P / P_C noise when those terms are used), then
fits it: optimum, emcee chain, percentiles.  Over many injections the fraction
whose 68% (16-84) and 95% (2.5-97.5) intervals contain the truth is compared
with the nominal value; the binomial standard error of a fraction ``p`` over
``n`` injections is ``sqrt(p (1 - p) / n)``, and ``z`` says how many of those
the measured coverage is away.  Bias (posterior median - truth) and interval
width are tabulated against the noise level and the number of geometries.

Beside the posterior intervals each member also records whether the truth
lies inside the *curvature* intervals of the optimum (``u_opt +- 1`` and ``+- 2``
Gauss-Newton standard deviations in sampling coordinates; for free noise levels
the ``1/sqrt(2N)`` approximation of :func:`~scatterbench.validation.fitting.sampling.optimize`).
They cost nothing and answer the first question a low coverage raises: when the
curvature intervals cover nominally on the same data sets and the posterior's
do not, the sampler (chain length, walkers, burn-in) is at fault, not the data;
when both fall short, the estimator's own distribution has heavy tails.

Injection ``j`` of a cell uses ``SeedSequence([seed, cell, j])`` for its noise
and its chain, so a study's numbers do not depend on the executor or on how
members are scheduled.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from .executors import SerialExecutor
from .fit import run_fit
from .fitspec import FitSpec
from .likelihood import Likelihood, replicate, term_variances
from .sampling import _progress_bar
from .settings import ChainSettings, _integer

__all__ = [
    "simulate",
    "Member",
    "run_member",
    "check_inputs",
    "recovery_study",
    "coverage_table",
    "subsample",
]


def subsample(data, n):
    """``n`` rows spread evenly over the data set (all of them when ``n >= len``)."""
    if n >= len(data):
        return data
    idx = np.unique(np.round(np.linspace(0, len(data) - 1, n)).astype(int))
    return data.subset(idx)


def simulate(scene, spec: FitSpec, data, truth: dict, noise: dict, rng):
    """A synthetic copy of ``data`` (same rows, incident states) from the scene at ``truth``.

    ``noise``: levels by term (``brdf`` fractional, ``eta_deg``, ``P``, ``P_C``);
    polarization columns are simulated only for terms with a level.  The model is the
    fit's own (its detector aperture, decided as the fit decides it) and the noise is the
    likelihood's (:func:`~scatterbench.validation.fitting.likelihood.replicate`); error columns are not kept.
    """
    lik = Likelihood(scene, spec, data)
    pred = lik.predict(lik.model(truth), data)
    terms = ["brdf"] + [t for t in ("eta", "P", "P_C") if ("eta_deg" if t == "eta" else t) in noise]
    rep = replicate(pred, term_variances(noise, None, terms), rng)
    kw = dict.fromkeys(("eta", "P", "P_C", "brdf_err", "eta_err", "P_err", "P_C_err"))
    kw.update(rep)
    return data.replace(**kw)


@dataclass(frozen=True)
class Member:
    """One injection: everything it needs, picklable, so any executor can run it.

    ``seed`` is ``(study seed, cell, injection)``; the chain's own seed derives from it
    and replaces ``chain.seed``.
    """

    scene: object
    spec: FitSpec
    data: object
    truth: dict
    noise: dict
    seed: tuple
    chain: ChainSettings


def run_member(m: Member) -> dict:
    """Simulate the member's data set, fit it, and say which intervals contain the truth."""
    ss = np.random.SeedSequence(list(m.seed))
    noise_seed, chain_seed = (int(s.generate_state(1)[0]) for s in ss.spawn(2))
    data = simulate(m.scene, m.spec, m.data, m.truth, m.noise, np.random.default_rng(noise_seed))
    # the fit a user would run (the optimizer starts from the scene's values, the truth here)
    fit = run_fit(Likelihood(m.scene, m.spec, data), m.chain.replace(seed=chain_seed))
    res = fit.chain
    out = {
        "tau_max": float(np.max(res.tau)),
        "steps": res.steps,
        "acceptance": float(res.acceptance.mean()),
        "params": {},
    }
    for i, p in enumerate(m.spec.free):
        q = fit.summary["parameters"][p.key]
        t = m.truth[p.key]
        zc = abs(fit.optimum["u"][i] - float(p.to_u(t))) / fit.optimum["sd_u"][i]
        out["params"][p.key] = {
            "truth": t,
            "median": q["median"],
            "in68": bool(q["p16"] <= t <= q["p84"]),
            "in95": bool(q["p2.5"] <= t <= q["p97.5"]),
            "curv_in68": bool(zc <= 1.0),
            "curv_in95": bool(zc <= 2.0),
            "width68": q["p84"] - q["p16"],
            "width95": q["p97.5"] - q["p2.5"],
        }
    return out


def coverage_table(results, keys):
    """Coverage, its binomial error and z, bias and widths per parameter."""
    n = len(results)
    out = {}
    for k in keys:
        rows = [r["params"][k] for r in results]
        cov = {}
        for level, nominal in (("68", 0.6827), ("95", 0.9545)):
            frac = float(np.mean([r[f"in{level}"] for r in rows]))
            se = math.sqrt(nominal * (1 - nominal) / n)
            cov[level] = {"measured": frac, "nominal": nominal, "binomial_se": se, "z": (frac - nominal) / se}
            cfrac = float(np.mean([r[f"curv_in{level}"] for r in rows]))
            cov[level]["curvature"] = cfrac
            cov[level]["curvature_z"] = (cfrac - nominal) / se
        med = np.array([r["median"] for r in rows])
        truth = rows[0]["truth"]
        out[k] = {
            "coverage": cov,
            "bias": float(np.mean(med - truth)),
            "bias_se": float(np.std(med, ddof=1) / math.sqrt(n)) if n > 1 else float("nan"),
            "width68_mean": float(np.mean([r["width68"] for r in rows])),
            "width95_mean": float(np.mean([r["width95"] for r in rows])),
            "injections": n,
        }
    return out


def check_inputs(spec, chain, noise_extra=None, injections=1):
    """Raise ``ValueError`` unless a study of ``spec`` can run: enough walkers for its free
    parameters, a level to simulate with (its truth) for every free polarization noise
    level, at least one injection per cell.

    Parameters
    ----------
    spec : FitSpec
    chain : ChainSettings
    noise_extra : dict, optional
        Fixed levels of polarization terms.
    injections : int
        Members per cell, >= 1.
    """
    _integer("injections", injections, 1)
    chain.require_walkers(len(spec.free))
    missing = [
        p.key
        for p in spec.free
        if p.is_noise and p.key[6:] != "brdf" and p.key[6:] not in (noise_extra or {})
    ]
    if missing:
        raise ValueError(
            f"{', '.join(missing)}: a free polarization noise level needs the level to simulate with "
            "(noise_extra, e.g. {'eta_deg': 1.0}); its truth is that level"
        )


def _cell(scene, spec, data, level, n_geometries, noise_extra):
    """One cell's data rows, spec (simulated noise levels fixed unless free), truth and noise."""
    d = data if n_geometries is None else subsample(data, n_geometries)
    noise = {"brdf": float(level), **(noise_extra or {})}
    free_noise = {p.key[6:] for p in spec.free if p.is_noise}
    cell_spec = dataclasses.replace(spec, noise={k: v for k, v in noise.items() if k not in free_noise})
    truth = {p.key: float(scene.get_value(p.key)) for p in spec.free if not p.is_noise}
    truth.update({f"noise.{k}": v for k, v in noise.items() if k in free_noise})
    return d, cell_spec, truth, noise


def _run_members(executor, members, per_cell, progress):
    """Every member's result, in order, one task per member, so a slow chain does not hold
    back a worker's whole share (members are independent and seeded by their own ``seed``:
    the results do not depend on the grouping or on where they run).  With a progress bar,
    one map per cell, so that the bar moves; without, one map, so that no cell waits for the
    previous one's slowest member (the full report's recovery study on 16 workers: 0.7 s less
    on its longest path, by ``benchmarks/report_schedule.py``'s replay, 2026-12-08)."""
    if not progress:
        return executor.map(run_member, members, tasks=len(members))
    results = []
    with _progress_bar(progress, len(members), unit="fit", desc="injections") as bar:
        for start in range(0, len(members), per_cell):
            cell = members[start : start + per_cell]
            results.extend(executor.map(run_member, cell, tasks=len(cell)))
            bar.update(per_cell)
    return results


def _summarize_cell(cell, results):
    """Coverage table and chain diagnostics of one cell's members (added to ``cell``)."""
    cell["summary"] = coverage_table(results, list(cell["truth"]))
    cell["tau_max_median"] = float(np.median([r["tau_max"] for r in results]))
    cell["steps_median"] = float(np.median([r["steps"] for r in results]))
    cell["steps_over_tau_min"] = float(min(r["steps"] / r["tau_max"] for r in results))
    cell["acceptance_median"] = float(np.median([r["acceptance"] for r in results]))
    cell["members"] = results
    return cell


def recovery_study(
    scene,
    spec: FitSpec,
    data,
    chain: ChainSettings,
    *,
    noise_levels=(0.05,),
    n_geometries=(None,),
    injections=50,
    executor=None,
    noise_extra=None,
    progress=False,
):
    """Cells (noise level x number of geometries), ``injections`` members each.

    The truth is the scene's value of every free scene parameter; noise levels
    are the fractional BRDF noise ``noise.brdf`` (fixed in each cell's spec at
    the simulated level unless the spec frees it, in which case its truth is
    that level).

    Parameters
    ----------
    scene, spec, data
        The scene (and its truth), the fit spec, the rows whose geometries and
        incident states the injections use.
    chain : ChainSettings
        Every member's chain; ``chain.seed`` is the study's seed (each member's
        chain seed derives from it, the cell and the injection).
    noise_levels : sequence of float
        Fractional BRDF noise levels.
    n_geometries : sequence of int or None
        Evenly spread subsets of the rows (``None``: all).
    injections : int
        Members per cell.
    executor : optional
        Runs the members (default in-process).
    noise_extra : dict, optional
        Fixed levels of polarization terms.
    progress : bool
        Show a progress bar.

    Returns
    -------
    list of dict
        One per cell: its level, geometries, truth, coverage summary, chain
        diagnostics and members.
    """

    check_inputs(spec, chain, noise_extra, injections)
    cells, members = [], []
    for ci, (lvl, ng) in enumerate((lv, g) for lv in noise_levels for g in n_geometries):
        d, cell_spec, truth, noise = _cell(scene, spec, data, lvl, ng, noise_extra)
        cells.append({"noise_brdf": float(lvl), "geometries": len(d), "truth": truth})
        members += [
            Member(scene, cell_spec, d, truth, noise, (chain.seed, ci, j), chain) for j in range(injections)
        ]
    results = _run_members(executor or SerialExecutor(), members, injections, progress)
    return [
        _summarize_cell(cell, results[i * injections : (i + 1) * injections]) for i, cell in enumerate(cells)
    ]
