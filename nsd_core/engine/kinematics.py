"""Recursive kinematics in the semirecursive (origin-point) velocities, Eqs. 2-5.

For body i, Z_i = [s'_i; w_i]: s'_i is the velocity of the body point that coincides with the
global origin, w_i the angular velocity. Then Z_i = Z_parent + b_i z'_i (Eq. 4: Z = T R_d z'), with
b_i = [d x u; u] for a revolute joint (axis u through point d) and [u; 0] for a prismatic one, and
Z'_i = Z'_parent + b_i z''_i + b'_i z'_i (Eq. 5). ``vp`` accumulates the velocity-product terms
sum(b'_j z'_j) along the path, i.e. T R'_d z'.

The recursions are compiled with numba (they run millions of times on a handful of bodies, where
numpy's per-call overhead would dominate); the Python wrappers keep a plain-array interface.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from nsd_core.engine.mechanism import Mechanism


def cross(a, b) -> np.ndarray:
    """3-vector cross product (np.cross costs ~10x more on single small vectors)."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def cross_rows(A: np.ndarray, B) -> np.ndarray:
    """Row-wise A[k] x B[k] for an (m, 3) array A and an (m, 3) array or a 3-vector B."""
    B = np.asarray(B)
    b0, b1, b2 = B[..., 0], B[..., 1], B[..., 2]
    out = np.empty_like(A)
    out[:, 0] = A[:, 1] * b2 - A[:, 2] * b1
    out[:, 1] = A[:, 2] * b0 - A[:, 0] * b2
    out[:, 2] = A[:, 0] * b1 - A[:, 1] * b0
    return out


def axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' rotation matrix about a unit axis."""
    out = np.empty((3, 3))
    _rodrigues(axis, angle, out)
    return out


@njit(cache=True, _nrt=False)
def _rodrigues(u, angle, R):
    x, y, z = u[0], u[1], u[2]
    c, s = math.cos(angle), math.sin(angle)
    C = 1.0 - c
    R[0, 0] = c + x * x * C
    R[0, 1] = x * y * C - z * s
    R[0, 2] = x * z * C + y * s
    R[1, 0] = y * x * C + z * s
    R[1, 1] = c + y * y * C
    R[1, 2] = y * z * C - x * s
    R[2, 0] = z * x * C - y * s
    R[2, 1] = z * y * C + x * s
    R[2, 2] = c + z * z * C


SCRATCH_ROWS = 12  # rows of the (rows, 3) scratch array every recursion kernel takes


def frozen(*arrays):
    """Read-only views of a mechanism's arrays, as the compiled model holds them: a kernel called from
    Python with these and every argument given gets the specialisation the compiled evaluation made
    (loaded from the cache), not one more compiled at a first run (1.2 s for positions and closure)."""
    out = []
    for a in arrays:
        v = a.view()
        v.flags.writeable = False
        out.append(v)
    return out


@njit(cache=True, _nrt=False)
def cross3(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@njit(cache=True, _nrt=False)
def positions_kernel(parent, jtype, axis, offset, z, A, r, B, scratch, start=0):
    """Root to leaves: body rotations A, origins r and the columns b_i of R_d. jtype 1 = revolute.
    scratch: any (>= 6, 3) array, so that nothing is allocated per call. ``start``: bodies before it
    are taken as already current (their coordinates unchanged since the last call)."""
    n = parent.shape[0]
    Rj = scratch[0:3]
    u = scratch[3]
    d = scratch[4]
    tmp = scratch[5]
    for i in range(start, n):
        p = parent[i]
        for a in range(3):
            ua = 0.0
            da = 0.0
            for b in range(3):
                if p < 0:
                    Apab = 1.0 if a == b else 0.0
                else:
                    Apab = A[p, a, b]
                ua += Apab * axis[i, b]
                da += Apab * offset[i, b]
            u[a] = ua
            d[a] = da + (r[p, a] if p >= 0 else 0.0)
        if jtype[i] == 1:
            _rodrigues(axis[i], z[i], Rj)
            for a in range(3):
                for b in range(3):
                    acc = 0.0
                    for c in range(3):
                        acc += (A[p, a, c] if p >= 0 else (1.0 if a == c else 0.0)) * Rj[c, b]
                    A[i, a, b] = acc
                r[i, a] = d[a]
            cross3(d, u, tmp)
            for a in range(3):
                B[i, a] = tmp[a]
                B[i, 3 + a] = u[a]
        else:
            for a in range(3):
                for b in range(3):
                    A[i, a, b] = A[p, a, b] if p >= 0 else (1.0 if a == b else 0.0)
                r[i, a] = d[a] + z[i] * u[a]
                B[i, a] = u[a]
                B[i, 3 + a] = 0.0


@njit(cache=True, _nrt=False)
def velocities_kernel(parent, jtype, B, r, zd, Z, vp, scratch):
    """Root to leaves: Z_i = Z_p + b_i z'_i and vp_i = vp_p + b'_i z'_i (Eqs. 4-5). scratch: (>= 4, 3)."""
    n = parent.shape[0]
    udot = scratch[0]
    ddot = scratch[1]
    t1 = scratch[2]
    t2 = scratch[3]
    for i in range(n):
        p = parent[i]
        if p < 0:
            for a in range(6):
                Z[i, a] = B[i, a] * zd[i]
                vp[i, a] = 0.0  # the ground's axes do not move: b'_i = 0
            continue
        w = Z[p, 3:]
        if jtype[i] == 1:
            u = B[i, 3:]
            cross3(w, u, udot)
            cross3(w, r[i], t1)
            for a in range(3):
                ddot[a] = Z[p, a] + t1[a]
            cross3(ddot, u, t1)
            cross3(r[i], udot, t2)
            for a in range(3):
                vp[i, a] = vp[p, a] + (t1[a] + t2[a]) * zd[i]
                vp[i, 3 + a] = vp[p, 3 + a] + udot[a] * zd[i]
        else:
            cross3(w, B[i, :3], udot)
            for a in range(3):
                vp[i, a] = vp[p, a] + udot[a] * zd[i]
                vp[i, 3 + a] = vp[p, 3 + a]
        for a in range(6):
            Z[i, a] = Z[p, a] + B[i, a] * zd[i]


@dataclass
class Kinematics:
    """Mutable kinematic state of a mechanism at (z, z'): the recursions' results, all global."""
    A: np.ndarray    # (n, 3, 3) rotation of each body frame
    r: np.ndarray    # (n, 3) body frame origin
    B: np.ndarray    # (n, 6) columns b_i of R_d (Eq. 4)
    Z: np.ndarray | None = None   # (n, 6) Cartesian velocities (Eq. 2)
    vp: np.ndarray | None = None  # (n, 6) velocity-product accelerations T R'_d z' (Eq. 5)

    def point(self, i: int, local) -> np.ndarray:
        if i < 0:
            return np.asarray(local, dtype=float)
        return self.r[i] + self.A[i] @ np.asarray(local, dtype=float)

    def vector(self, i: int, local) -> np.ndarray:
        return np.asarray(local, dtype=float) if i < 0 else self.A[i] @ np.asarray(local, dtype=float)

    def point_velocity(self, i: int, p: np.ndarray) -> np.ndarray:
        """Velocity of the material point of body i at global position p: s' + w x p."""
        return np.zeros(3) if i < 0 else self.Z[i, :3] + cross(self.Z[i, 3:], p)


def positions(m: Mechanism, z: np.ndarray) -> Kinematics:
    """Forward position kinematics and the joint columns b_i of R_d (root to leaves)."""
    n = m.n
    A, r, B = np.empty((n, 3, 3)), np.empty((n, 3)), np.empty((n, 6))
    a = m.arrays
    positions_kernel(*frozen(a.parent, a.jtype, m.joint_axis, m.joint_offset), np.asarray(z, dtype=float), A, r, B,
                     np.empty((SCRATCH_ROWS, 3)), 0)   # start = 0 given: frozen says why
    return Kinematics(A, r, B)


def velocities(m: Mechanism, k: Kinematics, zd: np.ndarray) -> Kinematics:
    """Fill Z (Eq. 4) and the velocity-product terms vp (Eq. 5) into k, root to leaves."""
    k.Z, k.vp = np.empty((m.n, 6)), np.empty((m.n, 6))
    a = m.arrays
    velocities_kernel(a.parent, a.jtype, k.B, k.r, np.asarray(zd, dtype=float), k.Z, k.vp, np.empty((SCRATCH_ROWS, 3)))
    return k
