"""Executors: where likelihood evaluations and study members run.

Every executor has ``map(fn, items, tasks=None, meanwhile=None) -> list`` (results in the
order of ``items``, as emcee's ``pool`` expects; ``meanwhile``: this process's own work done
while the tasks run, :meth:`SerialExecutor.map`) and ``close()``.  By default
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

Workers share their machine's cores: each runs the compiled kernels, BLAS and OpenMP on its
share of them (:func:`kernel_threads`, :func:`_share_cores`), not on one thread per core as
each library would, so that workers on one machine do not start more threads than it has
cores.  The thread count changes no result.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import hashlib
import importlib
import multiprocessing
import os
import pickle
import signal
import threading
import time

from threadpoolctl import threadpool_limits

from .scheduler import SchedulerError, check_scheduler_address, probe_scheduler
from .settings import _integer

__all__ = [
    "SerialExecutor",
    "ProcessExecutor",
    "DaskExecutor",
    "SchedulerError",
    "make_executor",
    "check_scheduler_address",
    "default_workers",
]

#: seconds :class:`DaskExecutor` waits for a scheduler given by address to answer: one deadline
#: for the connection, distributed's handshake and the scheduler's first reply
SCHEDULER_TIMEOUT = 30


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


def _local_cores() -> int:
    """The cores this process may run on (its affinity: a container's limit, not the host's)."""

    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def default_workers() -> int:
    """``--workers``' default for the commands that run the whole suite (``report``,
    ``validate``, ``nightly``): the cores this process may run on."""
    return _local_cores()


def kernel_threads(workers: int) -> int:
    """The compiled kernels' threads in each of ``workers`` local processes: their share of the
    cores, at least one."""
    return max(1, _local_cores() // workers)


_LIMITED = None  # the BLAS/OpenMP thread limit this process applied (see _share_cores)


def _share_cores(threads):
    """Run this thread's compiled kernels, and this process's BLAS and OpenMP, on ``threads``
    threads: a worker's share of its machine's cores (:func:`kernel_threads`).

    Left at their defaults, every worker starts a thread per core and the workers' threads
    then wait on each other (the full report's model comparison, 8 fits on 2 workers on 2
    cores, ``python benchmarks/study_workers.py --baseline <d6f7214>``: 129.9 s with a
    kernel thread per core in each, against 63.1 s in-process and 34.3 s with one); BLAS's
    threads also spin between calls, so the workers' small eigenvalue and least-squares
    problems kept the other workers' cores busy (the stability sweep on 2 workers, ``--study
    sweep``: 25.2 s against 10.1 s in-process; 8.6 s with BLAS limited too).  numba's count is
    per thread (a Dask worker's task threads each set theirs); the BLAS limit is per process
    and applied once."""
    global _LIMITED
    import numba  # numba (heavy): loaded only in a worker that runs kernels

    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    if _LIMITED != threads:
        import scipy.linalg  # noqa: F401  (loads scipy's own BLAS now, so that the limit covers it)

        threadpool_limits(limits=threads)
        _LIMITED = threads


#: the modules a local worker imports as it starts (as ``multiprocessing``'s forkserver
#: preload): the fitting machinery (emcee, SciPy's optimizers, numba, the models), ~1 s that
#: a worker otherwise spends at its first task; names, not imports, because the executors sit
#: below the modules that use them
PRELOAD = ("scatterbench.validation.fitting.fit",)


def _worker_init(threads, preload=()):
    """A local worker's set-up: it leaves Ctrl-C to the parent (which stops the pool and says
    how to resume: the terminal sends it to every process of the group, and each would print
    a traceback), runs on its share of the cores (:func:`_share_cores`) and imports
    ``preload``."""

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _share_cores(threads)
    for name in preload:
        importlib.import_module(name)


def _started():
    """A task that does nothing: :class:`ProcessExecutor` submits one per worker to start them."""


#: the functions a worker keeps unpickled: a report's sections run at once
#: (:func:`scatterbench.validation.report.build.build_report`), so one worker's tasks
#: alternate between a few studies' functions
WORKER_FUNCTIONS = 8


def _run_pickled_chunk(key, blob, chunk):
    """Worker side: unpickle the function once per worker process and reuse it."""
    fn = _WORKER_FNS.pop(key, None)
    if fn is None:
        fn = pickle.loads(blob)
        while len(_WORKER_FNS) >= WORKER_FUNCTIONS:
            _WORKER_FNS.pop(next(iter(_WORKER_FNS)))  # the least recently used
    _WORKER_FNS[key] = fn
    return [fn(x) for x in chunk]


@contextlib.contextmanager
def _sigint_between_calls():
    """Ctrl-C during the block is held until the caller asks (``pending()``): a
    KeyboardInterrupt raised inside emcee's wrapper of the log-probability makes it print
    a traceback; raised between calls, the fit stops with one line saying how to resume."""

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


def _gathered(futs, meanwhile, gather):
    """``gather()`` of submitted ``futs`` after running ``meanwhile`` (if any) in this thread; if
    ``meanwhile`` raises an error, the tasks are still waited for (none is left running behind
    the caller's back) before it propagates.  An interrupt (Ctrl-C) propagates at once, as it
    does from the wait itself: the executor's ``close`` cancels what has not started."""
    try:
        if meanwhile is not None:
            meanwhile()
    except Exception:
        for f in futs:
            with contextlib.suppress(BaseException):
                f.result()
        raise
    return gather()


class SerialExecutor:
    workers = 1
    kind = "serial"
    #: whether each worker process runs one task at a time (what the report needs to compute
    #: sections at once: :func:`scatterbench.validation.report.build.side_by_side`)
    one_task_per_process = False

    def map(self, fn, items, tasks=None, meanwhile=None):
        """``[fn(x) for x in items]``; ``tasks`` (how many pieces the work is cut into
        elsewhere) changes nothing in-process.

        ``meanwhile``: a callable of no arguments that the calling thread runs once (here before
        the items; elsewhere while the tasks run, before it waits for them): work of this
        process that it needs after the map, such as importing what will read the results.
        What it returns is dropped; what it raises propagates (from local processes or a
        cluster, once the tasks have ended)."""
        if meanwhile is not None:
            meanwhile()
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
    one_task_per_process = True

    def __init__(self, workers: int, preload=PRELOAD):
        self.workers = _integer("workers", workers, 1)
        # spawn: no inherited locks or threads from the parent (safe with Dask/matplotlib loaded)
        self._fn = self._blob = self._key = None
        self._lock = threading.Lock()
        self._pool = cf.ProcessPoolExecutor(
            workers,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_worker_init,
            initargs=(kernel_threads(workers), tuple(preload)),
        )
        # every worker started now (a pool starts them at its first tasks), so that they import
        # ``preload`` while this process sets its own work up
        for _ in range(self.workers):
            self._pool.submit(_started)

    def map(self, fn, items, tasks=None, meanwhile=None):
        """``fn`` over ``items`` in ``tasks`` contiguous chunks (default: one per worker);
        ``meanwhile`` (:meth:`SerialExecutor.map`) runs here while they run."""
        # The function (e.g. a likelihood holding the data) is pickled once per
        # distinct function object, not once per call; workers unpickle it once.
        # one lock: sections call map from threads at once (the last function is per executor)
        with self._lock:
            if self._fn is not fn:
                blob = pickle.dumps(fn)
                self._fn, self._blob, self._key = fn, blob, hashlib.sha1(blob).hexdigest()
            key, blob = self._key, self._blob
        futs = [
            self._pool.submit(_run_pickled_chunk, key, blob, c) for c in _chunks(items, tasks or self.workers)
        ]
        return _gathered(futs, meanwhile, lambda: [y for f in futs for y in f.result()])

    def close(self):
        self._pool.shutdown(wait=True, cancel_futures=True)

    def describe(self):
        return f"{self.workers} local processes"


class DaskExecutor(SerialExecutor):
    kind = "dask"

    def __init__(self, address_or_client, timeout=None):
        from dask.distributed import Client  # dask.distributed (heavy): loaded only for a cluster

        if isinstance(address_or_client, Client):
            self.client, self._own = address_or_client, False
        else:
            self.client, self._own = _connect(address_or_client, timeout), True
        info = self.client.scheduler_info().get("workers", {})
        self.workers = max(1, len(info))
        self.one_task_per_process = bool(info) and all(w["nthreads"] == 1 for w in info.values())
        self._threads = _dask_kernel_threads(info, self.client.run(_local_cores) if info else {})

    def map(self, fn, items, tasks=None, meanwhile=None):
        """``fn`` over ``items`` in ``tasks`` contiguous chunks (default: one per worker);
        ``meanwhile`` (:meth:`SerialExecutor.map`) runs here while they run."""
        chunks = _chunks(items, tasks or self.workers)
        # pure=False: every call runs (no result caching across identical inputs)
        futs = [self.client.submit(_run_chunk_dask, fn, c, self._threads, pure=False) for c in chunks]
        return _gathered(futs, meanwhile, lambda: [y for part in self.client.gather(futs) for y in part])

    def close(self):
        if self._own:
            self.client.close()

    def describe(self):
        return f"dask.distributed at {self.client.scheduler.address} ({self.workers} workers)"


def _connect(address, timeout=None):
    """A ``Client`` of the scheduler at ``address``, with one deadline (``timeout``, default
    :data:`SCHEDULER_TIMEOUT`) for the connection, the handshake and the first reply
    (:func:`~scatterbench.validation.fitting.scheduler.probe_scheduler`: ``Client``'s own timeout
    covers only the connection); :class:`SchedulerError` when no scheduler can be used there."""
    from dask.distributed import Client, Security  # dask.distributed (heavy): loaded only for a cluster

    timeout = SCHEDULER_TIMEOUT if timeout is None else timeout
    address = check_scheduler_address(address)
    end = time.monotonic() + timeout
    probe_scheduler(address, timeout, Security().get_connection_args("client"))
    left = max(1.0, end - time.monotonic())
    try:
        return Client(address, timeout=left)
    except Exception as exc:  # noqa: BLE001 - the scheduler went away or changed since the probe
        raise SchedulerError(
            f"scheduler {address!r}: answered, then the client could not connect within {left:.0f} s "
            f"({type(exc).__name__}: {exc})"
        ) from None


def _dask_kernel_threads(info, cores):
    """``{worker address: kernel threads}``: a host's cores shared among the task threads of
    all its workers (``info``: the scheduler's view of the workers; ``cores``: each worker's
    :func:`_local_cores`), at least one each, as local processes share theirs."""
    per_host = {}
    for w in info.values():
        per_host[w["host"]] = per_host.get(w["host"], 0) + w["nthreads"]
    return {a: max(1, cores.get(a, 1) // per_host[w["host"]]) for a, w in info.items()}


def _run_chunk_dask(fn, chunk, threads):
    """A chunk on a Dask worker, on the worker's share of its host's cores (:func:`_share_cores`;
    one thread for a worker that joined after the executor was made)."""
    from dask.distributed import get_worker  # dask.distributed (heavy): loaded only for a cluster

    _share_cores(threads.get(get_worker().address, 1))
    return _run_chunk(fn, chunk)


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
