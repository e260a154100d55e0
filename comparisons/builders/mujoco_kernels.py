"""The compiled pieces of comparisons.builders.mujoco's compiled path that know no mechanism and no law:
the layout of ``mjData.userdata``, the helpers the generated passive callback strings together
(mujoco_codegen), and the native step loop.

The helpers compute what comparisons.builders.mujoco.Passive computes, arranged for speed (the two
paths agree to round-off: tests/test_mujoco_codegen.py):
- ``prepare_bodies``: once per evaluation, for each body that carries an element end, MuJoCo's own
  mj_jac at the body's origin (translational J_o and rotational J_w, 3 x nv each), its origin's
  velocity v_o = J_o qvel and its angular velocity w = J_w qvel. Passive calls mj_jac at every end
  (13 calls per evaluation for the device, ~1.2 us of its 1.7 us); a point at r from the origin has
  J = J_o - [r x] J_w, the same numbers re-associated;
- ``points_state``: an element's two world points (xpos + xmat p; ground: p), their velocities
  v_o + w x r, L, L' and the unit vector a -> b (L = 0: no direction, as Passive);
- ``points_state_along``: the same for an element with a direction e: x = (p_a - p_b) . e, x' its
  rate, and u = -e (the law's -T e on a);
- ``ground_load``: the excitation's -m a_g(t) at the centre of mass of every body slot that carries
  a mass, as F and M about the origin (a_g from nsd_core.ground.motions.ground_values, called by the
  generated callback at the stage's time);
- ``apply_points``: the tension as wrenches on the two bodies, +T u at a, -T u at b, summed per body
  about its origin (F, r x F); ``finish_bodies`` then adds J_o^T F + J_w^T M to qfrc_passive, which
  is Passive's (T u) (J_a - J_b) summed over the elements;
- ``drive_feeds``: the heavy virtual drives' feed-forward A q''(t) + tau + tau' (t - t_tau) at this
  stage's time, each stage's value kept for the step's average drive force.

- ``_measure``: each step's drive force (RK4: the step's average; Euler: its one evaluation's, the
  last output's taken at n = n_steps) into the outputs that use it, and the feed-forward's estimate.

The prescribed accelerations come from the step loop, which writes q'' at the step's start, middle
and end before each step; a stage picks its own by its time (Euler and the first stage: start; RK4's
two middle stages: middle; its last: end).

userdata layout (float64): a header, scratch (the two ends' arms r and the unit vector), one block
per body slot, per drive, per force element (its parameters last, so that a law receives them as one
array view), the states' rates (by act index, copied to act_dot by the generated mjcb_act_dyn) and
the excitation's ground motion block (its length in the header: a record's length is data, not the
description's shape, so the generated source does not depend on it).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from comparisons.builders.mujoco_cabi import call_jac, call_md, call_md_int
from nsd_core.ground.motions import ground_values

# header (EXCITATION_SIZE: the length of the excitation's ground_values block, last in userdata;
# ADVANCE: 1 where the passive callback advances the laws' states itself (Euler), 0 where MuJoCo
# integrates them from their rates (RK4); T_COMMIT: the time of the states' last advance, NaN before it)
(JAC_FN, COUNT, T_STEP, STEP, T_TAU, N_DRIVES, DRIVES_AT, N_SLOTS, SLOTS_AT, EXCITATION_SIZE, ADVANCE, T_COMMIT,
 HEADER) = range(13)
SCRATCH = 9          # the ends' arms r_a, r_b and the unit vector u
MAX_STAGES = 4       # RK4's; a step of more stages keeps only its first 4 feeds and the loop fails it
# a body slot: body id, point (its origin), v_o, w, F, M, the mass the excitation loads (0: none) and
# its centre in the body's frame, then J_o and J_w (3 x nv each)
S_BODY, S_POINT, S_VEL, S_OMEGA, S_FORCE, S_MOMENT, S_MASS, S_COM, S_JAC = 0, 1, 4, 7, 10, 13, 16, 17, 20
# a drive: dof address, armature, tau, tau', q'' at the step's start / middle / end, the stages' feeds
D_DOF, D_ARM, D_TAU, D_SLOPE, D_ACC, D_FEED, DRIVE_SIZE = 0, 1, 2, 3, 4, 7, 7 + MAX_STAGES
# a points element: slot of body a (-1: ground), point a (3), slot of body b, point b (3), its state's
# index in act (-1: none), its x at the states' last advance (ADVANCE), last value, its x' (kept by a
# description with work outputs), its direction e (ground frame; zero for a line element), then the
# law's parameters; a joint element: qpos and dof address, act index, x at the last advance, value, x'
# (as a points element's), parameters
P_SLOT, P_PREVIOUS, P_VALUE, P_DIRECTION, POINTS_HEAD = 8, 9, 10, 12, 15
J_SLOT, J_PREVIOUS, J_VALUE, JOINT_HEAD = 2, 3, 4, 6


def slot_size(nv: int) -> int:
    return S_JAC + 6 * nv


@njit(cache=True)
def prepare_bodies(m, d, ud, ud_addr, xpos, qvel, nv):
    """Each body slot's Jacobians at its origin, origin velocity and angular velocity; F = M = 0."""
    size = S_JAC + 6 * nv
    at = int(ud[SLOTS_AT])
    for i in range(int(ud[N_SLOTS])):
        s = at + size * i
        b = int(ud[s + S_BODY])
        for c in range(3):
            ud[s + S_POINT + c] = xpos[b, c]
            ud[s + S_FORCE + c] = 0.0
            ud[s + S_MOMENT + c] = 0.0
        jo = s + S_JAC
        jw = jo + 3 * nv
        call_jac(np.int64(ud[JAC_FN]), m, d, ud_addr + 8 * jo, ud_addr + 8 * jw, ud_addr + 8 * (s + S_POINT), b)
        for c in range(3):
            v = w = 0.0
            for j in range(nv):
                v += ud[jo + c * nv + j] * qvel[j]
                w += ud[jw + c * nv + j] * qvel[j]
            ud[s + S_VEL + c] = v
            ud[s + S_OMEGA + c] = w


@njit(cache=True, inline="always")
def _end(ud, at, end, xpos, xmat, nv):
    """World point and velocity of one end of a points element; its arm r from the body's origin is
    kept in scratch."""
    slot = int(ud[at + 4 * end])
    p0, p1, p2 = ud[at + 4 * end + 1], ud[at + 4 * end + 2], ud[at + 4 * end + 3]
    r = HEADER + 3 * end
    if slot < 0:
        ud[r], ud[r + 1], ud[r + 2] = 0.0, 0.0, 0.0
        return p0, p1, p2, 0.0, 0.0, 0.0
    s = int(ud[SLOTS_AT]) + (S_JAC + 6 * nv) * slot
    b = int(ud[s + S_BODY])
    r0 = xmat[b, 0] * p0 + xmat[b, 1] * p1 + xmat[b, 2] * p2
    r1 = xmat[b, 3] * p0 + xmat[b, 4] * p1 + xmat[b, 5] * p2
    r2 = xmat[b, 6] * p0 + xmat[b, 7] * p1 + xmat[b, 8] * p2
    ud[r], ud[r + 1], ud[r + 2] = r0, r1, r2
    w0, w1, w2 = ud[s + S_OMEGA], ud[s + S_OMEGA + 1], ud[s + S_OMEGA + 2]
    return (xpos[b, 0] + r0, xpos[b, 1] + r1, xpos[b, 2] + r2, ud[s + S_VEL] + (w1 * r2 - w2 * r1),
            ud[s + S_VEL + 1] + (w2 * r0 - w0 * r2), ud[s + S_VEL + 2] + (w0 * r1 - w1 * r0))


@njit(cache=True)
def points_state(ud, at, xpos, xmat, nv):
    """(L, L') of the points element whose block starts at ``at``; u and the arms stay in scratch."""
    a0, a1, a2, va0, va1, va2 = _end(ud, at, 0, xpos, xmat, nv)
    b0, b1, b2, vb0, vb1, vb2 = _end(ud, at, 1, xpos, xmat, nv)
    r0, r1, r2 = b0 - a0, b1 - a1, b2 - a2
    L = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
    u = HEADER + 6
    if L > 0.0:
        ud[u], ud[u + 1], ud[u + 2] = r0 / L, r1 / L, r2 / L
    else:
        ud[u], ud[u + 1], ud[u + 2] = 0.0, 0.0, 0.0
    return L, ud[u] * (vb0 - va0) + ud[u + 1] * (vb1 - va1) + ud[u + 2] * (vb2 - va2)


@njit(cache=True)
def points_state_along(ud, at, xpos, xmat, nv):
    """(x, x') of a points element with a direction e: x = (p_a - p_b) . e and its rate. The scratch
    unit vector is u = -e, so that apply_points' +T u on a is the law's -T e on a, +T e on b."""
    a0, a1, a2, va0, va1, va2 = _end(ud, at, 0, xpos, xmat, nv)
    b0, b1, b2, vb0, vb1, vb2 = _end(ud, at, 1, xpos, xmat, nv)
    e0, e1, e2 = ud[at + P_DIRECTION], ud[at + P_DIRECTION + 1], ud[at + P_DIRECTION + 2]
    u = HEADER + 6
    ud[u], ud[u + 1], ud[u + 2] = -e0, -e1, -e2
    return (e0 * (a0 - b0) + e1 * (a1 - b1) + e2 * (a2 - b2),
            e0 * (va0 - vb0) + e1 * (va1 - vb1) + e2 * (va2 - vb2))


@njit(cache=True)
def ground_load(ud, xmat, ax, ay, nv):
    """The excitation: -m a_g at every loaded slot's centre of mass, added to its F and M (about the
    body's origin: r_c x F, r_c = xmat c). a_g = (ax, ay, 0)."""
    size = S_JAC + 6 * nv
    at = int(ud[SLOTS_AT])
    for i in range(int(ud[N_SLOTS])):
        s = at + size * i
        mass = ud[s + S_MASS]
        if mass == 0.0:
            continue
        b = int(ud[s + S_BODY])
        c0, c1, c2 = ud[s + S_COM], ud[s + S_COM + 1], ud[s + S_COM + 2]
        r0 = xmat[b, 0] * c0 + xmat[b, 1] * c1 + xmat[b, 2] * c2
        r1 = xmat[b, 3] * c0 + xmat[b, 4] * c1 + xmat[b, 5] * c2
        r2 = xmat[b, 6] * c0 + xmat[b, 7] * c1 + xmat[b, 8] * c2
        f0, f1 = -mass * ax, -mass * ay
        ud[s + S_FORCE] += f0
        ud[s + S_FORCE + 1] += f1
        ud[s + S_MOMENT] += -r2 * f1
        ud[s + S_MOMENT + 1] += r2 * f0
        ud[s + S_MOMENT + 2] += r0 * f1 - r1 * f0


@njit(cache=True)
def apply_points(ud, at, T, nv):
    """+T u on end a, -T u on end b, as forces and moments about each body's origin."""
    u = HEADER + 6
    for end in range(2):
        slot = int(ud[at + 4 * end])
        if slot < 0:
            continue
        sign = T if end == 0 else -T
        f0, f1, f2 = sign * ud[u], sign * ud[u + 1], sign * ud[u + 2]
        r = HEADER + 3 * end
        r0, r1, r2 = ud[r], ud[r + 1], ud[r + 2]
        s = int(ud[SLOTS_AT]) + (S_JAC + 6 * nv) * slot
        ud[s + S_FORCE] += f0
        ud[s + S_FORCE + 1] += f1
        ud[s + S_FORCE + 2] += f2
        ud[s + S_MOMENT] += r1 * f2 - r2 * f1
        ud[s + S_MOMENT + 1] += r2 * f0 - r0 * f2
        ud[s + S_MOMENT + 2] += r0 * f1 - r1 * f0


@njit(cache=True)
def finish_bodies(ud, qfrc, nv):
    """qfrc_passive += J_o^T F + J_w^T M of every body slot."""
    size = S_JAC + 6 * nv
    at = int(ud[SLOTS_AT])
    for i in range(int(ud[N_SLOTS])):
        s = at + size * i
        jo = s + S_JAC
        jw = jo + 3 * nv
        for j in range(nv):
            q = 0.0
            for c in range(3):
                q += ud[jo + c * nv + j] * ud[s + S_FORCE + c] + ud[jw + c * nv + j] * ud[s + S_MOMENT + c]
            qfrc[j] += q


@njit(cache=True)
def drive_feeds(ud, qfrc, t):
    """Add each heavy virtual drive's feed-forward at stage time t; keep it for the step's average."""
    count = int(ud[COUNT])
    half = 0.5 * ud[STEP]
    stage = min(2, max(0, int(np.floor((t - ud[T_STEP]) / half + 0.5)))) if half > 0.0 else 0
    at = int(ud[DRIVES_AT])
    for i in range(int(ud[N_DRIVES])):
        b = at + DRIVE_SIZE * i
        feed = ud[b + D_ARM] * ud[b + D_ACC + stage] + ud[b + D_TAU] + ud[b + D_SLOPE] * (t - ud[T_TAU])
        qfrc[int(ud[b + D_DOF])] += feed
        if count < MAX_STAGES:
            ud[b + D_FEED + count] = feed
    ud[COUNT] = count + 1


@njit(cache=True)
def set_stage_accelerations(ud, acc_half, n):
    """q'' of every drive at step n's start, middle and end (acc_half: drives x half-steps)."""
    at = int(ud[DRIVES_AT])
    for i in range(int(ud[N_DRIVES])):
        b = at + DRIVE_SIZE * i + D_ACC
        ud[b], ud[b + 1], ud[b + 2] = acc_half[i, 2 * n], acc_half[i, 2 * n + 1], acc_half[i, 2 * n + 2]


@njit(cache=True, inline="always")
def _measure(ud, weights, qacc, uses_ptr, uses_k, uses_w, drive_at, n, h, t, rk4):
    """Step n's drive forces, added to the outputs that use them, and the feed-forward's estimate
    updated; False when the step evaluated the passive forces other than the integrator's number of
    times. RK4: the step's average, the stages' weighted feed-forward less A x the step's average
    acceleration (comparisons.builders.mujoco says why), at the step's middle; Euler: the same
    arithmetic on its one evaluation, the force at the step's start."""
    if int(ud[COUNT]) != weights.shape[0]:
        return False
    at = int(ud[DRIVES_AT])
    for i in range(int(ud[N_DRIVES])):
        b = at + DRIVE_SIZE * i
        bar = 0.0
        for s in range(weights.shape[0]):
            bar += weights[s] * ud[b + D_FEED + s]
        bar -= ud[b + D_ARM] * qacc[int(ud[b + D_DOF])]
        for j in range(uses_ptr[n], uses_ptr[n + 1]):
            drive_at[uses_k[j], i] += uses_w[j] * bar
        ud[b + D_SLOPE] = (bar - ud[b + D_TAU]) / h if n else 0.0
        ud[b + D_TAU] = bar
    ud[T_TAU] = t + 0.5 * h if rk4 else t
    return True


@njit(cache=True, inline="always")
def work_powers(ud, values, sign, work_of, power, fn_subtree, m_addr, d_addr, linvel, mass, t, ground):
    """Each work output's power at this evaluation (mujoco_passive.Passive.powers, the same arithmetic):
    an element's sign x value x x' (the generated callback keeps x' beside the value), the excitation's
    -a_g(t) . (M v_com) (MuJoCo's mj_subtreeVel: v_com of the whole mechanism), a drive's 0 (the loop
    adds each step's drive work)."""
    for k in range(work_of.shape[0]):
        e = work_of[k]
        if e >= 0:
            power[k] = sign[e] * ud[values[e]] * ud[values[e] + 1]
        elif e == -1:
            call_md(fn_subtree, m_addr, d_addr)
            ag = ground_values(t, ground, 0)
            power[k] = -mass * (ag[4] * linvel[0, 0] + ag[5] * linvel[0, 1])
        else:
            power[k] = 0.0


@njit(cache=True)
def step_loop(fn_forward, fn_advance, rk4, m_addr, d_addr, time, qpos, qvel, act, qacc, site_xpos, ud,
              n_sub, n_steps, h, weights, acc_half, q_at, qd_at, drive_qa, uses_ptr, uses_k, uses_w,
              pairs, closure_limit, values, rec_qpos, rec_qvel, rec_act, rec_val, rec_qacc, gaps, drive_at,
              work_of, sign, fn_subtree, linvel, mass, ground, rec_work, t_end):
    """comparisons.builders.mujoco.simulate's step loop, natively, in the same order of operations.

    Records, at every output time, qpos, qvel, act, qacc, each element's last law value, the loop gap
    and the work outputs (``work_of``: mujoco_passive.work_plan; the trapezoid of their powers at the
    steps' first evaluations, a drive's as each step's average force times q's change; none: no cost).
    Returns (largest tracking error, failing output index or -1, -2 for a stage count that is not the
    integrator's)."""
    nd = drive_qa.shape[0]
    tracking = 0.0
    nw = work_of.shape[0]
    work, power, now = np.zeros(nw), np.zeros(nw), np.zeros(nw)
    for n in range(n_steps + 1):
        t = min(n * h, t_end)   # n h may pass the run's end by an ulp, past a closed-form excitation's block
        time[0] = t
        ud[COUNT] = 0.0
        ud[T_STEP] = t
        set_stage_accelerations(ud, acc_half, n)
        call_md(fn_forward, m_addr, d_addr)
        if nw:
            work_powers(ud, values, sign, work_of, now, fn_subtree, m_addr, d_addr, linvel, mass, t, ground)
            for i in range(nw):
                if n:
                    work[i] += 0.5 * h * (power[i] + now[i])
                power[i] = now[i]
        if n % n_sub == 0:
            k = n // n_sub
            for i in range(nw):
                rec_work[k, i] = work[i]
            gap = 0.0
            for i in range(pairs.shape[0]):
                a, b = pairs[i, 0], pairs[i, 1]
                dx = site_xpos[a, 0] - site_xpos[b, 0]
                dy = site_xpos[a, 1] - site_xpos[b, 1]
                dz = site_xpos[a, 2] - site_xpos[b, 2]
                gap = max(gap, np.sqrt(dx * dx + dy * dy + dz * dz))
            gaps[k] = gap
            # element by element: a row assigned from an array (rec[k, :] = a) makes numba compile its
            # shape-mismatch error path, ~2 s in every process that compiles this loop
            for i in range(qpos.shape[0]):
                rec_qpos[k, i] = qpos[i]
            for i in range(qvel.shape[0]):
                rec_qvel[k, i] = qvel[i]
                rec_qacc[k, i] = qacc[i]
            for i in range(act.shape[0]):
                rec_act[k, i] = act[i]
            for e in range(values.shape[0]):
                rec_val[k, e] = ud[values[e]]
            if not (np.all(np.isfinite(qpos)) and gap < closure_limit):
                return tracking, k
        if n == n_steps:
            # Euler's measurement is its one evaluation's, the step's start state: the last output's
            # comes from this evaluation (MuJoCo's Euler leaves qacc as mj_forward computed it)
            if nd and not rk4 and not _measure(ud, weights, qacc, uses_ptr, uses_k, uses_w, drive_at, n, h, t, rk4):
                return tracking, -2
            break
        if rk4:
            call_md_int(fn_advance, m_addr, d_addr, 4)
        else:
            call_md(fn_advance, m_addr, d_addr)
        if nd and not _measure(ud, weights, qacc, uses_ptr, uses_k, uses_w, drive_at, n, h, t, rk4):
            return tracking, -2
        for j in range(nw):
            if work_of[j] == -2:   # the step's drive work: each drive's average force times q's change
                for i in range(nd):
                    work[j] += ud[int(ud[DRIVES_AT]) + DRIVE_SIZE * i + D_TAU] * (q_at[i, n + 1] - q_at[i, n])
        for i in range(nd):   # the drive's coordinate, exactly on its path
            qa, da = drive_qa[i, 0], drive_qa[i, 1]
            tracking = max(tracking, abs(qpos[qa] - q_at[i, n + 1]))
            qpos[qa], qvel[da] = q_at[i, n + 1], qd_at[i, n + 1]
    return tracking, -1
