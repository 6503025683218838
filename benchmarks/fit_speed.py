"""The issue's fit case, before and after in one run: a 110-row, 2-parameter fit of
SCATMECH-made flake data reduced to the BRDF, run to N >= 50 tau by ``scatterbench fit``.

    python benchmarks/fit_speed.py [--baseline DIR] [--workers N] [--seed S]

The data: 110 rows spread evenly over ``references/data/scatmech_flake_measurement.csv``,
with the BRDF column only (written to a temporary folder with its sidecar).  Free:
``substrate.sigma`` (log-uniform) and ``coating.index``; speckle noise fixed at the 5% the
data were made with.  The whole command is timed (interpreter start, imports, optimum,
chain, posterior.json and plots), and its own report of the chain gives the likelihood
evaluations per second.  ``--baseline DIR``: another checkout (e.g. ``git worktree add DIR
990a666``) run the same way in the same run, and the ratios printed.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
from benchmarks.checkouts import environment  # noqa: E402

SOURCE = os.path.join(ROOT, "references", "data", "scatmech_flake_measurement.csv")
SCENE = os.path.join(ROOT, "references", "scenes", "aluminium_flakes_clearcoat.toml")
COLUMNS = ("theta_i_deg", "theta_r_deg", "phi_r_deg", "brdf", "incident")


def write_data(folder, rows=110):
    """The BRDF-only data file (and sidecar) of ``rows`` rows spread over the SCATMECH file."""
    with open(SOURCE) as fh:
        lines = [ln for ln in fh.read().splitlines() if ln and not ln.startswith("#")]
    header = lines[0].split(",")
    body = [ln.split(",") for ln in lines[1:]]
    pick = np.unique(np.round(np.linspace(0, len(body) - 1, rows)).astype(int))
    path = os.path.join(folder, "flake_brdf_110.csv")
    with open(path, "w") as fh:
        fh.write(
            "# 110 rows of references/data/scatmech_flake_measurement.csv, BRDF only (benchmarks/fit_speed.py)\n"
        )
        fh.write(",".join(COLUMNS) + "\n")
        for i in pick:
            fh.write(",".join(body[i][header.index(c)] for c in COLUMNS) + "\n")
    with open(SOURCE[:-4] + ".json") as fh:
        meta = json.load(fh)
    meta["truth"] = {k: v for k, v in meta["truth"].items() if k in ("substrate.sigma", "coating.index")}
    with open(path[:-4] + ".json", "w") as fh:
        json.dump(meta, fh)
    return path, len(pick)


def run(checkout, data, out, workers, seed):
    """Run ``scatterbench fit`` from ``checkout``: ``(seconds, evaluations/s, stop line, executor)``."""
    cli = (
        "scatterbench.validation.cli"
        if os.path.isdir(os.path.join(checkout, "namespace"))
        else "validation.cli"
    )
    cmd = [
        sys.executable, "-m", cli, "fit", data, "--scene", SCENE,
        "--free", "sigma:0.01:1:log", "--free", "coating:1.2:2", "--noise", "brdf=0.05",
        "--out", out, "--force", "--no-progress", "--workers", str(workers), "--seed", str(seed),
    ]  # fmt: skip
    env = environment(checkout)
    t = time.perf_counter()
    r = subprocess.run(cmd, cwd=checkout, env=env, capture_output=True, text=True)
    seconds = time.perf_counter() - t
    if r.returncode != 0:
        raise RuntimeError(f"{checkout}: exit {r.returncode}\n{r.stdout}\n{r.stderr}")
    rate = float(re.search(r"([0-9.]+) evaluations/s", r.stdout).group(1))
    stop = next(ln for ln in r.stdout.splitlines() if ln.startswith(("converged", "step budget")))
    executor = next((ln for ln in r.stdout.splitlines() if ln.startswith("executor:")), "executor: ?")
    return seconds, rate, stop, executor


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", help="another checkout to time the same way, for ratios")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        data, rows = write_data(tmp)
        print(
            f"{rows} rows (BRDF only), 2 free parameters, 32 walkers to N >= 50 tau; load {os.getloadavg()}"
        )
        results = {}
        for name, checkout in (("this checkout", ROOT), ("baseline", args.baseline)):
            if checkout is None:
                continue
            s, rate, stop, ex = run(
                checkout, data, os.path.join(tmp, name.replace(" ", "_")), args.workers, args.seed
            )
            results[name] = (s, rate)
            print(f"{name:<14} {s:7.1f} s for the command, {rate:8.0f} evaluations/s; {ex}; {stop}")
        if len(results) == 2:
            (s1, r1), (s0, r0) = results["this checkout"], results["baseline"]
            print(f"ratios: command {s0 / s1:.1f}x faster, evaluations/s {r1 / r0:.1f}x")
        print(f"load after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
