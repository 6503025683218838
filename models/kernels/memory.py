"""The memory of the loops on SIMD lanes (:mod:`~scatterbench.models.kernels.vector`): their
scratch (:func:`line_aligned`), and the block copies into it and out of it, compiled as LLVM's
``memcpy`` or with streaming stores.

:func:`copy_into` is a ``memcpy``.  :func:`copy_rows` copies rows, each a ``memcpy`` or, for a
result too large for the caches, with non-temporal stores, which write whole cache lines to
memory without reading them first: the result then costs the bandwidth of one write, not of a
read and a write.  For a smaller result, which its reader finds in the cache, ordinary stores
are faster: FacetBRDF's Mueller matrices on one thread (``mueller`` then a sum of the result,
ad hoc, three rounds alternating), 2.6 MB of result 27.0-27.6 ns a geometry streamed against
23.4-23.5, 5.1 MB 26.7-27.7 against 24.9-26.9, 7.7 MB 26.4-28.4 against 29.5-32.9, 12.8 MB
27.2-29.4 against 31.4-33.8.  :data:`STREAM_MIN` is where
:func:`~scatterbench.models.kernels.vector.put` changes over.

They all take C-contiguous arrays of one dtype that do not overlap (other layouts are refused
when the caller compiles: a strided array's elements are not one block); in Python
(``NUMBA_DISABLE_JIT=1``) they are numpy's copies.  Streaming stores and their fence are x86's
(``vmovntpd``, ``sfence``); on other CPUs every row is a ``memcpy``.

:func:`fill` (a value into a row: a line's worth a store, then one element a store) and
:func:`pick_rows` (rows of a model set's parameters, picked by column per geometry) are loops
LLVM neither vectorizes nor unrolls: they run once per call or once per block, and LLVM
optimizes the copies again in each lane entry.  Written so, they took 6-9% off the lane
entries' compilation (eight entries, Cook-Torrance's, the diffuse and the single-scattering
ones but the first, which types the helpers: 3.34 / 3.33 s of CPU against 3.56 / 3.62 s with
the loops LLVM vectorized, a fresh cache, two rounds alternating, ad hoc), and the
vectorized picking was the slower: a model set of 24 elements over 2 x 10^5 geometries (both
cores, best of 15, three rounds alternating, ad hoc) took 12.6-13.1 ns a geometry of
Cook-Torrance picked one element at a time against 14.3-16.5 vectorized, FacetBRDF 14.1-15.2
against 16.3-16.7, the same sums.
"""

from __future__ import annotations

import contextlib
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


def fill(dst, dst_at, count, value):
    """``count`` elements of ``dst`` (flat, from ``dst_at``) set to ``value``: compiled, a line's
    worth a store in a loop LLVM neither vectorizes nor unrolls (:func:`_fill`).  For what a call
    writes once, not per block: as loops LLVM vectorized and unrolled, such fills were code it
    optimized again in every entry."""
    dst.reshape(-1)[dst_at : dst_at + count] = value


def pick_rows(dst, dst_at, dst_step, src, index, lo, rows, count):
    """``rows`` rows of ``count`` elements picked by column: element ``k`` of row ``r`` of ``dst``
    (flat, from ``dst_at + r * dst_step``) is ``src[r, index[lo + k]]`` (``index`` in ``0 ..
    src.shape[1] - 1``, unchecked: the caller's to check).  Compiled, two loops LLVM neither
    vectorizes nor unrolls (:func:`_pick`): vectorized, the picking was the largest loop of
    every lane entry's parameter copy, optimized again in each."""
    for r in range(rows):
        o = dst_at + r * dst_step
        dst.reshape(-1)[o : o + count] = src[r, index[lo : lo + count]]


def copy_rows(dst, dst_at, dst_step, src, src_at, src_step, rows, count, stream):
    """``rows`` rows of ``count`` elements, row ``r`` of ``src`` (flat) from ``src_at + r *
    src_step`` into ``dst`` (flat) from ``dst_at + r * dst_step``: compiled, one loop over the rows
    (:func:`_rows`), each row a ``memcpy``, or with ``stream`` (float64, x86-64) streamed to
    memory and fenced once after the last (``sfence``: streaming stores are weakly ordered, and
    another thread must see the rows written when it sees the copy done)."""
    for r in range(rows):
        copy_into(dst, dst_at + r * dst_step, src, src_at + r * src_step, count)


def _checked(name, arrays, *ints):
    """The compiled forms' typing checks of their ``arrays`` (C-contiguous, one dtype) and
    integer arguments, ``TypingError`` naming ``name``."""
    if not all(isinstance(a, types.Array) for a in arrays):
        raise TypingError(f"{name}: arrays only")
    if any(a.layout != "C" or a.dtype != arrays[0].dtype for a in arrays):
        raise TypingError(f"{name}: C-contiguous arrays of one dtype only, not {', '.join(map(str, arrays))}")
    if not all(isinstance(t, types.Integer) and t.signed for t in ints):
        raise TypingError(f"{name}: offsets, steps and counts are signed integers")


# the compiled forms inline into their callers (the lanes test reads a lane loop's calls)
@overload(copy_into, jit_options={"forceinline": True})
def _copy_into_compiled(dst, dst_at, src, src_at, count):
    _checked("copy_into", (dst, src), dst_at, src_at, count)
    return lambda dst, dst_at, src, src_at, count: _memcpy(dst, dst_at, src, src_at, count)


@overload(copy_rows, jit_options={"forceinline": True})
def _copy_rows_compiled(dst, dst_at, dst_step, src, src_at, src_step, rows, count, stream):
    _checked("copy_rows", (dst, src), dst_at, dst_step, src_at, src_step, rows, count)
    if not isinstance(stream, types.Boolean):
        raise TypingError(f"copy_rows: stream is a boolean, not {stream}")
    return lambda dst, dst_at, dst_step, src, src_at, src_step, rows, count, stream: _rows(
        dst, dst_at, dst_step, src, src_at, src_step, rows, count, stream
    )


@overload(fill, jit_options={"forceinline": True})
def _fill_compiled(dst, dst_at, count, value):
    _checked("fill", (dst,), dst_at, count)
    return lambda dst, dst_at, count, value: _fill(dst, dst_at, count, dst.dtype.type(value))


@overload(pick_rows, jit_options={"forceinline": True})
def _pick_rows_compiled(dst, dst_at, dst_step, src, index, lo, rows, count):
    _checked("pick_rows", (dst, src), dst_at, dst_step, lo, rows, count)
    if src.ndim != 2:  # _pick reads a row's length from the second dimension
        raise TypingError(f"pick_rows: src is 2-d (rows by columns), not {src}")
    if not (isinstance(index, types.Array) and index.ndim == 1 and index.layout == "C"):
        raise TypingError(f"pick_rows: index is a C-contiguous 1-d array, not {index}")
    if not (isinstance(index.dtype, types.Integer) and index.dtype.bitwidth == 64):
        raise TypingError(f"pick_rows: index holds 64-bit integers, not {index.dtype}")
    return lambda dst, dst_at, dst_step, src, index, lo, rows, count: _pick(
        dst, dst_at, dst_step, src, index, lo, rows, count
    )


def _wide(builder, v):
    """A signed integer of any width as int64."""
    i64 = ir.IntType(64)
    return v if v.type == i64 else builder.sext(v, i64)


@intrinsic
def _memcpy(typingctx, dst, dst_at, src, src_at, count):
    """:func:`copy_into`'s compiled form, LLVM's ``memcpy``."""
    sig = types.void(dst, dst_at, src, src_at, count)

    def codegen(context, builder, signature, args):
        d = context.make_array(signature.args[0])(context, builder, args[0])
        s = context.make_array(signature.args[2])(context, builder, args[2])
        dp, sp = (
            builder.gep(d.data, [_wide(builder, args[1])]),
            builder.gep(s.data, [_wide(builder, args[3])]),
        )
        size = context.get_abi_sizeof(context.get_data_type(signature.args[0].dtype))
        cgutils.raw_memcpy(builder, dp, sp, _wide(builder, args[4]), size)
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def _rows(typingctx, dst, dst_at, dst_step, src, src_at, src_step, rows, count, stream):
    """:func:`copy_rows`' compiled form: its loop over the rows, which LLVM does not unroll
    (:func:`_rolled_loop`: unrolled 16 times, a row's copy stood 16 times in every lane entry)."""
    sig = types.void(dst, dst_at, dst_step, src, src_at, src_step, rows, count, stream)

    def codegen(context, builder, signature, args):
        d = context.make_array(signature.args[0])(context, builder, args[0])
        s = context.make_array(signature.args[3])(context, builder, args[3])
        da, ds, sa, ss, nr, n = (_wide(builder, args[k]) for k in (1, 2, 4, 5, 6, 7))
        size = context.get_abi_sizeof(context.get_data_type(signature.args[0].dtype))
        streamed = None  # no streaming code at all but on x86-64, in float64
        if STREAMS and signature.args[0].dtype == types.float64:
            streamed = builder.icmp_unsigned("!=", args[8], ir.Constant(args[8].type, 0))
        with _rolled_loop(builder, nr) as r:
            dp = builder.gep(d.data, [builder.add(da, builder.mul(r, ds))])
            sp = builder.gep(s.data, [builder.add(sa, builder.mul(r, ss))])
            if streamed is None:
                cgutils.raw_memcpy(builder, dp, sp, n, size)
            else:
                with builder.if_else(streamed) as (then, otherwise):
                    with then:
                        _streamed_row(builder, dp, sp, n)
                    with otherwise:
                        cgutils.raw_memcpy(builder, dp, sp, n, size)
        if streamed is not None:
            with builder.if_then(streamed):
                fence = ir.FunctionType(ir.VoidType(), [])
                builder.call(builder.module.declare_intrinsic("llvm.x86.sse.sfence", fnty=fence), [])
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def _fill(typingctx, dst, dst_at, count, value):
    """:func:`fill`'s compiled form: a cache line's worth of elements a store (a vector of the
    value), then one store an element for the rest, in loops LLVM keeps as they are
    (:func:`_rolled_loop`): one store an element throughout made a 100-geometry call of the
    lanes 1-3% slower than the vectorized fills (``benchmarks/kernel_ab.py --what small``)."""
    sig = types.void(dst, dst_at, count, dst.dtype)

    def codegen(context, builder, signature, args):
        d = context.make_array(signature.args[0])(context, builder, args[0])
        at, n, value = _wide(builder, args[1]), _wide(builder, args[2]), args[3]
        i64, size = ir.IntType(64), context.get_abi_sizeof(value.type)
        per = LINE_BYTES // size
        vec = ir.VectorType(value.type, per)
        splat = builder.insert_element(ir.Constant(vec, ir.Undefined), value, ir.Constant(ir.IntType(32), 0))
        splat = builder.shuffle_vector(splat, splat, ir.Constant(ir.VectorType(ir.IntType(32), per), None))
        whole = builder.sdiv(n, ir.Constant(i64, per))
        with _rolled_loop(builder, whole) as k:
            p = builder.gep(d.data, [builder.add(at, builder.mul(k, ir.Constant(i64, per)))])
            builder.store(splat, builder.bitcast(p, vec.as_pointer()), align=size)  # an element's alignment
        done = builder.mul(whole, ir.Constant(i64, per))
        with _rolled_loop(builder, builder.sub(n, done)) as k:
            builder.store(value, builder.gep(d.data, [builder.add(at, builder.add(done, k))]))
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def _pick(typingctx, dst, dst_at, dst_step, src, index, lo, rows, count):
    """:func:`pick_rows`' compiled form: a load and a store an element (:func:`_rolled_loop`)."""
    sig = types.void(dst, dst_at, dst_step, src, index, lo, rows, count)

    def codegen(context, builder, signature, args):
        d = context.make_array(signature.args[0])(context, builder, args[0])
        s = context.make_array(signature.args[3])(context, builder, args[3])
        ix = context.make_array(signature.args[4])(context, builder, args[4])
        da, ds, first, nr, n = (_wide(builder, args[k]) for k in (1, 2, 5, 6, 7))
        columns = builder.extract_value(s.shape, 1)  # a C-contiguous row's length
        with _rolled_loop(builder, nr) as r:
            row, at = builder.mul(r, columns), builder.add(da, builder.mul(r, ds))
            with _rolled_loop(builder, n) as k:
                col = builder.load(builder.gep(ix.data, [builder.add(first, k)]))
                v = builder.load(builder.gep(s.data, [builder.add(row, col)]))
                builder.store(v, builder.gep(d.data, [builder.add(at, k)]))
        return context.get_dummy_value()

    return sig, codegen


def _streamed_row(builder, dp, sp, n):
    """``n`` float64 elements from ``sp`` to ``dp``: a ``memcpy`` up to the destination's first
    line boundary, then a line (eight elements) at a time with LLVM's ``nontemporal`` stores,
    aligned (x86's ``vmovntpd``; unaligned ones would be ordinary), and a ``memcpy`` of the rest."""
    i64, per = ir.IntType(64), LINE_BYTES // 8
    line = ir.VectorType(ir.DoubleType(), per).as_pointer()

    def c(v):
        return ir.Constant(i64, v)

    # elements to the first line boundary (0 .. per - 1), at most n
    off = builder.and_(builder.ptrtoint(dp, i64), c(LINE_BYTES - 1))
    head = builder.lshr(builder.and_(builder.sub(c(LINE_BYTES), off), c(LINE_BYTES - 1)), c(3))
    head = builder.select(builder.icmp_signed("<", n, head), n, head)
    lines = builder.sdiv(builder.sub(n, head), c(per))
    tail = builder.add(head, builder.mul(lines, c(per)))
    cgutils.raw_memcpy(builder, dp, sp, head, 8)
    flag = builder.module.add_metadata([ir.Constant(ir.IntType(32), 1)])
    with _rolled_loop(builder, lines) as k:
        at = builder.add(head, builder.mul(k, c(per)))
        v = builder.load(builder.bitcast(builder.gep(sp, [at]), line), align=8)
        st = builder.store(v, builder.bitcast(builder.gep(dp, [at]), line), align=LINE_BYTES)
        st.set_metadata("nontemporal", flag)
    cgutils.raw_memcpy(builder, builder.gep(dp, [tail]), builder.gep(sp, [tail]), builder.sub(n, tail), 8)


@contextlib.contextmanager
def _rolled_loop(builder, count):
    """A loop over ``0 .. count - 1`` (int64) in generated code, yielding its index, that LLVM
    neither unrolls nor vectorizes (``llvm.loop`` metadata): the copies' loops are over a
    result's 16 rows, a row's 32 lines or a block's 256 columns at most, which unrolled and
    vectorized were code to compile again in every entry."""
    i64, module = ir.IntType(64), builder.module
    before = builder.basic_block
    body, after = builder.append_basic_block("lines"), builder.append_basic_block("lines.done")
    builder.cbranch(builder.icmp_signed(">", count, ir.Constant(i64, 0)), body, after)
    builder.position_at_end(body)
    k = builder.phi(i64)
    k.add_incoming(ir.Constant(i64, 0), before)
    yield k
    step = builder.add(k, ir.Constant(i64, 1))
    k.add_incoming(step, builder.basic_block)
    back = builder.cbranch(builder.icmp_signed("<", step, count), body, after)
    off = [
        module.add_metadata([ir.MetaDataString(module, "llvm.loop.unroll.disable")]),
        module.add_metadata(
            [ir.MetaDataString(module, "llvm.loop.vectorize.enable"), ir.Constant(ir.IntType(1), 0)]
        ),
    ]
    loop_id = module.add_metadata(off)
    loop_id.operands = (loop_id, *off)  # a loop's id refers to itself (LLVM's convention)
    back.set_metadata("llvm.loop", loop_id)
    builder.position_at_end(after)
