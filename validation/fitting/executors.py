"""Executors: where likelihood evaluations and study members run.

Every executor has ``map(fn, items, tasks=None) -> list`` (results in the
order of ``items``, as emcee's ``pool`` expects) and ``close()``.  By default
the work is cut into one contiguous chunk per worker, so each call ships the
function once per worker: right for many cheap calls (a log posterior over
walkers).  Long, uneven calls (a study's members, the fits of a model
comparison, the stability sweep's models) pass ``tasks=len(items)``: one task
per item, so a slow item does not hold a whole chunk back behind one worker.
Randomness never happens inside a mapped call unless it is seeded from the
item itself (the sampler's random draws stay in the calling process; a study
member carries its own seed), so results are identical whatever the executor
and however the items are grouped.

* :class:`SerialExecutor`: in-process (``--workers 1``).
* :class:`ProcessExecutor`: local processes (``--workers N``), ``concurrent.futures``.
* :class:`DaskExecutor`: a ``dask.distributed`` cluster (``--scheduler ADDRESS``,
  or a ``Client``/``LocalCluster`` object in tests).
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import hashlib
import multiprocessing
import pickle

from .settings import _integer

__all__ = ["SerialExecutor", "ProcessExecutor", "DaskExecutor", "SchedulerError", "make_executor"]

#: seconds :class:`DaskExecutor` waits for a scheduler given by address to answer
SCHEDULER_TIMEOUT = 30


class SchedulerError(ValueError):
    """No dask.distributed scheduler answered at the address given (``--scheduler``): the
    address is the user's input (the command line turns it into ``error: ...``, exit 2)."""


def _chunks(items, n):
    """``items`` cut into at most ``n`` contiguous chunks of near-equal length, in order."""
    items = list(items)
    k, r = divmod(len(items), n)
    out, start = [], 0
    for i in range(n):
        stop = start + k + (1 if i < r else 0)
        if stop > start:
            out.append(items[start:stop])
        start = stop
    return out


def _run_chunk(fn, chunk):
    return [fn(x) for x in chunk]


_WORKER_FNS: dict = {}


def _ignore_sigint():
    """Workers leave Ctrl-C to the parent (which stops the pool and says how to resume):
    the terminal sends it to every process of the group, and each would print a traceback."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _run_pickled_chunk(key, blob, chunk):
    """Worker side: unpickle the function once per worker process and reuse it."""
    fn = _WORKER_FNS.get(key)
    if fn is None:
        _WORKER_FNS.clear()
        fn = _WORKER_FNS[key] = pickle.loads(blob)
    return [fn(x) for x in chunk]


@contextlib.contextmanager
def _sigint_between_calls():
    """Ctrl-C during the block is held until the caller asks (``pending()``): a
    KeyboardInterrupt raised inside emcee's wrapper of the log-probability makes it print
    a traceback; raised between calls, the fit stops with one line saying how to resume."""
    import signal
    import threading

    got = []
    if (
        threading.current_thread() is not threading.main_thread()
        or signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    ):
        yield lambda: False  # someone else handles Ctrl-C here: leave it to them
        return
    signal.signal(signal.SIGINT, lambda *_: got.append(True))
    try:
        yield lambda: bool(got)
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    if got:
        raise KeyboardInterrupt


class SerialExecutor:
    workers = 1
    kind = "serial"

    def map(self, fn, items, tasks=None):
        """``[fn(x) for x in items]``; ``tasks`` (how many pieces the work is cut
        into elsewhere) changes nothing in-process."""
        out = []
        with _sigint_between_calls() as pending:
            for x in items:
                out.append(fn(x))
                if pending():
                    break
        return out

    def close(self):
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def describe(self):
        return "serial (in-process)"


class ProcessExecutor(SerialExecutor):
    kind = "processes"

    def __init__(self, workers: int):
        self.workers = _integer("workers", workers, 1)
        # spawn: no inherited locks or threads from the parent (safe with Dask/matplotlib loaded)
        self._fn = self._blob = self._key = None
        self._pool = cf.ProcessPoolExecutor(
            workers, mp_context=multiprocessing.get_context("spawn"), initializer=_ignore_sigint
        )

    def map(self, fn, items, tasks=None):
        """``fn`` over ``items`` in ``tasks`` contiguous chunks (default: one per worker)."""
        # The function (e.g. a likelihood holding the data) is pickled once per
        # distinct function object, not once per call; workers unpickle it once.
        if self._fn is not fn:
            blob = pickle.dumps(fn)
            self._fn, self._blob, self._key = fn, blob, hashlib.sha1(blob).hexdigest()
        futs = [
            self._pool.submit(_run_pickled_chunk, self._key, self._blob, c)
            for c in _chunks(items, tasks or self.workers)
        ]
        return [y for f in futs for y in f.result()]

    def close(self):
        self._pool.shutdown(wait=True, cancel_futures=True)

    def describe(self):
        return f"{self.workers} local processes"


class DaskExecutor(SerialExecutor):
    kind = "dask"

    def __init__(self, address_or_client, timeout=None):
        from dask.distributed import Client

        timeout = SCHEDULER_TIMEOUT if timeout is None else timeout

        if isinstance(address_or_client, Client):
            self.client, self._own = address_or_client, False
        else:
            try:
                self.client = Client(address_or_client, timeout=timeout)
            except OSError as exc:  # refused, unreachable, timed out: the address is the user's input
                raise SchedulerError(
                    f"scheduler: no dask.distributed scheduler answered at {address_or_client!r} "
                    f"within {timeout} s ({exc})"
                ) from None
            self._own = True
        self.workers = max(1, len(self.client.scheduler_info().get("workers", {})))

    def map(self, fn, items, tasks=None):
        """``fn`` over ``items`` in ``tasks`` contiguous chunks (default: one per worker)."""
        chunks = _chunks(items, tasks or self.workers)
        # pure=False: every call runs (no result caching across identical inputs)
        futs = [self.client.submit(_run_chunk, fn, c, pure=False) for c in chunks]
        return [y for part in self.client.gather(futs) for y in part]

    def close(self):
        if self._own:
            self.client.close()

    def describe(self):
        return f"dask.distributed at {self.client.scheduler.address} ({self.workers} workers)"


def make_executor(workers: int = 1, scheduler: str | None = None):
    """``--workers N`` / ``--scheduler ADDRESS`` -> an executor.

    Raises ``ValueError`` for ``workers`` below 1, :class:`SchedulerError` (a ``ValueError``)
    for a scheduler that does not answer.
    """
    if scheduler:
        return DaskExecutor(scheduler)
    if workers == 1:
        return SerialExecutor()
    return ProcessExecutor(workers)
