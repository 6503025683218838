"""The report's sections, each computed by the run (nothing typed in)."""

from __future__ import annotations

import math
import os
import platform
import sys
import time
from importlib import metadata

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import models  # noqa: E402
import references  # noqa: E402
from models.geometry import signed_inplane  # noqa: E402
from validation.checks import table1  # noqa: E402
from validation.checks.registry import check_record, registered, run_checks  # noqa: E402
from validation.numerics.integrate import integrated_reflectance  # noqa: E402
from validation.numerics.reciprocity import reciprocity_error, reversed_mueller  # noqa: E402

from .core import Section, checks_block, figure_block, table_block, text_block  # noqa: E402

__all__ = ["SECTION_FUNCS", "report_checks"]

AL = 1.37 + 7.62j


def report_checks(ctx):
    """The records of the checks this report judges: ``ctx.cache["check_specs"]`` if set,
    else every registered check for ``ctx.quick`` (the set ``validate`` runs).  Each runs
    once per context, sharing its computations with the sections that draw them."""
    specs = ctx.cache.get("check_specs")
    return [check_record(r) for r in run_checks(registered(ctx.quick) if specs is None else specs, ctx)]


def section_summary(ctx):
    s = Section("summary", "Summary: every check")
    checks = report_checks(ctx) + ctx.cache.get("section_failures", [])
    prev = (ctx.previous or {}).get("checks")
    s.blocks.append(
        text_block(
            "Each check: the value this run measured, the limit it is held to, the status (FINDING marks a "
            "property of a paper that the run established, not an implementation failure; each finding says "
            "under which condition it would fail instead) and the change since the previous report. The "
            "same checks, with the same settings, are run by `scatterbench validate` "
            f"{'--quick ' if ctx.quick else ''}and the test suite."
        )
    )
    if ctx.quick and "check_specs" not in ctx.cache:
        skipped = [spec.id for spec in registered() if spec.slow]
        s.blocks.append(
            text_block(
                "Quick run: these slow checks were not run (the full report and `scatterbench validate` run them): "
                + ", ".join(skipped)
            )
        )
    s.blocks.append(checks_block(checks, prev))
    s.checks = checks
    return s


def section_table1(ctx):
    s = Section("table1", "Seed 000 Table I: paper, scatterbench, SCATMECH")
    computed, seconds = ctx.compute(table1.compute_table1)  # the Table I check's computation
    rows = [r.as_dict() for r in computed]
    out = []
    for r in rows:
        key = f"{r['substrate']}|{r['coating']:g}|{r['sigma']:g}"
        out.append(
            {
                "substrate": r["substrate"],
                "coating": r["coating"],
                "sigma": r["sigma"],
                "paper": r["printed"],
                "scatterbench": r["computed"],
                "integration error": r["error"],
                "independent": r["independent"],
                "independent method": "SCATMECH slope integral" if r["sigma"] > 0 else "sigma -> 0 integral",
                "within rounding": "yes" if r["within_rounding"] else "NO",
            }
        )
        s.tracked[f"table1|{key}"] = {"value": r["computed"], "tol": max(2e-4, 2 * r["error"])}
    s.blocks.append(
        text_block(
            f"{len(rows)} integrals (theta_i = {math.degrees(table1.THETA_I):g} deg, unpolarized, exponential "
            f"slopes) computed in {seconds:.2f} s at tolerance {table1.TOL:g}. The flat column is the closed form; "
            f"its independent value is the model's integral at sigma = {table1.LIMIT_SIGMA:g}. Rough entries are compared with SCATMECH's model integrated over facet slopes "
            "(references/data/table1_scatmech.csv)."
        )
    )
    cols = [
        "substrate",
        "coating",
        "sigma",
        "paper",
        "scatterbench",
        "integration error",
        "independent",
        "independent method",
        "within rounding",
    ]
    s.blocks.append(
        table_block(
            s,
            "table1",
            cols,
            out,
            fmt={
                "scatterbench": ".4f",
                "independent": ".4f",
                "paper": ".2f",
                "coating": ".1f",
                "sigma": ".1f",
                "integration error": ".1e",
            },
        )
    )
    bad = [r for r in rows if not r["within_rounding"]]
    if bad:
        s.blocks.append(
            text_block(
                "Entries outside the printed rounding:\n"
                + "\n".join(
                    f"* {r['substrate']}, n = {r['coating']:g}, sigma = {r['sigma']:g}: {r['verdict']}"
                    for r in bad
                )
            )
        )
    return s


def _inplane(model, theta_i, x_deg, incident="unpolarized"):
    return model.polarization(theta_i, *signed_inplane(np.radians(x_deg)), incident=incident)


def section_seed000(ctx):
    s = Section("seed000", "Seed 000 Fig. 2 and Fig. 3 reproduced")
    ti = math.radians(60)
    x = np.linspace(-89, 89, 179 if ctx.quick else 713)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    rows = []
    for ax, sigma in zip(axes, (0.1, 0.2), strict=True):
        for n, style in ((1.0, "-"), (1.5, "--"), (2.0, ":")):
            m = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(sigma), coating=n, substrate=AL)
            f = _inplane(m, ti, x)["brdf"]
            ax.semilogy(x, np.maximum(f, 1e-10), style, label=f"n = {n:g}")
            r = integrated_reflectance(m, ti, tol=1e-4)
            rows.append(
                {
                    "sigma": sigma,
                    "coating": n,
                    "BRDF at specular": float(m.brdf(ti, ti, 0.0)),
                    "BRDF at theta_r = 0": float(m.brdf(ti, 0.0, 0.0)),
                    "integrated reflectance": r.value,
                }
            )
            s.tracked[f"fig2|{sigma:g}|{n:g}|specular"] = {
                "value": rows[-1]["BRDF at specular"],
                "tol": 1e-9 * rows[-1]["BRDF at specular"],
            }
        ax.set_title(f"aluminium, exponential slopes sigma = {sigma:g}")
        ax.set_xlabel("scattering angle theta_r (deg, negative = incidence side)")
        ax.legend()
    axes[0].set_ylabel("BRDF (1/sr)")
    fig.tight_layout()
    s.blocks.append(
        figure_block(
            fig, "Fig. 2: BRDF for unpolarized light at theta_i = 60 deg, coatings 1.0, 1.5, 2.0 on aluminium"
        )
    )
    s.blocks.append(
        table_block(
            s,
            "fig2",
            ["sigma", "coating", "BRDF at specular", "BRDF at theta_r = 0", "integrated reflectance"],
            rows,
        )
    )
    # Fig. 3: polarization for light polarized at 45 deg; aluminium under n = 1.5 versus an exposed polymer.
    coated = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.2), coating=1.5, substrate=AL)
    polymer = models.FacetBRDF(slopes=models.ExponentialSlopes(0.2), substrate=1.5)
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 8), sharex=True)
    rows = []
    for model, label, style in (
        (coated, "aluminium under n = 1.5 coating", "-"),
        (polymer, "exposed polymer (n = 1.5)", "--"),
    ):
        p = _inplane(model, ti, x, incident="linear:45")
        axes[0].plot(x, np.degrees(p["eta"]), style, label=label)
        axes[1].plot(x, p["P"], style, label=label)
        axes[2].plot(x, p["P_C"], style, label=label)
        q = _inplane(model, ti, np.array([-30.0, 0.0, 30.0, 75.0]), incident="linear:45")
        for k, ang in enumerate((-30.0, 0.0, 30.0, 75.0)):
            rows.append(
                {
                    "model": label,
                    "theta_r (signed, deg)": ang,
                    "eta (deg)": float(np.degrees(q["eta"][k])),
                    "P": float(q["P"][k]),
                    "P_C": float(q["P_C"][k]),
                }
            )
    axes[0].set_ylabel("eta (deg)")
    axes[1].set_ylabel("P")
    axes[2].set_ylabel("P_C")
    axes[2].set_xlabel("scattering angle theta_r (deg)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    s.blocks.append(
        figure_block(
            fig,
            "Fig. 3 style: principal angle eta, degree of polarization P and of circular polarization P_C for incident light polarized at 45 deg (theta_i = 60 deg, sigma = 0.2)",
        )
    )
    s.blocks.append(table_block(s, "fig3", ["model", "theta_r (signed, deg)", "eta (deg)", "P", "P_C"], rows))
    return s


def _default_models():
    """One instance per model class: its defaults, or the stability sweep's
    representative base (the point-source wrapper around Cook-Torrance, the Monte
    Carlo model at 200 pairs)."""
    from validation.studies.stability import _BASES

    out = []
    for cls in models.Model.registry:
        if cls is models.Sum:
            continue
        try:
            out.append(_BASES[cls.__name__]() if cls.__name__ in _BASES else cls())
        except ValueError:
            continue
    return out


def _is_heavy(m):
    """Monte Carlo models and wrappers: hundreds of inner evaluations per geometry."""
    return hasattr(m, "pairs") or isinstance(getattr(m, "model", None), models.Model)


def section_conservation(ctx):
    s = Section("conservation", "Conservation: reciprocity and albedo")
    every = _default_models()
    ms = [m for m in every if not _is_heavy(m) and m.reciprocal]
    skipped = [type(m).__name__ for m in every if m not in ms]
    s.blocks.append(
        text_block(
            "Deterministic reciprocal models at their defaults. Not mapped here: "
            + ", ".join(skipped)
            + " (the Monte Carlo model is reciprocal and energy-bounded only within its standard error, "
            "tested statistically with the model; the point-source wrapper is not reciprocal by construction "
            "and its albedo is a weighted mean of its inner model's)."
        )
    )
    t = np.radians(np.linspace(0.5, 88.5, 30 if ctx.quick else 60))
    fig, axes = plt.subplots(1, len(ms), figsize=(4.2 * len(ms), 3.6), squeeze=False)
    rows = []
    for ax, m in zip(axes[0], ms, strict=True):
        TI, TR = np.meshgrid(t, t, indexing="ij")
        fwd = m.brdf(TI, TR, 0.7)
        rev = reversed_mueller(m, TI, TR, 0.7)[..., 0, 0]  # the reversed path, rotated sample if anisotropic
        scale = np.maximum(np.abs(fwd), np.abs(rev))
        err = np.where(scale > 0, np.abs(fwd - rev) / np.where(scale > 0, scale, 1), 0.0)
        im = ax.imshow(
            np.log10(err + 1e-17),
            origin="lower",
            extent=[0.5, 88.5, 0.5, 88.5],
            vmin=-17,
            vmax=-6,
            aspect="auto",
        )
        ax.set_title(f"{type(m).__name__}", fontsize=9)
        ax.set_xlabel("theta_r (deg)")
        ax.set_ylabel("theta_i (deg)")
        fig.colorbar(im, ax=ax, label="log10 rel. error")
        r = reciprocity_error(m, TI.ravel()[::7], TR.ravel()[::7], np.full(TI.size, 0.7)[::7])
        rows.append({"model": type(m).__name__, "scalar": r.scalar, "Mueller": r.mueller, "Jones": r.jones})
    fig.tight_layout()
    s.blocks.append(
        figure_block(
            fig, "Reciprocity error maps: |f(i->r) - f(r->i)| / f at phi_r = 0.7 rad, default parameters"
        )
    )
    s.blocks.append(
        table_block(
            s,
            "reciprocity",
            ["model", "scalar", "Mueller", "Jones"],
            rows,
            fmt={"scalar": ".2e", "Mueller": ".2e", "Jones": ".2e"},
        )
    )
    tis = np.radians(np.linspace(0, 85, 6 if ctx.quick else 18))
    fig, ax = plt.subplots(figsize=(7, 4))
    rows = []
    for m in ms:
        if m.transmission:
            continue
        vals = [integrated_reflectance(m, float(a), tol=1e-4).value for a in tis]
        ax.plot(np.degrees(tis), vals, "o-", label=type(m).__name__)
        for a, v in zip(tis, vals, strict=True):
            rows.append({"model": type(m).__name__, "theta_i (deg)": float(np.degrees(a)), "albedo": v})
    ax.axhline(1.0, color="k", lw=0.6)
    ax.set_xlabel("theta_i (deg)")
    ax.set_ylabel("integrated reflectance")
    ax.legend(fontsize=8)
    fig.tight_layout()
    s.blocks.append(
        figure_block(
            fig, "Albedo (hemispherical integral, tol 1e-4) versus theta_i for each model at its defaults"
        )
    )
    s.blocks.append(table_block(s, "albedo", ["model", "theta_i (deg)", "albedo"], rows))
    return s


def section_scatmech(ctx):
    from validation.checks.seed000 import scatmech_facet_errors
    from validation.checks.seed003 import scatmech_error_distributions

    s = Section("scatmech", "Agreement with SCATMECH")
    errs = {f"{k} (committed)": v for k, v in scatmech_facet_errors().items()}
    errs.update(scatmech_error_distributions())
    fig, ax = plt.subplots(figsize=(7, 4))
    rows = []
    for label, e in errs.items():
        e = np.asarray(e, dtype=float)
        ax.hist(np.log10(np.maximum(e, 1e-18)), bins=40, histtype="step", label=label)
        rows.append(
            {"model": label, "cases": int(e.size), "median": float(np.median(e)), "max": float(e.max())}
        )
    try:
        from pySCATMECH.brdf import BRDF_Model  # noqa: F401

        live = _live_scatmech(ctx)
        rows.append(
            {
                "model": "SubsurfaceFacetBRDF (live pySCATMECH)",
                "cases": live.size,
                "median": float(np.median(live)),
                "max": float(live.max()),
            }
        )
    except ImportError:
        s.blocks.append(
            text_block("pySCATMECH is not installed on this machine: no live comparison in this run.")
        )
    ax.set_xlabel("log10 max |M - M_scatmech| / M00 per case")
    ax.set_ylabel("cases")
    ax.legend(fontsize=8)
    fig.tight_layout()
    s.blocks.append(figure_block(fig, "Error distributions against SCATMECH reference values"))
    s.blocks.append(
        table_block(
            s, "scatmech", ["model", "cases", "median", "max"], rows, fmt={"median": ".2e", "max": ".2e"}
        )
    )
    return s


def _live_scatmech(ctx):
    from pySCATMECH.brdf import BRDF_Model

    rng = np.random.default_rng(ctx.seed)
    out = []
    for _ in range(5 if ctx.quick else 20):
        coat = float(rng.uniform(1.0, 2.2))
        sigma = float(rng.uniform(0.05, 1.0))
        ours = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(sigma), coating=coat, substrate=AL)
        ref = BRDF_Model(
            "Subsurface_Facet_BRDF_Model",
            substrate="(1.37,7.62)",
            overcoat=f"({coat!r},0)",
            sdf="Exponential_Slope_Distribution_Function",
            **{"sdf.s": sigma},
        )
        for _ in range(10):
            ti, tr = rng.uniform(0, 1.4, 2)
            pr = rng.uniform(-3, 3)
            R = np.array(ref.MuellerBRDF(ti, tr, pr))
            out.append(float(np.max(np.abs(ours.mueller(ti, tr, pr) - R)) / max(R[0, 0], 1e-300)))
    return np.array(out)


def section_speed(ctx):
    from validation.studies.tradeoff import pareto, study

    s = Section("speed", "Speed and accuracy")
    results = study(quick=ctx.quick)
    fig, axes = plt.subplots(1, len(results), figsize=(5.5 * len(results), 4), squeeze=False)
    for ax, r in zip(axes[0], results, strict=True):
        ax.loglog([p.seconds for p in r.points], [max(p.error, 1e-18) for p in r.points], "o-")
        for p in r.points:
            ax.annotate(f"{p.setting:g}", (p.seconds, max(p.error, 1e-18)), fontsize=7)
        ax.set_title(r.knob)
        ax.set_xlabel("cost (s)")
        ax.set_ylabel("error vs independent reference")
        rows = [
            {"setting": p.setting, "error": p.error, "seconds": p.seconds, "evaluations": p.evaluations}
            for p in pareto(r.points)
        ]
        s.blocks.append(
            table_block(
                s,
                f"pareto|{r.knob}",
                ["setting", "error", "seconds", "evaluations"],
                rows,
                caption=f"Pareto front: {r.knob} ({r.reference})",
            )
        )
    fig.tight_layout()
    s.blocks.insert(0, figure_block(fig, "Measured error versus cost for each accuracy knob"))
    n = 20_000 if ctx.quick else 200_000
    rng = np.random.default_rng(ctx.seed)
    ti, tr = rng.uniform(0, 1.45, (2, n))
    pr = rng.uniform(-math.pi, math.pi, n)
    rows = []
    quoted = {"FacetBRDF": 0.5, "SubsurfaceFacetBRDF": 5.2}
    for m in _default_models():
        k = 200 if _is_heavy(m) else n  # per-geometry cost is what is compared
        best = math.inf
        for _ in range(3):
            t0 = time.perf_counter()
            m.mueller(ti[:k], tr[:k], pr[:k])
            best = min(best, time.perf_counter() - t0)
        us = best / k * 1e6
        q = quoted.get(type(m).__name__)
        rows.append(
            {
                "model": type(m).__name__,
                "us per geometry (mueller)": us,
                "compiled SCATMECH us (quoted, DESIGN.md)": q,
                "ratio": (q / us) if q else None,
            }
        )
    s.blocks.append(
        table_block(
            s,
            "throughput",
            ["model", "us per geometry (mueller)", "compiled SCATMECH us (quoted, DESIGN.md)", "ratio"],
            rows,
            caption=f"throughput over {n} random geometries, best of 3, one process",
        )
    )
    return s


def section_stability(ctx):
    from validation.checks.stability import sweep_findings
    from validation.studies.stability import classify

    s = Section("stability", "Stability sweep at the extremes")
    found = sweep_findings(ctx)  # the stability check's sweep, run once
    if ctx.quick:
        s.blocks.append(
            text_block(
                "Quick run: the energy integrals of the sweep are skipped (the full report runs them)."
            )
        )
    ok, bad = classify(found)
    rows = [
        {
            "model": f.model,
            "kind": f.kind,
            "value": f.value,
            "where": f.where,
            "accepted": "yes" if r else "NO",
            "reason": r or "",
        }
        for f, r in ok + bad
    ]
    s.blocks.append(
        text_block(
            f"{len(found)} findings: {len(ok)} accepted (each with its reason), {len(bad)} unaccepted."
        )
    )
    s.blocks.append(
        table_block(s, "stability", ["model", "kind", "value", "where", "accepted", "reason"], rows)
    )
    return s


def _git_commit():
    from .provenance import git_commit

    return git_commit()


def section_scenes(ctx):
    from models import scene as scene_mod

    s = Section("scenes", "Scenes and the mechanisms they build")
    rows = []
    paths = list(references.scene_paths()) + list(ctx.cache.get("extra_scenes", []))
    fig, ax = plt.subplots(figsize=(7.5, 4))
    for path in paths:
        try:
            sc = scene_mod.load(path)
            mech = sc.mechanisms()
        except ValueError as exc:
            rows.append(
                {
                    "scene": os.path.basename(path),
                    "mechanisms": "",
                    "why": f"error: {exc}",
                    "source and detector": "",
                }
            )
            continue
        rows.append(
            {
                "scene": sc.name,
                "mechanisms": ", ".join(f"{m.name} ({type(m.model).__name__})" for m in mech),
                "why": "; ".join(m.why for m in mech),
                "source and detector": f"{sc.source_decision()}; {sc.aperture_decision()}" if mech else "",
            }
        )
        if mech:
            x = np.linspace(-89, 89, 179)
            f = _inplane(sc.build(), sc.theta_i, x, incident=np.array(sc.polarization))["brdf"]
            ax.semilogy(x, np.maximum(f, 1e-10), label=sc.name)
    ax.set_xlabel("scattering angle theta_r (deg)")
    ax.set_ylabel("BRDF (1/sr)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    s.blocks.append(
        figure_block(
            fig,
            "In-plane BRDF of each example scene for its declared incident polarization (with its point source "
            "and detector aperture where they matter, as measured in the table)",
        )
    )
    s.blocks.append(table_block(s, "scenes", ["scene", "mechanisms", "why", "source and detector"], rows))
    return s


def section_provenance(ctx):
    s = Section("provenance", "Provenance")
    rows = []
    for pkg in ("scatterbench", "numpy", "scipy", "matplotlib", "emcee", "jinja2", "tqdm", "pyscatmech"):
        try:
            v = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            v = "not installed"
        rows.append({"item": pkg, "value": v})
    rows += [
        {"item": "python", "value": sys.version.split()[0]},
        {"item": "git commit", "value": _git_commit()},
        {
            "item": "machine",
            "value": f"{platform.machine()} {platform.processor() or ''} {os.cpu_count()} cores, {platform.system()} {platform.release()}",
        },
        {"item": "seed", "value": str(ctx.seed)},
        {
            "item": "reference data",
            "value": "; ".join(
                references.provenance(n).splitlines()[0]
                for n in ("scatmech_facet.csv", "table1_scatmech.csv")
            ),
        },
    ]
    s.blocks.append(table_block(s, "provenance", ["item", "value"], rows))
    times = ctx.cache.get("section_times", {})
    s.blocks.append(
        table_block(
            s,
            "section_times",
            ["section", "seconds"],
            [{"section": k, "seconds": v} for k, v in times.items()],
            caption="run time per section (this run)",
        )
    )
    return s


from .sections_compare import section_model_comparison  # noqa: E402  (issue 6 item 8)
from .sections_papers import (  # noqa: E402  (issue 7: the papers' figures, uncertainty)
    section_seed001,
    section_seed003_fig1,
    section_seed003_presets,
    section_uncertainty,
)

#: in page order; ``summary`` is computed last (it collects the others' checks)
SECTION_FUNCS = [
    section_summary,
    section_table1,
    section_seed000,
    section_conservation,
    section_scatmech,
    section_seed003_fig1,
    section_seed003_presets,
    section_seed001,
    section_uncertainty,
    section_model_comparison,
    section_speed,
    section_stability,
    section_scenes,
    section_provenance,
]
