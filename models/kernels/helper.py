"""How the kernels compile: :func:`helper`, the one decorator of every function an entry
inlines, and :func:`entry_point`, that of the entries (numba; which functions are entries:
:mod:`scatterbench.models.kernels`)."""

from __future__ import annotations

import contextlib
import threading

from numba import njit
from numba.core import config
from numba.extending import register_jitable

#: one switch of numba's cache folder at a time: two threads' side by side could restore it in
#: the wrong order and leave it on ours for the rest of the process (the report's sections run
#: on threads; R-bar's integrand is imported, and a vector loop decorated, on first use)
_CACHING_LOCK = threading.RLock()


@contextlib.contextmanager
def caching_in(path):
    """numba's cache locator reads ``config.CACHE_DIR`` when a function is decorated: set to
    ``path`` for the block, one thread at a time (:data:`_CACHING_LOCK`)."""
    with _CACHING_LOCK:
        old = config.CACHE_DIR
        config.CACHE_DIR = path
        try:
            yield
        finally:
            config.CACHE_DIR = old


def helper(fn=None, *, forceinline=True, fastmath=False):
    """``fn`` compiled where a compiled function calls it, in the caller's process, without the
    on-disk cache, inlined by LLVM (``forceinline``); from Python it is ``fn`` itself.

    A helper is numba's ``register_jitable`` (an overload of ``fn`` by itself), not an
    ``@njit`` dispatcher, for what a first run spends: a dispatcher compiles a Python wrapper
    and a C wrapper for every helper, which nothing calls (the callers inline its IR), and a
    copy of it per literal argument (``smith_g`` two: Cook-Torrance passes the constant
    ``SMITH``, the facet kernel its option); an overload has neither wrapper and types its
    arguments as plain values first.  The report's two largest compile-ahead groups took
    11-19% less CPU (each in a fresh process and cache, three rounds alternating with
    ad3c607's ``@njit`` helpers, ad hoc: Cook-Torrance's and the Monte Carlo's 15.3 / 15.0 /
    13.7 s against 17.4 / 17.7 / 16.9 s, the facet's 12.6 / 11.9 / 11.5 s against 14.4 / 13.3
    / 13.1 s); the kernel tests' bit equalities hold, 12 models' checksums at 10^5 geometries
    equal ad3c607's, their time per geometry within the noise.

    ``forceinline=None``: that of the compiled function that calls it first (numba's flags
    not set are inherited), which is what LLVM then does with it: inlined into a kernel
    (Cook-Torrance's ``fresnel_average``: with ``False`` LLVM called it from the lanes' loop,
    which ran 3.5-5x slower, ad hoc), or left to LLVM's own measure in an entry (the block
    copies of :mod:`~scatterbench.models.kernels.vector`, called from several loops).
    ``fastmath``: numba's (a set of LLVM's flags), for the helper's own operations."""

    options = {"error_model": "numpy", "no_cfunc_wrapper": True, "fastmath": fastmath}
    if forceinline is not None:
        options["forceinline"] = forceinline
    register = register_jitable(**options)
    return register if fn is None else register(fn)


def entry_point(fn=None, *, nogil=False):
    """``fn`` compiled when Python first calls it, into numba's on-disk cache (once per machine),
    with numpy's error model (a division by zero gives inf, as numpy's), releasing the GIL with
    ``nogil`` (the loops :func:`~scatterbench.models.kernels.threads.spread` runs on threads),
    and without the C wrapper (``no_cfunc_wrapper``) that only a caller through a C function
    pointer would use, which nothing here is: a facet lane entry's code is 4713 lines of
    assembly against 4915 with it.  What that saves of a first run is within the noise: the
    report's compile-ahead groups (each in a fresh process and cache, two rounds alternating,
    ad hoc) 29.5 / 30.0 s of CPU against 29.7 / 31.2 s, Cook-Torrance's and the Monte Carlo's
    alone (the lane entries without it, three rounds) 11.1 / 11.1 / 11.1 s against 11.5 / 11.6 /
    11.5 s."""
    compile_ = njit(cache=True, error_model="numpy", nogil=nogil, no_cfunc_wrapper=True)
    return compile_ if fn is None else compile_(fn)
