"""MuJoCo's seismic mode in compiled code: the passive callback and the steps between output samples.

The gate's seismic cases cost MuJoCo 3.6-9.7 wall s per model second with the Python callback of
mujoco_seismic (issue 35, item 2): a profile of seismic_nf1_pulse put ~85 % of it in Python (the
elements' geometry and forces, the energy rates with four mj_objectVelocity calls, the commit of
the hysteretic states, the step loop), against ~15 % in mj_step itself. Here the same model, the same
laws and the same order of operations run natively, as the drive mode does (mujoco_native):

- ``seismic_passive``: ``mujoco_seismic._Forces.passive`` (ropes, wires and spring on the cap, turning
  with the plate; the supports; the restrainer; the energy balance's rates, integrated by trapezoids
  over MuJoCo's own time), the shared scalar laws of ``nsd_core.device.forces``; every constant, the
  committed states and the energy integrals in ``mjData.userdata`` (layout below), the addresses of
  ``d->qvel``, ``d->cvel``, ``d->xipos`` and ``d->subtree_com`` too (fixed for the life of an mjData);
  ``passive_callback()`` is its ``mjcb_passive`` C function.
- ``step_block``: the steps between two output samples (the ground's load as MuJoCo's gravity, mj_step,
  MuJoCo's clock, the commit of the hysteretic states) without entering Python; the samples (a
  row of outputs, the stability check) stay in mujoco_seismic's Python loop, once per output interval.

A body's linear velocity at its centre of mass is ``mj_objectVelocity``'s (world axes): the spatial
velocity ``d->cvel`` moved from the subtree's centre of mass to ``d->xipos``, written out as MuJoCo does.
"""
from __future__ import annotations

import functools

import numpy as np
from numba import carray, cfunc, njit, types

from nsd_core.device.forces import (advance_spring_zeta_scalar, advance_wire_stress_scalar, restrainer_force_scalar,
                                    rope_tension_scalar, spring_push_scalar, wire_tension_scalar)

from comparisons.engines.mujoco_native import _as_double_ptr, _call_model_data, _pointer_fields

# ---- userdata layout (float64 indices) ----------------------------------------------------------
NR, NW, SUBSTEPS, ZC0, ZW0 = range(5)
WIRE = 5            # 11 values: E, Y, alpha, n, fT, a, Em, eps_t, c, area, natural_length
SPRING = 16         # 6 values: kse, ksd, beta, gamma, n, free_length
ZETA, X_C = 22, 23
KB, CB, RS = 24, 25, 26                  # supports: stiffness, damping, radius
RON, RGAP, RK, RN, RC = 27, 28, 29, 30, 31  # restrainer: on, gap, stiffness, exponent, damping
AGX, AGY, TNOW = 32, 33, 34              # the ground's acceleration now, MuJoCo's time
EN, LAST, TLAST, HAS_LAST = 35, 40, 45, 46   # 5 integrals, the 5 rates at TLAST
A_QVEL, A_CVEL, A_XIPOS, A_COM = 47, 48, 49, 50   # addresses in mjData
MASS, IDS, ROOTS = 51, 55, 59            # 4 bodies (plate, cap, wall, rod): nominal masses, ids, root ids
NF = 63
HEADER = 64         # then cap points, low points (n, 3); rope L0, k (n_r); sigma, eps_c (n_w);
#                     floors: dof pairs (n_f, 2), masses, story damping, slab damping (n_f each)


def userdata_size(n_ropes: int, n_wires: int, n_floors: int) -> int:
    return HEADER + 6 * (n_ropes + n_wires) + 2 * n_ropes + 2 * n_wires + 5 * n_floors


@njit(cache=True, inline="always")
def _blocks(ud):
    nr, nw, nf = int(ud[NR]), int(ud[NW]), int(ud[NF])
    cp = HEADER
    lp = cp + 3 * (nr + nw)
    l0 = lp + 3 * (nr + nw)
    sg = l0 + 2 * nr
    fl = sg + 2 * nw
    return nr, nw, nf, cp, lp, l0, sg, sg + nw, fl


def pack(ud, g, st, dev, model, data, floors) -> None:
    """Everything ``seismic_passive`` reads, from mujoco_seismic's ``_Forces`` (committed states) and
    ``_Energy`` (nominal masses, body ids), the structure ``st`` and MuJoCo's model and data."""
    nr, nw = g.n_ropes, g.n_wires
    nf = 0 if floors is None else len(floors.ids)
    ud[:] = 0.0
    ud[NR], ud[NW], ud[NF], ud[SUBSTEPS], ud[ZC0], ud[ZW0] = nr, nw, nf, dev.substeps, g.cap_rest_z, g.wall_rest_z
    ud[WIRE:WIRE + 11] = tuple(g.wire)
    ud[SPRING:SPRING + 6] = tuple(g.spring)
    ud[ZETA], ud[X_C] = dev.zeta, dev.x_c
    ud[KB], ud[CB], ud[RS] = st.stiffness, st.damping, st.support_radius
    r = st.restrainer
    if r is not None:
        ud[RON], ud[RGAP], ud[RK], ud[RN], ud[RC] = 1.0, r.gap, r.stiffness, r.exponent, r.damping
    for k, a in ((A_QVEL, data.qvel), (A_CVEL, data.cvel), (A_XIPOS, data.xipos), (A_COM, data.subtree_com)):
        ud[k] = float(a.ctypes.data)   # an address below 2**53: exact in a float64
    e = dev.energy
    ud[MASS:MASS + 4] = e.mass
    ud[IDS:IDS + 4] = e.ids
    ud[ROOTS:ROOTS + 4] = [model.body_rootid[b] for b in e.ids]
    _, _, _, cp, lp, l0, sg, ec, fl = _blocks(ud)
    ud[cp:lp] = dev.cap_pts.ravel()
    ud[lp:l0] = dev.low_pts.ravel()
    ud[l0:l0 + nr] = np.broadcast_to(g.rope_natural_length, (nr,))
    ud[l0 + nr:sg] = np.broadcast_to(g.rope_stiffness, (nr,))
    ud[sg:sg + nw], ud[ec:ec + nw] = dev.sigma, dev.eps_c
    if nf:
        b = floors.b
        ud[fl:fl + 2 * nf] = floors.dof.ravel()
        ud[fl + 2 * nf:fl + 3 * nf] = b.masses
        ud[fl + 3 * nf:fl + 4 * nf] = b.story_damping
        ud[fl + 4 * nf:fl + 5 * nf] = b.slab_damping


def states(ud):
    """(wire stresses, spring zeta, the energy integrals) committed in ``ud``."""
    sg, nw = _blocks(ud)[6], int(ud[NW])
    return ud[sg:sg + nw].copy(), float(ud[ZETA]), ud[EN:EN + 5].copy()


@njit(cache=True)
def _element(ud, i, nr, cp, lp, px, py, c, s, zc, wz):
    """Element i's cap end (world) and vector to it from its lower end, as _Forces.geometry."""
    p0, p1, p2 = ud[cp + 3 * i], ud[cp + 3 * i + 1], ud[cp + 3 * i + 2]
    capx = px + c * p0 - s * p1
    capy = py + s * p0 + c * p1
    capz = zc + p2
    lz = ud[lp + 3 * i + 2]
    if i >= nr:
        lz = lz + wz
    vx, vy, vz = capx - ud[lp + 3 * i], capy - ud[lp + 3 * i + 1], capz - lz
    return capx, capy, vx, vy, vz, np.sqrt(vx * vx + vy * vy + vz * vz)


@njit(cache=True)
def commit_seismic(q, ud):
    """_Forces.commit: the wires' stresses and the spring's zeta along the strain change since the last
    commit (RK4 in strain, ``SUBSTEPS`` substeps)."""
    nr, nw, nf, cp, lp, l0, sg, ec, fl = _blocks(ud)
    c, s = np.cos(q[2]), np.sin(q[2])
    zc, wz = ud[ZC0] + q[3], ud[ZW0] + q[4]
    E, Y, al, n, fT, a, Em, et, cc = (ud[WIRE], ud[WIRE + 1], ud[WIRE + 2], ud[WIRE + 3], ud[WIRE + 4], ud[WIRE + 5],
                                      ud[WIRE + 6], ud[WIRE + 7], ud[WIRE + 8])
    L0w = ud[WIRE + 10]
    sub = int(ud[SUBSTEPS])
    for j in range(nw):
        L = _element(ud, nr + j, nr, cp, lp, q[0], q[1], c, s, zc, wz)[5]
        eps = (L - L0w) / L0w
        ud[sg + j] = advance_wire_stress_scalar(ud[ec + j], eps, ud[sg + j], E, Y, al, n, fT, a, Em, et, cc, sub, 4)
        ud[ec + j] = eps
    x = ud[SPRING + 5] - wz
    ud[ZETA] = advance_spring_zeta_scalar(ud[X_C], x, ud[ZETA], ud[SPRING + 1], ud[SPRING + 2], ud[SPRING + 3],
                                          ud[SPRING + 4], sub, 4)
    ud[X_C] = x


@njit(cache=True)
def seismic_passive(q, v, qf, ud, cvel, xipos, com):
    """_Forces.passive: the device on the cap and the wall, the supports, the restrainer into qf, and
    the energy balance's rates (E_input, E_device, supports, restrainer, building) integrated."""
    nr, nw, nf, cp, lp, l0, sg, ec, fl = _blocks(ud)
    px, py = q[0], q[1]
    c, s = np.cos(q[2]), np.sin(q[2])
    zc, wz = ud[ZC0] + q[3], ud[ZW0] + q[4]
    area = ud[WIRE + 9]
    fx = fy = fz = moment = wires_z = 0.0
    for i in range(nr + nw):
        capx, capy, vx, vy, vz, L = _element(ud, i, nr, cp, lp, px, py, c, s, zc, wz)
        T = rope_tension_scalar(L, ud[l0 + i], ud[l0 + nr + i]) if i < nr else wire_tension_scalar(ud[sg + i - nr], area)
        w = -(T / L)   # every element pulls its cap end towards its lower end
        ex, ey, ez = w * vx, w * vy, w * vz
        fx += ex
        fy += ey
        fz += ez
        moment += (capx - px) * ey - (capy - py) * ex
        if i >= nr:
            wires_z += ez
    wall = -wires_z + spring_push_scalar(wz, ud[ZETA], ud[SPRING], ud[SPRING + 5])
    k, cb, r = ud[KB], ud[CB], ud[RS]
    sx, sy, st = k * q[0] + cb * v[0], k * q[1] + cb * v[1], k * r ** 2 * q[2] + cb * r ** 2 * v[2]
    rx = ry = rF = rrate = 0.0
    if ud[RON] != 0.0:
        rx, ry, rF, _, rrate = restrainer_force_scalar(q[0], q[1], v[0], v[1], ud[RGAP], ud[RK], ud[RN], ud[RC])
    # the energy rates at this state (_Energy.rates)
    applied = fx * v[0] + fy * v[1] + moment * v[2] + fz * v[3] + wall * v[4]
    Px = Py = 0.0
    for b in range(4):
        bid, root = int(ud[IDS + b]), int(ud[ROOTS + b])
        dx = xipos[3 * bid] - com[3 * root]
        dy = xipos[3 * bid + 1] - com[3 * root + 1]
        dz = xipos[3 * bid + 2] - com[3 * root + 2]
        w0, w1, w2 = cvel[6 * bid], cvel[6 * bid + 1], cvel[6 * bid + 2]
        Px += ud[MASS + b] * (cvel[6 * bid + 3] - (dy * w2 - dz * w1))
        Py += ud[MASS + b] * (cvel[6 * bid + 4] - (dz * w0 - dx * w2))
    diss = cb * (v[0] ** 2 + v[1] ** 2) + cb * r ** 2 * v[2] ** 2
    bld = 0.0
    for i in range(nf):
        jx, jy = int(ud[fl + 2 * i]), int(ud[fl + 2 * i + 1])
        m = ud[fl + 2 * nf + i]
        Px += m * v[jx]
        Py += m * v[jy]
        bx, by = (v[0], v[1]) if i == 0 else (v[int(ud[fl + 2 * i - 2])], v[int(ud[fl + 2 * i - 1])])
        dvx, dvy, rvx, rvy = v[jx] - bx, v[jy] - by, v[jx] - v[0], v[jy] - v[1]
        bld += ud[fl + 3 * nf + i] * (dvx * dvx + dvy * dvy) + ud[fl + 4 * nf + i] * (rvx * rvx + rvy * rvy)
    now0, now1, now2, now3, now4 = -(ud[AGX] * Px + ud[AGY] * Py), -applied, diss, rF * rrate, bld
    t = ud[TNOW]
    if ud[HAS_LAST] != 0.0 and t > ud[TLAST]:
        half = 0.5 * (t - ud[TLAST])
        ud[EN] += half * (now0 + ud[LAST])
        ud[EN + 1] += half * (now1 + ud[LAST + 1])
        ud[EN + 2] += half * (now2 + ud[LAST + 2])
        ud[EN + 3] += half * (now3 + ud[LAST + 3])
        ud[EN + 4] += half * (now4 + ud[LAST + 4])
    ud[TLAST], ud[HAS_LAST] = t, 1.0
    ud[LAST], ud[LAST + 1], ud[LAST + 2], ud[LAST + 3], ud[LAST + 4] = now0, now1, now2, now3, now4
    qf[0] += fx - sx - rx
    qf[1] += fy - sy - ry
    qf[2] += moment - st
    qf[3] += fz
    qf[4] += wall


@functools.lru_cache(maxsize=1)
def passive_callback():
    """The compiled mjcb_passive of the seismic mode (a numba cfunc; keep it alive while installed)."""
    o_qpos, o_frc, o_usr = _pointer_fields()

    @cfunc(types.void(types.voidptr, types.voidptr))
    def mjcb_passive(m, d):
        words = carray(d, (o_usr + 1,), dtype=np.uint64)
        head = carray(_as_double_ptr(words[o_usr]), (HEADER,))
        nr, nw, nf = int(head[NR]), int(head[NW]), int(head[NF])
        ud = carray(_as_double_ptr(words[o_usr]), (userdata_size_kernel(nr, nw, nf),))
        n = 5 + 2 * nf
        nb = int(ud[IDS:IDS + 4].max()) + 1
        seismic_passive(carray(_as_double_ptr(words[o_qpos]), (n,)), carray(_as_double_ptr(int(ud[A_QVEL])), (n,)),
                        carray(_as_double_ptr(words[o_frc]), (n,)), ud,
                        carray(_as_double_ptr(int(ud[A_CVEL])), (6 * nb,)),
                        carray(_as_double_ptr(int(ud[A_XIPOS])), (3 * nb,)),
                        carray(_as_double_ptr(int(ud[A_COM])), (3 * nb,)))
    return mjcb_passive


@njit(cache=True, inline="always")
def userdata_size_kernel(nr, nw, nf):
    return HEADER + 6 * (nr + nw) + 2 * nr + 2 * nw + 5 * nf


@njit(cache=True)
def step_block(fn_step, m_addr, d_addr, gravity, a_g, n0, n1, h, qpos, ud):
    """Steps n0 .. n1-1 of mujoco_seismic's loop: the ground's load (-a_g) as MuJoCo's gravity, mj_step,
    MuJoCo's clock (d->time += h, as mj_step advances it), then the commit of the hysteretic states."""
    for n in range(n0, n1):
        gravity[0] = -a_g[n, 0]
        gravity[1] = -a_g[n, 1]
        ud[AGX], ud[AGY] = a_g[n, 0], a_g[n, 1]
        _call_model_data(fn_step, m_addr, d_addr)
        ud[TNOW] = ud[TNOW] + h
        commit_seismic(qpos, ud)
