"""The kernels before and after a change, measured in one run.

    git archive <old commit> | tar -x -C /tmp/base
    python benchmarks/kernel_ab.py --base /tmp/base [--rounds 3] [--what small|geometry|wrappers]

Runs this checkout's :func:`benchmarks.kernel_speed.small_calls` (``--what small``, the
default: every closed-form model's one-geometry and 100-geometry ``mueller`` calls, and the
other input forms) or :func:`benchmarks.kernel_speed.per_geometry` (``--what geometry``: 10^6
geometries, one thread and every core, a fresh result and into ``out=``) or
:func:`benchmarks.kernel_speed.wrapper_calls` (``--what wrappers``: PointSourceBRDF's default
and DetectorAperture per geometry; no numpy column) against the package
in ``--base`` and against this checkout's, alternating fresh processes for ``--rounds`` rounds
so that both see the same machine load (on a shared machine figures drift by tens of percent
over minutes), and prints the best of the rounds per case with the ratio.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, HERE)
from benchmarks.checkouts import IMPORT_MODELS, environment  # noqa: E402

# kernel_speed puts its own checkout first on sys.path: run a copy of it inside each tree
CHILD = (
    r"""
import importlib.util, json, sys
spec = importlib.util.spec_from_file_location("ks", sys.argv[2])
ks = importlib.util.module_from_spec(spec)
spec.loader.exec_module(ks)
"""
    + IMPORT_MODELS
    + r"""
if sys.argv[3] == "small":
    calls = ks.small_calls(int(sys.argv[1]))
elif sys.argv[3] == "wrappers":
    calls = ks.wrapper_calls(int(sys.argv[1]))
else:
    calls = {f"{name}, {col}": (t[0], v) for name, t in ks.per_geometry(10**6, int(sys.argv[1])).items()
             for col, v in zip(ks.COLUMNS, t[1:])}
print(json.dumps({"models": models.__file__, "calls": calls}))
"""
)


def measure(root, repeat, what):
    """``{case: (numpy us, kernel us)}`` of the package in ``root``."""
    copy = os.path.join(root, "benchmarks", "_kernel_ab_copy.py")
    shutil.copy(os.path.join(HERE, "benchmarks", "kernel_speed.py"), copy)
    try:
        env = environment(root)
        r = subprocess.run(
            [sys.executable, "-c", CHILD, str(repeat), copy, what],
            env=env,
            capture_output=True,
            text=True,
            cwd=root,
        )
    finally:
        os.remove(copy)
    if r.returncode:
        raise SystemExit(r.stderr)
    data = json.loads(r.stdout.strip().splitlines()[-1])
    where = env.get("PYTHONPATH") or os.path.realpath(root)
    if not os.path.realpath(data["models"]).startswith(os.path.realpath(where)):
        raise SystemExit(f"measured {data['models']}, not the package of {root}")
    return data["calls"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--base", required=True, help="a checkout of the older version")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--what", choices=("small", "geometry", "wrappers"), default="small")
    args = ap.parse_args()
    best = {"before": {}, "after": {}}
    print(f"load {os.getloadavg()}")
    for _ in range(args.rounds):
        for label, root in (("before", args.base), ("after", HERE)):
            for case, (t_np, t_k) in measure(root, 3, args.what).items():
                old = best[label].get(case, (float("inf"), float("inf")))
                best[label][case] = (min(old[0], t_np), min(old[1], t_k))
    print(f"load after: {os.getloadavg()}")
    print(
        f"{'model, case':<48} {'before us':>10} {'after us':>10} {'ratio':>7}   numpy path before / after us"
    )
    for case, after in best["after"].items():
        before = best["before"].get(case)
        if before is None:
            continue
        print(
            f"{case:<48} {before[1]:10.4g} {after[1]:10.4g} {before[1] / after[1]:6.2f}x   "
            + (f"{before[0]:.0f} / {after[0]:.0f}" if before[0] < float("inf") else "-")
        )


if __name__ == "__main__":
    main()
