"""The joint fit of a physical PTFE model over all of NIST's data (7296 rows, 4 wavelengths, 16
elements) toward N >= 50 tau: wall time, likelihood evaluations per second, and where a batch's
time goes.

    python benchmarks/ptfe_joint_fit.py [--scene FILE] [--walkers W] [--max-steps N]
                                        [--threads T] [--seed S] [--moves de|stretch] [--burn B]

Default scene: ``references/scenes/ptfe_rough_diffuse_joint.toml`` (facets + totally diffuse
subsurface under the rough interface, by quadrature; 11 free parameters: roughness, albedo per
wavelength, a Cauchy index, calibration, incidence offset, two noise levels): the best physical
model of the joint comparison (docs/guide/ptfe.md, "`rough_diffuse` jointly"), the fit issue
29's 120 s is about.  ``--scene references/scenes/ptfe_smooth_diffuse_joint.toml``: the
smooth-interface model, the figures of the sessions before.

The run is ``run_fit`` (optimum, then emcee, every walker of a step in one call) with a step
budget; the script prints the chain's own evaluations per second, the autocorrelation time it
reached (per parameter too, with each one's largest correlation) and, when the budget ends
before N >= 50 tau, the time 50 tau would take at the measured rate.  It prints the load average before and after: on a shared machine the figures scale with
the share of the cores this process got.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import emcee
import numba
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

from scatterbench.models import scene as scene_mod  # noqa: E402
from scatterbench.references import nist_ptfe_path  # noqa: E402
from scatterbench.validation.fitting.fit import run_fit  # noqa: E402
from scatterbench.validation.fitting.mueller_data import load_mueller_data  # noqa: E402
from scatterbench.validation.fitting.mueller_fit import mueller_likelihood  # noqa: E402
from scatterbench.validation.fitting.mueller_kernel import loglike_rows  # noqa: E402
from scatterbench.validation.fitting.sampling import _default_start, at_bounds  # noqa: E402
from scatterbench.validation.fitting.settings import ChainSettings  # noqa: E402


def _best(f, n=5):
    times = []
    for _ in range(n):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return min(times)


def _breakdown(lik, walkers):
    """Seconds per batch of ``walkers``: the model's 16 elements, the fused likelihood, the whole
    (at repeated positions, and at new ones as in a chain)."""
    u0 = _default_start(lik, lik.spec.u_bounds())
    rng = np.random.default_rng(0)
    U = u0 + 1e-3 * rng.standard_normal((walkers, len(u0)))
    lik.batch(U)  # compile / warm
    M = np.ascontiguousarray(lik.predict_psps(U, lik.rows))
    c, _, _ = lik.nuisance(U)
    s2 = np.full((len(lik.elements), walkers), 1e-2)
    out = np.empty((walkers, len(lik.data)))
    return {
        "model": _best(lambda: lik.predict_psps(U, lik.rows)),
        "likelihood kernel": _best(
            lambda: loglike_rows(M, *lik._packed, c[:, 0].copy(), s2, lik._errvar, out)
        ),
        "batch (log posterior)": _best(lambda: lik.batch(U)),
        # as in a chain: every walker's index new at every wavelength, so R-bar's quadrature
        # runs (the batch above repeats positions whose R-bar is cached)
        "batch, new positions": _best(lambda: lik.batch(U + 1e-6 * rng.standard_normal(U.shape))),
        # the route before the range-by-range one (mueller_kernel.loglike_terms): the model's
        # (16, walkers, rows) elements first, then the likelihood; the same bits
        "same, elements first": _best(lambda: _elements_first(lik, U + 1e-6 * rng.standard_normal(U.shape))),
    }


def _elements_first(lik, U):
    lik._unit_terms = lambda U: None
    try:
        return lik.batch(U)
    finally:
        del lik._unit_terms


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default=os.path.join(ROOT, "references/scenes/ptfe_rough_diffuse_joint.toml"))
    ap.add_argument("--walkers", type=int, default=24)
    ap.add_argument("--max-steps", type=int, default=20000)
    ap.add_argument("--threads", type=int, default=numba.config.NUMBA_NUM_THREADS, help="numba threads")
    ap.add_argument("--seed", type=int, default=0)
    # de by default: converged on this scene at tau 191.5 steps (N = 9600), the stretch move at
    # 334.5 (N = 16800), both seed 0 (the closing notes of 2026-11-29)
    ap.add_argument(
        "--moves", default="de", choices=("de", "stretch"), help="emcee's proposal (ChainSettings.moves)"
    )
    ap.add_argument(
        "--burn",
        type=int,
        default=0,
        help="steps run and discarded before the kept chain (ChainSettings.burn)",
    )
    args = ap.parse_args(argv)
    numba.set_num_threads(args.threads)
    print(
        f"load average before: {os.getloadavg()}; cores {os.cpu_count()}; numba threads {args.threads}; "
        f"moves {args.moves}"
    )
    t0 = time.perf_counter()
    data = load_mueller_data(nist_ptfe_path())
    lik = mueller_likelihood(scene_mod.load(args.scene), data)
    print(
        f"{args.scene}: {len(lik.data)} rows x {len(lik.elements)} elements, {len(lik.spec.free)} free parameters"
    )
    for k, v in _breakdown(lik, args.walkers).items():
        print(f"  {k:<24} {v * 1e3:8.1f} ms per batch of {args.walkers} walkers")
    settings = ChainSettings(
        walkers=args.walkers,
        seed=args.seed,
        max_steps=args.max_steps,
        check_every=100,
        tau_factor=50,
        starts=1,
        moves=args.moves,
        burn=args.burn,
    )
    fit = run_fit(lik, settings)
    wall = time.perf_counter() - t0
    ch = fit.chain
    tau = float(np.nanmax(ch.tau))
    rate = ch.evaluations / ch.seconds
    print(ch.stop_reason)
    print(f"steps {ch.steps}, tau (max) {tau:.1f} steps, N / tau {ch.steps / tau:.1f}")
    print(f"evaluations per second (walker log posteriors): {rate:.0f}")
    print(
        "tau per parameter (steps), each one's largest correlation with another, and the fraction"
        " of the kept samples within 1% of a bound (at_bound; ~0.02 for a flat posterior):"
    )
    kept = ch.samples()
    corr = np.corrcoef(kept.T)
    np.fill_diagonal(corr, 0.0)
    near = at_bounds(kept, lik.spec.u_bounds())
    for k, name in enumerate(lik.spec.names):
        j = int(np.argmax(np.abs(corr[k])))
        print(
            f"  {name:<28} {ch.tau[k]:8.1f}   r = {corr[k, j]:+.2f} with {lik.spec.names[j]:<28}"
            f" at_bound {near[k]:.2f}"
        )
    # the start-up transient: tau estimated as the convergence rule does, on the chain without
    # its first tenth and half (a stationary chain's estimate barely moves)
    for frac in (0.1, 0.5):
        t = emcee.autocorr.integrated_time(ch.chain[int(frac * ch.steps) :], c=5, tol=0, quiet=True)
        print(f"tau (max) without the chain's first {frac:.0%}: {np.max(t):.1f} steps")
    burned = fit.summary["sampling"]["burned_before_chain"]
    print(
        f"sampling {ch.seconds + burned['seconds']:.1f} s ({burned['steps']} burn-in steps"
        f" {burned['seconds']:.1f} s, then the kept chain {ch.seconds:.1f} s); wall time (load,"
        f" optimum, chain) {wall:.1f} s"
    )
    if not ch.converged and np.isfinite(tau):
        need = burned["seconds"] + 50 * tau * args.walkers / rate
        print(f"at this rate, N = 50 tau = {50 * tau:.0f} steps would take {need:.0f} s of sampling")
    print(f"load average after: {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
