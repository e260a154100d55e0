"""comparisons.builders.mujoco's compiled path (``passive = "compiled"``, the default): the passive
callback generated from the description (mujoco_codegen) and the step loop in native code
(mujoco_kernels.step_loop, calling mj_forward / mj_RungeKutta / mj_Euler by address): Python is
entered once per run, not four times per step.

It does exactly what the Python path (``passive = "python"``, the readable reference) does, in the same
order; the outputs agree to round-off (tests/test_mujoco_codegen.py). Differences of form only:
- the prescribed motions are tabulated before the run, at every half step (the RK4 stages' times),
  from ``Prescribed.__call__``'s own code run on arrays (its ``math`` taken from numpy; checked
  against scalar calls, and evaluated time by time where numpy cannot run it);
- the loop records, at each output time, qpos, qvel, act, qacc and every element's law value of that
  evaluation; coordinates, forces and states come from those records, and the other outputs (points,
  their velocities and accelerations, energies) from the Python sampler after the run, on the
  recorded states (their kinematics are functions of qpos, qvel only; the accelerations take the
  recorded qacc, since mj_forward run again would see the drives' feed-forward of the run's end).
"""
from __future__ import annotations

import ctypes
import time
import types

import mujoco
import numba
import numpy as np

from comparisons.builders import mujoco_kernels as K
from comparisons.builders.mujoco_cabi import data_offsets, function_address
from comparisons.builders.mujoco_codegen import callbacks, layout, pack
from comparisons.builders.mujoco_mjcf import joint_name, state_activations
from comparisons.builders.mujoco_passive import EXCITATION
from comparisons.builders.mujoco_start import rigid_start
from comparisons.builders.subnormals import flushed
from comparisons.engines.base import EngineError

REPLAYED = ("point", "point_velocity", "point_acceleration", "energy")


def motion_table(p, times: np.ndarray) -> np.ndarray:
    """(q, q', q'') of prescribed motion ``p`` at ``times`` (3 x len(times))."""
    if "motion" in p.values:   # a registered motion's own table over every time at once, not a call each
        return p.values["motion"].table(times)
    call = type(p).__call__
    arrays = types.FunctionType(call.__code__, {**call.__globals__, "math": np})
    at = np.linspace(0, len(times) - 1, min(len(times), 7)).astype(int)
    try:
        table = np.array([np.broadcast_to(np.asarray(v, float), times.shape) for v in arrays(p, times)])
        scalar = np.array([p(t) for t in times[at]]).T
        scale = np.max(np.abs(scalar), axis=1, keepdims=True) + 1e-300
        if table.shape == (3, len(times)) and np.all(np.abs(table[:, at] - scalar) <= 1e-14 * scale):
            return table
    except (TypeError, AttributeError, ValueError):
        pass
    return np.array([p(t) for t in times]).T   # numpy cannot run this motion's code: one call a time


def _uses_arrays(uses: dict, n_steps: int):
    """mujoco.point_from_averages' map as compressed rows: step n's (output, weight) pairs are
    uses_k / uses_w[uses_ptr[n]:uses_ptr[n + 1]]."""
    counts = np.zeros(n_steps + 2, dtype=np.int64)   # n = n_steps: Euler's last evaluation
    for n, pairs in uses.items():
        counts[n + 1] = len(pairs)
    ptr = np.cumsum(counts)
    flat = [pair for n in sorted(uses) for pair in uses[n]]   # the steps that have pairs only (a few of n_steps)
    return ptr, np.array([k for k, _ in flat], dtype=np.int64), np.array([w for _, w in flat], dtype=float)


class _Recorded:
    """The sampler's law values at output k: those the loop recorded (no law is evaluated again)."""

    def __init__(self, model, values, columns):
        self.names, self.values, self.columns, self.k = [f.name for f in model.forces], values, columns, 0

    def law_values(self, m, d) -> dict:   # a plane law's value: its pair (Q_x, Q_y)
        row = self.values[self.k]
        return {n: float(row[c[0]]) if len(c) == 1 else (float(row[c[0]]), float(row[c[1]]))
                for n, c in zip(self.names, self.columns)}


def run(model, s: dict, m, d, drives: list, pairs: list, t_out: np.ndarray, n_sub: int, h: float,
        n_steps: int, weights: np.ndarray, uses: dict, sampler, plan) -> tuple:
    """The run: (outputs at t_out (drive forces and work NaN), drive forces at t_out, wall time [s], largest
    loop gap, tracking error, the work outputs at t_out). ``sampler(forces)`` is mujoco._sampler on (m, d)
    with law values ``forces``; ``plan`` mujoco_passive.work_plan."""
    lay = layout(model)
    ud = d.userdata
    pack(ud, model, m, drives, lay)
    module = callbacks(model)
    nd, n_out = len(drives), len(t_out)
    acc_half, q_at, qd_at, drive_qa = _drive_tables(drives, h, n_steps)
    uses_ptr, uses_k, uses_w = _uses_arrays(uses, n_steps)
    site_pairs = np.array(pairs, dtype=np.int64).reshape(-1, 2)
    rec_qpos, rec_qvel = np.zeros((n_out, m.nq)), np.zeros((n_out, m.nv))
    rec_act, rec_val = np.zeros((n_out, m.na)), np.zeros((n_out, len(lay.values)))
    rec_qacc = np.zeros((n_out, m.nv))
    gaps, drive_at = np.zeros(n_out), np.zeros((n_out, nd))
    clock = np.ctypeslib.as_array((ctypes.c_double * 1).from_address(d._address + 8 * data_offsets()["time"]))
    rk4 = s["integrator"] == "RK4"
    work_of, sign, mass = _work_columns(plan, lay)
    rec_work = np.zeros((n_out, len(work_of)))
    fn_forward = function_address("mj_forward")
    fn_advance = function_address("mj_RungeKutta" if rk4 else "mj_Euler")
    previous = mujoco.get_mjcb_passive(), mujoco.get_mjcb_act_dyn()
    try:
        mujoco.set_mjcb_passive(module.passive.ctypes)
        mujoco.set_mjcb_act_dyn(module.act_dyn.ctypes)
        ud[K.STEP], ud[K.T_STEP] = h, clock[0]
        ud[K.ADVANCE] = 0.0 if rk4 else 1.0   # Euler: the callback advances the laws' states (Passive)
        start = _start(m, d, ud, lay, drives, pairs, acc_half)
        args = (fn_forward, fn_advance, rk4, m._address, d._address, clock, d.qpos, d.qvel, d.act, d.qacc,
                d.site_xpos, ud, n_sub, n_steps, h, weights, acc_half, q_at, qd_at, drive_qa, uses_ptr, uses_k,
                uses_w, site_pairs, float(s["closure_limit"]), lay.values, rec_qpos, rec_qvel, rec_act, rec_val,
                rec_qacc, gaps, drive_at, work_of, sign,
                function_address("mj_subtreeVel") if np.any(work_of == EXCITATION) else 0, d.subtree_linvel, mass,
                model.excitation.block if model.excitation is not None else np.zeros(1), rec_work, float(t_out[-1]))
        K.step_loop.compile(tuple(numba.typeof(a) for a in args))   # (or load) before the clock starts
        with flushed():   # subnormal round-off on a coordinate zero by symmetry (comparisons.builders.subnormals)
            begin = time.perf_counter()
            tracking, failed = K.step_loop(*args)
            if failed == -2:
                raise RuntimeError("mujoco_compiled: a step evaluated the passive forces an unexpected number of times")
            if failed >= 0:
                raise EngineError(f"mujoco: unstable at t = {t_out[failed]:.6g} s (loop gap {gaps[failed]:.3g} m); "
                                  "try a smaller timestep")
            if start is not None:
                rec_qacc[0], drive_at[0] = start
            data = _outputs(model, m, d, ud, sampler, t_out, lay, rec_qpos, rec_qvel, rec_act, rec_qacc, rec_val)
            wall = time.perf_counter() - begin
    finally:
        mujoco.set_mjcb_passive(previous[0])
        mujoco.set_mjcb_act_dyn(previous[1])
    return data, drive_at, wall, float(gaps.max()), float(tracking), rec_work


def _drive_tables(drives: list, h: float, n_steps: int) -> tuple:
    """The drives tabulated: (q'' at every half step (RK4's stages), q and q' at every step, (qposadr, dofadr))."""
    nd = len(drives)
    half = 0.5 * h * np.arange(2 * n_steps + 3)
    tables = [motion_table(p, half) for p, *_ in drives]
    acc_half = np.array([tb[2] for tb in tables]).reshape(nd, len(half))
    q_at = np.array([tb[0, ::2] for tb in tables]).reshape(nd, n_steps + 2)
    qd_at = np.array([tb[1, ::2] for tb in tables]).reshape(nd, n_steps + 2)
    drive_qa = np.array([[qa, da] for _, qa, da, _ in drives], dtype=np.int64).reshape(nd, 2)
    return acc_half, q_at, qd_at, drive_qa


def _work_columns(plan, lay) -> tuple:
    """work_plan on value columns: an element's power column (a plane law's: its power, sign +1)."""
    work_of, sign, mass = plan
    sign_of = np.ones(len(lay.values))
    for e, c in enumerate(lay.columns):
        sign_of[lay.power[e]] = sign[e] if len(c) == 1 else 1.0
    return np.array([lay.power[e] if e >= 0 else e for e in work_of], dtype=np.int64), sign_of, mass


def _start(m, d, ud, lay, drives: list, pairs: list, acc_half: np.ndarray):
    """t = 0: the drive forces refined; with loops, the rigid start's (accelerations, drive forces), else None."""
    nd = len(drives)
    if nd:
        K.set_stage_accelerations(ud, acc_half, 0)
    for _ in range(3 if nd else 0):   # the drive force at t = 0, refined by its own measurement
        ud[K.COUNT] = 0.0
        mujoco.mj_forward(m, d)
        for i, (_, _, da, A) in enumerate(drives):
            b = lay.drives_at + K.DRIVE_SIZE * i
            ud[b + K.D_TAU] = ud[b + K.D_FEED + int(ud[K.COUNT]) - 1] - A * d.qacc[da]
    if not len(pairs):
        return None
    # the loops' soft constraints start with a transient: t = 0 taken as rigid (mujoco_start)
    if not nd:   # (with drives, the refinement above left d evaluated at t = 0)
        advance, ud[K.ADVANCE] = ud[K.ADVANCE], 0.0
        mujoco.mj_forward(m, d)
        ud[K.ADVANCE] = advance
    feeds = [ud[lay.drives_at + K.DRIVE_SIZE * i + K.D_FEED + int(ud[K.COUNT]) - 1] for i in range(nd)]
    return rigid_start(m, d, drives, np.array(feeds), pairs, acc_half[:, 0] if nd else np.zeros(0))


def _outputs(model, m, d, ud, sampler, t_out, lay, rec_qpos, rec_qvel, rec_act, rec_qacc, rec_val) -> np.ndarray:
    """The outputs at t_out: coordinates, law values and states from the loop's records, the others (points,
    their velocities and accelerations, energies) from the Python sampler on each recorded state."""
    data = np.full((len(t_out), len(model.outputs)), np.nan)
    names, acts = [f.name for f in model.forces], state_activations(model, m)
    for c, o in enumerate(model.outputs):
        if o.kind == "coordinate":
            data[:, c] = rec_qpos[:, m.joint(joint_name(o.body, o.dof)).qposadr[0]]
        elif o.kind == "force":
            data[:, c] = rec_val[:, lay.columns[names.index(o.element)][o.component]]
        elif o.kind == "state":
            data[:, c] = rec_act[:, acts[o.element] + o.component]
    replayed = [c for c, o in enumerate(model.outputs) if o.kind in REPLAYED]
    ud[K.ADVANCE] = 0.0   # the replay below reads the recorded states: nothing is advanced
    if replayed:
        recorded = _Recorded(model, rec_val, lay.columns)
        sample = sampler(recorded)
        for k in range(len(t_out)):   # the recorded state again: its kinematics, mass matrix, energies
            d.qpos[:], d.qvel[:], d.act[:], d.time = rec_qpos[k], rec_qvel[k], rec_act[k], t_out[k]
            mujoco.mj_forward(m, d)
            d.qacc[:] = rec_qacc[k]
            recorded.k = k
            data[k, replayed] = np.asarray(sample(), dtype=float)[replayed]
    return data
