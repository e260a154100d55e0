"""The compiled kernels of Exudyn's compiled force path (comparisons.builders.exudyn_compiled): the
bodies' poses from Exudyn's node coordinates (3 positions + 4 Euler parameters each), every element's
(x, x') (``arguments``) and the laws' values mapped to generalized forces (``forces``). The code
generated per model (exudyn_codegen) calls these, so they live apart from the module that builds the
Exudyn object (no import circle).

Generalized forces of a rigid body on Euler parameters (e0, e1, e2, e3): a force F at the world arm
s from the centre of mass gives F on the position coordinates and G^T (s x F) on the parameters, where
omega = G e' (world), G = 2 [-e_v, e0 I + skew(e_v)] row-wise as below; the rotation matrix is the
Euler parameters' (unit at convergence, where Exudyn's normalisation constraint holds).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
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


@njit(cache=True)
def _mv(A, x):
    return np.array([A[0, 0] * x[0] + A[0, 1] * x[1] + A[0, 2] * x[2], A[1, 0] * x[0] + A[1, 1] * x[1] + A[1, 2] * x[2],
                     A[2, 0] * x[0] + A[2, 1] * x[1] + A[2, 2] * x[2]])


@njit(cache=True)
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@njit(cache=True)
def _point(i, p, R, r, v, w, out):
    """World position, arm from the centre of mass and velocity of local point p of body i (-1: the
    ground, p in the world) into out[0:3], out[3:6], out[6:9]."""
    if i < 0:
        for k in range(3):
            out[k], out[3 + k], out[6 + k] = p[k], 0.0, 0.0
        return
    for k in range(3):
        out[3 + k] = R[i, k, 0] * p[0] + R[i, k, 1] * p[1] + R[i, k, 2] * p[2]
    s0, s1, s2 = out[3], out[4], out[5]
    out[0], out[1], out[2] = r[i, 0] + s0, r[i, 1] + s1, r[i, 2] + s2
    out[6] = v[i, 0] + w[i, 1] * s2 - w[i, 2] * s1
    out[7] = v[i, 1] + w[i, 2] * s0 - w[i, 0] * s2
    out[8] = v[i, 2] + w[i, 0] * s1 - w[i, 1] * s0


@njit(cache=True)
def _load(f, G, i, c, F, j, S, k, m):
    """Force c F[j] at world arm S[k, m] of body i onto the generalized forces f (nothing for the
    ground); scalar arithmetic: no array is allocated (it runs ~10 times a Newton iteration)."""
    if i < 0:
        return
    o = 7 * i
    Fx, Fy, Fz = c * F[j, 0], c * F[j, 1], c * F[j, 2]
    sx, sy, sz = S[k, m, 0], S[k, m, 1], S[k, m, 2]
    tx, ty, tz = sy * Fz - sz * Fy, sz * Fx - sx * Fz, sx * Fy - sy * Fx
    f[o], f[o + 1], f[o + 2] = f[o] + Fx, f[o + 1] + Fy, f[o + 2] + Fz
    for n in range(4):
        f[o + 3 + n] += G[i, 0, n] * tx + G[i, 1, n] * ty + G[i, 2, n] * tz


@njit(cache=True)
def _torque(f, G, i, c, t, j):
    if i >= 0:
        for n in range(4):
            f[7 * i + 3 + n] += c * (G[i, 0, n] * t[j, 0] + G[i, 1, n] * t[j, 1] + G[i, 2, n] * t[j, 2])


@njit(cache=True)
def arguments(q, q_t, ref, ia, pa, ib, pb, e, jc, jp, jax, jx, jy, jpos, jorig, turn, last, R, G, r, v, w, x, xd, N, S):
    """(x, x') of every element: points elements first (distance, or offset along e[j] when e[j] is
    non-zero), then joint laws (a slide along jax in the parent's frame, or a turn about it measured
    from jx towards jy, continuous from ``last``). Keeps each element's unit vector N and the arms and
    points S (points: arm a, arm b; joints: the child's origin and its arm) for ``forces``."""
    _poses(q, q_t, ref, R, G, r, v, w)
    a, b = np.empty(9), np.empty(9)
    npts = ia.shape[0]
    for j in range(npts):
        _point(ia[j], pa[j], R, r, v, w, a)
        _point(ib[j], pb[j], R, r, v, w, b)
        d0, d1, d2 = a[0] - b[0], a[1] - b[1], a[2] - b[2]
        u0, u1, u2 = a[6] - b[6], a[7] - b[7], a[8] - b[8]
        if e[j, 0] != 0.0 or e[j, 1] != 0.0 or e[j, 2] != 0.0:
            N[j, 0], N[j, 1], N[j, 2] = e[j, 0], e[j, 1], e[j, 2]
            x[j] = d0 * e[j, 0] + d1 * e[j, 1] + d2 * e[j, 2]
        else:
            L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            x[j] = L
            if L > 0.0:
                N[j, 0], N[j, 1], N[j, 2] = d0 / L, d1 / L, d2 / L
            else:   # the points coincide (a stop at rest): no direction, no force
                N[j, 0], N[j, 1], N[j, 2] = 0.0, 0.0, 0.0
        xd[j] = u0 * N[j, 0] + u1 * N[j, 1] + u2 * N[j, 2]
        for k in range(3):
            S[j, 0, k], S[j, 1, k] = a[3 + k], b[3 + k]
    for m in range(jc.shape[0]):
        j, c, p = npts + m, jc[m], jp[m]
        _point(c, jorig[m], R, r, v, w, a)        # the child's frame origin: world point, arm, velocity
        if p < 0:
            ax, bx, by = jax[m].copy(), jx[m].copy(), jy[m].copy()
            rel = a[0:3] - jpos[m]
            vrel = a[6:9].copy()
            wrel = w[c].copy()
        else:
            ax, bx, by = _mv(R[p], jax[m]), _mv(R[p], jx[m]), _mv(R[p], jy[m])
            rel = a[0:3] - (r[p] + _mv(R[p], jpos[m]))
            # the rate of ax . rel in the turning parent's frame: the child origin's velocity less that of the
            # parent's material point under it (ax turns with the parent, which cancels rel's own turn)
            vrel = a[6:9] - (v[p] + _cross(w[p], a[0:3] - r[p]))
            wrel = w[c] - w[p]
        N[j, 0], N[j, 1], N[j, 2] = ax[0], ax[1], ax[2]   # not N[j] = ax: its shape check's error path compiles ~1.5 s
        if turn[m]:
            cx = _mv(R[c], jx[m])
            raw = math.atan2(_dot(by, cx), _dot(bx, cx))
            # continuous across +-pi: the turn nearest the last call's (a step turns far less than pi)
            x[j] = last[m] + (raw - last[m] + math.pi) % (2.0 * math.pi) - math.pi
            last[m] = x[j]
            xd[j] = _dot(ax, wrel)
        else:
            x[j] = _dot(ax, rel)
            xd[j] = _dot(ax, vrel)
        for k in range(3):
            S[j, 0, k], S[j, 1, k] = a[k], a[3 + k]


@njit(cache=True)
def forces(T, ia, ib, jc, jp, turn, R, G, r, N, S, f):
    """Generalized forces f of the elements' values T: a points element's tension pulls a by -T N at
    its arm and b by +T N; a joint law's Q drives its coordinate up: Q N on the child at its origin
    (or a torque Q N) and the opposite on the parent, there."""
    f[:] = 0.0
    npts = ia.shape[0]
    for j in range(npts):
        _load(f, G, ia[j], -T[j], N, j, S, j, 0)
        _load(f, G, ib[j], T[j], N, j, S, j, 1)
    for m in range(jc.shape[0]):
        j, c, p = npts + m, jc[m], jp[m]
        if turn[m]:
            _torque(f, G, c, T[j], N, j)
            _torque(f, G, p, -T[j], N, j)
        else:
            _load(f, G, c, T[j], N, j, S, j, 1)
            if p >= 0:   # the parent is pushed at the same world point: its arm from its own centre
                for k in range(3):
                    S[j, 0, k] -= r[p, k]
                _load(f, G, p, -T[j], N, j, S, j, 0)


@njit(cache=True)
def pose_series(Q, Q_t, ref, R, G, r, v, w):
    """``_poses`` at each of a series of samples (the first axis of every array)."""
    for k in range(Q.shape[0]):
        _poses(Q[k], Q_t[k], ref, R[k], G[k], r[k], v[k], w[k])
