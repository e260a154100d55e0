"""Axial two-point force elements on a mechanism: geometry in, wrenches out (compiled).

An element runs from a point on its "upper" body to a point on its "lower" body (GROUND = -1
allowed). ``element_kinematics`` gives every element's unit vector (lower -> upper), length and
length rate at once; ``apply_tensions`` turns scalar tensions (positive pulls the ends together,
negative pushes them apart) into wrenches about the global origin, [f; p x f], the form Eq. 8's
accumulated forces take.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, _nrt=False)
def _point_state(body, local, A, r, Z, p, v):
    for a in range(3):
        if body < 0:
            p[a] = local[a]
        else:
            acc = r[body, a]
            for b in range(3):
                acc += A[body, a, b] * local[b]
            p[a] = acc
    if body < 0:
        v[0] = v[1] = v[2] = 0.0
    else:  # s' + w x p
        w0, w1, w2 = Z[body, 3], Z[body, 4], Z[body, 5]
        v[0] = Z[body, 0] + w1 * p[2] - w2 * p[1]
        v[1] = Z[body, 1] + w2 * p[0] - w0 * p[2]
        v[2] = Z[body, 2] + w0 * p[1] - w1 * p[0]


@njit(cache=True, _nrt=False)
def element_kinematics(body_up, pts_up, body_lo, pts_lo, A, r, Z, P_up, P_lo, N, L, Ld, scratch):
    """Points, unit vectors, lengths and length rates of every element. scratch: (>= 4, 3)."""
    pu, pl, vu, vl = scratch[0], scratch[1], scratch[2], scratch[3]
    for e in range(body_up.shape[0]):
        _point_state(body_up[e], pts_up[e], A, r, Z, pu, vu)
        _point_state(body_lo[e], pts_lo[e], A, r, Z, pl, vl)
        d0, d1, d2 = pu[0] - pl[0], pu[1] - pl[1], pu[2] - pl[2]
        length = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        L[e] = length
        if length > 0.0:
            N[e, 0], N[e, 1], N[e, 2] = d0 / length, d1 / length, d2 / length
        else:   # coinciding points (a stop at rest): no direction, so no force and no rate
            N[e, 0], N[e, 1], N[e, 2] = 0.0, 0.0, 0.0
        Ld[e] = N[e, 0] * (vu[0] - vl[0]) + N[e, 1] * (vu[1] - vl[1]) + N[e, 2] * (vu[2] - vl[2])
        for a in range(3):
            P_up[e, a] = pu[a]
            P_lo[e, a] = pl[a]


@njit(cache=True, _nrt=False)
def apply_tensions(body_up, body_lo, P_up, P_lo, N, T, wrench):
    for e in range(body_up.shape[0]):
        for side in range(2):
            body = body_up[e] if side == 0 else body_lo[e]
            if body < 0:
                continue
            s = -T[e] if side == 0 else T[e]  # tension pulls the upper end down the element
            f0, f1, f2 = s * N[e, 0], s * N[e, 1], s * N[e, 2]
            p = P_up[e] if side == 0 else P_lo[e]
            wrench[body, 0] += f0
            wrench[body, 1] += f1
            wrench[body, 2] += f2
            wrench[body, 3] += p[1] * f2 - p[2] * f1
            wrench[body, 4] += p[2] * f0 - p[0] * f2
            wrench[body, 5] += p[0] * f1 - p[1] * f0


class AxialElements:
    """A fixed set of two-point elements; call ``state(kin)`` then ``wrench(tensions)``."""

    def __init__(self, body_up, pts_up, body_lo, pts_lo, n_bodies: int):
        self.body_up = np.asarray(body_up, dtype=np.int64)
        self.body_lo = np.asarray(body_lo, dtype=np.int64)
        self.pts_up = np.ascontiguousarray(pts_up, dtype=float).reshape(-1, 3)
        self.pts_lo = np.ascontiguousarray(pts_lo, dtype=float).reshape(-1, 3)
        self.n_bodies = n_bodies
        ne = len(self.body_up)
        self.P_up, self.P_lo, self.N = np.empty((ne, 3)), np.empty((ne, 3)), np.empty((ne, 3))
        self.L, self.Ld = np.empty(ne), np.empty(ne)

    def state(self, kin):
        """Unit vectors, lengths and length rates of all elements at kin (velocities required)."""
        element_kinematics(self.body_up, self.pts_up, self.body_lo, self.pts_lo, kin.A, kin.r, kin.Z,
                           self.P_up, self.P_lo, self.N, self.L, self.Ld, np.empty((4, 3)))
        return self.L, self.Ld

    def wrench(self, tensions: np.ndarray) -> np.ndarray:
        W = np.zeros((self.n_bodies, 6))
        apply_tensions(self.body_up, self.body_lo, self.P_up, self.P_lo, self.N,
                       np.asarray(tensions, dtype=float), W)
        return W
