"""Uncertainty: an example emcee posterior on held-out SCATMECH data, and the recovery coverage."""

from __future__ import annotations

import functools
import tempfile
from dataclasses import dataclass

from scatterbench import references
from scatterbench.models import scene as scene_mod
from scatterbench.validation.checks.fitting import RECOVERY_SCENE, recovery_cells, recovery_settings
from scatterbench.validation.fitting.datafile import load_data
from scatterbench.validation.fitting.fit import (
    corner_figure,
    fit_task,
    predictive,
    predictive_figure,
    write_fit,
)
from scatterbench.validation.fitting.fitspec import fitspec_from
from scatterbench.validation.fitting.likelihood import Likelihood
from scatterbench.validation.fitting.settings import ChainSettings

from ..core import figure_block, table_block, text_block

__all__ = ["UncertaintyData", "RecoveryData", "compute", "render", "FIT_SCENE", "FIT_DATA"]

FIT_SCENE = "aluminium_flakes_fit.toml"
FIT_DATA = "scatmech_flake_measurement.csv"
_RECOVERY_FMT = {
    "bias": ".2e",
    "bias SE": ".2e",
    "mean 68% width": ".3e",
    "min N / tau": ".1f",
    "z 68%": "+.2f",
    "z 95%": "+.2f",
}


@dataclass(frozen=True)
class RecoveryData:
    """The recovery-coverage check's study: its settings and one row per cell and parameter."""

    scene: str
    free: tuple[str, ...]
    injections: int
    walkers: int
    max_steps: int
    rows: tuple


@dataclass(frozen=True)
class UncertaintyData:
    """The example fit: ``fit`` (its chain, for the corner plot) and ``pp`` (posterior-predictive
    draws, for the band plot); ``sampling``: posterior.json's sampling summary; table rows."""

    quick: bool
    seed: int
    data_rows: int
    free: tuple[str, ...]
    max_steps: int
    starts: int
    sampling: dict
    fit: object
    pp: dict
    posterior_rows: tuple
    sampling_rows: tuple
    predictive_rows: tuple
    recovery: RecoveryData


def _fit_settings(quick, seed):

    if quick:
        return ChainSettings(walkers=16, seed=seed, max_steps=1000, check_every=100, starts=2)
    return ChainSettings(seed=seed)  # scatterbench fit's defaults: 32 walkers, 20000 steps, 4 starts


def _recovery_row(cell, name, v):
    c68, c95 = v["coverage"]["68"], v["coverage"]["95"]
    return {
        "noise (brdf, fractional)": cell["noise_brdf"],
        "geometries": cell["geometries"],
        "parameter": name,
        "injections": v["injections"],
        "coverage 68%": c68["measured"],
        "z 68%": c68["z"],
        "coverage 95%": c95["measured"],
        "z 95%": c95["z"],
        "binomial SE 68%": c68["binomial_se"],
        "binomial SE 95%": c95["binomial_se"],
        "curvature coverage 68%": c68["curvature"],
        "curvature coverage 95%": c95["curvature"],
        "bias": v["bias"],
        "bias SE": v["bias_se"],
        "mean 68% width": v["width68_mean"],
        "min N / tau": cell["steps_over_tau_min"],
    }


def _recovery(ctx):
    """The injection-recovery coverage: the recovery-coverage check's study, run once."""

    rs = recovery_settings(ctx.quick, ctx.seed)
    rows = tuple(_recovery_row(c, k, v) for c in recovery_cells(ctx) for k, v in c["summary"].items())
    return RecoveryData(
        RECOVERY_SCENE, tuple(rs["free"]), rs["injections"], rs["chain"].walkers, rs["chain"].max_steps, rows
    )


def _fit(ctx):
    """The example fit, its posterior.json summary (truth check, predictive checks) and data;
    the recovery study (:func:`recovery_cells`) run meanwhile."""

    sc = scene_mod.load(references.scene_path(FIT_SCENE))
    data = load_data(references.data_path(FIT_DATA))
    spec = fitspec_from(sc)
    st = _fit_settings(ctx.quick, ctx.seed)
    # a task, the recovery study's tasks submitted from here while it runs (its results kept
    # in ctx's memo): computed here before them, the fit took its CPU (8.9 s alone, 13.9 s in
    # a full report on 2 cores, ad hoc) from what every section thread shares and held the
    # recovery back (106.8 s after it), the whole fit on a many-core report's longest path;
    # each has its own seed, so the results are the same
    job = (Likelihood(sc, spec, data), st)
    fit = ctx.runner().map(fit_task, [job], tasks=1, meanwhile=functools.partial(recovery_cells, ctx))[0]
    with tempfile.TemporaryDirectory() as tmp:  # write_fit's summary (truth check, predictive checks)
        post = write_fit(fit, tmp, data_path=FIT_DATA, scene_path=FIT_SCENE, plots=False)
    return fit, post, data, spec, st


def _truth(data, post):
    """The sidecar's truth and truth check, with the speckle level the data were made with."""
    truth = dict(data.meta.get("truth", {}))
    tc = dict(post.get("truth_check", {}))
    lvl = (data.meta.get("provenance", {}).get("noise_levels", {}) or {}).get("brdf_frac")
    if lvl is not None and "noise.brdf" in post["parameters"]:
        p = post["parameters"]["noise.brdf"]
        truth["noise.brdf"] = lvl
        tc["noise.brdf"] = {
            "inside_68": bool(p["p16"] <= lvl <= p["p84"]),
            "inside_95": bool(p["p2.5"] <= lvl <= p["p97.5"]),
        }
    return truth, tc


def _posterior_rows(data, post):
    truth, tc = _truth(data, post)
    rows = []
    for k, p in post["parameters"].items():
        t = tc.get(k)
        rows.append(
            {
                "parameter": k,
                "true": truth.get(k),
                "median": p["median"],
                "16%": p["p16"],
                "84%": p["p84"],
                "2.5%": p["p2.5"],
                "97.5%": p["p97.5"],
                "truth inside 68%": "—" if t is None else ("yes" if t["inside_68"] else "no"),
                "truth inside 95%": "—" if t is None else ("yes" if t["inside_95"] else "NO"),
                "tau (steps)": p["tau_steps"],
            }
        )
    return tuple(rows)


def _sampling_row(samp, timing):
    return {
        "walkers": samp["walkers"],
        "steps N": samp["steps"],
        "max tau": samp["tau_max"],
        "N / max tau": samp["steps_over_tau_max"],
        "N > 50 tau": "yes" if samp["steps_over_tau_max"] > 50 else "NO",
        "converged (rule incl. tau stable)": "yes" if samp["converged"] else "NO",
        "acceptance mean": samp["acceptance_mean"],
        "acceptance min": samp["acceptance_min"],
        "seconds": timing["sampling_seconds"],
    }


def compute(ctx):

    fit, post, data, spec, st = _fit(ctx)
    pp = predictive(fit, n_draws=200, seed=ctx.seed)
    pprows = tuple(
        {"term": t, "rows": c["rows"], "inside 68%": c["inside_68"], "inside 95%": c["inside_95"]}
        for t, c in post["posterior_predictive"].items()
    )
    samp = post["sampling"]
    return UncertaintyData(
        quick=ctx.quick,
        seed=ctx.seed,
        data_rows=post["data"]["rows"],
        free=tuple(spec.names),
        max_steps=st.max_steps,
        starts=st.starts,
        sampling=samp,
        fit=fit,
        pp=pp,
        posterior_rows=_posterior_rows(data, post),
        sampling_rows=(_sampling_row(samp, post["timing"]),),
        predictive_rows=pprows,
        recovery=_recovery(ctx),  # its study already run, by _fit
    )


def _fit_text(d):
    samp = d.sampling
    return (
        f"Data: references/data/{FIT_DATA} ({d.data_rows} rows, synthetic SCATMECH measurement, "
        f"truth in its JSON sidecar); scene references/scenes/{FIT_SCENE} with its [fit] table "
        f"({', '.join(d.free)} free). emcee: {samp['walkers']} walkers, at most {d.max_steps} steps "
        f"({'quick' if d.quick else 'full'} run), seed {d.seed}, {d.starts} optimizer starts. "
        f"Stop: {samp['stop_reason']}."
        + (
            ""
            if samp["converged"]
            else " The chain did NOT reach N > 50 tau: its intervals are indicative only (quick mode's step "
            "budget); the full report runs to convergence."
        )
    )


def _recovery_text(d):
    r = d.recovery
    return (
        f"Injection-recovery (validation/fitting/recovery.py): scene references/scenes/{r.scene}, free "
        f"{', '.join(r.free)}, geometries from the data file (evenly spread subsets), log-normal speckle "
        f"at the listed level; {r.injections} injections per cell, each fitted with {r.walkers} walkers "
        f"and at most {r.max_steps} steps, seed {d.seed}"
        + (" (quick mode: the configuration of tests/test_recovery.py)." if d.quick else ".")
        + " z = (coverage - nominal) / binomial SE. The curvature columns are the coverage, on the same "
        "data sets, of the optimum +- 1 and 2 Gauss-Newton standard deviations: when they are nominal and "
        "the posterior's are not, the sampler is at fault, not the data."
    )


def _render_figures(s, d):

    samp = d.sampling
    s.blocks.append(
        figure_block(
            corner_figure(d.fit),
            f"Posterior (burn-in {samp['burn_in']} steps, thinned by {samp['thin']}: 2 max tau and min tau / 2 "
            "when converged, else the second half) with the 2.5/16/50/84/97.5 percentiles; "
            "blue lines: the true values of the sidecar.",
            dpi=60,
        )
    )
    s.blocks.append(
        figure_block(
            predictive_figure(d.fit, d.pp),
            "Posterior-predictive 95% bands from 200 posterior draws: the model (dark) and replicated data with "
            "the likelihood's noise (light), with the data (dots).",
            dpi=60,
        )
    )


def render(s, d: UncertaintyData):
    s.blocks.append(text_block(_fit_text(d)))
    _render_figures(s, d)
    caption = "posterior percentiles against the sidecar's truth (noise.brdf: its provenance.noise_levels.brdf_frac)"
    s.blocks.append(table_block(s, "posterior", list(d.posterior_rows[0]), d.posterior_rows, caption=caption))
    s.blocks.append(
        table_block(s, "sampling", list(d.sampling_rows[0]), d.sampling_rows, fmt={"N / max tau": ".1f"})
    )
    caption = "fraction of data inside the posterior-predictive intervals"
    s.blocks.append(
        table_block(s, "predictive_checks", list(d.predictive_rows[0]), d.predictive_rows, caption=caption)
    )
    s.blocks.append(text_block(_recovery_text(d)))
    caption = "coverage of the 68% and 95% intervals (nominal 0.6827 and 0.9545)"
    rows = d.recovery.rows
    s.blocks.append(table_block(s, "recovery", list(rows[0]), rows, caption=caption, fmt=_RECOVERY_FMT))
