"""``scatterbench`` command line: one module per command, listed in :data:`COMMANDS`.

Each command module defines ``register(subparsers)``, which adds its parser and sets
``func`` (returning the exit code).

Exit codes, the same for every command (:func:`main`):

* 0: done, every check passed;
* 1: a check failed or a regression was found (the command says which);
* 2: a usage or input error: a flag out of range, a malformed scene, data or fit
  file, an unusable checkpoint, a history folder the nightly run cannot use;
  one ``error: ...`` line naming the file (``file:line:column`` where known), key
  or flag, no traceback;
* 3: an internal error (a bug or a failing machine): ``error: internal: ...``;
  ``SCATTERBENCH_TRACEBACK=1`` shows the traceback.  Also code that is not the
  command's calling ``sys.exit`` (a plug-in's module, a model's ``mueller``, a module
  given to ``check``): whatever its code, the command did not finish, so it is
  never success: ``error: user code called sys.exit(CODE) in FILE:LINE (FUNCTION)``;
* 130: interrupted (Ctrl-C, or a ``KeyboardInterrupt`` raised by user code).
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import os
import sys

from . import check, fit, models, predict, report, scene, study, sweep, table1, tradeoff, validate

__all__ = ["main", "COMMANDS", "INPUT_ERRORS", "EXIT_OK", "EXIT_FAILED", "EXIT_USAGE", "EXIT_INTERNAL"]

#: every command module, in the order ``scatterbench --help`` lists them
COMMANDS = (validate, table1, sweep, tradeoff, scene, models, fit, predict, study, report, check)

EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_INTERNAL, EXIT_INTERRUPTED = 0, 1, 2, 3, 130

#: the exceptions the project raises for bad input, by module: exit 2.  Any other
#: exception that reaches :func:`main` is a bug (exit 3); a ``ValueError`` is not
#: input's by itself (numpy raises them too), only these subclasses are.
INPUT_ERRORS = {
    "scatterbench.validation.cli.args": "UsageError",
    "scatterbench.models.scene.schema": "SceneError",
    "scatterbench.validation.fitting.datafile": "DataFileError",
    "scatterbench.validation.fitting.fitspec": "FitSpecError",
    "scatterbench.validation.fitting.checkpoint": "CheckpointError",
    "scatterbench.validation.fitting.executors": "SchedulerError",
    "scatterbench.validation.report.nightly": "HistoryError",
    "scatterbench.validation.atomic": "FolderError",
    "scatterbench.validation.fitting.fit": "FitError",
}


def _is_input_error(exc) -> bool:
    # only modules already imported can have raised their class: nothing is imported here
    for module, name in INPUT_ERRORS.items():
        mod = sys.modules.get(module)
        if mod is not None and isinstance(exc, getattr(mod, name)):
            return True
    return False


def _where(exc) -> str:
    """``FILE:LINE (FUNCTION)`` of the frame that raised ``exc`` (the innermost one)."""
    tb = exc.__traceback__
    if tb is None:
        return "an unknown place"
    while tb.tb_next is not None:
        tb = tb.tb_next
    code = tb.tb_frame.f_code
    return f"{code.co_filename}:{tb.tb_lineno} ({code.co_name})"


def _parser():
    ap = argparse.ArgumentParser(
        prog="scatterbench",
        description="Validation and benchmark harness for polarized light-scattering models.",
        epilog="exit codes: 0 ok, 1 a failed check or regression, 2 usage or input error, "
        "3 internal error, 130 interrupted",
    )
    sub = ap.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        command.register(sub)
    return ap


def _show_compiling():
    """The kernels' compile notices (:mod:`scatterbench.models.kernels`) as progress lines on
    stderr: a first run spends a while compiling, once per machine."""
    log = logging.getLogger("scatterbench.models.kernels")
    if not log.handlers:
        handler = logging.StreamHandler(sys.stderr)
        handler.setFormatter(logging.Formatter("  %(message)s"))
        log.addHandler(handler)
        log.setLevel(logging.INFO)


def _tolerant_streams():
    """Let stdout and stderr show any character: one their encoding cannot hold (an em dash
    in a scene's description under ``PYTHONIOENCODING=latin-1``) is written as ``\\u2014``
    instead of ending the command.  Files are written as UTF-8 whatever the locale."""
    for stream in (sys.stdout, sys.stderr):
        reconfigure = getattr(stream, "reconfigure", None)
        if reconfigure is not None:
            with contextlib.suppress(ValueError, OSError, TypeError):  # a stream that cannot
                reconfigure(errors="backslashreplace")


def main(argv=None) -> int:
    """Run one command; returns its exit code (see the module docstring), never raises."""
    _tolerant_streams()
    try:
        args = _parser().parse_args(argv)
    except SystemExit as exc:  # argparse has printed usage and ``error: ...`` (2) or --help (0)
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    _show_compiling()
    try:
        return args.func(args)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except SystemExit as exc:  # no command exits this way: user code it ran did
        print(f"error: user code called sys.exit({exc.code!r}) in {_where(exc)}", file=sys.stderr)
        print("(the command did not finish: that is never success)", file=sys.stderr)
        return EXIT_INTERNAL
    except Exception as exc:
        if _is_input_error(exc):
            print(f"error: {exc}", file=sys.stderr)
            return EXIT_USAGE
        if os.environ.get("SCATTERBENCH_TRACEBACK"):
            raise
        print(
            f"error: internal: {type(exc).__name__}: {exc}\n"
            "(a bug or a failing machine, not your input: set SCATTERBENCH_TRACEBACK=1 for the "
            "traceback and report it with the command line)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL
