"""``scatterbench stability``: every model at the extremes of its parameters and geometries."""

from __future__ import annotations

import time

from scatterbench.validation.studies.edge_sweep import classify, format_sweep, sweep

from .fit import _check_executor, _executor_args, _open_executor

__all__ = ["register"]


def _cmd_stability(args) -> int:

    _check_executor(args)
    t0 = time.perf_counter()
    with _open_executor(args) as ex:
        findings = sweep(energy=not args.no_energy, executor=ex)
    print(format_sweep(findings))
    print(f"stability sweep finished in {time.perf_counter() - t0:.1f} s")
    _, bad = classify(findings)
    return 1 if bad else 0


def register(sub):
    p = sub.add_parser("stability", help="sweep every model at its extremes; exit 1 on unaccepted findings")
    p.add_argument("--no-energy", action="store_true", help="skip the integrated-reflectance checks")
    _executor_args(p)
    p.set_defaults(func=_cmd_stability)
