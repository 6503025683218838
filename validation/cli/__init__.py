"""``scatterbench`` command line: one module per command, listed in :data:`COMMANDS`.

Each command module defines ``register(subparsers)``, which adds its parser and sets
``func`` (returning the exit code).
"""

from __future__ import annotations

import argparse

from . import check, fit, models, report, scene, stability, study, table1, tradeoff, validate

__all__ = ["main", "COMMANDS"]

#: every command module, in the order ``scatterbench --help`` lists them
COMMANDS = (validate, table1, stability, tradeoff, scene, models, fit, study, report, check)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog="scatterbench",
        description="Validation and benchmark harness for polarized light-scattering models.",
    )
    sub = ap.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        command.register(sub)
    args = ap.parse_args(argv)
    return args.func(args)
