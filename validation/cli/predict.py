"""``scatterbench predict``: a fitted scene's posterior predictive at the rows of another data
file (how users judge a model on held-out measurements).

``scatterbench predict --posterior DIR DATA --out FILE`` reads ``DIR/posterior.json`` and
``DIR/posterior_samples.npz`` (written by ``scatterbench fit`` on Mueller-matrix data) and any
Mueller data file ``fit`` reads (NIST's ``PTFE.data.csv`` as published included), and writes a
CSV with one row per input row, in the input's order: the median and the 2.5/16/84/97.5
percentiles of M11 and of each normalized element, measurement noise included
(:func:`scatterbench.validation.fitting.mueller_fit.predictive_csv`), atomically.
"""

from __future__ import annotations

import os

from scatterbench.validation.fitting.mueller_fit import write_predictive

from .args import UsageError, int_at_least, writable_file

__all__ = ["register"]


def _cmd_predict(args) -> int:
    if not os.path.isdir(args.posterior):
        raise UsageError(f"--posterior {args.posterior}: not a folder (give a fit's --out folder)")
    writable_file(args.out, "--out")
    write_predictive(args.posterior, args.data, args.out, n_draws=args.draws, seed=args.seed)
    print(f"wrote {args.out}")
    return 0


def register(sub):
    p = sub.add_parser(
        "predict",
        help="posterior predictive of a fitted scene at the rows of another Mueller data file (CSV)",
    )
    p.add_argument(
        "data", help="Mueller data file (NIST's PTFE.data.csv as published, or scatterbench-mueller/1)"
    )
    p.add_argument(
        "--posterior", required=True, help="a fit's output folder (posterior.json, posterior_samples.npz)"
    )
    p.add_argument("--out", required=True, help="CSV file to write (replaced atomically)")
    p.add_argument("--draws", type=int_at_least(10), default=400, help="posterior draws (default 400)")
    p.add_argument("--seed", type=int, default=0, help="seed of the draws and of the noise")
    p.set_defaults(func=_cmd_predict)
