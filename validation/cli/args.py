"""Flag types and up-front checks shared by the commands.

A flag out of range is refused by its argparse type (``error: argument --tol: ...``,
exit 2) before any work; combinations and output folders are checked by the
command before it starts, raising :class:`UsageError` (``error: ...``, exit 2).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import re

from scatterbench.models.text import shown
from scatterbench.validation.atomic import write_problem
from scatterbench.validation.fitting.executors import (
    SchedulerError,
    check_scheduler_address,
    default_workers,
    make_executor,
)

__all__ = [
    "UsageError",
    "MAX_WORKERS",
    "int_at_least",
    "int_in",
    "positive_float",
    "nonneg_float",
    "positive_floats",
    "ints_at_least",
    "scheduler_address",
    "executor_args",
    "check_executor",
    "open_executor",
    "writable_folder",
    "writable_file",
]

#: the most local worker processes ``--workers`` takes: each holds a copy of the
#: likelihood and its data, and a local machine gains nothing beyond its cores
MAX_WORKERS = 256


class UsageError(ValueError):
    """Flags that do not go together, or an output the command could not write; the
    message names the flag (the command line turns it into ``error: ...``, exit 2)."""


def int_at_least(low):
    """An argparse type: an integer >= ``low``."""

    def parse(text):
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be an integer >= {low}; got {shown(text, 40)}") from None
        if v < low:
            raise argparse.ArgumentTypeError(f"must be an integer >= {low}; got {v}")
        return v

    parse.__name__ = f"integer >= {low}"
    return parse


def int_in(low, high):
    """An argparse type: an integer in ``[low, high]``."""

    def parse(text):
        v = int_at_least(low)(text)
        if v > high:
            raise argparse.ArgumentTypeError(f"must be an integer in [{low}, {high}]; got {v}")
        return v

    parse.__name__ = f"integer in [{low}, {high}]"
    return parse


def _finite(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a finite number; got {shown(text, 40)}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be a finite number; got {shown(text, 40)}")
    return v


def positive_float(text):
    """An argparse type: a finite number > 0 (a tolerance, a noise level)."""
    v = _finite(text)
    if v <= 0:
        raise argparse.ArgumentTypeError(f"must be a finite number > 0; got {shown(text, 40)}")
    return v


def nonneg_float(text):
    """An argparse type: a finite number >= 0 (a time to wait)."""
    v = _finite(text)
    if v < 0:
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0; got {shown(text, 40)}")
    return v


def positive_floats(text):
    """An argparse type: a comma-separated, non-empty list of finite numbers > 0."""
    parts = [p.strip() for p in text.split(",") if p.strip()]
    if not parts:
        raise argparse.ArgumentTypeError(f"must be one or more numbers > 0, comma separated; got {text!r}")
    return [positive_float(p) for p in parts]


def ints_at_least(low):
    """An argparse type: a comma-separated, non-empty list of integers >= ``low``."""

    def parse(text):
        parts = [p.strip() for p in text.split(",") if p.strip()]
        if not parts:
            raise argparse.ArgumentTypeError(f"must be one or more integers >= {low}, comma separated")
        return [int_at_least(low)(p) for p in parts]

    parse.__name__ = f"integers >= {low}"
    return parse


_ADDRESS = re.compile(r"^([a-z][a-z0-9+.-]*://)?[A-Za-z0-9_.\-\[\]:]+:\d+$")


def scheduler_address(text):
    """An argparse type: a Dask scheduler address, ``[PROTOCOL://]HOST:PORT``."""
    if not _ADDRESS.match(text):
        raise argparse.ArgumentTypeError(
            f"must be a scheduler address [PROTOCOL://]HOST:PORT, e.g. tcp://10.0.0.5:8786; got {shown(text, 40)}"
        )
    return text


def executor_args(p, all_cores=False):
    """``--workers N`` and ``--scheduler ADDRESS``, the one definition every command uses.
    ``all_cores``: ``--workers`` defaults to the cores of this process's affinity mask (the
    commands that run the whole suite), else to 1 (in-process)."""
    default = "the cores this process may run on" if all_cores else "1: in-process"
    p.add_argument(
        "--workers",
        type=int_in(1, MAX_WORKERS),
        default=None,
        help=f"local processes, 1-{MAX_WORKERS} (default {default}); the results do not depend on it",
    )
    p.add_argument(
        "--scheduler",
        type=scheduler_address,
        default=None,
        help="dask.distributed scheduler ADDRESS (tcp://host:8786; tls:// with dask's certificates)",
    )
    p.set_defaults(default_workers=default_workers if all_cores else (lambda: 1))


def check_executor(args):
    """Raise :class:`UsageError` for ``--workers`` with ``--scheduler``, or a scheduler address
    no scheduler can be reached at (before any work; nothing is sent)."""
    if args.scheduler and args.workers is not None:
        raise UsageError("--workers and --scheduler: give one (local processes or a Dask cluster)")
    if args.scheduler:
        with _as_flag_error(args.scheduler):
            args.scheduler = check_scheduler_address(args.scheduler)


@contextlib.contextmanager
def _as_flag_error(address):
    """A :class:`SchedulerError` (``scheduler 'ADDRESS': reason``) as ``--scheduler 'ADDRESS': reason``."""
    try:
        yield
    except SchedulerError as exc:
        reason = str(exc).split("': ", 1)[-1]
        raise UsageError(f"--scheduler {shown(address, 60)}: {reason}") from None


def open_executor(args):
    """The executor ``--workers``/``--scheduler`` ask for, its description printed.  A
    scheduler that does not answer within its deadline is a :class:`UsageError` (exit 2)."""
    workers = args.workers if args.workers is not None else args.default_workers()
    with _as_flag_error(args.scheduler):
        ex = make_executor(workers, args.scheduler)
    print(f"executor: {ex.describe()}", flush=True)
    return ex


def writable_folder(path, flag):
    """Raise :class:`UsageError` unless ``path`` is a folder this process can write to, or
    can be created (its nearest existing parent is a writable folder).  Nothing is created."""
    given, path = path, os.path.abspath(path)
    existing = path
    while not os.path.exists(existing):
        parent = os.path.dirname(existing)
        if parent == existing:
            break
        existing = parent
    if not os.path.isdir(existing):
        which = "" if existing == path else f" ({existing} is a file)"
        raise UsageError(f"{flag} {given}: not a folder{which}")
    problem = write_problem(existing)
    if problem:
        raise UsageError(f"{flag} {given}: cannot write in {existing} ({problem})")


def writable_file(path, flag):
    """Raise :class:`UsageError` unless ``path`` can be written as a file (not a folder,
    in a folder :func:`writable_folder` accepts)."""
    if os.path.isdir(path):
        raise UsageError(f"{flag} {path}: a folder, not a file")
    writable_folder(os.path.dirname(os.path.abspath(path)), flag)
