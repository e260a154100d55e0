"""MuJoCo's passive callback and step loop in compiled code (numba), calling the shared force laws.

The device's force elements and hysteretic states are the same as in mujoco_engine's Python callback
(``_Device``), evaluated by the same scalar laws of ``nsd_core.device.forces`` (rope_tension_scalar,
wire_tension_scalar, spring_push_scalar, sma_slope_scalar, bouc_wen_slope_scalar and the strain
integrators advance_*_scalar): one implementation of each law, compiled here instead of called from
Python. Three pieces:

- ``userdata``: every constant of the elements and the committed hysteretic states live in MuJoCo's
  own ``mjData.userdata`` (MJCF ``<size nuserdata>``), one float64 block (layout below), so the C
  callback needs nothing but its ``mjData``.
- ``passive_callback()``: an ``mjcb_passive`` C function (numba ``cfunc``) that reads ``d->qpos``,
  ``d->qfrc_passive`` and ``d->userdata`` and adds the ropes, wires and spring, exactly as
  ``_Device.passive``. MuJoCo's Python bindings accept its ctypes pointer (their "Callbacks" docs) and
  then call it without the GIL. The three field offsets inside ``mjData`` are found once per process
  by matching the addresses the bindings expose (checked on two instances), so no header is parsed.
- ``step_loop``: the drive loop of MujocoEngine.run (feed-forward on the heavy drive slide, reset of
  the driven coordinates, commits of the hysteretic states, samples at output times) compiled, calling
  MuJoCo's own ``mj_step`` / ``mj_forward`` through their C addresses: Python is entered once per run.

A MuJoCo fatal error inside the native loop cannot become a Python exception (the bindings' error
guard is not around it); MuJoCo's non-fatal instability handling (warnings, data reset) is caught by
the same loop-closure / finiteness check as the Python loop, at every output sample.
"""
from __future__ import annotations

import ctypes
import functools
import glob
import os

import mujoco
import numpy as np
from numba import carray, cfunc, njit, types

from comparisons.builders.mujoco_cabi import call_md, double_ptr
from nsd_core.device.forces import (advance_spring_zeta_scalar, advance_wire_stress_scalar, bouc_wen_slope_scalar,
                             rope_tension_scalar, sma_slope_scalar, spring_push_scalar, wire_tension_scalar)

# ---- userdata layout (float64 indices) ----------------------------------------------------------
E0, E1, ZC0, ZW0, NR, NW, PREDICT, SUBSTEPS = range(8)   # 8: unused (the stiffnesses are per rope)
WIRE = 9            # 11 values: E, Y, alpha, n, fT, a, Em, eps_t, c, area, natural_length
SPRING = 20         # 6 values: kse, ksd, beta, gamma, n, free_length
ZETA, X_C, Z_UP, Z_DN = 26, 27, 28, 29
HEADER = 30         # then: D (n_r + n_w, 3), rope L0 and k_r (n_r each), sigma, eps_c, s_up, s_dn (n_w each)


@njit(cache=True, inline="always")
def userdata_size(n_ropes, n_wires):
    return HEADER + 3 * (n_ropes + n_wires) + 2 * n_ropes + 4 * n_wires


@njit(cache=True, inline="always")
def _blocks(ud):
    nr, nw = int(ud[NR]), int(ud[NW])
    d0 = HEADER
    l0 = d0 + 3 * (nr + nw)
    sg = l0 + 2 * nr      # rope L0 at l0 + i, rope stiffness at l0 + nr + i
    return nr, nw, d0, l0, sg, sg + nw, sg + 2 * nw, sg + 3 * nw   # ..., sigma, eps_c, s_up, s_dn


def sigma_slice(ud) -> slice:
    """Where the committed wire stresses sit in ``ud``."""
    sg, nw = _blocks(ud)[4], int(ud[NW])
    return slice(sg, sg + nw)


def pack_userdata(ud: np.ndarray, g, unit_vector, sigma, zeta, eps_c, x_c, predict: bool, substeps: int) -> None:
    """Write the element constants and the committed states (as _Device holds them) into ``ud``."""
    nr, nw = g.n_ropes, g.n_wires
    ud[:] = 0.0
    ud[E0], ud[E1], ud[ZC0], ud[ZW0] = float(unit_vector[0]), float(unit_vector[1]), g.cap_rest_z, g.wall_rest_z
    ud[NR], ud[NW], ud[PREDICT], ud[SUBSTEPS] = nr, nw, float(predict), substeps
    ud[WIRE:WIRE + 11] = tuple(g.wire)
    ud[SPRING:SPRING + 6] = tuple(g.spring)
    ud[ZETA], ud[X_C] = zeta, x_c
    _, _, d0, l0, sg, ec, _, _ = _blocks(ud)
    ud[d0:l0] = np.vstack([g.rope_offsets, g.wire_offsets]).ravel()
    ud[l0:l0 + nr] = g.rope_natural_length
    ud[l0 + nr:sg] = g.rope_stiffness   # one value, or a perturbed rope's own (engines/perturb.py)
    ud[sg:sg + nw], ud[ec:ec + nw] = sigma, eps_c
    refresh_slopes(ud)


@njit(cache=True)
def _element(ud, d0, i, nr, cx, cy, cz, wz):
    """Element i's vector (upper end minus lower end) and length."""
    vx = ud[d0 + 3 * i] + cx
    vy = ud[d0 + 3 * i + 1] + cy
    vz = ud[d0 + 3 * i + 2] + cz
    if i >= nr:
        vz -= wz
    return vx, vy, vz, np.sqrt(vx * vx + vy * vy + vz * vz)


@njit(cache=True)
def _cap_wall(q, ud):
    cx = q[0] * ud[E0] - q[1] * ud[E1]
    cy = q[0] * ud[E1] + q[1] * ud[E0]
    return cx, cy, ud[ZC0] + q[2], ud[ZW0] + q[3]


@njit(cache=True)
def _wire_args(ud):
    w = WIRE
    return ud[w], ud[w + 1], ud[w + 2], ud[w + 3], ud[w + 4], ud[w + 5], ud[w + 6], ud[w + 7], ud[w + 8]


@njit(cache=True)
def refresh_slopes(ud):
    """Directional slopes at the committed states (the callback's first-order prediction)."""
    if ud[PREDICT] == 0.0:
        return
    nr, nw, d0, l0, sg, ec, su, sd = _blocks(ud)
    E, Y, al, n, fT, a, Em, et, c = _wire_args(ud)
    for j in range(nw):
        ud[su + j] = sma_slope_scalar(ud[ec + j], 1.0, ud[sg + j], E, Y, al, n, fT, a, Em, et, c)
        ud[sd + j] = sma_slope_scalar(ud[ec + j], -1.0, ud[sg + j], E, Y, al, n, fT, a, Em, et, c)
    s = SPRING
    ud[Z_UP] = bouc_wen_slope_scalar(ud[ZETA], 1.0, ud[s + 1], ud[s + 2], ud[s + 3], ud[s + 4])
    ud[Z_DN] = bouc_wen_slope_scalar(ud[ZETA], -1.0, ud[s + 1], ud[s + 2], ud[s + 3], ud[s + 4])


@njit(cache=True)
def commit(q, ud):
    """Advance the hysteretic states along the strain change since the last commit (RK4 in strain,
    ``SUBSTEPS`` substeps), as _Device.commit."""
    nr, nw, d0, l0, sg, ec, su, sd = _blocks(ud)
    cx, cy, cz, wz = _cap_wall(q, ud)
    E, Y, al, n, fT, a, Em, et, c = _wire_args(ud)
    L0w = ud[WIRE + 10]
    sub = int(ud[SUBSTEPS])
    for j in range(nw):
        L = _element(ud, d0, nr + j, nr, cx, cy, cz, wz)[3]
        eps = (L - L0w) / L0w
        ud[sg + j] = advance_wire_stress_scalar(ud[ec + j], eps, ud[sg + j], E, Y, al, n, fT, a, Em, et, c, sub, 4)
        ud[ec + j] = eps
    s = SPRING
    x = ud[s + 5] - wz
    ud[ZETA] = advance_spring_zeta_scalar(ud[X_C], x, ud[ZETA], ud[s + 1], ud[s + 2], ud[s + 3], ud[s + 4], sub, 4)
    ud[X_C] = x
    refresh_slopes(ud)


@njit(cache=True)
def passive_forces(q, qfrc, ud):
    """Add ropes (Eq. 16), wires (Eq. 17a) and the spring (Eq. 18) to qfrc; commits nothing."""
    nr, nw, d0, l0, sg, ec, su, sd = _blocks(ud)
    cx, cy, cz, wz = _cap_wall(q, ud)
    L0w, area = ud[WIRE + 10], ud[WIRE + 9]
    predict = ud[PREDICT] != 0.0
    fx = fy = fz = 0.0
    wall = 0.0
    for i in range(nr + nw):
        vx, vy, vz, L = _element(ud, d0, i, nr, cx, cy, cz, wz)
        if i < nr:
            T = rope_tension_scalar(L, ud[l0 + i], ud[l0 + nr + i])
        else:
            j = i - nr
            sigma = ud[sg + j]
            if predict:
                de = (L - L0w) / L0w - ud[ec + j]
                sigma = sigma + (ud[su + j] if de > 0.0 else ud[sd + j]) * de
            T = wire_tension_scalar(sigma, area)
        w = T / L
        fx -= w * vx      # every element pulls the cap towards its lower end
        fy -= w * vy
        fz -= w * vz
        if i >= nr:
            wall += w * vz    # wires pull the wall up
    zeta = ud[ZETA]
    s = SPRING
    if predict:
        dx = ud[s + 5] - wz - ud[X_C]
        zeta = zeta + (ud[Z_UP] if dx > 0.0 else ud[Z_DN]) * dx
    push = spring_push_scalar(wz, zeta, ud[s], ud[s + 5])
    e0, e1 = ud[E0], ud[E1]
    qfrc[0] += fx * e0 + fy * e1
    qfrc[1] += fy * e0 - fx * e1
    qfrc[2] += fz
    qfrc[3] += wall + push


# ---- the C callback --------------------------------------------------------------------------------
# the two LLVM intrinsics every compiled MuJoCo path uses have one home, the builders' C-ABI module
_as_double_ptr, _call_model_data = double_ptr, call_md


def _pointer_fields() -> tuple[int, int, int]:
    """Word offsets of d->qpos, d->qfrc_passive and d->userdata inside the mjData struct.

    Found by matching the array addresses the bindings expose against the struct's 64-bit words;
    qpos is recognised by the pair (qpos, qvel) (a buffer pointer may equal it), the others are the
    only words holding their address. Checked on two MjData instances of a small model."""
    # every array near the three is non-empty (an actuator with activation, a sensor), so no
    # zero-size neighbour shares an address with them
    xml = ("<mujoco><size nuserdata='3'/><worldbody><body><joint name='j' type='slide'/><inertial pos='0 0 0' "
           "mass='1' diaginertia='1 1 1'/></body></worldbody><actuator><general joint='j' dyntype='filter' "
           "dynprm='1'/></actuator><sensor><jointpos joint='j'/></sensor></mujoco>")
    model = mujoco.MjModel.from_xml_string(xml)
    found = []
    for data in (mujoco.MjData(model), mujoco.MjData(model)):
        want = {"qpos": data.qpos.ctypes.data, "qvel": data.qvel.ctypes.data,
                "qfrc_passive": data.qfrc_passive.ctypes.data, "userdata": data.userdata.ctypes.data}
        words = np.zeros(0, dtype=np.uint64)
        qpos, frc, usr = [], [], []
        while not (qpos and frc and usr) and len(words) < (1 << 20):  # read on only until all are found
            n = len(words) + 256
            words = np.ctypeslib.as_array((ctypes.c_uint64 * n).from_address(data._address)).copy()
            qpos = [i for i in np.flatnonzero(words[:-1] == want["qpos"]) if words[i + 1] == want["qvel"]]
            frc = list(np.flatnonzero(words == want["qfrc_passive"]))
            usr = list(np.flatnonzero(words == want["userdata"]))
        if len(qpos) != 1 or len(frc) != 1 or len(usr) != 1:
            raise RuntimeError("mujoco_native: cannot locate qpos / qfrc_passive / userdata in mjData")
        found.append((int(qpos[0]), int(frc[0]), int(usr[0])))
    if found[0] != found[1]:
        raise RuntimeError("mujoco_native: mjData field offsets differ between instances")
    return found[0]


@functools.lru_cache(maxsize=1)
def passive_callback():
    """The compiled mjcb_passive (a numba cfunc; keep the returned object alive while installed)."""
    o_qpos, o_frc, o_usr = _pointer_fields()

    @cfunc(types.void(types.voidptr, types.voidptr))
    def mjcb_passive(m, d):
        words = carray(d, (o_usr + 1,), dtype=np.uint64)
        ud = carray(_as_double_ptr(words[o_usr]), (HEADER,))
        nr, nw = int(ud[NR]), int(ud[NW])
        ud = carray(_as_double_ptr(words[o_usr]), (userdata_size(nr, nw),))
        passive_forces(carray(_as_double_ptr(words[o_qpos]), (4,)),
                       carray(_as_double_ptr(words[o_frc]), (4,)), ud)
    return mjcb_passive


@functools.lru_cache(maxsize=1)
def mujoco_functions() -> tuple[int, int]:
    """C addresses of mj_step and mj_forward in the library the bindings loaded."""
    pkg = os.path.dirname(mujoco.__file__)
    libs = sorted(glob.glob(os.path.join(pkg, "libmujoco.so*")))
    if not libs:
        raise RuntimeError(f"mujoco_native: no libmujoco.so* in {pkg}")
    lib = ctypes.CDLL(libs[-1])
    return (ctypes.cast(lib.mj_step, ctypes.c_void_p).value, ctypes.cast(lib.mj_forward, ctypes.c_void_p).value)


@njit(cache=True)
def step_loop(fn_step, fn_forward, m_addr, d_addr, qpos, qvel, qfa, qpas, qcon, qbias, xpos, site_xpos, ud,
              u_at, vel_at, acc_at, udd, n_sub, n_steps, commit_every, drive_mass, cap_mass, cap_id, tip,
              wall_rest_z, closure_limit, F, cap_pos, wall_z, sig, zet, clo):
    """MujocoEngine.run's Euler/RK4 drive loop, natively (same order of operations as the Python loop).

    Returns (largest tracking error, index of the failing output sample or -1)."""
    nr, nw, d0, l0, sg, ec, su, sd = _blocks(ud)
    f_prev = qpas[0] + qcon[0] - qbias[0]
    track = 0.0
    for n in range(n_steps + 1):
        qfa[0] = drive_mass * acc_at[n] - f_prev
        if n % n_sub == 0:
            k = n // n_sub
            _call_model_data(fn_forward, m_addr, d_addr)
            F[k] = cap_mass * udd[n + 1] - (qpas[0] + qcon[0] - qbias[0])
            cap_pos[k, :] = xpos[cap_id, :]
            wall_z[k] = wall_rest_z + qpos[3]
            sig[k, :] = ud[sg:sg + nw]
            zet[k] = ud[ZETA]
            dx = site_xpos[tip, 0] - xpos[cap_id, 0]
            dy = site_xpos[tip, 1] - xpos[cap_id, 1]
            dz = site_xpos[tip, 2] - xpos[cap_id, 2]
            clo[k] = np.sqrt(dx * dx + dy * dy + dz * dz)
            if not (np.all(np.isfinite(qpos)) and clo[k] < closure_limit):
                return track, k
            if n == n_steps:
                break
        _call_model_data(fn_step, m_addr, d_addr)
        f_prev = qpas[0] + qcon[0] - qbias[0]
        track = max(track, abs(qpos[0] - u_at[n + 1]), abs(qpos[1]))
        qpos[0], qvel[0], qpos[1], qvel[1] = u_at[n + 1], vel_at[n + 1], 0.0, 0.0
        if (n + 1) % commit_every == 0 or (n + 1) % n_sub == 0:
            commit(qpos, ud)
    return track, -1
