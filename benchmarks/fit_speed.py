"""Measure the issue's performance case: a 3-parameter fit of 200 data points with
32 walkers run to N >= 50 tau, and print the time and likelihood evaluations per second.

    python benchmarks/fit_speed.py [--workers N] [--seed S]

Data: the committed SCATMECH measurement (200 rows, BRDF + eta + P + P_C).
Free: substrate.sigma (log-uniform), coating.index, noise.brdf (log-uniform);
eta/P/P_C noise fixed at the levels the data were made with.  The time printed
is the sampling time (least-squares optimum excluded, printed separately).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import references  # noqa: E402
from models import scene  # noqa: E402
from validation.fitting.datafile import load_data  # noqa: E402
from validation.fitting.executors import make_executor  # noqa: E402
from validation.fitting.fitspec import fitspec_from  # noqa: E402
from validation.fitting.likelihood import Likelihood  # noqa: E402
from validation.fitting.sampling import initial_ball, optimize, run_chain, summarize  # noqa: E402
from validation.fitting.settings import ChainSettings  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    sc = scene.load(
        os.path.join(os.path.dirname(references.__file__), "scenes", "aluminium_flakes_clearcoat.toml")
    )
    data = load_data(references.data_path("scatmech_flake_measurement.csv"))
    spec = fitspec_from(
        sc,
        ["sigma:0.01:1:log", "coating:1.2:2", "noise.brdf:0.005:1:log"],
        ["eta_deg=1", "P=0.02", "P_C=0.02"],
    )
    lik = Likelihood(sc, spec, data)
    settings = ChainSettings(walkers=32, seed=args.seed, max_steps=20000, check_every=100, tau_factor=50)
    t0 = time.perf_counter()
    u0, _, info = optimize(lik, settings.seed, n_starts=settings.starts)
    t_opt = time.perf_counter() - t0
    p0 = initial_ball(u0, settings.walkers, settings.seed, spec.u_bounds(), sd=info["sd_u"])
    with make_executor(args.workers) as ex:
        res = run_chain(lik, settings, p0=p0, executor=ex)
        desc = ex.describe()
    s = summarize(res, spec)["sampling"]
    print(f"executor: {desc}; {len(data)} data points, 3 free parameters, {settings.walkers} walkers")
    print(f"least-squares optimum: {t_opt:.2f} s")
    print(f"{res.stop_reason}")
    print(
        f"tau (steps): {', '.join(f'{t:.1f}' for t in s['tau_steps'])}; acceptance {s['acceptance_mean']:.3f}"
    )
    print(
        f"sampling: {res.seconds:.1f} s for {res.evaluations} likelihood evaluations "
        f"= {res.evals_per_second:.0f} evaluations/s ({1e3 / res.evals_per_second:.3f} ms each)"
    )


if __name__ == "__main__":
    main()
