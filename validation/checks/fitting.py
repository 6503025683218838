"""Cheap checks of the fitting machinery, run by ``scatterbench validate``.

* the slope inversion of noise-free synthetic data returns the input P3 and
  its normalization (seed 000 Sec. 4);
* a chain interrupted after its first checkpoint and resumed equals an
  uninterrupted one with the same seed, bit for bit.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import tempfile

import numpy as np

import models
import references
from models.geometry import signed_inplane

from .seed000 import Check

__all__ = ["CHECKS"]


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
    from validation.fitting.datafile import Dataset

    b = np.einsum("nij,nj->ni", model.mueller(g[:, 0], g[:, 1], g[:, 2]), inc)[:, 0]
    k = b > 0
    return Dataset("synthetic", g[k, 0], g[k, 1], g[k, 2], b[k], inc[k])


def check_inversion_round_trip():
    from validation.fitting.inversion import fit_curve, invert

    out = []
    for slopes in (models.ExponentialSlopes(0.1), models.GaussianSlopes(0.15, coverage=0.8)):
        m = models.SubsurfaceFacetBRDF(slopes=slopes, coating=1.5, substrate=1.37 + 7.62j)
        inv = invert(m, _synthetic(m))
        p3_err = float(np.max(np.abs(inv.p3 / slopes.p3(inv.zeta_x, inv.zeta_y) - 1)))
        curve = fit_curve(inv)
        n_err = abs(curve.normalization - slopes.coverage)
        worst = max(p3_err, n_err)
        out.append(
            Check(
                f"inversion: noise-free P3 and normalization ({type(slopes).__name__}, C={slopes.coverage:g})",
                worst,
                1e-6,
                "pass" if worst <= 1e-6 else "fail",
                f"max |P3 est/P3 - 1| = {p3_err:.1e}, |norm - C| = {n_err:.1e} (unmeasured tail {curve.tail:.1e})",
            )
        )
    return out


class _Crash:
    def __init__(self, f, after):
        self.f, self.after, self.calls = f, after, 0

    def __call__(self, u):
        self.calls += 1
        if self.calls > self.after:
            raise KeyboardInterrupt
        return self.f(u)


def check_resume_identity():
    from models import scene
    from validation.fitting.datafile import load_data
    from validation.fitting.fitspec import fitspec_from
    from validation.fitting.likelihood import Likelihood
    from validation.fitting.recovery import subsample
    from validation.fitting.sampling import ChainSettings, CheckpointBackend, initial_ball, run_chain

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
                run_chain(_Crash(lik, 6 + 6 * 15), st, p0=p0, backend=CheckpointBackend(ck, "x"))
            except KeyboardInterrupt:
                pass
        resumed = run_chain(lik, st, backend=CheckpointBackend.load(ck, "x"))
    diff = (
        float(np.max(np.abs(resumed.chain - full.chain)))
        if resumed.chain.shape == full.chain.shape
        else math.inf
    )
    return Check(
        "fit: interrupted + resumed chain equals uninterrupted (same seed)",
        diff,
        0.0,
        "pass" if diff == 0.0 else "fail",
        "6 walkers x 30 steps, interrupted in step ~15, resumed from the step-10 checkpoint",
    )


CHECKS = [check_inversion_round_trip, check_resume_identity]
