"""The compiled passive callback of comparisons.builders.mujoco, generated once per set of laws.

No line here or in the generated code is written for a mechanism or a law: ``source`` writes, for
each law of the set (generated.law_set: every law registered by the modules that register the
description's laws, the model layer's own always among them), one branch that calls the law's
registry functions (its ``Law.force`` and ``Law.rate``, bound by name in the generated module's
namespace) between the generic helpers of mujoco_kernels, as comparisons.builders.mujoco.Passive
does in Python; ``passive`` loops over the description's force elements in order and takes each
element's branch by its law's code. The generated ``mjcb_passive`` and ``mjcb_act_dyn`` are numba
``cfunc``s that read mjData's fields at offsets found by mujoco_cabi; every number of the description
(the counts of coordinates, bodies, states, drives and body slots, each element's law code, block and
parameters, whether it has a direction, whether the description has work outputs or an excitation,
the drive armatures, the ground motion) lives in ``mjData.userdata`` (``pack``), so the source depends
on the set of laws and the MuJoCo build only. The device's drive, its seismic models (a restrainer, a
building) and every mechanism of the same laws share one compiled callback: a module made per
description shape compiled the kernels again for each (the restrainer's 1.8 s, the building's 3.1 s of
a cold gate's runs).

Compiled once per set of laws: the source is written to ``mujoco_passive_<hash>.py`` in numba's cache
folder (nsd_core.compilation.numba_cache) and compiled with ``cache=True``, so a later process loads the machine
code. numba's cache checks only that file, not the law functions it calls, so the hash covers, besides
the source, each law's module, name and the source files of everything it calls (transitively through
numba functions): an edit of a law (or of a device force it calls) gives a new file. A law defined
inside a function (``<locals>``) cannot be told from another of the same name, so its object's
identity enters the hash too (compiled again in each process).
The helper modules the source imports (mujoco_kernels, mujoco_cabi, nsd_core.ground.motions) enter it
as well: their code is compiled into the generated file's cache.

A law with a state gets, besides its rate's call (RK4: handed to MuJoCo), a generated
``advance_<rate>`` (one RK4 step in time along x linear over the interval, calling that same rate
function: its source is in the generated text, so the hash covers it): with Euler (userdata's ADVANCE)
the callback advances the state itself at each later evaluation, as mujoco_passive.Passive does.

A plane law's element (two slide coordinates, a two-component state: nsd_core.model.laws) has its own
block (PLANE_*, below): both coordinates' addresses, both values (Q_x, Q_y) and, for the work
outputs, its power Q_x x' + Q_y y' as a third value column (``Layout.columns``, ``Layout.power``),
with a generated ``advance2_<rate>`` (the same RK4 step, both components at once).

A points element with a ``direction`` takes points_state_along, one without points_state; with an
excitation the callback adds ground_values at the stage's time through ground_load on the body slots
(which then include every body with a mass); both are data (the element table, the header), as the
ground motion's block is (userdata's tail).
"""
from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numba
import numpy as np

from comparisons.builders import generated
from comparisons.builders import mujoco_kernels as K
from comparisons.builders import mujoco_cabi
from comparisons.builders.mujoco_cabi import data_offsets, function_address
from nsd_core.ground import motions as ground_motion
from comparisons.builders.mujoco_mjcf import joint_name, state_activations
from nsd_core.model.description import GROUND, Model
from nsd_core.model.laws import JOINT, PLANE, POINTS


HELPERS = (K, mujoco_cabi, ground_motion)   # the modules the generated source calls into
# a plane element's block: x's qposadr, dofadr, the state's first activation, x at the last advance,
# Q_x and x', then y's qposadr, dofadr, y at the last advance, Q_y and y', its power and the constant 1
PL_SLOT, PL_PREVIOUS, PL_VALUE, PL_Y, PL_POWER, PLANE_HEAD = 2, 3, 4, 6, 11, 13
# the description's numbers the source does not hold, after mujoco_kernels' header and scratch: the
# counts (coordinates, velocities, states, MuJoCo's bodies), the userdata ``ud`` covers, the element
# table (its length and start), the states' rates, 1 with work outputs
G_NQ, G_NV, G_NA, G_NBODY, G_CORE, G_N_ELEMENTS, G_ELEMENTS_AT, G_RATES_AT, G_WORK, SHAPE_SIZE = range(10)
SHAPE_AT = K.HEADER + K.SCRATCH
# an element's row of the table: its law's code (index in the law set), its block, its parameters
# [start, end), 1 for a points element with a direction
E_CODE, E_AT, E_P0, E_P1, E_ALONG, ELEMENT_SIZE = range(6)


@dataclass(frozen=True)
class Layout:
    """Where each number sits in mjData.userdata (float64 indices)."""
    size: int
    nq: int
    nv: int
    na: int
    drives_at: int
    slots: tuple[str, ...]           # the bodies that carry an element end (mujoco_kernels' body slots)
    slots_at: int
    blocks: tuple[int, ...]          # each force element's block
    params: tuple[tuple[int, int], ...]   # each element's parameters [start, end)
    rates_at: int                    # the states' rates, by actuator id
    values: np.ndarray               # each value column's index: an element's last law value (a plane law's
                                     # Q_x, Q_y and its power), x' beside it
    excitation_at: int               # the excitation's ground_values block, last (0: none)
    columns: tuple[tuple[int, ...], ...] = ()   # each element's value columns (a plane law's: Q_x, Q_y)
    power: tuple[int, ...] = ()      # each element's column whose value times the next is its power
    elements_at: int = 0             # the element table (ELEMENT_SIZE a row, in the description's order)

    @property
    def core(self) -> int:
        """The userdata the generated source addresses as ``ud`` (all but the excitation's block)."""
        return self.excitation_at or self.size


def layout(model: Model) -> Layout:
    """The layout of ``model``'s userdata (its sizes follow from the description alone, so the MJCF can
    declare ``nuserdata`` before MuJoCo compiles it)."""
    nq = sum(len(b.joint.dofs()) for b in model.bodies)
    nv = nq   # hinges and slides only (mujoco_mjcf): one qpos per dof
    na = sum(f.law.state_size for f in model.forces)
    slots = tuple(dict.fromkeys(b for f in model.forces if f.law.acts_on == POINTS
                                for b in (f.body_a, f.body_b) if b != GROUND))
    if model.excitation is not None:   # every body with a mass feels -m a_g: a slot holds its Jacobians
        slots += tuple(b.name for b in model.bodies if b.mass > 0.0 and b.name not in slots)
    slots_at = SHAPE_AT + SHAPE_SIZE
    drives_at = at = slots_at + K.slot_size(nv) * len(slots)
    at += K.DRIVE_SIZE * len(model.prescribed)
    blocks, params, values, columns, power = [], [], [], [], []
    for f in model.forces:
        head, value = (K.POINTS_HEAD, K.P_VALUE) if f.law.acts_on == POINTS else (K.JOINT_HEAD, K.J_VALUE)
        if f.law.acts_on == PLANE:
            head = PLANE_HEAD
            columns.append((len(values), len(values) + 1))
            power.append(len(values) + 2)
            values += [at + PL_VALUE, at + PL_Y + 3, at + PL_POWER]
        else:
            columns.append((len(values),))
            power.append(len(values))
            values.append(at + value)
        blocks.append(at)
        params.append((at + head, at + head + len(f.parameters)))
        at += head + len(f.parameters)
    elements_at = at
    at += ELEMENT_SIZE * len(model.forces)
    exc = 0 if model.excitation is None else len(model.excitation.block)
    return Layout(at + na + exc, nq, nv, na, drives_at, slots, slots_at, tuple(blocks), tuple(params), at,
                  np.array(values, dtype=np.int64), at + na if exc else 0, tuple(columns), tuple(power),
                  elements_at)


def pack(ud: np.ndarray, model: Model, m: mujoco.MjModel, drives: list, lay: Layout) -> None:
    """Write every number the callback needs into ``ud`` (mjData.userdata); drives as
    comparisons.builders.mujoco._compile gives them: (Prescribed, qposadr, dofadr, armature)."""
    if (m.nq, m.nv, m.na, m.nuserdata) != (lay.nq, lay.nv, lay.na, lay.size):
        raise RuntimeError(f"mujoco_codegen: the compiled model's sizes {(m.nq, m.nv, m.na, m.nuserdata)} "
                           f"are not the layout's {(lay.nq, lay.nv, lay.na, lay.size)}")
    ud[:] = 0.0
    ud[K.JAC_FN] = function_address("mj_jac")   # < 2^53: exact as a float64
    code = {law.name: i for i, law in enumerate(laws_of(model))}
    work = float(any(o.kind == "work" for o in model.outputs))
    ud[SHAPE_AT:SHAPE_AT + SHAPE_SIZE] = (lay.nq, lay.nv, lay.na, m.nbody, lay.core, len(model.forces),
                                          lay.elements_at, lay.rates_at, work)
    for e, (f, at, (p0, p1)) in enumerate(zip(model.forces, lay.blocks, lay.params)):
        row = lay.elements_at + ELEMENT_SIZE * e
        along = f.law.acts_on == POINTS and f.direction is not None
        ud[row:row + ELEMENT_SIZE] = (code[f.law.name], at, p0, p1, float(along))
    ud[K.T_COMMIT] = np.nan   # the states not advanced yet (ADVANCE is the run's: mujoco_compiled)
    ud[K.N_DRIVES], ud[K.DRIVES_AT] = len(drives), lay.drives_at
    ud[K.N_SLOTS], ud[K.SLOTS_AT] = len(lay.slots), lay.slots_at
    for i, body in enumerate(lay.slots):
        s, b = lay.slots_at + K.slot_size(lay.nv) * i, m.body(body).id
        ud[s + K.S_BODY] = b
        if model.excitation is not None:   # MuJoCo's own mass and centre (body frame), as its gravity's
            ud[s + K.S_MASS] = m.body_mass[b]
            ud[s + K.S_COM:s + K.S_COM + 3] = m.body_ipos[b]
    if model.excitation is not None:
        block = model.excitation.block
        ud[K.EXCITATION_SIZE] = len(block)
        ud[lay.excitation_at:lay.excitation_at + len(block)] = block
    for i, (_, _, da, A) in enumerate(drives):
        b = lay.drives_at + K.DRIVE_SIZE * i
        ud[b + K.D_DOF], ud[b + K.D_ARM] = da, A
    activations = state_activations(model, m)
    for f, at, (p0, p1) in zip(model.forces, lay.blocks, lay.params):
        slot = activations.get(f.name, -1)
        if f.law.acts_on == POINTS:
            for end, (body, p) in enumerate(((f.body_a, f.point_a), (f.body_b, f.point_b))):
                ud[at + 4 * end] = -1 if body == GROUND else lay.slots.index(body)
                ud[at + 4 * end + 1:at + 4 * end + 4] = np.asarray(p, float)
            ud[at + K.P_SLOT] = slot
            if f.direction is not None:
                ud[at + K.P_DIRECTION:at + K.P_DIRECTION + 3] = np.asarray(f.direction, float)
        elif f.law.acts_on == PLANE:
            for k, base in zip(f.dofs, (at, at + PL_Y)):
                j = m.joint(joint_name(f.joint, k))
                ud[base], ud[base + 1] = j.qposadr[0], j.dofadr[0]
            ud[at + PL_SLOT], ud[at + PL_POWER + 1] = slot, 1.0
        else:
            j = m.joint(joint_name(f.joint, f.dof))
            ud[at], ud[at + 1] = j.qposadr[0], j.dofadr[0]
            ud[at + K.J_SLOT] = slot
        ud[p0:p1] = f.parameters


def laws_of(model: Model) -> list:
    """The set of laws ``model``'s callback is generated for (generated.law_set); an element's law code is
    its law's index here."""
    return generated.law_set(model.forces)


def source(laws) -> tuple[str, dict]:
    """The generated module's text for ``laws`` (laws_of's list) and the law functions it expects bound
    by name (``law_<code>``, ``rate_<code>``)."""
    bound = generated.bound_laws(laws)
    o = data_offsets()
    words = max(o.values()) + 1
    ptr = lambda field, shape: f"carray(double_ptr(np.int64(w[{o[field]}])), {shape})"  # noqa: E731
    lines = _module_head(laws, bound) + _passive_head(o, words, ptr)
    branch = "if"
    for i, law in enumerate(laws):
        lines.append(f"        {branch} c == {i}:   # {law.name}")
        lines += ["        " + line for line in _law_lines(i, law)]
        branch = "elif"
    lines += _passive_tail(o) + _act_dyn_source(o, words, ptr)
    return "\n".join(lines), bound


def _module_head(laws, bound: dict) -> list[str]:
    """The module's docstring (the builds and the bound laws), its imports and each rate's advance."""
    return [
        f'"""Generated by comparisons.builders.mujoco_codegen: do not edit. MuJoCo {mujoco.__version__}, '
        f'numba {numba.__version__}.',
        "Bound by the loader before this runs: " + ", ".join(
            f"{name} = {generated.identity(fn)}" for name, fn in bound.items()) + '."""',
        "import numpy as np",
        "from numba import carray, cfunc, njit, types",
        "from comparisons.builders.mujoco_cabi import double_ptr",
        "from comparisons.builders.mujoco_kernels import apply_points, drive_feeds, finish_bodies, ground_load, "
        "points_state, points_state_along, prepare_bodies",
        "from nsd_core.ground.motions import ground_values",
        "", "",
        *[line for i, law in enumerate(laws) if law.rate is not None
          for line in (_advance_plane_source if law.acts_on == PLANE else _advance_source)(f"rate_{i}")]]


def _shape_value(k: int) -> str:
    """The source reading entry ``k`` (G_*) of the description's numbers in userdata, as an int64."""
    return f"np.int64(head[{SHAPE_AT + k}])"


def _passive_head(o: dict, words: int, ptr) -> list[str]:
    """``passive``'s start: the counts from userdata, mjData's arrays, the states' advance since the last
    call, the body slots, the loop over the element table."""
    return [
        "@cfunc(types.void(types.voidptr, types.voidptr), cache=True)",
        "def passive(m, d):",
        f"    w = carray(d, ({words},), dtype=np.uint64)",
        f"    ud_addr = np.int64(w[{o['userdata']}])",
        f"    head = carray(double_ptr(ud_addr), ({SHAPE_AT + SHAPE_SIZE},))",
        # the kernels' integer arguments as int64 values, never literals: numba compiles a kernel once per
        # literal value it is called with
        "    nq, nv, na, nbody, core = " + ", ".join(_shape_value(k) for k in (G_NQ, G_NV, G_NA, G_NBODY, G_CORE)),
        "    ud = carray(double_ptr(ud_addr), (core,))",
        f"    qpos = {ptr('qpos', '(nq,)')}",
        f"    qvel = {ptr('qvel', '(nv,)')}",
        f"    qfrc = {ptr('qfrc_passive', '(nv,)')}",
        f"    xpos = {ptr('xpos', '(nbody, 3)')}",
        f"    xmat = {ptr('xmat', '(nbody, 9)')}",
        f"    act = {ptr('act', '(na,)')}",
        # the states' advance along the actual change of x since the last one (Euler; see Passive)
        f"    advance = ud[{K.ADVANCE}] != 0.0",
        f"    now = carray(d, ({o['time'] + 1},), dtype=np.float64)[{o['time']}]",
        f"    dt = now - ud[{K.T_COMMIT}]",
        "    moved = na > 0 and advance and not dt <= 0.0   # (NaN before the first: x recorded, no advance)",
        f"    rates_at, work = {_shape_value(G_RATES_AT)}, head[{SHAPE_AT + G_WORK}] != 0.0",
        f"    if ud[{K.N_SLOTS}] > 0.0:",
        "        prepare_bodies(m, d, ud, ud_addr, xpos, qvel, nv)",
        f"    table = {_shape_value(G_ELEMENTS_AT)}",
        f"    for e in range({_shape_value(G_N_ELEMENTS)}):",
        f"        row = table + {ELEMENT_SIZE} * e",
        f"        c, at = np.int64(ud[row + {E_CODE}]), np.int64(ud[row + {E_AT}])",
        f"        p = ud[np.int64(ud[row + {E_P0}]):np.int64(ud[row + {E_P1}])]",
    ]


def _law_lines(i: int, law) -> list[str]:
    """Law ``i``'s branch of the element loop: the element's (x, x'), its law and state, its value kept,
    its force applied (Passive.law's arithmetic, in its order)."""
    if law.acts_on == PLANE:
        return _plane_lines(i, law)
    if law.acts_on == POINTS:
        lines = [f"    if ud[row + {E_ALONG}] != 0.0:",
                 "        x, xd = points_state_along(ud, at, xpos, xmat, nv)",
                 "    else:",
                 "        x, xd = points_state(ud, at, xpos, xmat, nv)"]
        slot, previous, value = K.P_SLOT, K.P_PREVIOUS, K.P_VALUE
    else:
        assert law.acts_on == JOINT, law.acts_on
        lines = ["    x, xd = qpos[int(ud[at])], qvel[int(ud[at + 1])]"]
        slot, previous, value = K.J_SLOT, K.J_PREVIOUS, K.J_VALUE
    if law.state is None:
        lines.append(f"    f = law_{i}(x, xd, p)")
    else:   # as Passive.law: advanced (Euler), or its rate handed to MuJoCo by mjcb_act_dyn (RK4)
        lines += [f"    k = int(ud[at + {slot}])",
                  "    s = act[k]",
                  "    if moved:",
                  "        if dt > 0.0:",
                  f"            s = advance_rate_{i}(ud[at + {previous}], x, s, dt, p)",
                  "            act[k] = s",
                  f"        ud[at + {previous}] = x",
                  "    elif not advance:",
                  f"        ud[rates_at + k] = rate_{i}(x, xd, s, p)",
                  f"    f = law_{i}(x, xd, s, p)"]
    lines += [f"    ud[at + {value}] = f",
              "    if work:   # x' beside the value: the step loop's power",
              f"        ud[at + {value + 1}] = xd"]
    return lines + ["    apply_points(ud, at, f, nv)" if law.acts_on == POINTS else "    qfrc[int(ud[at + 1])] += f"]


def _passive_tail(o: dict) -> list[str]:
    """``passive``'s end: the states' time, the ground's load, the bodies' forces, the drives' feeds."""
    return [
        "    if moved:",
        f"        ud[{K.T_COMMIT}] = now",
        f"    n_ground = np.int64(ud[{K.EXCITATION_SIZE}])",
        "    if n_ground > 0:   # -m a_g(t) at every body's centre, t: this stage's time (its block: core on)",
        "        ground = carray(double_ptr(ud_addr + 8 * core), (n_ground,))",
        "        ag = ground_values(now, ground, 0)",
        "        ground_load(ud, xmat, ag[4], ag[5], nv)",
        f"    if ud[{K.N_SLOTS}] > 0.0:",
        "        finish_bodies(ud, qfrc, nv)",
        f"    if ud[{K.N_DRIVES}] > 0.0:",
        "        drive_feeds(ud, qfrc, now)"]


def _act_dyn_source(o: dict, words: int, ptr) -> list[str]:
    """``act_dyn``: the states' rates that ``passive`` kept, into act_dot."""
    return ["", "",
            "@cfunc(types.float64(types.voidptr, types.voidptr, types.int32), cache=True)",
            "def act_dyn(m, d, actuator):",
            "    # the states' rates into act_dot (one actuator holds them all: mujoco_mjcf)",
            f"    w = carray(d, ({words},), dtype=np.uint64)",
            f"    ud_addr = np.int64(w[{o['userdata']}])",
            f"    head = carray(double_ptr(ud_addr), ({SHAPE_AT + SHAPE_SIZE},))",
            f"    na, rates_at, core = {_shape_value(G_NA)}, {_shape_value(G_RATES_AT)}, {_shape_value(G_CORE)}",
            "    if na == 0:",
            "        return 0.0",
            "    ud = carray(double_ptr(ud_addr), (core,))",
            f"    act_dot = {ptr('act_dot', '(na,)')}",
            "    for k in range(na):",
            "        act_dot[k] = ud[rates_at + k]",
            "    return ud[rates_at]",
            ""]


def _advance_source(rate: str) -> list[str]:
    """The generated advance of a state whose rate function is bound as ``rate``: one RK4 step in time
    over dt along x linear from x0 to x1 (Passive.advance, the same arithmetic in the same order)."""
    return [
        "@njit(cache=True, inline=\"always\")",
        f"def advance_{rate}(x0, x1, s, dt, p):",
        "    xd = (x1 - x0) / dt",
        "    xm = 0.5 * (x0 + x1)",
        f"    k1 = {rate}(x0, xd, s, p)",
        f"    k2 = {rate}(xm, xd, s + 0.5 * dt * k1, p)",
        f"    k3 = {rate}(xm, xd, s + 0.5 * dt * k2, p)",
        f"    k4 = {rate}(x1, xd, s + dt * k3, p)",
        "    return s + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)",
        "", ""]


def _plane_lines(i: int, law) -> list[str]:
    """A plane law's branch (Passive.plane_law, the same arithmetic): both coordinates, the state advanced
    (Euler) or its rates handed to MuJoCo (RK4), (Q_x, Q_y) applied and kept."""
    y = f"at + {PL_Y}"
    lines = ["    x, xd = qpos[int(ud[at])], qvel[int(ud[at + 1])]",
             f"    y, yd = qpos[int(ud[{y}])], qvel[int(ud[{y} + 1])]"]
    if law.state is None:
        lines.append(f"    fx, fy = law_{i}(x, y, xd, yd, 0.0, 0.0, p)")
    else:
        lines += [f"    k = int(ud[at + {PL_SLOT}])",
                  "    sx, sy = act[k], act[k + 1]",
                  "    if moved:",
                  "        if dt > 0.0:",
                  f"            sx, sy = advance2_rate_{i}(ud[at + {PL_PREVIOUS}], ud[{y} + 2], x, y, sx, sy, dt, p)",
                  "            act[k], act[k + 1] = sx, sy",
                  f"        ud[at + {PL_PREVIOUS}], ud[{y} + 2] = x, y",
                  "    elif not advance:",
                  f"        rx, ry = rate_{i}(x, y, xd, yd, sx, sy, p)",
                  "        ud[rates_at + k], ud[rates_at + k + 1] = rx, ry",
                  f"    fx, fy = law_{i}(x, y, xd, yd, sx, sy, p)"]
    lines += [f"    ud[at + {PL_VALUE}], ud[{y} + 3] = fx, fy",
              "    if work:   # x', y' beside the values, and the power as a third value column",
              f"        ud[at + {PL_VALUE + 1}], ud[{y} + 4] = xd, yd",
              f"        ud[at + {PL_POWER}] = fx * xd + fy * yd"]
    return lines + ["    qfrc[int(ud[at + 1])] += fx", f"    qfrc[int(ud[{y} + 1])] += fy"]


def _advance_plane_source(rate: str) -> list[str]:
    """``_advance_source`` for a plane law's rate (Passive.plane_step, the same arithmetic in the same order)."""
    return [
        "@njit(cache=True, inline=\"always\")",
        f"def advance2_{rate}(x0, y0, x1, y1, sx, sy, dt, p):",
        "    xd, yd = (x1 - x0) / dt, (y1 - y0) / dt",
        "    xm, ym = 0.5 * (x0 + x1), 0.5 * (y0 + y1)",
        f"    a1, b1 = {rate}(x0, y0, xd, yd, sx, sy, p)",
        f"    a2, b2 = {rate}(xm, ym, xd, yd, sx + 0.5 * dt * a1, sy + 0.5 * dt * b1, p)",
        f"    a3, b3 = {rate}(xm, ym, xd, yd, sx + 0.5 * dt * a2, sy + 0.5 * dt * b2, p)",
        f"    a4, b4 = {rate}(x1, y1, xd, yd, sx + dt * a3, sy + dt * b3, p)",
        "    return (sx + dt / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4), sy + dt / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4))",
        "", ""]


def fingerprint(text: str, bound: dict) -> str:
    """The name of the generated file: its text, HELPERS and the laws it is bound to (generated.py)."""
    return generated.fingerprint(text, bound, HELPERS)


def callbacks(model: Model):
    """The generated module (``passive``, ``act_dyn``: numba cfuncs; keep it alive while installed) for
    ``model``'s set of laws, compiled once per set and process, from numba's disk cache when an earlier
    process compiled it."""
    text, bound = source(laws_of(model))
    return generated.load(text, bound, HELPERS, "mujoco_passive")

