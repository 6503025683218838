"""``scatterbench validate``: every registered check with measured value, tolerance and status.

It judges exactly the checks ``report`` judges, with the same settings
(``--quick`` as ``report --quick``), then prints the registered text blocks.
"""

from __future__ import annotations

import time

from scatterbench.validation.atomic import atomic_write_json
from scatterbench.validation.checks.registry import (
    CheckContext,
    check_record,
    format_checks,
    run_checks,
    tally,
    texts,
)

from .args import check_executor, executor_args, open_executor, writable_file

__all__ = ["register", "run"]


def run(quick=False, json_path=None, ctx=None, specs=None, executor=None) -> int:
    """Run the checks, print the table and the text blocks, write ``json_path`` (strict
    JSON, atomically) if given; 1 if a check fails, else 0.

    ``ctx``: a :class:`~scatterbench.validation.checks.registry.CheckContext` whose memo is shared
    (e.g. with a report built on it); ``specs``: the checks (default: every registered
    check, less the slow ones when ``quick``).
    """

    t0 = time.perf_counter()
    ctx = ctx if ctx is not None else CheckContext(quick=quick)
    if ctx.quick != quick:
        raise ValueError(f"ctx: its quick flag ({ctx.quick}) must be the run's ({quick})")
    results = run_checks(specs, ctx)
    print(format_checks(results))
    if json_path:
        doc = {"quick": quick, "seed": ctx.seed, "summary": tally(results)}
        doc["checks"] = [check_record(r) for r in results]
        atomic_write_json(json_path, doc)
    for section in texts():
        out = section(ctx)
        if out:
            title, text = out
            print(f"\n{title}:")
            print(text)
    print(f"\nvalidate finished in {time.perf_counter() - t0:.1f} s")
    return 1 if tally(results)["n_fail"] else 0


def _cmd_validate(args) -> int:
    if args.json:
        writable_file(args.json, "--json")
    check_executor(args)
    with open_executor(args) as ex:  # every study of the checks runs there; same results on any
        return run(quick=args.quick, json_path=args.json, executor=ex)


def register(sub):
    p = sub.add_parser(
        "validate",
        help="run every check (the report's set); print a table; exit 1 if any fails",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="skip the slow checks and use the quick study settings (the set `report --quick` judges)",
    )
    p.add_argument("--json", metavar="FILE", help="also write every check as strict JSON to FILE")
    executor_args(p, all_cores=True)
    p.set_defaults(func=_cmd_validate)
