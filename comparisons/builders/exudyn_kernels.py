"""The compiled kernels of Exudyn's compiled force path (comparisons.builders.exudyn_compiled): the
bodies' poses from Exudyn's node coordinates (3 positions + 4 Euler parameters each), every element's
(x, x') (``arguments``) and the laws' values mapped to generalized forces (``forces``). The code
generated per model (exudyn_codegen) calls these, so they live apart from the module that builds the
Exudyn object (no import circle). ``_poses``, ``arguments`` and ``forces`` are called only from that
compiled code: they are compiled without numba's Python and C entry wrappers (machine code nothing would
run; a call from Python would crash the process: tests/test_compiled_only.py).

Generalized forces of a rigid body on Euler parameters (e0, e1, e2, e3): a force F at the world arm
s from the centre of mass gives F on the position coordinates and G^T (s x F) on the parameters, where
omega = G e' (world), G = 2 [-e_v, e0 I + skew(e_v)] row-wise as below; the rotation matrix is the
Euler parameters' (unit at convergence, where Exudyn's normalisation constraint holds).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

# the kernels only compiled code calls (the module's docstring)
compiled_only = njit(cache=True, no_cpython_wrapper=True, no_cfunc_wrapper=True)


@compiled_only
def _poses(q, q_t, ref, R, G, r, v, w):
    """Every body's rotation R, G matrix, centre of mass r and its velocity v, angular velocity w
    (world), from its node's coordinates (reference + displacement)."""
    for i in range(R.shape[0]):
        o = 7 * i
        e0, e1, e2, e3 = ref[o + 3] + q[o + 3], ref[o + 4] + q[o + 4], ref[o + 5] + q[o + 5], ref[o + 6] + q[o + 6]
        R[i, 0, 0], R[i, 0, 1], R[i, 0, 2] = e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3, 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2)
        R[i, 1, 0], R[i, 1, 1], R[i, 1, 2] = 2 * (e1 * e2 + e0 * e3), e0 * e0 - e1 * e1 + e2 * e2 - e3 * e3, 2 * (e2 * e3 - e0 * e1)
        R[i, 2, 0], R[i, 2, 1], R[i, 2, 2] = 2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), e0 * e0 - e1 * e1 - e2 * e2 + e3 * e3
        G[i, 0, 0], G[i, 0, 1], G[i, 0, 2], G[i, 0, 3] = -2 * e1, 2 * e0, -2 * e3, 2 * e2
        G[i, 1, 0], G[i, 1, 1], G[i, 1, 2], G[i, 1, 3] = -2 * e2, 2 * e3, 2 * e0, -2 * e1
        G[i, 2, 0], G[i, 2, 1], G[i, 2, 2], G[i, 2, 3] = -2 * e3, -2 * e2, 2 * e1, 2 * e0
        for k in range(3):
            r[i, k] = ref[o + k] + q[o + k]
            v[i, k] = q_t[o + k]
            w[i, k] = G[i, k, 0] * q_t[o + 3] + G[i, k, 1] * q_t[o + 4] + G[i, k, 2] * q_t[o + 5] + G[i, k, 3] * q_t[o + 6]


@compiled_only
def arguments(q, q_t, F, I, W, L, R, G, r, v, w, x, xd, N, S):
    """(x, x') of every element: points elements first (distance, or offset along e when e is non-zero),
    then joint laws (a slide along jax in the parent's frame, or a turn about it measured from jx
    towards jy, continuous from the last call's angle, W[m]). Keeps each element's unit vector N and
    the arms and points S (points: arm a, arm b; joints: the child's origin and its arm) for ``forces``.

    The model's numbers are read in place from F (its first block the bodies' reference coordinates,
    then 3 floats an element in the blocks at L's offsets) and I (the elements' bodies, turn flags),
    L = (npts, nj, pa, pb, e, jax, jx, jy, jpos, jorig, ia, ib, jc, jp, turn). One loop, no helper
    taking arrays, no view: numba counts references to every array a call or a view takes, each count
    an atomic operation that cost more than this arithmetic (~240 an evaluation of the device, 2/3 of
    its time). The products and sums are in the order of a matrix times a vector."""
    npts, nj, o_pa, o_pb, o_e, o_jax, o_jx, o_jy, o_jpos, o_jorig, o_ia, o_ib, o_jc, o_jp, o_turn = L
    _poses(q, q_t, F, R, G, r, v, w)
    P = np.empty((2, 9))   # an element's two ends (a joint's: the child's origin): world point, arm, velocity
    V = np.empty((5, 3))   # a joint's axis, x and y directions, position (in the world) and the child's x
    for j in range(npts + nj):
        m = j - npts
        for end in range(2 if m < 0 else 1):
            if m < 0:
                i, o = (I[o_ia + j], o_pa + 3 * j) if end == 0 else (I[o_ib + j], o_pb + 3 * j)
            else:
                i, o = I[o_jc + m], o_jorig + 3 * m
            if i < 0:   # the ground: the point is in the world
                for k in range(3):
                    P[end, k], P[end, 3 + k], P[end, 6 + k] = F[o + k], 0.0, 0.0
                continue
            for k in range(3):
                P[end, 3 + k] = R[i, k, 0] * F[o] + R[i, k, 1] * F[o + 1] + R[i, k, 2] * F[o + 2]
            s0, s1, s2 = P[end, 3], P[end, 4], P[end, 5]
            P[end, 0], P[end, 1], P[end, 2] = r[i, 0] + s0, r[i, 1] + s1, r[i, 2] + s2
            P[end, 6] = v[i, 0] + w[i, 1] * s2 - w[i, 2] * s1
            P[end, 7] = v[i, 1] + w[i, 2] * s0 - w[i, 0] * s2
            P[end, 8] = v[i, 2] + w[i, 0] * s1 - w[i, 1] * s0
        if m < 0:
            d0, d1, d2 = P[0, 0] - P[1, 0], P[0, 1] - P[1, 1], P[0, 2] - P[1, 2]
            u0, u1, u2 = P[0, 6] - P[1, 6], P[0, 7] - P[1, 7], P[0, 8] - P[1, 8]
            e0, e1, e2 = F[o_e + 3 * j], F[o_e + 3 * j + 1], F[o_e + 3 * j + 2]
            if e0 != 0.0 or e1 != 0.0 or e2 != 0.0:
                N[j, 0], N[j, 1], N[j, 2] = e0, e1, e2
                x[j] = d0 * e0 + d1 * e1 + d2 * e2
            else:
                length = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
                x[j] = length
                if length > 0.0:
                    N[j, 0], N[j, 1], N[j, 2] = d0 / length, d1 / length, d2 / length
                else:   # the points coincide (a stop at rest): no direction, no force
                    N[j, 0], N[j, 1], N[j, 2] = 0.0, 0.0, 0.0
            xd[j] = u0 * N[j, 0] + u1 * N[j, 1] + u2 * N[j, 2]
            for k in range(3):
                S[j, 0, k], S[j, 1, k] = P[0, 3 + k], P[1, 3 + k]
            continue
        c, p, turn = I[o_jc + m], I[o_jp + m], I[o_turn + m] != 0
        # the joint's directions and position in the world (turned by the parent; the ground's are), and
        # the child's x direction (a turn's angle)
        for t in range(5):
            o, i = (o_jax, o_jx, o_jy, o_jpos, o_jx)[t] + 3 * m, p if t < 4 else c
            if t == 4 and not turn:
                break
            for k in range(3):
                V[t, k] = F[o + k] if i < 0 else R[i, k, 0] * F[o] + R[i, k, 1] * F[o + 1] + R[i, k, 2] * F[o + 2]
        if p < 0:
            rel0, rel1, rel2 = P[0, 0] - V[3, 0], P[0, 1] - V[3, 1], P[0, 2] - V[3, 2]
            vr0, vr1, vr2 = P[0, 6], P[0, 7], P[0, 8]
            wr0, wr1, wr2 = w[c, 0], w[c, 1], w[c, 2]
        else:
            rel0, rel1, rel2 = P[0, 0] - (r[p, 0] + V[3, 0]), P[0, 1] - (r[p, 1] + V[3, 1]), P[0, 2] - (r[p, 2] + V[3, 2])
            # the rate of ax . rel in the turning parent's frame: the child origin's velocity less that of the
            # parent's material point under it (ax turns with the parent, which cancels rel's own turn)
            d0, d1, d2 = P[0, 0] - r[p, 0], P[0, 1] - r[p, 1], P[0, 2] - r[p, 2]
            vr0 = P[0, 6] - (v[p, 0] + (w[p, 1] * d2 - w[p, 2] * d1))
            vr1 = P[0, 7] - (v[p, 1] + (w[p, 2] * d0 - w[p, 0] * d2))
            vr2 = P[0, 8] - (v[p, 2] + (w[p, 0] * d1 - w[p, 1] * d0))
            wr0, wr1, wr2 = w[c, 0] - w[p, 0], w[c, 1] - w[p, 1], w[c, 2] - w[p, 2]
        a0, a1, a2 = V[0, 0], V[0, 1], V[0, 2]
        N[j, 0], N[j, 1], N[j, 2] = a0, a1, a2
        if turn:
            raw = math.atan2(V[2, 0] * V[4, 0] + V[2, 1] * V[4, 1] + V[2, 2] * V[4, 2],
                             V[1, 0] * V[4, 0] + V[1, 1] * V[4, 1] + V[1, 2] * V[4, 2])
            # continuous across +-pi: the turn nearest the last call's (a step turns far less than pi)
            x[j] = W[m] + (raw - W[m] + math.pi) % (2.0 * math.pi) - math.pi
            W[m] = x[j]
            xd[j] = a0 * wr0 + a1 * wr1 + a2 * wr2
        else:
            x[j] = a0 * rel0 + a1 * rel1 + a2 * rel2
            xd[j] = a0 * vr0 + a1 * vr1 + a2 * vr2
        for k in range(3):
            S[j, 0, k], S[j, 1, k] = P[0, k], P[0, 3 + k]


@compiled_only
def forces(T, I, L, R, G, r, N, S, f):
    """Generalized forces f of the elements' values T: a points element's tension pulls a by -T N at
    its arm and b by +T N; a joint law's Q drives its coordinate up: Q N on the child at its origin
    (or a torque Q N) and the opposite on the parent, there. Scalar arithmetic, written out here: a
    helper called with the arrays cost a reference count update per array and call, each an atomic
    operation (~140 an evaluation of the device, more than the loads' arithmetic). L: ``arguments``'."""
    npts, nj, o_ia, o_ib, o_jc, o_jp, o_turn = L[0], L[1], L[10], L[11], L[12], L[13], L[14]
    f[:] = 0.0
    for j in range(npts + nj):
        m = j - npts
        if m >= 0 and I[o_turn + m] != 0:
            for side in range(2):
                i, c = (I[o_jc + m], T[j]) if side == 0 else (I[o_jp + m], -T[j])
                if i >= 0:
                    for n in range(4):
                        f[7 * i + 3 + n] += c * (G[i, 0, n] * N[j, 0] + G[i, 1, n] * N[j, 1] + G[i, 2, n] * N[j, 2])
            continue
        for side in range(2):
            if m < 0:   # a points element: -T N on body a at arm S[j, 0], +T N on body b at arm S[j, 1]
                i, c, k = (I[o_ia + j], -T[j], 0) if side == 0 else (I[o_ib + j], T[j], 1)
            elif side == 0:   # a slide: Q N on the child at its origin (arm S[j, 1])
                i, c, k = I[o_jc + m], T[j], 1
            else:   # and -Q N on the parent at the same world point: its arm from its own centre
                i, c, k = I[o_jp + m], -T[j], 0
                if i >= 0:
                    for d in range(3):
                        S[j, 0, d] -= r[i, d]
            if i < 0:
                continue
            o = 7 * i
            Fx, Fy, Fz = c * N[j, 0], c * N[j, 1], c * N[j, 2]
            sx, sy, sz = S[j, k, 0], S[j, k, 1], S[j, k, 2]
            tx, ty, tz = sy * Fz - sz * Fy, sz * Fx - sx * Fz, sx * Fy - sy * Fx
            f[o], f[o + 1], f[o + 2] = f[o] + Fx, f[o + 1] + Fy, f[o + 2] + Fz
            for n in range(4):
                f[o + 3 + n] += G[i, 0, n] * tx + G[i, 1, n] * ty + G[i, 2, n] * tz


@njit(cache=True)
def pose_series(Q, Q_t, ref, R, G, r, v, w):
    """``_poses`` at each of a series of samples (the first axis of every array)."""
    for k in range(Q.shape[0]):
        _poses(Q[k], Q_t[k], ref, R[k], G[k], r[k], v[k], w[k])
