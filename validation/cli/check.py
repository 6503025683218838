"""``scatterbench check MODULE:NAME``: the conformance kit on any model (validation.testing)."""

from __future__ import annotations

import os
import sys
import time

from scatterbench.validation.atomic import atomic_write_json
from scatterbench.validation.testing import check_model, load_model

from .args import UsageError, writable_file

__all__ = ["register", "run"]


def run(spec, json_path=None, quick=False, checks=None) -> int:
    """Check the model ``spec`` names, print the table, write ``json_path`` (strict JSON,
    atomically) if given; 0 when no check fails, 1 when one does.  A bad argument raises
    :class:`~scatterbench.validation.cli.args.UsageError` (the command line: ``error: ...``, exit 2)."""

    # like pytest, a module beside the user is importable: `scatterbench check mybrdf:Model`
    if os.getcwd() not in sys.path:
        sys.path.insert(0, os.getcwd())
    try:
        names = None if checks is None else [c.strip() for c in checks.split(",") if c.strip()]
        if names == []:  # "" or ",": a list of no checks would run nothing and pass
            raise ValueError(
                f"--checks {checks!r}: no check name given (comma-separated names; omit it for all)"
            )
        model = load_model(spec)
        t0 = time.perf_counter()
        report = check_model(model, checks=names, quick=quick, label=spec)
    except ValueError as exc:  # a model spec that names no model, an unknown check name
        raise UsageError(str(exc)) from exc
    print(report.format())
    print(f"check finished in {time.perf_counter() - t0:.1f} s")
    if json_path:
        atomic_write_json(json_path, {"quick": quick, **report.as_dict()})
    return 0 if report.passed else 1


def _cmd_check(args) -> int:
    if args.json:  # refused before the kit runs, not after
        writable_file(args.json, "--json")
    return run(args.model, json_path=args.json, quick=args.quick, checks=args.checks)


def register(sub):
    p = sub.add_parser(
        "check",
        help="run the conformance kit on a model (MODULE:NAME); exit 1 if a check fails",
        description="Every conformance check (validation.testing.check_model) on the model MODULE:NAME "
        "names: an instance, or a class or callable returning one.  Exit 0 when every check passes "
        "(or is skipped, or is a finding accepted with its reason), 1 when one fails, 2 on a bad "
        "argument.",
    )
    p.add_argument(
        "model", metavar="MODULE:NAME", help="e.g. mypkg.brdf:MyModel (the current directory is importable)"
    )
    p.add_argument("--json", metavar="FILE", help="also write every result as strict JSON to FILE")
    p.add_argument(
        "--quick",
        action="store_true",
        help="skip the slow checks; energy at normal and grazing incidence only",
    )
    p.add_argument("--checks", metavar="NAMES", help="comma-separated check names to run (default: all)")
    p.set_defaults(func=_cmd_check)
