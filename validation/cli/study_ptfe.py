"""``scatterbench study ptfe``: the real-data study of NIST's sintered PTFE
(:mod:`scatterbench.validation.studies.ptfe`).  Writes ``results.json``, one folder per model
(``posterior.json``, ``posterior_samples.npz``, ``posterior.nc``) and the winner's polar maps
per incidence (``maps_<deg>.png``) into ``--out``, built beside it and swapped in whole."""

from __future__ import annotations

import os
import time

from scatterbench.references import nist_ptfe_path
from scatterbench.validation.atomic import atomic_savefig, atomic_write_json, replacing_folder
from scatterbench.validation.fitting.mueller_data import load_mueller_data
from scatterbench.validation.fitting.settings import MOVES
from scatterbench.validation.studies import ptfe
from scatterbench.validation.studies.ptfe_figures import incidence_figure, incidence_maps

from .args import UsageError, check_executor, executor_args, int_at_least, open_executor
from .fit import _check_out, locked_out

__all__ = ["register_ptfe", "format_results"]


def settings_from(args) -> ptfe.StudySettings:
    kw = dict(ptfe.QUICK) if args.quick else {}
    for key, val in (("row_step", args.row_step), ("steps", args.steps), ("walkers", args.walkers)):
        if val is not None:
            kw[key] = val
    if args.models:
        kw["models"] = tuple(m.strip() for m in args.models.split(","))
    if args.cv_incidences:
        try:
            kw["cv_incidences"] = tuple(float(a) for a in args.cv_incidences.split(","))
        except ValueError:
            raise UsageError(f"--cv-incidences: {args.cv_incidences!r} is not a list of degrees") from None
    try:
        if args.joint and args.wavelength is not None:
            raise UsageError("--wavelength: a joint study fits every wavelength (its maps show 532 nm)")
        return ptfe.StudySettings(
            wavelength_nm=532.0 if args.wavelength is None else args.wavelength,
            joint=args.joint,
            seed=args.seed,
            cv=not args.no_cv,
            moves=args.moves,
            burn=args.burn,
            **kw,
        )
    except ValueError as exc:
        raise UsageError(f"--{str(exc).split(':')[0].replace('_', '-')}: {exc}") from None


def _owned(name):
    return (
        name == "results.json" or name in ptfe.MODELS or (name.startswith("maps_") and name.endswith(".png"))
    )


def _cmd_ptfe(args) -> int:
    settings = settings_from(args)
    data = load_mueller_data(args.data)
    try:
        ptfe.select_rows(data, settings.wavelength_nm, settings.row_step)  # joint: the maps' wavelength
    except ValueError as exc:
        raise UsageError(f"--wavelength: {exc}") from None
    _check_out(args.out, args.force)
    check_executor(args)
    with locked_out(args), open_executor(args) as ex:
        return _ptfe(args, data, settings, ex)


def _ptfe(args, data, settings, executor) -> int:
    import matplotlib  # matplotlib (heavy): loaded only where a figure is drawn

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t0 = time.perf_counter()
    with replacing_folder(args.out, _owned, lock=False) as out:
        try:
            res, fits = ptfe.run_study(data, settings, out_dir=out, executor=executor)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        win = res["verdict"]["winner"]
        res["figures"] = {}
        shown = settings.wavelength_nm if settings.joint else None
        for a, maps in incidence_maps(fits[win], settings.draws, settings.seed, shown).items():
            name = f"maps_{a:g}.png"
            fig = incidence_figure(maps, a, win, plt)
            atomic_savefig(fig, os.path.join(out, name), dpi=80)
            plt.close(fig)
            res["figures"][f"{a:g}"] = name
        res["wall_seconds"] = time.perf_counter() - t0
        atomic_write_json(os.path.join(out, "results.json"), res)
    print(format_results(res))
    print(f"wrote {args.out}/results.json, {len(res['figures'])} maps, one folder per model")
    return 0


def format_results(res) -> str:
    """The comparison table, the coverages and the verdict as text."""
    lines = [
        f"{'model':<16} {'elpd_loo':>10} {'se':>7} {'elpd_diff':>10} {'dse':>7} {'elpd_waic':>10} "
        f"{'p_loo':>7} {'k>0.7':>6} {'ppc68':>6} {'ppc95':>6} {'cv68':>6} {'cv95':>6}"
    ]
    cv = res.get("cross_validation", {})
    for name in res["verdict"]["ranking"]:
        c, m = res["comparison"][name], res["models"][name]["posterior_predictive"]["all"]
        k = c["pareto_k"]["bad (0.7-1]"] + c["pareto_k"]["very bad (>1)"]
        p = cv.get(name, {}).get("pooled", {})
        lines.append(
            f"{name:<16} {c['elpd_loo']:>10.1f} {c['se_loo']:>7.1f} {c['elpd_diff']:>10.1f} {c['dse']:>7.1f} "
            f"{c['elpd_waic']:>10.1f} {c['p_loo']:>7.1f} {k:>6d} {m['inside_68']:>6.2f} {m['inside_95']:>6.2f} "
            f"{p.get('inside_68', float('nan')):>6.2f} {p.get('inside_95', float('nan')):>6.2f}"
        )
    v = res["verdict"]
    lines.append(f"winner by elpd_loo: {v['winner']}; losing model: {v['loser']}")
    if "margin" in v:
        lines.append(
            f"margin over {v['runner_up']}: elpd_diff {v['margin']['elpd_diff']:.1f} +- {v['margin']['dse']:.1f} (dse)"
        )
    bad = {m: n for m, n in v["pareto_k_above_0.7"].items() if n}
    if bad:
        lines.append(
            "Pareto k > 0.7 (PSIS-LOO unreliable) at rows: " + ", ".join(f"{m} {n}" for m, n in bad.items())
        )
    if "seed003_claim" in v:
        per = ", ".join(
            f"{m} {c['elpd_loo_minus_maxwell_beard']:+.1f}"
            for m, c in v["seed003_claim"]["per_model"].items()
        )
        held = {True: "holds", False: "does not hold", None: "not tested"}[v["seed003_claim"]["holds"]]
        lines.append(f"seed 003's claim (physical models beat Maxwell-Beard by elpd_loo): {held} ({per})")
    return "\n".join(lines)


def register_ptfe(ss):
    p = ss.add_parser("ptfe", help="NIST sintered PTFE: five models fitted, LOO/WAIC, predictive checks, CV")
    p.add_argument(
        "--data", default=nist_ptfe_path(), help="Mueller data file (default: NIST's PTFE.data.csv)"
    )
    p.add_argument("--out", required=True)
    p.add_argument("--force", action="store_true")
    p.add_argument("--quick", action="store_true", help="three models, every 48th row, 30 steps, 2 CV folds")
    p.add_argument("--wavelength", type=float, default=None, help="the wavelength fitted (nm; default 532)")
    p.add_argument(
        "--joint",
        action="store_true",
        help="every wavelength at once, with the joint scenes (shape shared, albedo per wavelength, Cauchy index)",
    )
    p.add_argument("--row-step", type=int_at_least(1), default=None, help="every N-th row (default 24)")
    p.add_argument("--steps", type=int_at_least(10), default=None, help="emcee steps (default 200)")
    p.add_argument("--walkers", type=int_at_least(2), default=None)
    p.add_argument("--seed", type=int_at_least(0), default=0)
    executor_args(p)  # the fits and the folds as tasks; the results do not depend on it
    p.add_argument(
        "--moves",
        choices=MOVES,
        default="stretch",
        help="emcee's proposal: stretch, or differential evolution",
    )
    p.add_argument(
        "--burn", type=int, default=0, help="steps run and discarded before each chain (default 0)"
    )
    p.add_argument("--models", default=None, help=f"comma separated, of {', '.join(ptfe.MODELS)}")
    p.add_argument("--cv-incidences", default=None, help="held-out incidences (deg); default: all")
    p.add_argument("--no-cv", action="store_true", help="skip the leave-one-incidence-out fits")
    p.set_defaults(func=_cmd_ptfe)
