"""Real data: NIST's sintered PTFE at 532 nm, five models compared by PSIS-LOO and WAIC
(ArviZ), posterior predictive coverage and leave-one-incidence-out cross-validation
(:mod:`scatterbench.validation.studies.ptfe`)."""

from __future__ import annotations

from dataclasses import dataclass

from scatterbench.references import nist_ptfe_path
from scatterbench.validation.fitting.mueller_data import load_mueller_data
from scatterbench.validation.studies import ptfe
from scatterbench.validation.studies.ptfe_figures import incidence_figure, incidence_maps

from ..core import figure_block, table_block, text_block

__all__ = ["PtfeData", "compute", "render"]

_CMP = ["model", "elpd_loo", "se_loo", "elpd_diff", "dse", "elpd_waic", "p_loo", "pareto_k>0.7"]
_COV = ["model", "ppc inside 68%", "ppc inside 95%", "CV inside 68%", "CV inside 95%", "held-out incidences"]


@dataclass(frozen=True)
class PtfeData:
    settings: dict
    rows: int
    comparison: tuple
    coverage: tuple
    verdict: dict
    maps_incidence: float
    maps: dict  # the winner's maps at one incidence (ptfe_figures.incidence_maps)


def compute(ctx):
    data = load_mueller_data(nist_ptfe_path())
    st = ptfe.StudySettings(seed=ctx.seed, **(ptfe.QUICK if ctx.quick else ptfe.REPORT))
    res, fits = ptfe.run_study(data, st, progress=lambda msg: None, executor=ctx.executor)
    cmp_rows, cov_rows = [], []
    for name in res["verdict"]["ranking"]:
        c, ppc = res["comparison"][name], res["models"][name]["posterior_predictive"]["all"]
        k = c["pareto_k"]
        cmp_rows.append(
            {
                "model": name,
                **{key: c[key] for key in _CMP[1:-1]},
                "pareto_k>0.7": k["bad (0.7-1]"] + k["very bad (>1)"],
            }
        )
        cv = res["cross_validation"][name]
        cov_rows.append(
            {
                "model": name,
                "ppc inside 68%": ppc["inside_68"],
                "ppc inside 95%": ppc["inside_95"],
                "CV inside 68%": cv["pooled"]["inside_68"],
                "CV inside 95%": cv["pooled"]["inside_95"],
                "held-out incidences": ", ".join(cv["folds"]),
            }
        )
    maps = incidence_maps(fits[res["verdict"]["winner"]], st.draws, st.seed)
    at = 45.0 if 45.0 in maps else sorted(maps)[0]
    return PtfeData(
        res["settings"], res["data"]["rows"], tuple(cmp_rows), tuple(cov_rows), res["verdict"], at, maps[at]
    )


def render(s, d: PtfeData):
    import matplotlib.pyplot as plt  # matplotlib (heavy): loaded only where a figure is drawn

    st = d.settings
    s.blocks.append(
        text_block(
            f"NIST's PTFE.data.csv at {st['wavelength_nm']:g} nm, every {st['row_step']}th row ({d.rows} rows), "
            f"emcee {st['steps']} steps; one observation = one row (its elements summed). Short chains: the "
            "fits are not converged by the N >= 50 tau rule; the numbers show the machinery, and "
            "`scatterbench study ptfe --steps N` runs longer chains."
        )
    )
    s.blocks.append(
        table_block(s, "ptfe_comparison", _CMP, d.comparison, caption="ArviZ compare (LOO) and WAIC")
    )
    s.blocks.append(
        table_block(s, "ptfe_coverage", _COV, d.coverage, caption="predictive coverage, all elements")
    )
    v = d.verdict
    text = f"Winner by elpd_loo: {v['winner']}; losing model: {v['loser']}."
    if "margin" in v:
        text += f" Margin over {v['runner_up']}: {v['margin']['elpd_diff']:.1f} +- {v['margin']['dse']:.1f}."
    claim = v.get("seed003_claim")
    if claim:
        held = {True: "holds", False: "does not hold", None: "is not tested"}[claim["holds"]]
        text += f" Seed 003's claim (its physical models improve over Maxwell-Beard) {held} on these rows."
    s.blocks.append(text_block(text))
    s.numbers["ptfe_verdict"] = {
        "winner": v["winner"],
        "loser": v["loser"],
        "claim_holds": claim and claim["holds"],
    }
    fig = incidence_figure(d.maps, d.maps_incidence, v["winner"], plt)
    s.blocks.append(figure_block(fig, f"{v['winner']} at incidence {d.maps_incidence:g} deg", dpi=70))
