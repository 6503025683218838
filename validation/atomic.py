"""Atomic file writes (a temporary file in the same folder, then ``os.replace``), strict
JSON, an exclusive lock for folders that several runs may write, and whole-folder
replacement.

A failed or interrupted run therefore never leaves a half-written result and
never damages the previous one; JSON is written without ``NaN`` or ``Infinity``
tokens (they are not JSON: a non-finite number becomes ``null``).

Output folders (``fit --out``, ``report --out``, the studies' ``--out``) are written
as a whole by :func:`replacing_folder`: the new folder is built beside the old one
(``.NAME.build-*``), then swapped in (old renamed aside, new renamed in, old
removed); a run that fails before the swap removes its build and leaves the old
folder exactly as it was.  The same function holds the folder's lock
(``.NAME.lock`` beside it) from before the old folder is read until the swap, so
a second run on the same folder is refused (:class:`FolderBusy`) instead of mixing
its files with the first's.  Nightly runs use the same lock (:func:`file_lock`)
on their history folder.
"""

from __future__ import annotations

import contextlib
import datetime
import json
import math
import os
import shutil
import socket
import tempfile
import time

import numpy as np

__all__ = [
    "atomic_write_bytes",
    "atomic_write_text",
    "atomic_write_json",
    "atomic_savefig",
    "write_problem",
    "strict_json",
    "LockHeld",
    "file_lock",
    "FolderError",
    "FolderBusy",
    "folder_lock",
    "replacing_folder",
    "swap_folder",
    "beside",
]


@contextlib.contextmanager
def _temp_beside(path, suffix=""):
    folder = os.path.dirname(os.path.abspath(path)) or "."
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=suffix, dir=folder)
    os.close(fd)
    try:
        yield tmp
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the file normal permissions
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def atomic_write_bytes(path, data: bytes):
    with _temp_beside(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())


def atomic_write_text(path, text: str):
    atomic_write_bytes(path, text.encode("utf-8"))


def _plain(v):
    """``v`` with numpy values as Python ones and non-finite floats as ``None``."""
    if isinstance(v, dict):
        return {k: _plain(x) for k, x in v.items()}
    if isinstance(v, list | tuple | np.ndarray):
        return [_plain(x) for x in v]
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def strict_json(obj) -> str:
    """``obj`` as strict JSON text: sorted keys, indented, numpy values converted, NaN and
    infinities as ``null``; anything else that is not JSON raises ``TypeError``."""
    return json.dumps(_plain(obj), indent=2, sort_keys=True, allow_nan=False) + "\n"


def atomic_write_json(path, obj):
    """Write ``obj`` as :func:`strict_json` to ``path`` atomically."""
    atomic_write_text(path, strict_json(obj))


def atomic_savefig(fig, path, **kwargs):
    ext = os.path.splitext(path)[1]
    with _temp_beside(path, suffix=ext) as tmp:
        fig.savefig(tmp, **kwargs)


def write_problem(folder):
    """Why this process cannot create a file in the existing ``folder`` (``None``: it can).
    The permission bits do not say it for root or on read-only file systems; a real file
    (created and removed at once) does."""
    try:
        fd, name = tempfile.mkstemp(prefix=".probe-", dir=folder)
    except OSError as exc:
        return exc.strerror or str(exc)
    os.close(fd)
    os.unlink(name)
    return None


class LockHeld(TimeoutError):
    """The lock stayed held by another process for longer than the caller would wait."""

    def __init__(self, path, holder, waited):
        self.path, self.holder, self.waited = path, holder, waited
        super().__init__(f"{path}: held by {holder or 'another process'} (waited {waited:.0f} s)")


def _holder(fh):
    fh.seek(0)
    return fh.read().strip()


@contextlib.contextmanager
def file_lock(path, wait=None, poll=0.2, on_wait=None):
    """Hold an exclusive lock on the file ``path`` (created if need be) for the ``with`` block.

    The lock is ``flock``'s: the kernel releases it when the process ends however it ends
    (a killed run never leaves a stale lock).  The holder writes who it is (pid, host,
    start time) into the file, for the messages of those who wait.

    Parameters
    ----------
    path : str
        The lock file.
    wait : float or None
        Seconds to wait for another holder (``None``: as long as it takes).
    poll : float
        Seconds between attempts.
    on_wait : callable, optional
        Called once, with the holder's description, when the lock is held by another.

    Raises
    ------
    LockHeld
        Still held after ``wait`` seconds.
    OSError
        The lock file cannot be created or opened.
    """
    import fcntl  # fcntl (POSIX only)

    with open(path, "a+", encoding="utf-8") as fh:
        t0 = time.monotonic()
        told = False
        while True:
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                waited = time.monotonic() - t0
                if wait is not None and waited >= wait:
                    raise LockHeld(path, _holder(fh), waited) from None
                if on_wait is not None and not told:
                    on_wait(_holder(fh))
                    told = True
                time.sleep(poll if wait is None else max(0.0, min(poll, wait - waited)))
        started = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M:%S UTC")
        fh.seek(0)
        fh.truncate()
        fh.write(f"pid {os.getpid()} on {socket.gethostname()} since {started}\n")
        fh.flush()
        try:
            yield
        finally:
            fh.seek(0)
            fh.truncate()  # released: nobody holds it (the kernel drops the flock on close)
            fh.flush()


class FolderError(ValueError):
    """An output folder that cannot be replaced as a whole (it holds files the command
    does not write, or is not a folder); the message names it (an input error, exit 2)."""


class FolderBusy(FolderError):
    """An output folder another run is writing: its lock is held (``holder``: pid, host
    and start time of that run, as it wrote them)."""

    def __init__(self, path, holder):
        self.path, self.holder = path, holder
        super().__init__(
            f"{path} is being written by {holder or 'another process'}; wait for that run to end "
            "(or give another --out)"
        )


def _resolved(out):
    """``out`` as an absolute path; a symlink to a folder is followed, so that the folder it
    names is replaced (and built beside, on its file system), not the link."""
    return os.path.realpath(out) if os.path.islink(out) else os.path.abspath(out)


def beside(out, tag):
    """The path ``.NAME.TAG`` in the folder that holds ``out`` (its lock, its build)."""
    out = _resolved(out)
    return os.path.join(os.path.dirname(out), f".{os.path.basename(out)}.{tag}")


@contextlib.contextmanager
def folder_lock(out, wait=0.0):
    """Hold the lock of the output folder ``out`` (the file ``.NAME.lock`` beside it: the
    folder itself is swapped, so its lock cannot live inside).  Raises :class:`FolderBusy`
    when another run holds it for longer than ``wait`` seconds (default: refuse at once,
    since two runs writing one folder is a mistake, not a queue)."""
    parent = os.path.dirname(_resolved(out))
    os.makedirs(parent, exist_ok=True)
    problem = write_problem(parent)
    if problem:
        raise FolderError(
            f"{out}: cannot write in {parent} ({problem}); the folder is built beside the old one "
            "and swapped in, under a lock there"
        )
    try:
        with file_lock(beside(out, "lock"), wait=wait):
            yield
    except LockHeld as exc:
        raise FolderBusy(out, exc.holder) from None


def swap_folder(new, out):
    """Put the complete folder ``new`` at ``out``: the old ``out`` is renamed aside, ``new``
    renamed in, the old one removed.  If the second rename fails the old folder is put back,
    so ``out`` is always the old folder or the new one, never a mixture."""
    out = _resolved(out)
    if not os.path.lexists(out):
        os.rename(new, out)
        return
    old = tempfile.mkdtemp(prefix=f".{os.path.basename(out)}.old-", dir=os.path.dirname(out))
    os.rmdir(old)  # a unique name for the old folder; rename needs it absent
    os.rename(out, old)
    try:
        os.rename(new, out)
    except BaseException:
        os.rename(old, out)
        raise
    shutil.rmtree(old, ignore_errors=True)


def _foreign(out, owned):
    """Entries of the existing folder ``out`` that ``owned`` (a predicate on names) disowns."""
    if owned is None or not os.path.isdir(out):
        return []
    return sorted(n for n in os.listdir(out) if not owned(n))


@contextlib.contextmanager
def replacing_folder(out, owned=None, build=None, keep_build=(), wait=0.0, lock=True):
    """Build a new ``out`` beside the old one and swap it in when the block ends normally.

    Parameters
    ----------
    out : str
        The output folder (need not exist).
    owned : callable, optional
        ``owned(name)`` is true for the files the command writes; an old folder holding
        anything else is refused (:class:`FolderError`) rather than deleted with the swap.
    build : str, optional
        The build folder (default: a new ``.NAME.build-*`` beside ``out``); one that exists
        is used as it is (a resumed fit's).
    keep_build : tuple of exception types
        The build is kept (not removed) when the block raises one of these (a fit
        interrupted with Ctrl-C keeps its checkpoint for ``--resume``).
    wait : float
        Seconds to wait for another run holding the folder's lock (:func:`folder_lock`).
    lock : bool
        Take the lock (``False``: the caller holds it already, from before it checked ``out``).

    Yields
    ------
    str
        The build folder to write into.
    """
    with folder_lock(out, wait) if lock else contextlib.nullcontext():
        if os.path.lexists(out) and not os.path.isdir(out):
            raise FolderError(f"{out}: not a folder")
        foreign = _foreign(out, owned)
        if foreign:
            raise FolderError(
                f"{out} holds files this command does not write ({', '.join(foreign[:5])}"
                f"{', ...' if len(foreign) > 5 else ''}); it replaces the folder as a whole: give a folder of its own"
            )
        if build is None:
            where = beside(out, "build-")
            build = tempfile.mkdtemp(prefix=os.path.basename(where), dir=os.path.dirname(where))
        os.makedirs(build, exist_ok=True)
        try:
            yield build
            swap_folder(build, out)
        except BaseException as exc:
            if not isinstance(exc, keep_build):
                shutil.rmtree(build, ignore_errors=True)
            raise
