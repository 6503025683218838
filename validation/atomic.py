"""Atomic file writes (a temporary file in the same folder, then ``os.replace``), strict
JSON, and an exclusive lock for folders that several runs may write.

A failed or interrupted run therefore never leaves a half-written result and
never damages the previous one; JSON is written without ``NaN`` or ``Infinity``
tokens (they are not JSON: a non-finite number becomes ``null``).
"""

from __future__ import annotations

import contextlib
import datetime
import json
import math
import os
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
