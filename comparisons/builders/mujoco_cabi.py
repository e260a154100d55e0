"""What compiled code needs to reach MuJoCo from numba without Python: where mjData keeps its fields,
where libmujoco keeps its functions, and intrinsics that call those functions by address.

Used by comparisons.builders.mujoco_codegen (the generated passive callback) and mujoco_loop (the
native step loop). Nothing here knows a mechanism or a law.

Field offsets: MuJoCo's bindings expose each array's address but not the C struct's layout, so the
64-bit word of ``mjData`` that holds each pointer is found by matching addresses (as
comparisons.engines.mujoco_native does for three fields). A zero-size array gets the address of the
array allocated after it, so one address can sit in several words; the field itself is then the last
of them (zero-size arrays that share its address come earlier in the struct; ``buffer`` precedes
``qpos``). ``time`` is a double inside the struct: found by a sentinel value. Both are checked on two
probe models of different sizes, which must agree. The offsets depend on the MuJoCo build only; the
generated source bakes them in and names the MuJoCo version, so an upgrade regenerates it.

Addresses of MuJoCo's functions travel as plain integers (a cached kernel must not hold a process's
pointers: libmujoco loads at a different address in every process).
"""
from __future__ import annotations

import ctypes
import functools
import glob
import os

import mujoco
import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

FIELDS = ("qpos", "qvel", "act", "act_dot", "qacc", "qfrc_passive", "userdata", "xpos", "xmat")
_SENTINELS = (1234.5678125, -8765.4321875)   # exact binary fractions: a stored time matches bit for bit

_PROBES = (
    "<mujoco><size nuserdata='3'/><worldbody><body><joint name='j' type='slide'/><inertial pos='0 0 0' "
    "mass='1' diaginertia='1 1 1'/><site name='s'/></body></worldbody><actuator><general joint='j' "
    "dyntype='filter' dynprm='1'/></actuator><sensor><jointpos joint='j'/></sensor></mujoco>",
    "<mujoco><size nuserdata='7'/><worldbody><body><joint name='a' type='hinge'/><joint name='b' "
    "type='slide'/><inertial pos='0 0 0' mass='1' diaginertia='1 1 1'/><site name='s'/><body pos='1 0 0'>"
    "<joint name='c' type='ball'/><inertial pos='0 0 0' mass='1' diaginertia='1 1 1'/><site name='t'/>"
    "</body></body></worldbody><actuator><general joint='a' dyntype='filter' dynprm='1'/><general "
    "joint='b' dyntype='integrator'/></actuator><sensor><jointpos joint='a'/></sensor></mujoco>",
)


def _offsets_of(xml: str, sentinel: float) -> dict[str, int]:
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    data.time = sentinel
    want = {f: getattr(data, f).ctypes.data for f in FIELDS}
    n, margin = 256, None
    # read on 256 words at a time, as mujoco_native does: past the fields sought lies the rest of the
    # struct's pointer block, but reading far beyond the struct could leave its allocation
    while n <= 1 << 18:
        words = np.ctypeslib.as_array((ctypes.c_uint64 * n).from_address(data._address)).copy()
        found = {f: np.flatnonzero(words == a) for f, a in want.items()}
        if margin is not None:
            break
        if all(len(v) for v in found.values()):
            n, margin = n + 64, True   # a field's own word follows its zero-size aliases closely
        else:
            n += 256
    # the array pointers sit after qpos (the word holding qpos followed by the one holding qvel; the
    # ``buffer`` word before it holds the same address); time is a double before them
    anchor = [i for i in found.get("qpos", ()) if i + 1 < len(words) and words[i + 1] == want["qvel"]]
    time = np.flatnonzero(words[:anchor[-1] if anchor else 0].view(np.float64) == sentinel)
    if margin is None or not anchor or len(time) != 1:
        raise RuntimeError("mujoco_cabi: cannot locate mjData's fields")
    out = {f: field_word(v, anchor[-1]) for f, v in found.items()}
    out["time"] = int(time[0])
    return out


def field_word(candidates: np.ndarray, start: int) -> int:
    """The word of a field among the words holding its address, from ``start`` on: the last of the first
    run of adjacent words (its zero-size aliases sit just before it in the struct). A later match is
    not the field: the words read past the struct are the heap's, and one may hold the same address
    by chance (seen once: ``act`` matched 192 words past its own, and two probes disagreed)."""
    c = candidates[candidates >= start]
    i = 0
    while i + 1 < len(c) and c[i + 1] == c[i] + 1:
        i += 1
    return int(c[i])


@functools.lru_cache(maxsize=1)
def data_offsets() -> dict[str, int]:
    """Word offset inside mjData of each field of FIELDS (a pointer) and of ``time`` (a double)."""
    a, b = (_offsets_of(xml, s) for xml, s in zip(_PROBES, _SENTINELS))
    if a != b:
        raise RuntimeError(f"mujoco_cabi: mjData field offsets differ between probe models: {a} vs {b}")
    return a


@functools.lru_cache(maxsize=None)
def function_address(name: str) -> int:
    """The C address of one of libmujoco's functions (the library the bindings loaded)."""
    libs = sorted(glob.glob(os.path.join(os.path.dirname(mujoco.__file__), "libmujoco.so*")))
    if not libs:
        raise RuntimeError("mujoco_cabi: no libmujoco.so* beside the bindings")
    return int(ctypes.cast(getattr(ctypes.CDLL(libs[-1]), name), ctypes.c_void_p).value)


def _as_i8p(builder, value, typ):
    i8p = ir.IntType(8).as_pointer()
    return builder.inttoptr(value, i8p) if isinstance(typ, types.Integer) else builder.bitcast(value, i8p)


@intrinsic
def double_ptr(typingctx, addr):
    """An integer address as a float64 pointer (for numba's carray)."""
    def codegen(context, builder, sig, args):
        return builder.inttoptr(args[0], context.get_value_type(types.CPointer(types.float64)))
    return types.CPointer(types.float64)(addr), codegen


@intrinsic
def call_md(typingctx, fn, m, d):
    """void fn(const mjModel*, mjData*): mj_forward, mj_Euler. m, d: addresses or void pointers."""
    def codegen(context, builder, sig, args):
        i8p = ir.IntType(8).as_pointer()
        f = builder.inttoptr(args[0], ir.FunctionType(ir.VoidType(), [i8p, i8p]).as_pointer())
        builder.call(f, [_as_i8p(builder, args[1], sig.args[1]), _as_i8p(builder, args[2], sig.args[2])])
        return context.get_dummy_value()
    return types.void(fn, m, d), codegen


@intrinsic
def call_md_int(typingctx, fn, m, d, k):
    """void fn(const mjModel*, mjData*, int): mj_RungeKutta."""
    def codegen(context, builder, sig, args):
        i8p, i32 = ir.IntType(8).as_pointer(), ir.IntType(32)
        f = builder.inttoptr(args[0], ir.FunctionType(ir.VoidType(), [i8p, i8p, i32]).as_pointer())
        builder.call(f, [_as_i8p(builder, args[1], sig.args[1]), _as_i8p(builder, args[2], sig.args[2]),
                         builder.trunc(args[3], i32)])
        return context.get_dummy_value()
    return types.void(fn, m, d, k), codegen


@intrinsic
def call_jac(typingctx, fn, m, d, jacp, jacr, point, body):
    """mj_jac(m, d, jacp, jacr, point, body): the translational and rotational Jacobians of a world
    point on a body (jacp, jacr, point: addresses of float64 buffers)."""
    def codegen(context, builder, sig, args):
        i8p, i32 = ir.IntType(8).as_pointer(), ir.IntType(32)
        dp = ir.DoubleType().as_pointer()
        fnty = ir.FunctionType(ir.VoidType(), [i8p, i8p, dp, dp, dp, i32])
        f = builder.inttoptr(args[0], fnty.as_pointer())
        builder.call(f, [_as_i8p(builder, args[1], sig.args[1]), _as_i8p(builder, args[2], sig.args[2]),
                         builder.inttoptr(args[3], dp), builder.inttoptr(args[4], dp), builder.inttoptr(args[5], dp),
                         builder.trunc(args[6], i32)])
        return context.get_dummy_value()
    return types.void(fn, m, d, jacp, jacr, point, body), codegen
