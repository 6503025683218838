"""The memory of the loops on SIMD lanes (:mod:`~scatterbench.models.kernels.vector`): their
scratch (:func:`line_aligned`), and the block copies into it and out of it, compiled as LLVM's
``memcpy`` or as streaming stores.

:func:`copy_into` is a ``memcpy``.  :func:`stream_into` copies with non-temporal stores, which
write whole cache lines to memory without reading them first: a result too large for the caches
then costs the bandwidth of one write, not of a read and a write.  For a smaller result, which
its reader finds in the cache, ordinary stores are faster: FacetBRDF's Mueller matrices on
one thread (``mueller`` then a sum of the result, ad hoc, three rounds alternating), 2.6 MB
of result 27.0-27.6 ns a geometry streamed against 23.4-23.5, 5.1 MB 26.7-27.7 against
24.9-26.9, 7.7 MB 26.4-28.4 against 29.5-32.9, 12.8 MB 27.2-29.4 against 31.4-33.8.
:data:`STREAM_MIN` is where :func:`~scatterbench.models.kernels.vector.put` changes over.

Both take C-contiguous arrays of one dtype that do not overlap (other layouts are refused when
the caller compiles: a strided array's elements are not one block); in Python
(``NUMBA_DISABLE_JIT=1``) both are numpy's copy.  Streaming stores and their fence are x86's
(``vmovntpd``, ``sfence``); on other CPUs :func:`stream_into` is :func:`copy_into`.
"""

from __future__ import annotations

import platform

import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.core.errors import TypingError
from numba.core.extending import intrinsic, overload

from .helper import helper

#: the elements of a result (float64: 8 MB) above which the lanes stream it: above the 2.6-5.1 MB
#: where ordinary stores were as fast or faster (the module docstring), and not below the largest
#: buffer the kernels' callers write and at once read back (16 rows of
#: :data:`scatterbench.models.evaluation.KERNEL_CHUNK` columns; ``tests/test_vector_kernels.py``)
STREAM_MIN = 1 << 20
#: a cache line's bytes on x86-64 (and the other CPUs numba targets), the unit a streaming store writes
LINE_BYTES = 64
#: streaming stores and their fence compiled (x86-64)
STREAMS = platform.machine().lower() in ("x86_64", "amd64")


@helper
def line_aligned(size):
    """An uninitialized float64 array of ``size`` elements that starts on a cache line: a
    scratch array the SIMD lanes load from and store to.  ``np.empty`` aligns to 16 bytes only,
    and where its array starts off a line, 64-byte vector loads straddle two: FacetBRDF's GGX
    loops (three shadowing forms, 2000 geometries in the cache, one thread, five processes each,
    ad hoc) took 17.0-27.6 ns a geometry with ``np.empty``'s scratch, by process, and with this
    one 17.2-18.0 ns in 14 of 15 (one 20.5)."""
    raw = np.empty(size + LINE_BYTES // 8)
    at = ((-raw.ctypes.data) % LINE_BYTES) // 8
    return raw[at : at + size]


def copy_into(dst, dst_at, src, src_at, count):
    """``count`` elements of ``src`` (flat, from ``src_at``) into ``dst`` (flat, from ``dst_at``):
    compiled, one ``memcpy`` (:func:`_memcpy`)."""
    dst.reshape(-1)[dst_at : dst_at + count] = src.reshape(-1)[src_at : src_at + count]


def stream_into(dst, dst_at, src, src_at, count):
    """:func:`copy_into` with streaming stores (:func:`_stream`) where ``dst`` is line-aligned;
    a compiled caller then calls :func:`store_fence` before its results are read elsewhere."""
    copy_into(dst, dst_at, src, src_at, count)


def store_fence():
    """Orders the streaming stores before it before every store after it (``sfence``): they
    are weakly ordered, and another thread must see a range's results written when it sees
    the range done.  Nothing in Python."""


#: the compiled forms inline into their callers (the lanes test reads a lane loop's calls)
_INLINE = {"forceinline": True}


def _checked(name, dst, src, dst_at, src_at, count):
    """The compiled forms' typing checks, ``TypingError`` naming ``name``."""
    if not (isinstance(dst, types.Array) and isinstance(src, types.Array)):
        raise TypingError(f"{name}: arrays only")
    if dst.layout != "C" or src.layout != "C" or dst.dtype != src.dtype:
        raise TypingError(f"{name}: C-contiguous arrays of one dtype only, not {dst} and {src}")
    if not all(isinstance(t, types.Integer) and t.signed for t in (dst_at, src_at, count)):
        raise TypingError(f"{name}: offsets and count are signed integers")


@overload(copy_into, jit_options=_INLINE)
def _copy_into_compiled(dst, dst_at, src, src_at, count):
    _checked("copy_into", dst, src, dst_at, src_at, count)
    return lambda dst, dst_at, src, src_at, count: _memcpy(dst, dst_at, src, src_at, count)


@overload(stream_into, jit_options=_INLINE)
def _stream_into_compiled(dst, dst_at, src, src_at, count):
    _checked("stream_into", dst, src, dst_at, src_at, count)
    if dst.dtype != types.float64:
        raise TypingError(f"stream_into: float64 arrays only, not {dst.dtype}")
    if not STREAMS:
        return lambda dst, dst_at, src, src_at, count: _memcpy(dst, dst_at, src, src_at, count)
    return lambda dst, dst_at, src, src_at, count: _stream(dst, dst_at, src, src_at, count)


@overload(store_fence, jit_options=_INLINE)
def _store_fence_compiled():
    if not STREAMS:
        return lambda: None
    return lambda: _sfence()


def _pointers(context, builder, signature, args):
    """The destination's and source's element pointers at their offsets, and the count, as int64."""
    d = context.make_array(signature.args[0])(context, builder, args[0])
    s = context.make_array(signature.args[2])(context, builder, args[2])
    i64 = ir.IntType(64)

    def wide(v):  # the offsets and count, signed integers of any width, as int64
        return v if v.type == i64 else builder.sext(v, i64)

    return builder.gep(d.data, [wide(args[1])]), builder.gep(s.data, [wide(args[3])]), wide(args[4])


@intrinsic
def _memcpy(typingctx, dst, dst_at, src, src_at, count):
    """:func:`copy_into`'s compiled form, LLVM's ``memcpy``."""
    sig = types.void(dst, dst_at, src, src_at, count)

    def codegen(context, builder, signature, args):
        dp, sp, n = _pointers(context, builder, signature, args)
        size = context.get_abi_sizeof(context.get_data_type(signature.args[0].dtype))
        cgutils.raw_memcpy(builder, dp, sp, n, size)
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def _stream(typingctx, dst, dst_at, src, src_at, count):
    """:func:`stream_into`'s compiled form (float64): ordinary stores up to the destination's
    first line boundary, then a line (eight elements) at a time with LLVM's ``nontemporal``
    stores, aligned (x86's ``vmovntpd``; unaligned ones would be ordinary), the rest ordinary."""
    sig = types.void(dst, dst_at, src, src_at, count)

    def codegen(context, builder, signature, args):
        dp, sp, n = _pointers(context, builder, signature, args)
        i64, per = ir.IntType(64), LINE_BYTES // 8
        line = ir.VectorType(ir.DoubleType(), per)

        def c(v):
            return ir.Constant(i64, v)

        # elements to the first line boundary (0 .. per - 1), at most n
        off = builder.and_(builder.ptrtoint(dp, i64), c(LINE_BYTES - 1))
        head = builder.lshr(builder.and_(builder.sub(c(LINE_BYTES), off), c(LINE_BYTES - 1)), c(3))
        head = builder.select(builder.icmp_signed("<", n, head), n, head)
        lines = builder.sdiv(builder.sub(n, head), c(per))
        tail = builder.add(head, builder.mul(lines, c(per)))
        _plain(builder, dp, sp, c(0), head)
        flag = builder.module.add_metadata([ir.Constant(ir.IntType(32), 1)])
        with cgutils.for_range(builder, lines) as loop:
            at = builder.add(head, builder.mul(loop.index, c(per)))
            v = builder.load(builder.bitcast(builder.gep(sp, [at]), line.as_pointer()), align=8)
            st = builder.store(v, builder.bitcast(builder.gep(dp, [at]), line.as_pointer()), align=LINE_BYTES)
            st.set_metadata("nontemporal", flag)
        _plain(builder, dp, sp, tail, n)
        return context.get_dummy_value()

    return sig, codegen


def _plain(builder, dp, sp, start, stop):
    """Ordinary element copies ``start .. stop - 1`` in :func:`_stream`'s code."""
    with cgutils.for_range(builder, stop, start=start) as loop:
        builder.store(builder.load(builder.gep(sp, [loop.index])), builder.gep(dp, [loop.index]))


@intrinsic
def _sfence(typingctx):
    """:func:`store_fence`'s compiled form, x86's ``sfence``."""

    def codegen(context, builder, signature, args):
        fn = builder.module.declare_intrinsic("llvm.x86.sse.sfence", fnty=ir.FunctionType(ir.VoidType(), []))
        builder.call(fn, [])
        return context.get_dummy_value()

    return types.void(), codegen
