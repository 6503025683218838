"""Nightly runs with history and regression detection.

Layout of the history folder::

    HISTORY/runs/<stamp>/report.html, results.json   one folder per completed run
    HISTORY/latest -> runs/<stamp>                   the last completed run (a symlink)
    HISTORY/.lock                                     held by the run in progress

A run is built in ``HISTORY/.tmp-<stamp>/`` and only renamed into ``runs/``
when complete; then ``latest`` is switched atomically (a new symlink renamed
over the old one).  Killing a run at any point therefore leaves the previous
``latest`` report and every earlier results.json untouched.  The history of
results.json is the ``runs`` folder itself.

Runs that overlap (two cron entries, a manual run during the nightly one) take
turns: a run holds ``HISTORY/.lock`` (an ``flock``, released by the kernel when
the process ends, however it ends) from before it reads the previous night until
``latest`` is switched; the next one waits for it, up to ``wait`` seconds, then
refuses with a :class:`HistoryError` naming the holder.  Only the holder removes
the leftovers of killed runs, so no run deletes another's work in progress.  A
second run in the same second gets the stamp ``<stamp>-1`` (``-2``, ...).

Everything a run needs from the folder is checked before any work: the folder
and ``runs/`` writable, ``latest`` absent or a symlink (a real file or folder there
is refused, never replaced).  A previous night that cannot be read (``latest``
pointing nowhere, a corrupt results.json) is said so in :attr:`NightlyRun.notes`:
the run compares with the newest earlier run that can be read, if any, and exits 1.
"""

from __future__ import annotations

import datetime
import os
import re
import shutil
from typing import NamedTuple

from scatterbench.validation.atomic import LockHeld, file_lock, write_problem

from .build import build_report, read_results_checked, write_files

__all__ = ["nightly", "compare_results", "HistoryError", "NightlyRun"]

_STAMP = re.compile(r"^[0-9A-Za-z][0-9A-Za-z._:+-]*$")


class HistoryError(ValueError):
    """A history folder a nightly run cannot use (not writable, a ``latest`` that is not the
    symlink it maintains, held by another run for too long); the message names the path."""


class NightlyRun(NamedTuple):
    """What :func:`nightly` did: its exit code (1 on a failed check, a regression or a
    note), the regressions, the run's folder and notes on the history."""

    code: int
    regressions: list
    run_dir: str
    notes: list


def compare_results(old, new):
    """Regressions from ``old`` to ``new``: checks that passed and now fail, tracked
    numbers that moved beyond their tolerance, sections that now fail."""
    if not old:
        return []
    out = []
    prev = {c["name"]: c for c in old.get("checks", [])}
    for c in new.get("checks", []):
        p = prev.get(c["name"])
        if p and p["status"] != "fail" and c["status"] == "fail":
            out.append(
                f"check '{c['name']}' passed before and now fails (measured {c['measured']}, tolerance {c['tolerance']})"
            )
    for sid, sec in new.get("sections", {}).items():
        old_sec = old.get("sections", {}).get(sid, {})
        if sec.get("error") and not old_sec.get("error"):
            out.append(f"section '{sid}' failed: {sec['error']}")
        old_tracked = old_sec.get("tracked", {})
        for key, t in sec.get("tracked", {}).items():
            o = old_tracked.get(key)
            if o is None or o.get("value") is None or t.get("value") is None:
                continue
            tol = max(float(t.get("tol", 0.0)), float(o.get("tol", 0.0)))
            if abs(t["value"] - o["value"]) > tol:
                out.append(f"'{key}' moved from {o['value']:.6g} to {t['value']:.6g} (tolerance {tol:.3g})")
    return out


def _check_folder(history):
    """The history folder exists (made if need be) and this process can write in it."""
    if os.path.lexists(history) and not os.path.isdir(history):
        raise HistoryError(f"{history}: not a folder; the history is a folder (runs/, latest)")
    try:
        os.makedirs(history, exist_ok=True)
    except OSError as exc:
        raise HistoryError(f"{history}: cannot create the history folder ({exc.strerror})") from exc
    problem = write_problem(history)
    if problem:
        raise HistoryError(
            f"{history}: cannot write in the history folder ({problem}); a nightly run writes its "
            "run, its lock and latest there"
        )


def _check_layout(history):
    """``runs/`` a writable folder, ``latest`` absent or a symlink: before any work."""
    runs = os.path.join(history, "runs")
    if os.path.lexists(runs) and not os.path.isdir(runs):
        raise HistoryError(f"{runs}: not a folder; the history keeps one folder per run there")
    os.makedirs(runs, exist_ok=True)
    problem = write_problem(runs)
    if problem:
        raise HistoryError(f"{runs}: cannot write in it ({problem})")
    latest = os.path.join(history, "latest")
    if os.path.lexists(latest) and not os.path.islink(latest):
        kind = "a folder" if os.path.isdir(latest) else "a file"
        raise HistoryError(
            f"{latest}: {kind}, not the symlink nightly maintains (latest -> runs/<stamp>); "
            "move it away: it is not replaced"
        )


def _remove_leftovers(history):
    """Build folders and links of killed runs (only the lock's holder calls this)."""
    for name in os.listdir(history):
        p = os.path.join(history, name)
        if name.startswith(".tmp-latest-"):
            os.unlink(p)
        elif name.startswith(".tmp-"):
            shutil.rmtree(p, ignore_errors=True)


def _readable_run(history, skip=()):
    """``(results, name)`` of the newest run in ``runs/`` whose results.json can be read."""
    runs = os.path.join(history, "runs")
    for name in sorted(os.listdir(runs), reverse=True):
        if name in skip:
            continue
        res, problem = read_results_checked(os.path.join(runs, name, "results.json"))
        if res is not None and problem is None:
            return res, name
    return None, None


def _previous(history):
    """``(results of the previous night or None, notes)``: ``latest``'s results, or, when
    they cannot be read, the newest earlier run's, with a note saying so."""
    latest = os.path.join(history, "latest")
    if not os.path.lexists(latest):
        res, name = _readable_run(history)
        if res is None:
            return None, []  # the first night
        return res, [f"{latest} is missing; compared with runs/{name}, the newest run"]
    target = os.readlink(latest)
    res, problem = read_results_checked(os.path.join(latest, "results.json"))
    if problem is None and res is None:
        problem = f"{latest} -> {target} does not exist"
    if problem is None:
        return res, []
    res, name = _readable_run(history, skip={os.path.basename(os.path.normpath(target))})
    then = (
        f"compared with runs/{name} instead" if res else "no earlier run can be read: no regression detection"
    )
    return res, [f"the previous night cannot be read: {problem}; {then}"]


def _stamp(history, stamp):
    """A stamp no run of the history has: ``stamp`` (default: now, UTC), or with ``-1``, ``-2``, ..."""
    base = stamp or datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H%M%SZ")
    if not isinstance(base, str) or not _STAMP.match(base):
        raise HistoryError(f"stamp: a run's folder name (letters, digits, ._:+-); got {base!r}")
    taken = set(os.listdir(os.path.join(history, "runs")))
    out, n = base, 0
    while out in taken:
        n += 1
        out = f"{base}-{n}"
    return out


def _say_waiting(history):
    def say(holder):
        print(f"nightly: {history}/.lock is held by {holder or 'another run'}; waiting for it", flush=True)

    return say


def nightly(history, quick=False, stamp=None, wait=3600.0, _after_build=None, **kwargs):
    """Run the suite into the history folder (see the module docstring).

    Parameters
    ----------
    history : str
        The history folder (made if need be).
    quick : bool
        The quick report.
    stamp : str, optional
        The run's folder name (default: the UTC time); made unique if taken.
    wait : float or None
        Seconds to wait for another run holding the history (``None``: as long as it takes).
    **kwargs
        Passed to :func:`~scatterbench.validation.report.build.build_report` (``only``, ``checks``, ...).

    Returns
    -------
    NightlyRun

    Raises
    ------
    HistoryError
        The folder cannot be used, or another run held it for longer than ``wait``.
    """
    _check_folder(history)
    lock = file_lock(os.path.join(history, ".lock"), wait=wait, on_wait=_say_waiting(history))
    try:
        with lock:
            return _run(history, quick, stamp, _after_build, kwargs)
    except LockHeld as exc:
        raise HistoryError(
            f"{exc.path}: another nightly run holds the history ({exc.holder or 'holder unknown'}); "
            f"waited {exc.waited:.0f} s"
        ) from exc


def _build(tmp, quick, previous, notes, after_build, kwargs):
    """The run's report and results (with its regressions and notes) written into ``tmp``."""
    results, html = build_report(quick=quick, previous=previous or {}, **kwargs)
    results["regressions"] = compare_results(previous, results)
    results["history_notes"] = notes
    write_files(tmp, results, html)
    if after_build is not None:
        after_build(tmp)  # test hook: simulate a kill before the commit point
    return results


def _run(history, quick, stamp, after_build, kwargs):
    """The run itself, under the history's lock."""
    _check_layout(history)
    _remove_leftovers(history)
    stamp = _stamp(history, stamp)
    previous, notes = _previous(history)
    tmp = os.path.join(history, f".tmp-{stamp}")
    os.makedirs(tmp)
    try:
        results = _build(tmp, quick, previous, notes, after_build, kwargs)
        final = os.path.join(history, "runs", stamp)
        os.replace(tmp, final)
    except BaseException:
        # whatever stopped the run (an error, Ctrl-C, user code calling sys.exit): no half run left
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    link_tmp = os.path.join(history, f".tmp-latest-{stamp}")
    os.symlink(os.path.join("runs", stamp), link_tmp)
    os.replace(link_tmp, os.path.join(history, "latest"))
    failed = any(c["status"] == "fail" for c in results["checks"])
    regressions = results["regressions"]
    return NightlyRun(1 if (regressions or failed or notes) else 0, regressions, final, notes)
