"""How the kernels' helpers compile: :func:`helper`, the one decorator of every function an
entry inlines (numba; the entries themselves: :mod:`scatterbench.models.kernels`)."""

from __future__ import annotations

from numba.extending import register_jitable


def helper(fn=None, *, forceinline=True):
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
    copies of :mod:`~scatterbench.models.kernels.vector`, called from several loops)."""

    options = {"error_model": "numpy", "no_cfunc_wrapper": True}
    if forceinline is not None:
        options["forceinline"] = forceinline
    register = register_jitable(**options)
    return register if fn is None else register(fn)
