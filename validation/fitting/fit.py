"""A fit from data file + scene + spec to a posterior: optimum, chain, summary, checks, plots.

``run_fit`` does the work (no files except the resumable checkpoint, a
:class:`~scatterbench.validation.fitting.checkpoint.CheckpointBackend`: chain, log posterior,
acceptance counts, the sampler's random state, tau history; ``scatterbench fit``
keeps it as ``chain.npz``); ``write_fit`` writes ``posterior.json`` and the
plots ``corner.png``, ``predictive.png``, ``residuals.png``.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import dataclass

import numpy as np

from scatterbench.models.polarization import wrap_axis
from scatterbench.validation.atomic import atomic_savefig, atomic_write_json

from .checkpoint import CheckpointBackend
from .likelihood import TERMS, Likelihood, replicate, term_variances
from .sampling import ChainResult, burn_in, initial_ball, optimize, run_chain, summarize
from .settings import ChainSettings

__all__ = [
    "FitError",
    "FitResult",
    "run_fit",
    "fit_task",
    "predictive",
    "write_fit",
    "fingerprint",
    "corner_figure",
    "predictive_figure",
    "scan_x",
]


class FitError(ValueError):
    """Data a fit cannot start from: the log likelihood is not finite at the best start
    (a row the model cannot reach, an error column that overflows its variance); the
    message names the rows (the command line: ``error: ...``, exit 2)."""


def _require_finite(lik, u, lp):
    """Raise :class:`FitError` when ``lp`` (the best start's log posterior) is not finite:
    every walker would start where ln L = -inf, never move, and its starting ball would be
    reported as a posterior."""
    if math.isfinite(lp):
        return
    with np.errstate(all="ignore"):
        bad = np.flatnonzero(~np.isfinite(lik.pointwise(u)))
    lines = getattr(lik.data, "lines", None)
    where = (
        ", ".join(f"line {int(lines[i])}" if lines is not None else f"row {int(i)}" for i in bad[:5])
        + (", ..." if len(bad) > 5 else "")
        if len(bad)
        else "the prior"
    )
    raise FitError(
        f"{getattr(lik.data_all, 'path', 'data')}: ln L is not finite ({lp}) at the best of the fit's "
        f"starts: {len(bad)} row(s) give an impossible likelihood ({where}): an error column so large "
        "its variance overflows, or a value the model cannot reach; the chain would never move"
    )


@dataclass
class FitResult:
    """A fit's likelihood, optimum, chain, posterior summary and the settings it ran with."""

    lik: Likelihood
    optimum: dict
    chain: ChainResult
    summary: dict
    settings: ChainSettings

    @property
    def spec(self):
        return self.lik.spec


def fingerprint(lik, settings: ChainSettings) -> str:
    """Hash of everything a resumed chain must share with the checkpoint: data, scene,
    spec and the settings that shape the chain (the step budget may change)."""
    h = hashlib.sha256()
    d = lik.data_all
    for name in d._ARRAYS:  # every array the likelihood can read, by name
        a = getattr(d, name)
        if a is not None and name != "lines":
            h.update(name.encode())
            h.update(np.ascontiguousarray(a).tobytes())
    h.update(json.dumps(lik.scene.raw, sort_keys=True, default=str).encode())
    h.update(json.dumps(lik.spec.as_dict(), sort_keys=True).encode())
    kept = ("walkers", "seed", "check_every", "tau_factor", "tau_rtol", "starts")
    shaping = {k: getattr(settings, k) for k in kept}
    if settings.burn:  # where the kept chain starts; chains without a burn-in keep their hash
        shaping["burn"] = settings.burn
    if settings.moves != "stretch":  # the stretch move's checkpoints predate the setting: same hash
        shaping["moves"] = settings.moves
    h.update(json.dumps(shaping, sort_keys=True).encode())
    return h.hexdigest()


def run_fit(
    lik: Likelihood,
    settings: ChainSettings | None = None,
    *,
    executor=None,
    checkpoint=None,
    resume=False,
    progress=False,
    resume_from=None,
):
    """Optimum, then an emcee chain from a ball around it, then the posterior summary.

    Parameters
    ----------
    lik : Likelihood
    settings : ChainSettings, optional
        Default ``ChainSettings()`` (``scatterbench fit``'s defaults).
    executor : optional
        Maps the log posterior over walkers.
    checkpoint : str, optional
        Where the chain's checkpoint is written at every check.
    resume : bool
        Continue the chain saved in ``resume_from`` (default ``checkpoint``);
        a :class:`~scatterbench.validation.fitting.checkpoint.CheckpointError` if it cannot be.
    progress : bool
        Show a progress bar.

    Returns
    -------
    FitResult
    """
    settings = ChainSettings() if settings is None else settings
    settings.require_walkers(len(lik.spec.free))
    fp = fingerprint(lik, settings)
    if resume:  # before the optimum: a checkpoint that cannot be resumed fails at once
        backend = CheckpointBackend.load(resume_from or checkpoint, fp, save_to=checkpoint)
    else:
        backend = CheckpointBackend(checkpoint, fp)
    u_opt, lp_opt, info = optimize(lik, settings.seed, n_starts=settings.starts)
    _require_finite(lik, u_opt, lp_opt)  # before sampling: a chain from -inf never moves
    p0, burned = None, {"steps": 0, "seconds": 0.0}
    if not resume:
        p0 = initial_ball(u_opt, settings.walkers, settings.seed, lik.spec.u_bounds(), sd=info["sd_u"])
        if settings.burn:
            p0, seconds = burn_in(lik, settings, p0, executor)
            burned = {"steps": settings.burn, "seconds": seconds}
    chain = run_chain(lik, settings, p0=p0, backend=backend, executor=executor, progress=progress)
    optimum = {
        "values": lik.spec.physical(u_opt),
        "u": [float(x) for x in u_opt],  # sampling coordinates
        "sd_u": [float(x) for x in info["sd_u"]],  # Gauss-Newton standard deviations there
        "log_posterior": lp_opt,
        "log_likelihood": lik.loglike(u_opt),
        "starts": info["starts"],
    }
    summary = summarize(chain, lik.spec)
    # steps run and discarded before the chain (ChainSettings.burn; a resumed chain: 0 here), not
    # the kept chain's own burn-in ("burn_in": 2 max tau of it, dropped from its samples)
    summary["sampling"]["burned_before_chain"] = burned
    return FitResult(lik, optimum, chain, summary, settings)


def fit_task(job):
    """:func:`run_fit` of ``job``, ``(likelihood, settings)``, as an executor's task (a
    module-level function of one item): it runs wherever the executor puts it, whole, and
    gives the same chain there, which ``settings`` alone seeds."""
    lik, settings = job
    return run_fit(lik, settings)


def information_criteria(fit: FitResult) -> dict:
    """Maximum log-likelihood (best of the optimum and the chain: the prior is flat inside the
    bounds, so the chain's log posterior is ln L), AIC and BIC (lower is better)."""
    k, n = len(fit.spec.free), fit.lik.n_points
    ll = max(fit.optimum["log_likelihood"], float(np.max(fit.chain.log_prob)))
    return {"max_log_likelihood": ll, "k": k, "n": n, "AIC": 2 * k - 2 * ll, "BIC": k * math.log(n) - 2 * ll}


def predictive(fit: FitResult, n_draws=200, seed=0, data=None):
    """Posterior-predictive draws at the rows of ``data`` (default: every row of the file).

    Returns ``{term: {"model": (n_draws, N), "replicated": (n_draws, N)}}`` with
    ``term`` in brdf, eta, P, P_C (eta in radians) and the replicated data drawn
    with the likelihood's noise model, plus the used-row mask.
    """
    lik = fit.lik
    data = lik.data_all if data is None else data
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 3]))
    samples = fit.chain.samples()
    pick = rng.choice(len(samples), size=min(n_draws, len(samples)), replace=False)
    U = samples[pick]
    v = lik.spec.values(U)
    if lik.binding is not None:  # every draw's model at once (a model set)
        pred = lik.predict(lik.model(v.scene), data)
    else:  # the scene rebuilt at each draw
        each = [lik.predict(lik.model(lik.spec.values(u).scene), data) for u in U]
        pred = {t: np.array([p[t] for p in each]) for t in TERMS}
    rep = replicate(pred, term_variances(v.noise, data, TERMS), rng)
    res = {t: {"model": pred[t], "replicated": rep[t]} for t in TERMS}
    res["mask"] = lik.spec.mask(data)
    return res


def _observed(data, term):
    return {"brdf": data.brdf, "eta": data.eta, "P": data.P, "P_C": data.P_C}[term]


def predictive_checks(fit: FitResult, pp) -> dict:
    """Fraction of used rows inside the 68% / 95% posterior-predictive intervals, per term."""
    data = fit.lik.data_all
    mask = pp["mask"]
    out = {}
    for t in fit.lik.terms:
        obs = _observed(data, t)[mask]
        rep = pp[t]["replicated"][:, mask]
        if t == "eta":  # compare on the axis: centre the replicates on the observation
            rep = obs + wrap_axis(rep - obs)
        lo68, hi68, lo95, hi95 = np.percentile(rep, [16, 84, 2.5, 97.5], axis=0)
        out[t] = {
            "inside_68": float(np.mean((obs >= lo68) & (obs <= hi68))),
            "inside_95": float(np.mean((obs >= lo95) & (obs <= hi95))),
            "rows": int(mask.sum()),
        }
    return out


def scan_x(data):
    """x coordinate for plots: signed theta_r (deg) in-plane, phi_r (deg) + 200 out-of-plane."""
    ti, tr, pr = np.degrees(data.theta_i), np.degrees(data.theta_r), np.degrees(data.phi_r)
    inplane = np.isclose(np.mod(pr, 180.0), 0.0)
    x = np.where(inplane, np.where(np.isclose(np.mod(pr, 360.0), 180.0), -tr, tr), pr)
    label = np.where(
        inplane,
        [f"in-plane ti={a:g}" for a in ti],
        [f"out-of-plane ti={a:g} tr={b:g}" for a, b in zip(ti, tr, strict=True)],
    )
    return x, label


#: the sampling summary's entries that are wall-clock measurements: posterior.json keeps
#: them apart, under ``timing``, so two runs with the same seed differ there only
TIMING = {"seconds": "sampling_seconds", "evaluations_per_second": "evaluations_per_second"}


def _truth_check(parameters, truth):
    """Where each true value (the data's sidecar) lies in its posterior."""
    out = {}
    for key, v in (truth or {}).items():
        if key in parameters and isinstance(v, (int, float)) and not isinstance(v, bool):
            p = parameters[key]
            out[key] = {
                "true": v,
                "inside_68": bool(p["p16"] <= v <= p["p84"]),
                "inside_95": bool(p["p2.5"] <= v <= p["p97.5"]),
                "z": (p["median"] - v) / p["std"] if p["std"] > 0 else None,
            }
    return out


def write_fit(fit: FitResult, out, *, data_path, scene_path, executor_desc="", plots=True, n_draws=200):
    """Write posterior.json (strict JSON; the wall-clock measurements under ``timing``, so
    the rest is the same, byte for byte, for the same inputs and seed) and the plots into
    ``out`` (atomic writes)."""

    os.makedirs(out, exist_ok=True)
    pp = predictive(fit, n_draws=n_draws, seed=fit.settings.seed)
    checks = predictive_checks(fit, pp)
    post = dict(fit.summary)
    sampling = dict(post["sampling"])
    post["sampling"] = {k: v for k, v in sampling.items() if k not in TIMING}
    post["timing"] = {new: sampling[old] for old, new in TIMING.items() if old in sampling}
    post["timing"]["note"] = "wall-clock measurements: they differ between runs that are otherwise identical"
    if fit.lik.data_all.meta.get("truth"):
        post["truth_check"] = _truth_check(post["parameters"], fit.lik.data_all.meta["truth"])
    post.update(
        {
            "data": {
                "path": data_path,
                "rows": len(fit.lik.data_all),
                "used_rows": fit.lik.n_points,
                "terms": list(fit.lik.terms),
            },
            "scene": {"path": scene_path, "name": fit.lik.scene.name},
            "spec": fit.spec.as_dict(),
            "optimum": fit.optimum,
            "information_criteria": information_criteria(fit),
            "posterior_predictive": checks,
            "settings": dict(fit.settings.as_dict(), executor=executor_desc),
        }
    )
    atomic_write_json(os.path.join(out, "posterior.json"), post)
    if plots:
        _plots(fit, pp, out)
    return post


def corner_figure(fit: FitResult):
    """Corner plot of the posterior (physical units), truths from the data's sidecar if any."""
    import matplotlib  # matplotlib (heavy): loaded only where a figure is drawn

    matplotlib.use("Agg")
    import corner  # corner (with matplotlib, heavy): loaded only where a corner plot is drawn

    spec = fit.spec
    u = fit.chain.samples()
    x = np.column_stack([p.from_u(u[:, i]) for i, p in enumerate(spec.free)])
    truth = fit.lik.data_all.meta.get("truth") or {}
    truths = [truth.get(p.key) for p in spec.free]
    if not any(t is not None for t in truths):
        truths = None
    one = x.shape[1] == 1  # corner draws one Axes, not a grid: its truth lines index a grid
    fig = corner.corner(
        x,
        labels=spec.names,
        truths=None if one else truths,
        quantiles=[0.025, 0.16, 0.5, 0.84, 0.975],
        title_quantiles=[0.16, 0.5, 0.84],
        show_titles=True,
        title_fmt=".4g",
    )
    if one and truths is not None:
        fig.axes[0].axvline(truths[0], color="#4682b4")  # corner's truth colour
    return fig


def predictive_figure(fit: FitResult, pp):
    """Posterior-predictive 95% bands (model and replicated data) with the data, per scan and term."""
    import matplotlib  # matplotlib (heavy): loaded only where a figure is drawn

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib (heavy): loaded only where a figure is drawn

    data = fit.lik.data_all
    xs, labels = scan_x(data)
    groups = list(dict.fromkeys(labels))
    terms = [t for t in ("brdf", "eta", "P", "P_C") if _observed(data, t) is not None]
    fig, axes = plt.subplots(
        len(terms), len(groups), figsize=(4.2 * len(groups), 2.8 * len(terms)), squeeze=False
    )
    mask = pp["mask"]
    for j, g in enumerate(groups):
        sel = labels == g
        order = np.argsort(xs[sel])
        xg = xs[sel][order]
        for i, t in enumerate(terms):
            ax = axes[i, j]
            scale = 180 / math.pi if t == "eta" else 1.0
            obs = _observed(data, t)[sel][order] * scale
            for key, alpha in (("replicated", 0.2), ("model", 0.45)):
                arr = pp[t][key][:, sel][:, order] * scale
                lo, hi = np.percentile(arr, [2.5, 97.5], axis=0)
                ax.fill_between(xg, lo, hi, alpha=alpha, lw=0, label=f"{key} 95%")
            used = mask[sel][order]
            ax.plot(xg[used], obs[used], "k.", ms=3, label="data")
            ax.plot(xg[~used], obs[~used], "x", color="grey", ms=3, label="masked")
            if t == "brdf":
                ax.set_yscale("log")
            ax.set_ylabel({"brdf": "BRDF (1/sr)", "eta": "eta (deg)", "P": "P", "P_C": "P_C"}[t])
            if i == 0:
                ax.set_title(g, fontsize=9)
            if i == len(terms) - 1:
                ax.set_xlabel("signed theta_r (deg)" if g.startswith("in") else "phi_r (deg)")
    axes[0, 0].legend(fontsize=6)
    fig.tight_layout()
    return fig


def _plots(fit, pp, out):
    import matplotlib  # matplotlib (heavy): loaded only where a figure is drawn

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib (heavy): loaded only where a figure is drawn

    spec = fit.spec
    fig = corner_figure(fit)
    atomic_savefig(fig, os.path.join(out, "corner.png"), dpi=80)
    plt.close(fig)

    fig = predictive_figure(fit, pp)
    atomic_savefig(fig, os.path.join(out, "predictive.png"), dpi=80)
    plt.close(fig)

    # whitened residuals at the posterior median
    lik = fit.lik
    med = np.array([p.to_u(fit.summary["parameters"][p.key]["median"]) for p in spec.free])
    w = lik.whitened(med)
    fig, ax = plt.subplots(figsize=(8, 3))
    start = 0
    for t in lik.terms:
        ax.plot(np.arange(start, start + lik.n_points), w[start : start + lik.n_points], ".", ms=3, label=t)
        start += lik.n_points
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("used row (per term)")
    ax.set_ylabel("residual / sigma at median")
    ax.legend(fontsize=7)
    fig.tight_layout()
    atomic_savefig(fig, os.path.join(out, "residuals.png"), dpi=80)
    plt.close(fig)
