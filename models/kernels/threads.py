"""Compiled loops over a range, run on Python threads (the loops release the GIL).

Every loop here has the form ``loop(*args, lo, hi)`` and writes only its own part of the
result, so :func:`spread` gives the same bits on any number of threads.  A ``prange`` entry
per loop did the same, but numba compiles a ``prange`` function through its parallel
pipeline and has LLVM optimize the loop's code again in it: a ``prange`` entry cost 7.8 s
of a cold cache beside its loop's own 6.2 s (a Cook-Torrance vector loop), 13.7 s for the
detector aperture's 20-line sum.
"""

from __future__ import annotations

import itertools
import os
from concurrent.futures import ThreadPoolExecutor

import numba

__all__ = ["spread"]

_POOL = []  # made on first use; forgotten in a fork's child, which has the object but no threads


def _forget():
    _POOL.clear()


os.register_at_fork(after_in_child=_forget)


#: ranges per thread: a thread that finishes early (or was descheduled less) takes the next
#: one, so that one slow thread does not hold the call up as with one range each.  FacetBRDF
#: on 10^7 geometries, 16 threads against one, into ``out=`` / into a fresh result, with 2, 4,
#: 8, 16 ranges per thread: 10.64x/10.26x, 11.56x/10.63x, 12.38x/11.19x, 11.54x/10.31x (one run
#: each, 16-core device machine, ad hoc probe run by ``benchmarks/scaling_16core.sh``, part 2)
PER_THREAD = 8


def spread(loop, args, n, grain):
    """``loop(*args, lo, hi)`` over ``0 .. n - 1``: in one call below ``2 * grain``, otherwise
    on up to ``numba.get_num_threads()`` threads (what ``numba.set_num_threads`` sets, as for
    numba's own parallel loops), the calling thread one of them, each taking the next of up to
    :data:`PER_THREAD` equal ranges per thread (each at least ``grain``) until none is left."""
    k = min(numba.get_num_threads(), n // max(grain, 1))
    if k <= 1:
        loop(*args, 0, n)
        return
    if not _POOL:
        _POOL.append(
            ThreadPoolExecutor(numba.config.NUMBA_NUM_THREADS, thread_name_prefix="scatterbench-kernel")
        )
    parts = min(PER_THREAD * k, n // grain)
    cuts = [n * j // parts for j in range(parts + 1)]
    ticket = itertools.count()  # next() on it is atomic under the GIL: each range runs once

    def work():
        while (j := next(ticket)) < parts:
            loop(*args, cuts[j], cuts[j + 1])

    rest = [_POOL[0].submit(work) for _ in range(k - 1)]
    work()
    for f in rest:
        f.result()
