"""The real-data study (issue 29 part 4): NIST's sintered PTFE, five models fitted, compared by
PSIS-LOO and WAIC (ArviZ), checked by posterior predictive coverage and by leaving one incidence
angle out.  Compute only: the figures are in :mod:`.ptfe_figures`, the CLI in
:mod:`scatterbench.validation.cli.study`.

One observation is one row (a geometry and wavelength): its log-likelihood is the sum over the
fitted elements, because the elements of one measured matrix share their calibration and
geometry.  ArviZ is imported inside the functions that need it (its import takes seconds).
"""

from __future__ import annotations

import os
import warnings
from dataclasses import asdict, dataclass, replace

import numpy as np

from scatterbench.models import scene as scene_mod
from scatterbench.references import scene_path
from scatterbench.validation.fitting import diagnostics
from scatterbench.validation.fitting.executors import SerialExecutor
from scatterbench.validation.fitting.fit import run_fit
from scatterbench.validation.fitting.mueller_fit import (
    interval_coverage,
    mueller_likelihood,
    write_mueller_fit,
)
from scatterbench.validation.fitting.mueller_likelihood import Rows
from scatterbench.validation.fitting.settings import MOVES, ChainSettings

__all__ = [
    "MODELS",
    "PHYSICAL",
    "QUICK",
    "REPORT",
    "StudySettings",
    "scene_file",
    "select_rows",
    "fit_model",
    "pointwise_loglik",
    "inference_data",
    "compare_models",
    "heldout_coverage",
    "leave_one_incidence_out",
    "verdict",
    "run_study",
]

#: the study's models: name -> shipped per-wavelength scene
MODELS = {
    "smooth_diffuse": "ptfe_smooth_diffuse_per_wavelength.toml",
    "rough_diffuse": "ptfe_rough_diffuse_per_wavelength.toml",
    "single_hg": "ptfe_single_hg_per_wavelength.toml",
    "maxwell_beard": "ptfe_maxwell_beard_per_wavelength.toml",
    "lambertian": "ptfe_lambertian_per_wavelength.toml",
}


def scene_file(name, joint=False) -> str:
    """The shipped scene of model ``name``: fitted to one wavelength, or (``joint``) to all of
    them at once (``ptfe_<name>_joint.toml``: the shape shared, the albedo per wavelength, the
    index a Cauchy law)."""
    return MODELS[name].replace("_per_wavelength", "_joint") if joint else MODELS[name]


#: seed 003's physical models (its claim: they improve over Maxwell-Beard)
PHYSICAL = ("smooth_diffuse", "rough_diffuse", "single_hg")

#: ``--quick`` and the report's quick run: three models (the fast ones), every 48th row,
#: short chains, two held-out incidences
QUICK = {
    "row_step": 48,
    "steps": 30,
    "models": ("lambertian", "maxwell_beard", "smooth_diffuse"),
    "cv_incidences": (0.0, 45.0),
    "draws": 60,
}
#: the report's full run: every model (rough_diffuse's quadrature interface binds to a model set
#: like the others; its Monte Carlo form, 0.33 s a 14-walker batch on these rows, had been left
#: out), every 24th row, three held-out incidences
REPORT = {
    "row_step": 24,
    "steps": 100,
    "models": ("lambertian", "maxwell_beard", "smooth_diffuse", "single_hg", "rough_diffuse"),
    "cv_incidences": (0.0, 45.0, 75.0),
}


@dataclass(frozen=True)
class StudySettings:
    """What the study fits: one wavelength, every ``row_step``-th of its rows (file order,
    deterministic), ``walkers`` x ``steps`` emcee chains, seeded; ``joint``: every wavelength
    at once with the joint scenes (:func:`scene_file`), ``wavelength_nm`` then only the one the
    maps show."""

    wavelength_nm: float = 532.0
    joint: bool = False
    row_step: int = 24
    walkers: int = 16
    steps: int = 200
    seed: int = 0
    models: tuple = tuple(MODELS)
    cv: bool = True
    cv_incidences: tuple | None = None  # None: every incidence of the subset
    draws: int = 200
    moves: str = "stretch"  # emcee's proposal (ChainSettings.moves: "stretch" or "de")
    burn: int = 0  # steps run and discarded before each chain (ChainSettings.burn)

    def __post_init__(self):
        if self.moves not in MOVES:
            raise ValueError(f"moves: {self.moves!r} is not one of {', '.join(MOVES)}")
        if not (isinstance(self.burn, int) and self.burn >= 0):
            raise ValueError(f"burn: {self.burn!r} is not an integer >= 0")
        if not (isinstance(self.row_step, int) and self.row_step >= 1):
            raise ValueError(f"row_step: {self.row_step!r} is not an integer >= 1")
        if not (isinstance(self.steps, int) and self.steps >= 10):
            raise ValueError(f"steps: {self.steps!r} is not an integer >= 10")
        if not (isinstance(self.walkers, int) and self.walkers >= 2 and self.walkers % 2 == 0):
            raise ValueError(f"walkers: {self.walkers!r} is not an even integer >= 2")
        unknown = [m for m in self.models if m not in MODELS]
        if unknown or not self.models:
            raise ValueError(f"models: {unknown or 'none'} not in {list(MODELS)}")

    def chain(self, seed_offset=0) -> ChainSettings:
        return ChainSettings(
            walkers=self.walkers,  # raised to 2 x free parameters per model by fit_model
            max_steps=self.steps,
            # ten autocorrelation estimates: the N >= 50 tau rule needs two to say a chain
            # converged (one, at the end, left every long chain "NOT converged"), and stops there
            check_every=max(1, self.steps // 10),
            starts=1,
            seed=self.seed + seed_offset,
            moves=self.moves,
            burn=self.burn,
        )


def select_rows(data, wavelength_nm, row_step):
    """Indices of ``data``'s rows at ``wavelength_nm`` (``None``: all of them), every
    ``row_step``-th in file order; ``ValueError`` when the wavelength is absent."""
    if wavelength_nm is None:
        return np.arange(len(data))[::row_step]
    at = np.flatnonzero(np.abs(data.wavelength_nm - wavelength_nm) <= 1e-6 * wavelength_nm)
    if not len(at):
        have = ", ".join(f"{w:g}" for w in np.unique(data.wavelength_nm))
        raise ValueError(f"wavelength_nm: {wavelength_nm:g} is not in the data (it has {have} nm)")
    return at[::row_step]


def fit_model(name, data, chain: ChainSettings, scene=None, joint=False):
    """:func:`run_fit` of model ``name``'s shipped scene (:func:`scene_file`; or ``scene``) on ``data``."""
    sc = scene if scene is not None else scene_mod.load(scene_path(scene_file(name, joint)))
    lik = mueller_likelihood(sc, data)
    need = 2 * len(lik.spec.free)  # emcee's ensemble needs >= 2 walkers per dimension
    if chain.walkers < need:
        chain = replace(chain, walkers=need)
    with warnings.catch_warnings():
        # a walker that never moved in a short chain makes emcee's autocorrelation divide 0 by 0;
        # its tau is then NaN, which the burn-in rule handles (half the chain kept)
        warnings.filterwarnings("ignore", "invalid value encountered in divide", RuntimeWarning)
        return run_fit(lik, chain)


def _kept(fit):
    """The kept chain ``(walkers, draws, k)``: burned and thinned as the fit's summary."""
    burn, thin = fit.chain.burn_thin()
    return np.swapaxes(fit.chain.chain[burn::thin], 0, 1)


def pointwise_loglik(fit) -> np.ndarray:
    """Per-row log-likelihood ``(walkers, draws, rows)`` at the kept samples (the prior
    excluded: PSIS-LOO and WAIC need the likelihood alone)."""
    U = _kept(fit)
    W, D, k = U.shape
    return fit.lik.pointwise_batch(U.reshape(-1, k)).reshape(W, D, -1)


def inference_data(fit, loglik):
    """An ArviZ InferenceData: the posterior in physical units (one chain per walker) and
    the per-row log-likelihood as ``log_likelihood['rows']``."""
    diagnostics.load()  # ArviZ imported by one thread at a time (beside a report's others)
    import arviz as az

    U = _kept(fit)
    post = {p.key: np.vectorize(p.from_u)(U[..., i]) for i, p in enumerate(fit.lik.spec.free)}
    return az.from_dict(posterior=post, log_likelihood={"rows": loglik}, dims={"rows": ["row"]})


def compare_models(idatas: dict) -> dict:
    """PSIS-LOO (with Pareto-k counts) and WAIC per model and ArviZ's LOO comparison
    (``elpd_diff`` and its standard error ``dse`` against the best)."""
    diagnostics.load()  # ArviZ imported by one thread at a time (beside a report's others)
    import arviz as az

    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the Pareto-k and WAIC warnings are reported as counts
        for name, idata in idatas.items():
            loo = az.loo(idata, pointwise=True)
            waic = az.waic(idata)
            k = np.asarray(loo.pareto_k)
            out[name] = {
                "elpd_loo": float(loo.elpd_loo),
                "se_loo": float(loo.se),
                "p_loo": float(loo.p_loo),
                "elpd_waic": float(waic.elpd_waic),
                "se_waic": float(waic.se),
                "p_waic": float(waic.p_waic),
                "pareto_k": {
                    "good (<=0.7)": int(np.sum(k <= 0.7)),
                    "bad (0.7-1]": int(np.sum((k > 0.7) & (k <= 1))),
                    "very bad (>1)": int(np.sum(k > 1)),
                    "max": float(np.max(k)),
                },
            }
        table = az.compare(idatas, ic="loo")
    for name, row in table.iterrows():
        out[name].update(rank=int(row["rank"]), elpd_diff=float(row["elpd_diff"]), dse=float(row["dse"]))
    return out


def heldout_coverage(fit, held, draws=200, seed=0) -> dict:
    """Fraction of the rows of ``held`` (a MuellerData: held-out rows for cross-validation, the
    fitted rows for the posterior predictive check) inside the 68% and 95% posterior-predictive
    intervals, per fitted element and all elements pooled."""
    lik = fit.lik
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 11]))
    rows = Rows(held, lik.spec.wavelengths, range(16))
    return interval_coverage(lik, fit.chain.samples(), held, rows, rng, draws)


def leave_one_incidence_out(name, data, settings: StudySettings, scene=None, executor=None) -> dict:
    """For each incidence angle of ``data`` (or ``settings.cv_incidences``): fit on the other
    incidences, then the 68%/95% coverage of the held-out rows only; the folds' fits on
    ``executor`` (default in-process; the same result on any)."""
    jobs = _fold_jobs(name, data, settings, scene)
    return _pooled(jobs, (executor or SerialExecutor()).map(_task, jobs, tasks=len(jobs)))


def _fold_jobs(name, data, settings: StudySettings, scene=None) -> list:
    """The tasks (:func:`_task`) of :func:`leave_one_incidence_out`: one ``("fold", ...)`` per
    held-out incidence, each seeded by its index."""
    inc = np.round(np.degrees(data.theta_i), 1)  # NIST's normal incidence is 0.001 deg
    angles = sorted(set(inc.tolist())) if settings.cv_incidences is None else list(settings.cv_incidences)
    jobs = []
    for j, a in enumerate(angles):
        held = np.abs(inc - a) < 0.05
        if not held.any() or held.all():
            have = ", ".join(f"{x:g}" for x in sorted(set(inc.tolist())))
            raise ValueError(
                f"cv_incidences: {a:g} deg leaves no held-out or no training rows (incidences: {have})"
            )
        chain = settings.chain(seed_offset=1 + j)
        jobs.append(
            ("fold", name, f"{a:g}", data.subset(~held), data.subset(held), chain, scene, settings, j)
        )
    return jobs


def _task(job):
    """One task of the study, run where the executor puts it (its chain is seeded by its
    settings alone, so it is the same anywhere): ``("fit", name, data, chain, joint)`` gives
    the fit; ``("fold", name, label, train, held, chain, scene, settings, j)`` the coverage of
    the held-out rows by the fit to the others (:func:`leave_one_incidence_out`)."""
    if job[0] == "fit":
        _, name, data, chain, joint = job
        return fit_model(name, data, chain, joint=joint)
    _, name, _, train, held, chain, scene, settings, j = job
    fit = fit_model(name, train, chain, scene, settings.joint)
    return {
        "heldout_rows": len(held),
        "coverage": heldout_coverage(fit, held, settings.draws, settings.seed + j),
    }


def _pooled(jobs, done) -> dict:
    """One model's folds (``("fold", ...)`` jobs and their results) and their pooled coverage."""
    folds = {job[2]: f for job, f in zip(jobs, done, strict=True)}
    pooled = {
        q: float(
            sum(f["coverage"]["all"][q] * f["heldout_rows"] for f in folds.values())
            / sum(f["heldout_rows"] for f in folds.values())
        )
        for q in ("inside_68", "inside_95")
    }
    return {"folds": folds, "pooled": pooled}


def verdict(comparison: dict) -> dict:
    """The winner by elpd_loo, its margin over the runner-up (difference and SE from
    ``az.compare``), the losing model, and whether each of seed 003's physical models fitted
    improves over Maxwell-Beard (elpd_loo higher by more than 2 SE of the difference)."""
    order = sorted(comparison, key=lambda m: comparison[m]["rank"])
    best = order[0]
    out = {
        "winner": best,
        "ranking": order,
        "loser": order[-1],
        "runner_up": order[1] if len(order) > 1 else None,
    }
    # rows whose PSIS estimate is unreliable (Pareto k > 0.7): their elpd_loo is suspect
    out["pareto_k_above_0.7"] = {
        m: comparison[m]["pareto_k"]["bad (0.7-1]"] + comparison[m]["pareto_k"]["very bad (>1)"]
        for m in order
    }
    if len(order) > 1:
        r = comparison[order[1]]
        out["margin"] = {"elpd_diff": r["elpd_diff"], "dse": r["dse"]}
    if "maxwell_beard" in comparison:
        mb = comparison["maxwell_beard"]["elpd_loo"]
        claim = {}
        for m in PHYSICAL:
            if m in comparison:
                d = comparison[m]["elpd_loo"] - mb
                claim[m] = {"elpd_loo_minus_maxwell_beard": d, "improves": bool(d > 0)}
        out["seed003_claim"] = {
            "per_model": claim,
            # None: no physical model was fitted, so the claim is not tested
            "holds": all(c["improves"] for c in claim.values()) if claim else None,
            "rule": "a physical model improves when its elpd_loo exceeds Maxwell-Beard's",
        }
    return out


def run_study(
    data, settings: StudySettings, out_dir=None, progress=print, executor=None
) -> tuple[dict, dict]:
    """Fit every model on the subset, compare, check and cross-validate.  Returns ``(results,
    fits)``; with ``out_dir``, each model's ``posterior.json``, samples and ``posterior.nc``
    are written under ``out_dir/<model>/`` (atomically; the caller swaps the folder in).  The
    fits and the cross-validation's folds are tasks of one map on ``executor`` (default
    in-process; the results are the same on any)."""
    rows = select_rows(data, None if settings.joint else settings.wavelength_nm, settings.row_step)
    sub = data.subset(rows)
    where = "all wavelengths (joint)" if settings.joint else f"{settings.wavelength_nm:g} nm"
    jobs = [("fit", name, sub, settings.chain(), settings.joint) for name in settings.models]
    folds = {name: _fold_jobs(name, sub, settings) if settings.cv else [] for name in settings.models}
    jobs += [job for name in settings.models for job in folds[name]]
    progress(
        f"ptfe: fitting {', '.join(settings.models)} on {len(sub)} rows at {where}"
        + (", and leaving one incidence out" if settings.cv else "")
    )
    done = (executor or SerialExecutor()).map(_task, jobs, tasks=len(jobs))
    fits, idatas, models = {}, {}, {}
    for name, fit in zip(settings.models, done, strict=False):
        fits[name] = fit
        idatas[name] = inference_data(fit, pointwise_loglik(fit))
        entry = {"scene": scene_file(name, settings.joint), "parameters": fit.summary["parameters"]}
        if out_dir is not None:
            folder = os.path.join(out_dir, name)
            post = write_mueller_fit(fit, folder, data_path=data.path, scene_path=entry["scene"])
            _write_netcdf(idatas[name], os.path.join(folder, "posterior.nc"))
            entry["posterior_json"] = os.path.join(name, "posterior.json") if post else None
        # in-sample posterior predictive check: the fitted rows inside the 68/95% intervals
        entry["posterior_predictive"] = heldout_coverage(fit, fit.lik.data, settings.draws, settings.seed)
        models[name] = entry
    comparison = compare_models(idatas)
    res = {
        "settings": asdict(settings),
        "data": {"path": data.path, "rows": len(sub), "row_indices": rows.tolist()},
        "models": models,
        "comparison": comparison,
        "verdict": verdict(comparison),
    }
    if settings.cv:
        at = len(settings.models)
        res["cross_validation"] = {}
        for name in settings.models:
            res["cross_validation"][name] = _pooled(folds[name], done[at : at + len(folds[name])])
            at += len(folds[name])
    return res, fits


def _write_netcdf(idata, path):
    """The InferenceData as netCDF (h5netcdf), written beside and renamed into place."""
    tmp = f"{path}.tmp{os.getpid()}"
    try:
        idata.to_netcdf(tmp, engine="h5netcdf")
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
