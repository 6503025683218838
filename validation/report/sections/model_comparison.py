"""Model comparison: seed 003's combination against Maxwell-Beard on the same data (issue 6 item 8).

Both hypotheses are fitted (emcee, :func:`scatterbench.validation.fitting.compare.seed003_pairing`)
to two held-out SCATMECH data sets, one made by each hypothesis's generator,
once with every likelihood term (BRDF, eta, P, P_C) and once with the BRDF
alone; the page shows the information criteria, the fitted speckle level
(against the level the data were made with) and the posterior-predictive coverage.  The check
that the generating hypothesis is preferred on each data set is registered in
:mod:`scatterbench.validation.checks.fitting`, whose fits this section draws.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scatterbench.validation.checks.fitting import comparison_cases, comparison_settings
from scatterbench.validation.fitting.compare import SEED003_PAIRING

from ..core import figure_block, table_block, text_block
from ._common import plt

__all__ = ["ComparisonData", "Scan", "compute", "render"]

_FMT = {
    "ln L max": ".1f",
    "dAIC": ".1f",
    "dBIC": ".1f",
    "dWAIC": ".1f",
    "fitted noise.brdf (median)": ".3f",
    "BRDF inside 95% predictive": ".2f",
    "eta inside 95% predictive": ".2f",
    "max tau": ".0f",
    "R-hat (max, between chains)": ".3f",
}
_TERMS = ("brdf", "eta", "P")


@dataclass(frozen=True)
class Scan:
    """One data set fitted with every term: the in-plane scan at theta_i = 60 deg, sorted by
    signed theta_r (deg); ``observed`` and each hypothesis's prediction per term (eta in deg)."""

    data: str
    generator: str
    x: np.ndarray
    observed: dict
    predicted: tuple  # ((hypothesis, {term: values}), ...)


@dataclass(frozen=True)
class ComparisonData:
    rows: tuple
    speckle: float
    rows_per_file: int
    all_rows: bool
    walkers: int
    max_steps: int
    burn: int
    seed: int
    chains: int
    data_files: tuple[str, ...]
    scene_files: tuple[str, ...]
    scans: tuple


def _best_values(fit):
    """The highest-posterior sample of the chain (physical values), for the figure."""
    c = fit.chain
    i, j = np.unravel_index(int(np.argmax(c.log_prob)), c.log_prob.shape)
    return fit.spec.physical(c.chain[i, j])


def _scan(case):
    """The in-plane data at theta_i = 60 deg and each hypothesis at its best sample."""
    data = case["fits"][0].lik.data_all
    sel = np.isclose(np.degrees(data.theta_i), 60.0) & np.isclose(np.mod(np.degrees(data.phi_r), 180.0), 0.0)
    x = np.where(np.isclose(np.degrees(data.phi_r), 180.0), -1.0, 1.0) * np.degrees(data.theta_r)
    order = np.argsort(x[sel])
    observed = {"brdf": data.brdf, "eta": np.degrees(data.eta), "P": data.P}
    predicted = []
    for row, fit in zip(case["rows"], case["fits"], strict=True):
        pred = fit.lik.predict(fit.lik.model(_best_values(fit)), data)
        pred = {"brdf": pred["brdf"], "eta": np.degrees(pred["eta"]), "P": pred["P"]}
        predicted.append((row["scene"], {t: pred[t][sel][order] for t in _TERMS}))
    return Scan(
        case["data"],
        case["generator"],
        x[sel][order],
        {t: observed[t][sel][order] for t in _TERMS},
        tuple(predicted),
    )


def _converged(row):
    """``"yes"`` when every chain of the row reached N > 50 tau, else how many did."""
    n = row.get("chains", 1)
    return "yes" if row["converged_chains"] == n else f"NO ({row['converged_chains']} of {n})"


def _comparison_rows(cases):
    """One table row per data set, term choice and hypothesis."""
    rows = []
    for c in cases:
        for r in c["rows"]:
            pc = r["predictive"]
            rows.append(
                {
                    "data (generator)": c["generator"],
                    "terms": "BRDF, eta, P, P_C" if c["terms"] == "all" else "BRDF only",
                    "hypothesis": r["scene"],
                    "k": r["k"],
                    "rows": r["n"],
                    "ln L max": r["max_log_likelihood"],
                    "dAIC": r["dAIC"],
                    "dBIC": r["dBIC"],
                    "dWAIC": r["dWAIC"],
                    "fitted noise.brdf (median)": r["medians"].get("noise.brdf"),
                    "BRDF inside 95% predictive": pc["brdf"]["inside_95"],
                    "eta inside 95% predictive": pc["eta"]["inside_95"] if "eta" in pc else None,
                    "max tau": r["tau_max"],
                    "N > 50 tau": _converged(r),
                    "R-hat (max, between chains)": r.get("rhat_max"),
                }
            )
    return tuple(rows)


def compute(ctx):

    st = comparison_settings(ctx.quick)
    cases = comparison_cases(ctx)  # the model-comparison check's fits, run once
    speckle = {c["fits"][0].lik.data_all.meta["provenance"]["noise_levels"]["brdf_frac"] for c in cases}
    (speckle,) = speckle  # both files were made with the same level
    return ComparisonData(
        rows=_comparison_rows(cases),
        speckle=speckle,
        rows_per_file=cases[0]["rows"][0]["n"],
        all_rows=st["rows"] is None,
        walkers=st["settings"].walkers,
        max_steps=st["settings"].max_steps,
        burn=st["settings"].burn,
        seed=st["settings"].seed,
        chains=st.get("chains", 1),
        data_files=tuple(SEED003_PAIRING["data"].values()),
        scene_files=tuple(SEED003_PAIRING["scenes"].values()),
        scans=tuple(_scan(c) for c in cases if c["terms"] == "all"),
    )


def _draw(scan):
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    for ax, t in zip(axes, _TERMS, strict=True):
        ax.plot(scan.x, scan.observed[t], "k.", ms=4, label="data (SCATMECH + noise)")
        for (hypothesis, pred), style in zip(scan.predicted, ("C0-", "C3--"), strict=True):
            xx, y = scan.x, pred[t]
            if t == "eta":  # eta is an axis: break the line where it wraps from +90 to -90
                cut = np.flatnonzero(np.abs(np.diff(y)) > 90.0) + 1
                xx, y = np.insert(xx, cut, np.nan), np.insert(y, cut, np.nan)
            ax.plot(xx, y, style, lw=1.2, label=hypothesis)
        ax.set_xlabel("signed theta_r (deg), theta_i = 60 deg")
        ax.set_ylabel({"brdf": "BRDF (1/sr)", "eta": "eta (deg)", "P": "P"}[t])
        if t == "brdf":
            ax.set_yscale("log")
    axes[0].legend(fontsize=7)
    fig.suptitle(f"{scan.data} (made by the {scan.generator} generator): fits with every term", fontsize=9)
    fig.tight_layout()
    return fig


def _text(d):
    return (
        "Seed 003 Sec. 4 sets its combination (facet reflection by the binder's surface + single volume "
        "scattering + totally diffuse scattering, under a smooth interface) against the Maxwell-Beard BRDF, "
        "which has no refraction and 'does not fully describe the polarization state'. Both are fitted to "
        "two held-out SCATMECH data sets (references/scripts/make_scatmech_paint_data.py), one made by each "
        f"hypothesis's generator: {', '.join(d.data_files)}; scenes references/scenes/"
        f"{' and references/scenes/'.join(d.scene_files)}. Each pair is fitted with every "
        "likelihood term (BRDF, eta, P, P_C) and with the BRDF alone (eta, P, P_C off). "
        f"{'All ' if d.all_rows else ''}{d.rows_per_file} rows per file"
        f"{'' if d.all_rows else ' (evenly spread)'}; emcee {d.walkers} walkers, "
        f"{f'{d.burn} steps of burn-in (not kept), then ' if d.burn else ''}at most "
        f"{d.max_steps} steps, {d.chains} independent chain(s) per fit (the first seeded {d.seed}, the "
        "others from it and their index), pooled for WAIC, predictive coverage and medians, the best "
        "ln L over them all; R-hat is the rank-normalized split R-hat between them (Vehtari et al. 2021; "
        "below about 1.01: the chains agree). The data were made with {d.speckle:g} speckle (their "
        "sidecars' provenance): a fitted "
        "noise.brdf far above it is a hypothesis absorbing its misfit into the noise. Lower AIC/BIC/WAIC "
        "is better; differences from the best per data set and term choice."
    )


def render(s, d: ComparisonData):
    s.blocks.append(text_block(_text(d)))
    caption = (
        "information criteria and posterior-predictive coverage per data set, term choice and hypothesis"
    )
    s.blocks.append(table_block(s, "comparison", list(d.rows[0]), d.rows, caption=caption, fmt=_FMT))
    if not all(r["N > 50 tau"] == "yes" for r in d.rows):  # every chain of every fit
        s.blocks.append(
            text_block(
                "Chains that did not reach N > 50 tau: their WAIC and predictive coverage are indicative; the "
                "maximum likelihood (best of the optimum and the chain) and so AIC/BIC do not depend on it."
            )
        )
    for scan in d.scans:
        s.blocks.append(
            figure_block(
                _draw(scan),
                "Each hypothesis at its highest-posterior sample against the in-plane data at theta_i = 60 deg.",
                dpi=60,
            )
        )
