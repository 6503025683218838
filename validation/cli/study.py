"""``scatterbench study recovery | inversion | compare | ptfe``: uncertainty studies and the
PTFE real-data study (:mod:`.study_ptfe`).

* ``recovery``: injection-recovery coverage, bias and width versus noise level
  and number of geometries (:mod:`scatterbench.validation.fitting.recovery`).
* ``inversion``: slope distribution from measured BRDF (:mod:`scatterbench.validation.fitting.inversion`).
* ``compare``: several scenes fitted to the same data (:mod:`scatterbench.validation.fitting.compare`).

Each writes JSON and PNG into ``--out`` (refused when it exists and is not
empty, unless ``--force``), built beside the old folder and swapped in whole,
under the folder's lock (see :mod:`scatterbench.validation.cli.fit`).
"""

from __future__ import annotations

import math
import os
import time

import numpy as np

from scatterbench.models import DetectorAperture
from scatterbench.models import scene as scene_mod
from scatterbench.validation.atomic import atomic_savefig, atomic_write_json, replacing_folder
from scatterbench.validation.fitting.compare import check_comparable, compare_fits, format_comparison
from scatterbench.validation.fitting.datafile import load_data
from scatterbench.validation.fitting.fitspec import fitspec_from, masked_rows
from scatterbench.validation.fitting.inversion import inversion_figure, inversion_study
from scatterbench.validation.fitting.likelihood import Likelihood, scene_for_data
from scatterbench.validation.fitting.recovery import check_inputs, recovery_study

from .args import UsageError, int_at_least, ints_at_least, positive_floats
from .fit import (
    _chain_settings,
    _check_executor,
    _check_out,
    _executor_args,
    _load_and_describe,
    _mcmc_args,
    _open_executor,
    _require_walkers,
    _spec_args,
    locked_out,
)
from .study_ptfe import register_ptfe

__all__ = ["register"]


# ----------------------------------------------------------------------------- recovery
def _print_recovery(cells, injections):
    print(
        f"\n{'noise':>6} {'geoms':>5} {'parameter':<20} {'cov68':>6} {'z68':>6} {'cov95':>6} {'z95':>6} "
        f"{'bias':>10} {'width68':>10} {'curv68':>6} {'curv95':>6}  steps/tau(min)"
    )
    for c in cells:
        for k, s in c["summary"].items():
            c68, c95 = s["coverage"]["68"], s["coverage"]["95"]
            print(
                f"{c['noise_brdf']:>6g} {c['geometries']:>5} {k:<20} {c68['measured']:>6.3f} {c68['z']:>6.2f} "
                f"{c95['measured']:>6.3f} {c95['z']:>6.2f} {s['bias']:>10.3g} {s['width68_mean']:>10.3g} "
                f"{c68['curvature']:>6.3f} {c95['curvature']:>6.3f}  "
                f"{c['steps_over_tau_min']:.1f}"
            )
    print("curv68/curv95: coverage of the optimum's curvature (Gauss-Newton) intervals on the same data sets")
    print(
        f"binomial standard errors over {injections} injections: 68%: "
        f"{math.sqrt(0.6827 * 0.3173 / injections):.3f}, 95%: {math.sqrt(0.9545 * 0.0455 / injections):.3f}"
    )


def _cmd_recovery(args) -> int:
    _check_out(args.out, args.force)
    with locked_out(args):  # held from the check of --out to the swap of the new folder
        return _recovery(args)


def _recovery(args) -> int:
    _check_executor(args)
    settings, sc, data, spec, _ = _load_and_describe(args)
    extra = {k: v for k, v in spec.noise.items() if k != "brdf"}
    try:
        check_inputs(spec, settings, extra, args.injections)
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    t0 = time.perf_counter()
    with _open_executor(args) as ex:
        cells = recovery_study(
            sc,
            spec,
            data,
            settings,
            noise_levels=args.noise_levels,
            n_geometries=args.n_geometries or (None,),
            injections=args.injections,
            executor=ex,
            noise_extra=extra,
            progress=not args.no_progress,
        )
    seconds = time.perf_counter() - t0
    record = {
        "scene": args.scene,
        "geometries_from": args.data,
        "spec": spec.as_dict(),
        "seed": settings.seed,
        "injections_per_cell": args.injections,
        "walkers": settings.walkers,
        "max_steps": settings.max_steps,
        "seconds": seconds,
        "cells": cells,
    }
    with replacing_folder(args.out, {"recovery.json", "recovery.png"}.__contains__, lock=False) as out:
        atomic_write_json(os.path.join(out, "recovery.json"), record)
        _recovery_plot(cells, out)
    _print_recovery(cells, args.injections)
    print(
        f"{len(cells)} cells x {args.injections} injections in {seconds:.1f} s; wrote {args.out}/recovery.json, recovery.png"
    )
    return 0


def _recovery_plot(cells, out):
    import matplotlib  # matplotlib (heavy): loaded only where a figure is drawn

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib (heavy): loaded only where a figure is drawn

    keys = list(cells[0]["summary"])
    fig, axes = plt.subplots(3, len(keys), figsize=(4.5 * len(keys), 8), squeeze=False)
    labels = [f"f={c['noise_brdf']:g}\nN={c['geometries']}" for c in cells]
    x = np.arange(len(cells))
    for j, k in enumerate(keys):
        for lvl, col in (("68", "C0"), ("95", "C1")):
            m = [c["summary"][k]["coverage"][lvl]["measured"] for c in cells]
            se = [c["summary"][k]["coverage"][lvl]["binomial_se"] for c in cells]
            nom = cells[0]["summary"][k]["coverage"][lvl]["nominal"]
            axes[0, j].errorbar(x, m, yerr=se, fmt="o", color=col, label=f"{lvl}% (binomial 1 s.e.)")
            axes[0, j].axhline(nom, color=col, lw=0.8, ls="--")
        axes[0, j].set_title(k)
        axes[0, j].set_ylabel("coverage")
        axes[0, j].legend(fontsize=7)
        b = [c["summary"][k]["bias"] for c in cells]
        be = [c["summary"][k]["bias_se"] for c in cells]
        axes[1, j].errorbar(x, b, yerr=be, fmt="s")
        axes[1, j].axhline(0, color="k", lw=0.5)
        axes[1, j].set_ylabel("bias (median - truth)")
        axes[2, j].plot(x, [c["summary"][k]["width68_mean"] for c in cells], "o-", label="68%")
        axes[2, j].plot(x, [c["summary"][k]["width95_mean"] for c in cells], "s-", label="95%")
        axes[2, j].set_yscale("log")
        axes[2, j].set_ylabel("mean interval width")
        axes[2, j].legend(fontsize=7)
        for i in range(3):
            axes[i, j].set_xticks(x, labels, fontsize=7)
    fig.tight_layout()
    atomic_savefig(fig, os.path.join(out, "recovery.png"), dpi=90)
    plt.close(fig)


# ----------------------------------------------------------------------------- inversion
def _inversion_model(args):
    """The data (masked) and the scene's model for them, at a point detector."""

    sc = scene_mod.load(args.scene)
    data = masked_rows(load_data(args.data), args.near_specular_deg, args.exclude)
    model = scene_for_data(sc, data).build()
    if isinstance(model, DetectorAperture):
        print(
            f"note: the inversion (seed 000 Sec. 4) assumes a point detector; the "
            f"{math.degrees(model.aperture):g} deg aperture is not deconvolved"
        )
        model = model.model
    return data, model


def _print_inversion(study):
    curve, boot = study.curve, study.bootstrap
    lo, hi = boot["normalization_p2.5_p97.5"]
    p16, _, p84 = boot["normalization_p16_p50_p84"]
    print(f"{len(study.inversion.p3)} rows; probed slopes 0-{curve.zeta_max:.3f}")
    print(
        f"normalization over the probed range (Eq. 33): {curve.normalization:.6f} "
        f"(interpolation error estimate {curve.interpolation_error:.2g}); "
        f"bootstrap 68%: {p16:.4f}-{p84:.4f}, 95%: {lo:.4f}-{hi:.4f} ({boot['replicates']} replicates)"
    )
    print(
        f"unmeasured tail beyond zeta_max (log-linear extrapolation): {curve.tail:.3g}; the paper's 0.77 is for its measured sample"
    )
    for g, r in study.collapse.items():
        print(f"  rms ln(P3 / common curve), {g}: {r:.4f}")


def _cmd_inversion(args) -> int:
    import matplotlib  # matplotlib (heavy): loaded only where a figure is drawn

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib (heavy): loaded only where a figure is drawn

    _check_out(args.out, args.force)
    with locked_out(args):  # held from the check of --out to the swap of the new folder
        return _inversion(args, plt)


def _inversion(args, plt) -> int:
    data, model = _inversion_model(args)
    try:
        study = inversion_study(model, data, bins=args.bins, n_bootstrap=args.bootstrap, seed=args.seed)
    except ValueError as exc:  # too few distinct slopes for the curve, a model it cannot invert
        raise UsageError(f"{args.data}: {exc}") from exc
    with replacing_folder(args.out, {"inversion.json", "inversion.png"}.__contains__, lock=False) as out:
        atomic_write_json(
            os.path.join(out, "inversion.json"), {"data": args.data, "scene": args.scene, **study.as_dict()}
        )
        fig = inversion_figure(study, model)
        atomic_savefig(fig, os.path.join(out, "inversion.png"), dpi=90)
        plt.close(fig)
    _print_inversion(study)
    print(f"wrote {args.out}/inversion.json, inversion.png")
    return 0


# ----------------------------------------------------------------------------- compare
def _compare_likelihoods(args):
    """One likelihood per ``--scene`` on the data, named by the scene file."""

    data = load_data(args.data)
    liks, names = [], []
    for path in args.scene:
        sc = scene_mod.load(path)
        spec = fitspec_from(sc, None, args.noise, args.near_specular_deg, args.exclude)
        liks.append(Likelihood(sc, spec, data))
        names.append(os.path.basename(path))
    return liks, names


def _cmd_compare(args) -> int:
    _check_out(args.out, args.force)
    with locked_out(args):  # held from the check of --out to the swap of the new folder
        return _compare(args)


def _compare(args) -> int:
    _check_executor(args)
    settings = _chain_settings(args)
    liks, names = _compare_likelihoods(args)
    try:
        check_comparable(liks, names)
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    for lik in liks:
        _require_walkers(settings, len(lik.spec.free))
    for nm, lik in zip(names, liks, strict=True):
        print(
            f"{nm}: {len(lik.spec.free)} free ({', '.join(lik.spec.names)}); likelihood terms: {', '.join(lik.terms)}"
        )
    with _open_executor(args) as ex:
        rows, _ = compare_fits(liks, names, settings, executor=ex)
    with replacing_folder(args.out, {"compare.json"}.__contains__, lock=False) as out:
        atomic_write_json(
            os.path.join(out, "compare.json"), {"data": args.data, "scenes": args.scene, "rows": rows}
        )
    print(format_comparison(rows))
    for r in rows:
        print(f"  {r['scene']}: {r['stop_reason']}; acceptance {r['acceptance']:.3f}")
    print(f"wrote {args.out}/compare.json")
    return 0


def register(sub):
    p = sub.add_parser("study", help="studies: recovery, inversion, compare, ptfe (real data)")
    ss = p.add_subparsers(dest="study", required=True)

    r = ss.add_parser("recovery", help="injection-recovery coverage, bias and width")
    r.add_argument("data", help="data file whose geometries and incident states the injections use")
    _spec_args(r)
    r.add_argument(
        "--noise-levels",
        type=positive_floats,
        default=[0.05],
        help="fractional BRDF noise levels (> 0), comma separated",
    )
    r.add_argument(
        "--n-geometries",
        type=ints_at_least(1),
        default=None,
        help="numbers of geometries (evenly spread subsets, >= 1), comma separated; default: every row",
    )
    r.add_argument("--injections", type=int, default=50, help="injections per cell, >= 1")
    r.add_argument("--out", required=True)
    r.add_argument("--force", action="store_true")
    r.add_argument("--no-progress", action="store_true")
    _mcmc_args(r, walkers=16, max_steps=2000)
    _executor_args(r)
    r.set_defaults(func=_cmd_recovery)

    v = ss.add_parser("inversion", help="slope distribution P3 from measured BRDF (seed 000 Fig. 4)")
    v.add_argument("data")
    v.add_argument("--scene", required=True, help="scene with a single facet mechanism")
    v.add_argument(
        "--bins",
        type=int_at_least(4),
        default=None,
        help="bin ln P3 in |zeta| (noisy data; >= 4 bins, the curve's knots); default: every slope",
    )
    v.add_argument("--bootstrap", type=int_at_least(1), default=200, help="bootstrap replicates, >= 1")
    v.add_argument("--seed", type=int_at_least(0), default=0)
    v.add_argument("--near-specular-deg", type=float, default=None)
    v.add_argument("--exclude", action="append", default=None)
    v.add_argument("--out", required=True)
    v.add_argument("--force", action="store_true")
    v.set_defaults(func=_cmd_inversion)

    c = ss.add_parser("compare", help="fit several scenes to the same data; information criteria")
    c.add_argument("data")
    c.add_argument("--scene", action="append", required=True, help="scene with a [fit] table (repeat)")
    c.add_argument("--noise", action="append", default=None)
    c.add_argument("--near-specular-deg", type=float, default=None)
    c.add_argument("--exclude", action="append", default=None)
    c.add_argument("--out", required=True)
    c.add_argument("--force", action="store_true")
    _mcmc_args(c)
    _executor_args(c)
    c.set_defaults(func=_cmd_compare)

    register_ptfe(ss)
