"""Open-tree dynamics in relative coordinates: Eqs. 6-8, computed recursively.

Body i's inertia in origin-point form, with g its centre of mass (global) and J_G its inertia:
    M_i = [[m I, -m g~], [m g~, J_G - m g~ g~]],
    Q_i = [f - m w x g',  n_O - w x J_G w - m g x (w x g')],   g' = s' + w x g,
where (f, n_O) is the applied wrench about the global origin. The composite inertias
M^S = T^T M T (Eq. 7) and accumulated forces Q^S = T^T Q (Eq. 8) are sums over each subtree,
accumulated leaves to root, so no dense T^T M T is ever formed. The tree's equations are
    R_d^T M^S R_d z'' = R_d^T (Q^S - P^S),  P^S = T^T M (T R'_d z')  (Eq. 6 with lambda = 0).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from nsd_core.engine.kinematics import SCRATCH_ROWS, Kinematics, cross3
from nsd_core.engine.mechanism import Mechanism


@njit(cache=True, _nrt=False)
def linear_momentum_kernel(mass, com, A, r, Z, out):
    """The mechanism's linear momentum sum m_i (s'_i + w_i x g_i), g_i = r_i + A_i c_i (global
    centre of mass), into out (3,): what a force callback needs for the power of a moving frame's
    inertial forces (-m_i a_frame on every body)."""
    out[0] = out[1] = out[2] = 0.0
    for i in range(mass.shape[0]):
        m = mass[i]
        if m == 0.0:
            continue
        g0 = r[i, 0] + A[i, 0, 0] * com[i, 0] + A[i, 0, 1] * com[i, 1] + A[i, 0, 2] * com[i, 2]
        g1 = r[i, 1] + A[i, 1, 0] * com[i, 0] + A[i, 1, 1] * com[i, 1] + A[i, 1, 2] * com[i, 2]
        g2 = r[i, 2] + A[i, 2, 0] * com[i, 0] + A[i, 2, 1] * com[i, 1] + A[i, 2, 2] * com[i, 2]
        w0, w1, w2 = Z[i, 3], Z[i, 4], Z[i, 5]
        out[0] += m * (Z[i, 0] + w1 * g2 - w2 * g1)
        out[1] += m * (Z[i, 1] + w2 * g0 - w0 * g2)
        out[2] += m * (Z[i, 2] + w0 * g1 - w1 * g0)


@njit(cache=True, _nrt=False)
def body_terms_kernel(mass, com, inertia, gravity, A, r, Z, has_vel, Mb, Qb, scratch):
    """Per-body M_i into Mb (n,6,6) and gravity + velocity terms added into Qb (n,6).
    scratch: (>= 11, 3), so that nothing is allocated per call."""
    n = mass.shape[0]
    g = scratch[0]
    JG = scratch[1:4]
    G = scratch[4:7]
    t1 = scratch[7]
    gd = scratch[8]
    wgd = scratch[9]
    Jw = scratch[10]
    for i in range(n):
        m = mass[i]
        massless = m == 0.0
        for a in range(3):
            for b in range(3):
                massless = massless and inertia[i, a, b] == 0.0
        if massless:
            continue  # massless auxiliary body
        for a in range(3):
            acc = r[i, a]
            for b in range(3):
                acc += A[i, a, b] * com[i, b]
            g[a] = acc
        for a in range(3):  # JG = A J A^T as two 3x3 products (G holds A J for now)
            for d in range(3):
                acc = 0.0
                for c in range(3):
                    acc += A[i, a, c] * inertia[i, c, d]
                G[a, d] = acc
        for a in range(3):
            for b in range(3):
                acc = 0.0
                for d in range(3):
                    acc += G[a, d] * A[i, b, d]
                JG[a, b] = acc
        G[0, 0], G[0, 1], G[0, 2] = 0.0, -g[2], g[1]
        G[1, 0], G[1, 1], G[1, 2] = g[2], 0.0, -g[0]
        G[2, 0], G[2, 1], G[2, 2] = -g[1], g[0], 0.0
        for a in range(3):
            for b in range(3):
                GG = 0.0
                for c in range(3):
                    GG += G[a, c] * G[c, b]
                Mb[i, a, b] = m if a == b else 0.0
                Mb[i, a, 3 + b] = -m * G[a, b]
                Mb[i, 3 + a, b] = m * G[a, b]
                Mb[i, 3 + a, 3 + b] = JG[a, b] - m * GG
        for a in range(3):
            t1[a] = m * gravity[a]
        cross3(g, t1, gd)
        for a in range(3):
            Qb[i, a] += t1[a]
            Qb[i, 3 + a] += gd[a]
        if has_vel:
            w = Z[i, 3:]
            cross3(w, g, t1)
            for a in range(3):
                gd[a] = Z[i, a] + t1[a]
            cross3(w, gd, wgd)
            for a in range(3):
                Jw[a] = JG[a, 0] * w[0] + JG[a, 1] * w[1] + JG[a, 2] * w[2]
            cross3(w, Jw, t1)
            cross3(g, wgd, gd)
            for a in range(3):
                Qb[i, a] -= m * wgd[a]
                Qb[i, 3 + a] -= t1[a] + m * gd[a]


@njit(cache=True, _nrt=False)
def tree_kernel(parent, B, vp, Mb, Fb, Mred, Qred, F):
    """Subtree sums (Eqs. 7-8) leaves to root, then R_d^T M^S R_d and R_d^T (Q^S - P^S). F: a 6-vector
    of scratch."""
    n = parent.shape[0]
    for i in range(n):  # P_i = M_i vp_i moves to the force side
        for a in range(6):
            acc = 0.0
            for b in range(6):
                acc += Mb[i, a, b] * vp[i, b]
            Fb[i, a] -= acc
    for i in range(n - 1, -1, -1):
        p = parent[i]
        if p >= 0:
            for a in range(6):
                Fb[p, a] += Fb[i, a]
                for b in range(6):
                    Mb[p, a, b] += Mb[i, a, b]
    for k in range(n):
        for a in range(6):
            acc = 0.0
            for b in range(6):
                acc += Mb[k, a, b] * B[k, b]
            F[a] = acc
        j = k
        while j >= 0:  # ancestors of k share k's subtree composite inertia
            acc = 0.0
            for a in range(6):
                acc += B[j, a] * F[a]
            Mred[j, k] = acc
            Mred[k, j] = acc
            j = parent[j]
        acc = 0.0
        for a in range(6):
            acc += B[k, a] * Fb[k, a]
        Qred[k] = acc



@njit(cache=True, _nrt=False)
def tree_product(parent, B, vp, Mb, Qb, gen, v, bias, acc, F, out):
    """out = M v - Q (with ``bias``) or M v (without), M and Q those of tree_kernel, without forming M.

    Eqs. 7-8 applied to one vector: the bodies' accelerations T R_d v (+ vp: the velocity products)
    root to leaves, each body's M_i a_i - Qb_i, the subtree sums leaves to root, each summed wrench
    projected on its joint's b_k (minus the joint force gen_k). O(n) where M itself is O(n^2), so a
    mechanism with few free coordinates never needs the full matrix. acc, F: (n, 6) scratch; Mb, Qb
    the bodies' own terms (body_terms_kernel), left unchanged.
    """
    n = parent.shape[0]
    for i in range(n):
        p = parent[i]
        for a in range(6):
            acc[i, a] = (acc[p, a] if p >= 0 else 0.0) + B[i, a] * v[i]
    for i in range(n):
        massless = Mb[i, 0, 0] == 0.0 and Mb[i, 3, 3] == 0.0 and Mb[i, 4, 4] == 0.0 and Mb[i, 5, 5] == 0.0
        for a in range(6):
            f = -Qb[i, a] if bias else 0.0
            if not massless:  # a zero diagonal of the positive semidefinite M_i: M_i = 0
                for b in range(6):
                    f += Mb[i, a, b] * (acc[i, b] + vp[i, b] if bias else acc[i, b])
            F[i, a] = f
    for i in range(n - 1, -1, -1):
        p = parent[i]
        if p >= 0:
            for a in range(6):
                F[p, a] += F[i, a]
    for k in range(n):
        acc_k = 0.0
        for a in range(6):
            acc_k += B[k, a] * F[k, a]
        out[k] = acc_k - gen[k] if bias else acc_k


def body_inertia_terms(m: Mechanism, k: Kinematics, wrench: np.ndarray):
    """Per-body M_i (n,6,6) and Q_i (n,6), gravity and velocity terms included."""
    Mb = np.zeros((m.n, 6, 6))
    Qb = np.array(wrench, dtype=float, copy=True)
    Z = k.Z if k.Z is not None else np.zeros((m.n, 6))
    body_terms_kernel(m.mass, m.com, m.inertia, m.gravity, k.A, k.r, Z, k.Z is not None, Mb, Qb,
                      np.empty((SCRATCH_ROWS, 3)))
    return Mb, Qb


def tree_equations(m: Mechanism, k: Kinematics, wrench: np.ndarray, gen_force=None):
    """Reduced mass matrix R_d^T M^S R_d and force R_d^T (Q^S - P^S) (+ joint forces)."""
    Mb, Qb = body_inertia_terms(m, k, wrench)
    vp = k.vp if k.vp is not None else np.zeros((m.n, 6))
    M_red, Q_red = np.zeros((m.n, m.n)), np.zeros(m.n)
    tree_kernel(m.arrays.parent, k.B, vp, Mb, Qb, M_red, Q_red, np.empty(6))
    if gen_force is not None:
        Q_red = Q_red + gen_force
    return M_red, Q_red


def kinetic_energy(m: Mechanism, k: Kinematics) -> float:
    """T = 1/2 sum Z_i^T M_i Z_i."""
    Mb, _ = body_inertia_terms(m, Kinematics(k.A, k.r, k.B), np.zeros((m.n, 6)))
    return 0.5 * float(np.einsum("ni,nij,nj->", k.Z, Mb, k.Z))


def potential_energy_gravity(m: Mechanism, k: Kinematics) -> float:
    g = k.r + np.einsum("nij,nj->ni", k.A, m.com)
    return -float(np.sum(m.mass * (g @ m.gravity)))
