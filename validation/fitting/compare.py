"""Model comparison on the same data: several scenes fitted, then ranked.

For every scene: the maximum log-likelihood (best of the optimum and the
chain), AIC ``= 2k - 2 ln L_max``, BIC ``= k ln N - 2 ln L_max``, WAIC
(Watanabe; ``-2 (lppd - p_waic)`` from the per-row log-likelihood over
posterior draws) and the posterior-predictive coverage of the rows (the
fraction inside the 68% / 95% predictive intervals).  Lower AIC/BIC/WAIC is
better; the table gives the differences from the best.  Scenes must use the
same rows (same masks) or the numbers are not comparable, so that is checked.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.special import logsumexp

from scatterbench import references
from scatterbench.models import scene as scene_mod

from .datafile import load_data
from .diagnostics import chain_seed, rhat
from .diagnostics import load as load_diagnostics
from .executors import SerialExecutor
from .fit import FitResult, fit_task, information_criteria, predictive, predictive_checks
from .fitspec import fitspec_from
from .likelihood import Likelihood
from .recovery import subsample
from .settings import ChainSettings, _integer

__all__ = ["waic", "check_comparable", "compare_fits", "format_comparison", "seed003_pairing"]


def waic(fit, n_draws=200, seed=0):
    """WAIC of a fit from the per-row log-likelihood of ``n_draws`` posterior draws (all
    evaluated in one :meth:`~scatterbench.validation.fitting.likelihood.Likelihood.pointwise_batch`)."""
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 5]))
    s = fit.chain.samples()
    pick = rng.choice(len(s), size=min(n_draws, len(s)), replace=False)
    ll = fit.lik.pointwise_batch(s[pick])  # (draws, rows)
    lppd = float(np.sum(logsumexp(ll, axis=0) - math.log(len(pick))))
    p = float(np.sum(np.var(ll, axis=0, ddof=1)))
    return {"WAIC": -2 * (lppd - p), "lppd": lppd, "p_waic": p}


def check_comparable(liks, names):
    """Raise ``ValueError`` unless the likelihoods use the same rows and the same terms
    (scenes compared on the same data)."""
    for nm, lk in zip(names[1:], liks[1:], strict=True):
        if not np.array_equal(lk.mask, liks[0].mask):
            raise ValueError(
                f"scene {nm}: its mask uses other rows than {names[0]}'s; compare on the same rows"
            )
    for nm, lk in zip(names[1:], liks[1:], strict=True):
        if lk.terms != liks[0].terms:
            raise ValueError(
                f"scene {nm}: its likelihood uses the terms {lk.terms}, {names[0]}'s {liks[0].terms}; "
                "compare with the same terms"
            )


def _pooled(fits):
    """The chains of ``fits`` (one likelihood, independent chains) as one fit for the posterior
    quantities (WAIC, predictive draws, medians): their burned and thinned samples together;
    the optimum and the best chain otherwise those of the fit with the highest ln L."""
    if len(fits) == 1:
        return fits[0]
    best = max(fits, key=lambda f: information_criteria(f)["max_log_likelihood"])
    return FitResult(best.lik, best.optimum, _PooledChains(fits), best.summary, best.settings)


class _PooledChains:
    """Independent chains' samples, pooled in chain order (what :func:`waic` and
    :func:`~scatterbench.validation.fitting.fit.predictive` read of a chain)."""

    def __init__(self, fits):
        self._samples = np.concatenate([f.chain.samples() for f in fits])

    def samples(self):
        return self._samples


def _between_chains(fits):
    """Per free parameter, the rank-normalized split R-hat between the chains of ``fits``
    (each chain's burned and thinned samples in sampling coordinates, cut to the shortest)."""
    each = [f.chain.samples() for f in fits]
    n = min(len(s) for s in each)
    names = fits[0].spec.names
    return {k: rhat(np.stack([s[:n, i] for s in each])) for i, k in enumerate(names)}


def _medians(fit):
    u = fit.chain.samples()
    return {p.key: float(np.median(p.from_u(u[:, i]))) for i, p in enumerate(fit.spec.free)}


def _comparison_row(name, fits, seed):
    """One scene's row from its independent chains ``fits`` (one or more): the maximum ln L
    over them all, WAIC, predictive coverage and medians of their pooled samples, their worst
    tau and mean acceptance (the between-chain R-hat: :func:`_with_rhat`)."""
    pooled = _pooled(fits)
    best = max(fits, key=lambda f: information_criteria(f)["max_log_likelihood"])
    row = {
        "scene": name,
        **information_criteria(best),
        **waic(pooled, seed=seed),
        "predictive": predictive_checks(pooled, predictive(pooled, seed=seed)),
        "tau_max": max(float(np.max(f.chain.tau)) for f in fits),
        "acceptance": float(np.mean([f.chain.acceptance.mean() for f in fits])),
        "stop_reason": fits[0].chain.stop_reason,
        "medians": (
            {k: v["median"] for k, v in fits[0].summary["parameters"].items()}
            if len(fits) == 1
            else _medians(pooled)
        ),
    }
    row["converged_chains"] = sum(bool(f.chain.converged) for f in fits)
    if len(fits) > 1:
        row["stop_reason"] = (
            f"{row['converged_chains']} of {len(fits)} chains converged (N >= tau_factor tau)"
        )
    return row


def _with_rhat(row, fits):
    """``row`` (:func:`_comparison_row` of ``fits``) with, for several chains, their number, the
    between-chain R-hat per parameter and its largest: computed where the rows are gathered,
    which has ArviZ loaded (:func:`_compare_groups`)."""
    if len(fits) > 1:
        rh = _between_chains(fits)
        row.update(chains=len(fits), rhat=rh, rhat_max=max(rh.values()))
    return row


def _row(job):
    """A scene's comparison row from its chains (a task): ``job`` is ``(name, fits, seed)``."""
    return _comparison_row(*job)


def _ranked(rows):
    """``rows`` with ``dAIC``, ``dBIC``, ``dWAIC``: each criterion minus the best (lowest)."""
    for key in ("AIC", "BIC", "WAIC"):
        best = min(r[key] for r in rows)
        for r in rows:
            r[f"d{key}"] = r[key] - best
    return rows


def _compare_groups(groups, settings, executor, chains=1):
    """:func:`compare_fits` of several ``(liks, names)`` groups with one map over all their
    fits' chains (so every worker has a chain to run), then one over their rows, regrouped in
    order.  Chain ``c`` of every fit is seeded :func:`chain_seed` ``(settings.seed, c)``.

    With several chains the between-chain R-hat needs ArviZ (~2 s to import), which this
    process loads while the chains run (``meanwhile``) and uses once their rows are back
    (:func:`_with_rhat`, ~3 ms a parameter); the rows (WAIC, predictive draws) are tasks and
    need no ArviZ.  Before, the rows computed the R-hat on the workers, which imported ArviZ
    from tasks queued behind the chains: with 16 workers (on 2 cores, ad hoc) one row in eight
    still landed on a worker that had not, where it costs ~2 s after the longest chain.  In a
    report this runs on a section's thread while the report's thread imports ArviZ
    (:attr:`~scatterbench.validation.report.core.SectionSpec.preloads`); the load here waits
    for that import (a lock), as an import on a thread beside another's can cross it (877275d,
    reverted: CPython handed one a half-imported ``dask.array``)."""

    ex = executor or SerialExecutor()
    pairs = [(lik, nm) for liks, names in groups for lik, nm in zip(liks, names, strict=True)]
    seeds = [chain_seed(settings.seed, c) for c in range(chains)]
    jobs = [(lik, dataclasses.replace(settings, seed=s)) for lik, _ in pairs for s in seeds]
    done = ex.map(fit_task, jobs, tasks=len(jobs), meanwhile=load_diagnostics if chains > 1 else None)
    per_fit = [done[i * chains : (i + 1) * chains] for i in range(len(pairs))]
    rows = ex.map(
        _row, [(nm, f, settings.seed) for (_, nm), f in zip(pairs, per_fit, strict=True)], tasks=len(pairs)
    )
    rows = [_with_rhat(row, f) for row, f in zip(rows, per_fit, strict=True)]
    out, start = [], 0
    for liks, _ in groups:
        part = slice(start, start + len(liks))
        start += len(liks)
        out.append((_ranked(rows[part]), [f[0] for f in per_fit[part]]))
    return out


def compare_fits(liks, names, settings: ChainSettings | None = None, *, executor=None, chains=1):
    """Fit every likelihood (same data, same used rows) and rank them.

    Parameters
    ----------
    liks : list of Likelihood
    names : list of str
        One per likelihood (the rows' ``scene``).
    settings : ChainSettings, optional
        Every fit's chain (default ``ChainSettings()``); its seed also seeds the
        predictive draws and the WAIC.
    executor : optional
        Runs the fits, one task per chain (:mod:`scatterbench.validation.fitting.executors`;
        default in-process); the rows are the same on any executor.
    chains : int
        Independent chains per fit (chain 0 seeded by ``settings.seed``, the others by
        :func:`~scatterbench.validation.fitting.diagnostics.chain_seed`): with more than one,
        each row's posterior quantities pool them and its ``rhat`` gives the between-chain
        R-hat of every free parameter (``rhat_max`` the worst).

    Returns
    -------
    rows : list of dict
        The comparison, with ``dAIC``, ``dBIC``, ``dWAIC`` from the best.
    fits : list of FitResult
        Each scene's first chain.
    """
    settings = ChainSettings() if settings is None else settings
    check_comparable(liks, names)
    ((rows, fits),) = _compare_groups([(liks, names)], settings, executor, _integer("chains", chains, 1))
    return rows, fits


def format_comparison(rows) -> str:
    lines = [f"{'scene':<40} {'k':>2} {'ln L_max':>10} {'dAIC':>8} {'dBIC':>8} {'dWAIC':>8}  brdf in 68%/95%"]
    for r in rows:
        pc = r["predictive"].get("brdf", {})
        lines.append(
            f"{r['scene'][:40]:<40} {r['k']:>2} {r['max_log_likelihood']:>10.2f} {r['dAIC']:>8.2f} {r['dBIC']:>8.2f} "
            f"{r['dWAIC']:>8.2f}  {pc.get('inside_68', float('nan')):.2f}/{pc.get('inside_95', float('nan')):.2f}"
        )
    return "\n".join(lines)


#: Seed 003 Sec. 4's pairing: the paper's combination (facet reflection + single + totally diffuse
#: volume scattering under a smooth interface) against the Maxwell-Beard BRDF, each hypothesis with a
#: held-out SCATMECH data set made by its own generator (references/scripts/make_scatmech_paint_data.py).
SEED003_PAIRING = {
    "scenes": {"combination": "red_paint_fit.toml", "maxwell-beard": "maxwell_beard_fit.toml"},
    "data": {"combination": "scatmech_paint_measurement.csv", "maxwell-beard": "scatmech_mb_measurement.csv"},
}
_POLARIZATION_OFF = ("eta_deg=off", "P=off", "P_C=off")


def seed003_pairing(settings: ChainSettings, *, rows=None, terms=("all", "brdf"), executor=None, chains=1):
    """Fit both scenes of :data:`SEED003_PAIRING` to both data sets, with every likelihood
    term the scenes declare (``"all"``: BRDF, eta, P, P_C) and/or the BRDF alone
    (``"brdf"``), on ``rows`` evenly spread rows of each file (default all), every
    chain with ``settings``, ``chains`` independent chains per fit (:func:`compare_fits`).

    Returns a list of ``{"data", "generator", "terms", "rows", "fits"}``, one per data
    set and term choice, ``rows`` being :func:`compare_fits`' table (scene names are
    the hypotheses) and ``fits`` its fit results.  All the fits (data sets x term
    choices x scenes) go to ``executor`` in one map, one task each.  The result does
    not depend on the executor, so it is kept for the process keyed by every other
    argument (the fits are deterministic for a seed): the report and the tests that
    show the same pairing fit it once; treat it as read-only.
    """
    key = (rows, tuple(terms), settings, chains)
    if key in _PAIRING_CACHE:
        return _PAIRING_CACHE[key]
    cases, groups = _pairing_cases(rows, terms)
    out = []
    done = _compare_groups(groups, settings, executor, _integer("chains", chains, 1))
    for case, (table, fits) in zip(cases, done, strict=True):
        out.append({**case, "rows": table, "fits": fits})
    _PAIRING_CACHE[key] = out
    return out


def _pairing_cases(rows, terms):
    """The pairing's cases (``{"data", "generator", "terms"}``) and, for each, the
    ``(likelihoods, hypothesis names)`` to compare."""

    scenes = {h: scene_mod.load(references.scene_path(f)) for h, f in SEED003_PAIRING["scenes"].items()}
    cases, groups = [], []
    for generator, fname in SEED003_PAIRING["data"].items():
        data = load_data(references.data_path(fname))
        if rows is not None:
            data = subsample(data, rows)
        for t in terms:
            noise = None if t == "all" else list(_POLARIZATION_OFF)
            liks = [Likelihood(sc, fitspec_from(sc, None, noise), data) for sc in scenes.values()]
            check_comparable(liks, list(scenes))
            cases.append({"data": fname, "generator": generator, "terms": t})
            groups.append((liks, list(scenes)))
    return cases, groups


_PAIRING_CACHE: dict = {}
