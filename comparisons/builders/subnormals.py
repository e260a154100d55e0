"""Subnormal numbers flushed to zero while a peer's step loop runs (x86-64's MXCSR: FTZ and DAZ).

A coordinate that is zero in exact arithmetic (the device's out-of-plane tilt on an axial drive)
picks up round-off in MuJoCo's own arithmetic (1e-33 m after the first steps), which the damping
then carries below 2.2e-308, the smallest normal double. The processor handles such numbers on a
slow path: MuJoCo's axial drive cases ran 1.3-1.5x the CPU time of the same runs with them flushed
(docs/performance.md). Flushing changes only values below 2.2e-308 (each becomes zero), so every
output is the same to that absolute level. The control register belongs to the thread, so the
flag is set around the loop and the caller's value put back after it, also on an error. On a
processor other than x86-64 nothing changes.
"""
from __future__ import annotations

import contextlib
import platform

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

FLUSH = 0x8040   # MXCSR: flush-to-zero (bit 15) and denormals-are-zero (bit 6)
ON_X86 = platform.machine().lower() in ("x86_64", "amd64")


def _call(builder, name: str, slot) -> None:
    fnty = ir.FunctionType(ir.VoidType(), [ir.IntType(8).as_pointer()])
    fn = cgutils.get_or_insert_function(builder.module, fnty, name)
    builder.call(fn, [builder.bitcast(slot, ir.IntType(8).as_pointer())])


@intrinsic
def _stmxcsr(typingctx):
    def codegen(context, builder, signature, args):
        slot = cgutils.alloca_once(builder, ir.IntType(32))
        _call(builder, "llvm.x86.sse.stmxcsr", slot)
        return builder.load(slot)
    return types.uint32(), codegen


@intrinsic
def _ldmxcsr(typingctx, value):
    def codegen(context, builder, signature, args):
        slot = cgutils.alloca_once(builder, ir.IntType(32))
        builder.store(args[0], slot)
        _call(builder, "llvm.x86.sse.ldmxcsr", slot)
        return context.get_dummy_value()
    return types.none(types.uint32), codegen


@njit(cache=True)
def control_register() -> int:
    """This thread's MXCSR (x86-64 only)."""
    return _stmxcsr()


@njit(cache=True)
def set_control_register(value) -> None:
    """Load ``value`` (a uint32) into this thread's MXCSR (x86-64 only)."""
    _ldmxcsr(value)


@contextlib.contextmanager
def flushed():
    """Within the block, this thread flushes subnormal results and inputs to zero (x86-64 only)."""
    if not ON_X86:
        yield
        return
    before = control_register()
    set_control_register(np.uint32(before | FLUSH))
    try:
        yield
    finally:
        set_control_register(np.uint32(before))
