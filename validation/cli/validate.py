"""``scatterbench validate``: every check with measured value, tolerance and status."""

from __future__ import annotations

import time

__all__ = ["register"]


def _cmd_validate(args) -> int:
    from validation.checks.seed000 import all_sections, format_checks, run_checks

    t0 = time.perf_counter()
    results = run_checks()
    print(format_checks(results))
    for section in all_sections():
        out = section(results)
        if out:
            title, text = out
            print(f"\n{title}:")
            print(text)
    print(f"\nvalidate finished in {time.perf_counter() - t0:.1f} s")
    return 1 if any(c.status == "fail" for c in results) else 0


def register(sub):
    p = sub.add_parser("validate", help="run every check; print a table; exit 1 if any fails")
    p.set_defaults(func=_cmd_validate)
