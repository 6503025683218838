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
the ``1/sqrt(2N)`` approximation of :func:`~validation.sampling.optimize`).
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

from .fitspec import FitSpec
from .likelihood import Likelihood
from .sampling import initial_ball, optimize, run_chain

__all__ = ["simulate", "Member", "run_member", "recovery_study", "coverage_table", "subsample"]


def subsample(data, n):
    """``n`` rows spread evenly over the data set (all of them when ``n >= len``)."""
    if n >= len(data):
        return data
    idx = np.unique(np.round(np.linspace(0, len(data) - 1, n)).astype(int))
    return data.subset(idx)


def simulate(scene, spec: FitSpec, data, truth: dict, noise: dict, rng):
    """A synthetic copy of ``data`` (same rows, incident states) from the scene at ``truth``.

    ``noise``: levels by term (``brdf`` fractional, ``eta_deg``, ``P``, ``P_C``);
    polarization columns are simulated only for terms with a level.
    """
    # the fit's own model (its detector aperture, decided as the fit decides it), at every row
    lik = Likelihood(scene, spec, data)
    pred = lik.predict(lik.model(truth), data)
    n = len(data)
    b = pred["brdf"] * np.exp(noise["brdf"] * rng.standard_normal(n))
    kw = {
        "brdf": b,
        "brdf_err": None,
        "eta": None,
        "P": None,
        "P_C": None,
        "eta_err": None,
        "P_err": None,
        "P_C_err": None,
    }
    if "eta_deg" in noise:
        e = pred["eta"] + math.radians(noise["eta_deg"]) * rng.standard_normal(n)
        kw["eta"] = 0.5 * np.angle(np.exp(2j * e))
    for t in ("P", "P_C"):
        if t in noise:
            kw[t] = pred[t] + noise[t] * rng.standard_normal(n)
    return data.replace(**kw)


@dataclass(frozen=True)
class Member:
    """One injection: everything it needs, picklable, so any executor can run it."""

    scene: object
    spec: FitSpec
    data: object
    truth: dict
    noise: dict
    seed: tuple
    walkers: int
    max_steps: int
    check_every: int
    tau_factor: float
    starts: int


def run_member(m: Member) -> dict:
    ss = np.random.SeedSequence(list(m.seed))
    noise_seed, chain_seed = (int(s.generate_state(1)[0]) for s in ss.spawn(2))
    data = simulate(m.scene, m.spec, m.data, m.truth, m.noise, np.random.default_rng(noise_seed))
    lik = Likelihood(m.scene, m.spec, data)
    # the optimizer starts from the scene's values (the truth here) plus m.starts - 1 prior draws
    u0, _, info = optimize(lik, chain_seed, n_starts=m.starts)
    p0 = initial_ball(u0, m.walkers, chain_seed, m.spec.u_bounds(), sd=info["sd_u"])
    res = run_chain(
        lik, p0=p0, seed=chain_seed, max_steps=m.max_steps, check_every=m.check_every, tau_factor=m.tau_factor
    )
    u = res.samples()
    sd = np.asarray(info["sd_u"], float)
    out = {
        "tau_max": float(np.max(res.tau)),
        "steps": res.steps,
        "acceptance": float(res.acceptance.mean()),
        "params": {},
    }
    for i, p in enumerate(m.spec.free):
        x = p.from_u(u[:, i])
        q = np.percentile(x, [2.5, 16, 50, 84, 97.5])
        t = m.truth[p.key]
        zc = abs(float(u0[i]) - float(p.to_u(t))) / sd[i]
        out["params"][p.key] = {
            "truth": t,
            "median": float(q[2]),
            "in68": bool(q[1] <= t <= q[3]),
            "in95": bool(q[0] <= t <= q[4]),
            "curv_in68": bool(zc <= 1.0),
            "curv_in95": bool(zc <= 2.0),
            "width68": float(q[3] - q[1]),
            "width95": float(q[4] - q[0]),
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


def recovery_study(
    scene,
    spec: FitSpec,
    data,
    *,
    noise_levels=(0.05,),
    n_geometries=(None,),
    injections=50,
    seed=0,
    walkers=16,
    max_steps=2000,
    check_every=100,
    tau_factor=50.0,
    starts=1,
    executor=None,
    noise_extra=None,
    progress=False,
):
    """Cells (noise level x number of geometries), ``injections`` members each.

    The truth is the scene's value of every free scene parameter; noise levels
    are the fractional BRDF noise ``noise.brdf`` (fixed in each cell's spec at
    the simulated level unless the spec frees it, in which case its truth is
    that level).  ``noise_extra``: fixed levels of polarization terms.
    """
    from .executors import SerialExecutor

    executor = executor or SerialExecutor()
    cells = []
    members = []
    for ci, (lvl, ng) in enumerate((lv, g) for lv in noise_levels for g in n_geometries):
        d = data if ng is None else subsample(data, ng)
        noise = {"brdf": float(lvl), **(noise_extra or {})}
        free_noise = {p.key[6:] for p in spec.free if p.is_noise}
        fixed = {k: v for k, v in noise.items() if k not in free_noise}
        cell_spec = dataclasses.replace(spec, noise=fixed)
        truth = {p.key: float(scene.get_value(p.key)) for p in spec.free if not p.is_noise}
        truth.update({f"noise.{k}": v for k, v in noise.items() if k in free_noise})
        cells.append({"noise_brdf": float(lvl), "geometries": len(d), "truth": truth})
        for j in range(injections):
            members.append(
                Member(
                    scene,
                    cell_spec,
                    d,
                    truth,
                    noise,
                    (int(seed), ci, j),
                    walkers,
                    max_steps,
                    check_every,
                    tau_factor,
                    starts,
                )
            )
    # one map per cell: a progress bar that moves, and the same results (members are independent)
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(members), unit="fit", desc="injections", mininterval=1.0)
    results = []
    for start in range(0, len(members), injections):
        results.extend(executor.map(run_member, members[start : start + injections]))
        if bar is not None:
            bar.update(injections)
    if bar is not None:
        bar.close()
    k = 0
    for cell in cells:
        rs = results[k : k + injections]
        k += injections
        cell["summary"] = coverage_table(rs, list(cell["truth"]))
        cell["tau_max_median"] = float(np.median([r["tau_max"] for r in rs]))
        cell["steps_median"] = float(np.median([r["steps"] for r in rs]))
        cell["steps_over_tau_min"] = float(min(r["steps"] / r["tau_max"] for r in rs))
        cell["acceptance_median"] = float(np.median([r["acceptance"] for r in rs]))
        cell["members"] = rs
    return cells
