"""Checks of the fitting machinery and of the studies built on it.

* the slope inversion of noise-free synthetic data returns the input P3 and
  its normalization (seed 000 Sec. 4);
* a chain interrupted after its first checkpoint and resumed equals an
  uninterrupted one with the same seed, bit for bit;
* the injection-recovery coverage is nominal within binomial error;
* seed 003's model comparison prefers the generating hypothesis on each data set.

The recovery study and the model-comparison fits run once per run
(:meth:`~scatterbench.validation.checks.registry.CheckContext.compute`); the report's
uncertainty and model-comparison sections draw the same computation
(:func:`recovery_cells`, :func:`comparison_cases`) with the same settings.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import tempfile

import numpy as np

from scatterbench import models, references
from scatterbench.models import scene
from scatterbench.models import scene as scene_mod
from scatterbench.models.geometry import signed_inplane
from scatterbench.validation.fitting.compare import seed003_pairing
from scatterbench.validation.fitting.datafile import Dataset, load_data
from scatterbench.validation.fitting.fitspec import fitspec_from
from scatterbench.validation.fitting.inversion import fit_curve, invert
from scatterbench.validation.fitting.likelihood import Likelihood
from scatterbench.validation.fitting.recovery import recovery_study, subsample
from scatterbench.validation.fitting.sampling import (
    ChainSettings,
    CheckpointBackend,
    initial_ball,
    run_chain,
)

from .registry import check, judge

__all__ = [
    "recovery_settings",
    "recovery_cells",
    "comparison_settings",
    "comparison_cases",
    "comparison_margins",
    "RECOVERY_SCENE",
    "RECOVERY_DATA",
    "STRONG_DBIC",
]


def _synthetic(model):
    tr, pr = signed_inplane(np.radians(np.linspace(-89.0, 89.0, 357)))
    phi = np.radians(np.linspace(0.0, 180.0, 91))
    g = np.column_stack(
        [
            np.concatenate([np.full(tr.size, math.radians(60.0)), np.full(phi.size, math.radians(45.0))]),
            np.concatenate([tr, np.full(phi.size, math.radians(45.0))]),
            np.concatenate([pr, phi]),
        ]
    )
    inc = np.tile([1.0, 0.0, 1.0, 0.0], (len(g), 1))

    b = np.einsum("nij,nj->ni", model.mueller(g[:, 0], g[:, 1], g[:, 2]), inc)[:, 0]
    k = b > 0
    return Dataset("synthetic", g[k, 0], g[k, 1], g[k, 2], b[k], inc[k])


@check(paper="seed 000 Sec. 4 (slope distribution from the BRDF)")
def check_inversion_round_trip(ctx):

    out = []
    for slopes in (models.ExponentialSlopes(0.1), models.GaussianSlopes(0.15, coverage=0.8)):
        m = models.SubsurfaceFacetBRDF(slopes=slopes, coating=1.5, substrate=1.37 + 7.62j)
        inv = invert(m, _synthetic(m))
        p3_err = float(np.max(np.abs(inv.p3 / slopes.p3(inv.zeta_x, inv.zeta_y) - 1)))
        curve = fit_curve(inv)
        n_err = abs(curve.normalization - slopes.coverage)
        worst = max(p3_err, n_err)
        out.append(
            judge(
                f"inversion: noise-free P3 and normalization ({type(slopes).__name__}, C={slopes.coverage:g})",
                worst,
                1e-6,
                f"max |P3 est/P3 - 1| = {p3_err:.1e}, |norm - C| = {n_err:.1e} (unmeasured tail {curve.tail:.1e})",
            )
        )
    return out


class InterruptAfter:
    """A log-probability ``f`` that raises KeyboardInterrupt after ``after`` calls: a simulated
    Ctrl-C or kill in the middle of a chain (the resume check here and tests/test_fit.py)."""

    def __init__(self, f, after):
        self.f, self.after, self.calls = f, after, 0

    def __call__(self, u):
        self.calls += 1
        if self.calls > self.after:
            raise KeyboardInterrupt("simulated interruption")
        return self.f(u)


@check(paper="fitting machinery (emcee checkpoints)")
def check_resume_identity(ctx):

    sc = scene.load(
        os.path.join(os.path.dirname(references.__file__), "scenes", "aluminium_flakes_clearcoat.toml")
    )
    data = subsample(load_data(references.data_path("scatmech_flake_measurement.csv")), 20)
    lik = Likelihood(sc, fitspec_from(sc, ["sigma:0.01:1:log", "coating:1.2:2"], ["brdf=0.05"]), data)
    p0 = initial_ball(np.array([math.log(0.1), 1.5]), 6, 3, lik.spec.u_bounds())
    st = ChainSettings(walkers=6, seed=3, max_steps=30, check_every=10)
    with tempfile.TemporaryDirectory() as tmp:
        full = run_chain(lik, st, p0=p0, backend=CheckpointBackend(os.path.join(tmp, "a.npz"), "x"))
        ck = os.path.join(tmp, "b.npz")
        # emcee prints the interrupted call's traceback; keep validate's table clean
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            try:
                run_chain(InterruptAfter(lik, 6 + 6 * 15), st, p0=p0, backend=CheckpointBackend(ck, "x"))
            except KeyboardInterrupt:
                pass
        resumed = run_chain(lik, st, backend=CheckpointBackend.load(ck, "x"))
    diff = (
        float(np.max(np.abs(resumed.chain - full.chain)))
        if resumed.chain.shape == full.chain.shape
        else math.inf
    )
    return judge(
        "fit: interrupted + resumed chain equals uninterrupted (same seed)",
        diff,
        0.0,
        "6 walkers x 30 steps, interrupted in step ~15, resumed from the step-10 checkpoint",
    )


# ----------------------------------------------------------------------------- recovery coverage
#: the scene injected and refitted by the recovery study, and the file whose geometries it uses
RECOVERY_SCENE = "aluminium_flakes_clearcoat.toml"
RECOVERY_DATA = "scatmech_flake_measurement.csv"


def recovery_settings(quick, seed=0):
    """The recovery study's configuration (its chain a :class:`ChainSettings` with ``seed``):
    quick runs use that of tests/test_recovery.py."""

    if quick:
        return dict(
            free=["sigma:0.01:1:log"],
            noise=["brdf=0.1"],
            noise_levels=(0.1,),
            n_geometries=(8,),
            injections=50,
            chain=ChainSettings(walkers=4, seed=seed, max_steps=150, check_every=150, starts=1),
        )
    # Two correlated parameters, 16 walkers run to N > 50 tau, on the run's executor: the same study over 4
    # cells (8 and 32 geometries) took 1315 s on a loaded machine; the 8-geometry cells are the cheaper half.
    return dict(
        free=["sigma:0.01:1:log", "coating:1.2:2"],
        noise=["brdf=0.1"],
        noise_levels=(0.05, 0.1),
        n_geometries=(8,),
        injections=50,
        chain=ChainSettings(walkers=16, seed=seed, max_steps=4000, check_every=100, starts=1),
    )


def _recovery(quick, seed, executor=None):
    """The recovery study of the run, its members on ``executor`` (default: in-process)."""

    rs = recovery_settings(quick, seed)
    sc = scene_mod.load(os.path.join(os.path.dirname(references.__file__), "scenes", RECOVERY_SCENE))
    spec = fitspec_from(sc, rs["free"], rs["noise"])
    data = load_data(references.data_path(RECOVERY_DATA))
    return recovery_study(  # identical results on any executor (tested)
        sc,
        spec,
        data,
        rs["chain"],
        noise_levels=rs["noise_levels"],
        n_geometries=rs["n_geometries"],
        injections=rs["injections"],
        executor=executor,
    )


def recovery_cells(ctx):
    """The recovery study's cells (:func:`scatterbench.validation.fitting.recovery.recovery_study`) for the
    run's quick flag and seed, computed once per run on the run's executor."""
    return ctx.study(_recovery, ctx.quick, ctx.seed)


@check(paper="fitting machinery (interval coverage by injection-recovery)")
def check_recovery_coverage(ctx, cells=None):
    """``cells``: :func:`recovery_cells`."""
    cells = recovery_cells(ctx) if cells is None else cells
    worst_z = max(
        abs(v["coverage"][level]["z"]) for c in cells for v in c["summary"].values() for level in ("68", "95")
    )
    rs = recovery_settings(ctx.quick, ctx.seed)
    return judge(
        "uncertainty: recovery coverage within 3 binomial SE of nominal",
        worst_z,
        3.0,
        f"{len(cells)} cell(s) x {rs['injections']} injections ({'quick' if ctx.quick else 'full'})",
    )


# ----------------------------------------------------------------------------- model comparison
#: Kass & Raftery's "very strong" evidence: a BIC difference above 10
STRONG_DBIC = 10.0


#: independent chains per fit of the model comparison (validation/fitting/compare.py)
COMPARISON_CHAINS = 2


def comparison_settings(quick):
    """Seed 003's model comparison, ``dict(rows, settings, chains)``: quick runs use the configuration of
    tests/test_recovery.py (the same seed, so a test session fits it once)."""

    # Two independent chains per fit (the second seeded from the first's seed and its index): the
    # between-chain R-hat in the rows, and twice the tasks to keep the workers busy (16, not 8).
    if quick:
        return dict(
            rows=40,
            settings=ChainSettings(walkers=16, seed=3, max_steps=200, check_every=100, starts=3),
            chains=COMPARISON_CHAINS,
        )
    # Differential evolution: at 2000 steps the stretch move converged (N >= 50 tau) 0 of the
    # 8 chains (max tau 44-156), "de" 5 of 8 (by 800-1900 steps), measured 2026-11-24 by
    # `python benchmarks/fit_moves.py --max-steps 2000` (it prints both).
    # A burn-in of 1000 steps: the walkers' start-up counted in the whole chain's tau, and the
    # Maxwell-Beard hypothesis on the combination's polarized data (a misfit) ran one chain to
    # the 12000-step limit unconverged (tau 298.9, 69.4 s) where, after the burn-in, it converges
    # at 3100 kept steps (tau 62.0, 20.5 s with the burn-in): the comparison's longest chain
    # bounds it on many workers (`python benchmarks/comparison_chains.py`, 2026-11-29: 279.6 s
    # and 259.3 s for all 16 chains, the longest 69.4 s and 25.4 s).
    return dict(
        rows=None,
        settings=ChainSettings(
            walkers=24, seed=3, max_steps=12000, check_every=100, starts=4, moves="de", burn=1000
        ),
        chains=COMPARISON_CHAINS,
    )


def _comparison(quick, executor=None):
    """Seed 003's model comparison, its fits on ``executor`` (default: in-process); the full
    run's 8 fits of two chains: 86.4 s in-process, 42.2 s on 2 workers at 6e188bc (2 cores,
    ``python benchmarks/study_workers.py --study comparison --workers 2 1``)."""
    return seed003_pairing(**comparison_settings(quick), executor=executor)  # same on any executor


def comparison_cases(ctx):
    """:func:`scatterbench.validation.fitting.compare.seed003_pairing` with the run's settings, once per
    run on the run's executor."""
    return ctx.study(_comparison, ctx.quick)


def comparison_margins(cases):
    """``[(generator, terms, margin)]``: by how much the generating hypothesis's BIC beats
    the best other hypothesis's, per data set and term choice (> 0: the generator wins)."""
    out = []
    for c in cases:
        gen = next(r for r in c["rows"] if r["scene"] == c["generator"])
        other = min(r["dBIC"] for r in c["rows"] if r["scene"] != c["generator"])
        out.append((c["generator"], c["terms"], other - gen["dBIC"]))
    return out


@check(paper="seed 003 Sec. 4 (the combination against Maxwell-Beard)")
def check_model_comparison(ctx, cases=None):
    """``cases``: :func:`comparison_cases`."""
    margins = comparison_margins(comparison_cases(ctx) if cases is None else cases)
    return judge(
        "model comparison: the generating hypothesis wins by dBIC > 10 on each SCATMECH data set",
        min(m for *_, m in margins),
        STRONG_DBIC,
        "dBIC margin of the generator: " + "; ".join(f"{g} data, {t}: {m:.0f}" for g, t, m in margins),
        op=">",
    )
