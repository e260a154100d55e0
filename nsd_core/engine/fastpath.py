"""Compiled fast path of SemiRecursiveSystem.rhs_parts: the same equations, fused into three calls.

``SemiRecursiveSystem`` keeps the readable numpy version of each step (the specification); these
kernels do the identical arithmetic without numpy's per-call overhead, which dominates on a
ten-body tree. tests/test_engine.py checks that both paths agree to round-off.
    newton_kernel:    Newton on the independent loop equations for the dependent coordinates;
    velocity_kernel:  positions, Phi_z, the dependent velocities (Eq. 10), Z, vp and c (Eq. 5);
    dynamics_kernel:  Eqs. 7-8 recursively, Eq. 12 in the free coordinates, and the reactions.
Linear algebra is LAPACK's (numba's np.linalg), as in the numpy path; a singular block raises, and
the caller then takes the numpy path, which handles it.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from nsd_core.engine.closure import closure_kernel
from nsd_core.engine.dynamics import body_terms_kernel, tree_kernel
from nsd_core.engine.kinematics import positions_kernel, velocities_kernel


@njit(cache=True)
def newton_kernel(parent, jtype, axis, offset, ck, ca, cva, cb, cvb, z, rows, dep, tol, maxit, nc, A, r, B):
    """Newton from z (updated in place). Returns 1 converged, 0 not converged."""
    Phi = np.zeros(nc)
    J = np.zeros((nc, z.shape[0]))
    dummy = np.zeros((z.shape[0], 6))
    nd = dep.shape[0]
    Jd = np.empty((nd, nd))
    rhs = np.empty(nd)
    for _ in range(maxit):
        positions_kernel(parent, jtype, axis, offset, z, A, r, B)
        Phi[:] = 0.0
        J[:, :] = 0.0
        closure_kernel(parent, ck, ca, cva, cb, cvb, A, r, B, dummy, dummy, False, Phi, J, Phi)
        # converged when the residual is at round-off of the positions (near a singular position
        # the step cannot shrink below the conditioning, but the loop is already closed)
        res, pos = 0.0, 1.0
        for i in range(nd):
            res = max(res, abs(Phi[rows[i]]))
        for i in range(r.shape[0]):
            for a in range(3):
                pos = max(pos, abs(r[i, a]))
        if res <= 4e-16 * pos:
            return 1
        for i in range(nd):
            rhs[i] = Phi[rows[i]]
            for j in range(nd):
                Jd[i, j] = J[rows[i], dep[j]]
        step = np.linalg.solve(Jd, rhs)  # LAPACK, as the numpy path; singular raises to the caller
        smax, zmax = 0.0, 0.0
        for i in range(nd):
            z[dep[i]] -= step[i]
            smax = max(smax, abs(step[i]))
            zmax = max(zmax, abs(z[dep[i]]))
        if smax < tol * (1.0 + zmax):
            return 1
    return 0


@njit(cache=True)
def velocity_kernel(parent, jtype, axis, offset, ck, ca, cva, cb, cvb, z, zd, rows, dep, A, r, B, Z, vp,
                    Phi, J, c, Jd_inv):
    """zd holds the prescribed and free velocities on entry; the dependent ones are filled in."""
    positions_kernel(parent, jtype, axis, offset, z, A, r, B)
    Phi[:] = 0.0
    J[:, :] = 0.0
    closure_kernel(parent, ck, ca, cva, cb, cvb, A, r, B, Z, vp, False, Phi, J, c)
    nd = dep.shape[0]
    Jd = np.empty((nd, nd))
    for i in range(nd):
        for j in range(nd):
            Jd[i, j] = J[rows[i], dep[j]]
    inv = np.linalg.inv(Jd)  # LAPACK, as the numpy path; singular raises to the caller
    Jd_inv[:, :] = inv
    for j in range(nd):
        zd[dep[j]] = 0.0
    t = np.zeros(nd)
    for i in range(nd):
        acc = 0.0
        for k in range(z.shape[0]):
            acc += J[rows[i], k] * zd[k]
        t[i] = acc
    for j in range(nd):
        acc = 0.0
        for i in range(nd):
            acc += inv[j, i] * t[i]
        zd[dep[j]] = -acc
    velocities_kernel(parent, jtype, B, r, zd, Z, vp)
    Phi2 = np.zeros(Phi.shape[0])
    J2 = np.zeros(J.shape)
    c[:] = 0.0
    closure_kernel(parent, ck, ca, cva, cb, cvb, A, r, B, Z, vp, True, Phi2, J2, c)
    return True


@njit(cache=True)
def dynamics_kernel(parent, mass, com, inertia, gravity, A, r, B, Z, vp, wrench, gen, J, c, rows, dep, free,
                    pres, qdd, Jd_inv, zdd, lam, tau):
    """Eq. 12 in the free coordinates (z'' = R_z z''_f + z''_0) and the reactions lambda, tau."""
    n = parent.shape[0]
    Mb = np.zeros((n, 6, 6))
    Qb = wrench.copy()
    body_terms_kernel(mass, com, inertia, gravity, A, r, Z, True, Mb, Qb)
    M = np.zeros((n, n))
    Q = np.zeros(n)
    tree_kernel(parent, B, vp, Mb, Qb, M, Q)
    for i in range(n):
        Q[i] += gen[i]
    nd, nf, npr = dep.shape[0], free.shape[0], pres.shape[0]
    Rz = np.zeros((n, nf))
    for a in range(nf):
        Rz[free[a], a] = 1.0
        for j in range(nd):
            acc = 0.0
            for i in range(nd):
                acc -= Jd_inv[j, i] * J[rows[i], free[a]]
            Rz[dep[j], a] = acc
    zdd0 = np.zeros(n)
    for a in range(npr):
        zdd0[pres[a]] = qdd[a]
    for j in range(nd):
        acc = 0.0
        for i in range(nd):
            rhs_i = -c[rows[i]]
            for a in range(npr):
                rhs_i -= J[rows[i], pres[a]] * qdd[a]
            acc += Jd_inv[j, i] * rhs_i
        zdd0[dep[j]] = acc
    MRz = M @ Rz
    lhs = Rz.T @ MRz
    rhs = Rz.T @ (Q - M @ zdd0)
    zfdd = np.linalg.solve(lhs, rhs)
    zdd[:] = Rz @ zfdd + zdd0
    res = M @ zdd - Q
    for j in range(nd):
        acc = 0.0
        for i in range(nd):
            acc += Jd_inv[i, j] * res[dep[i]]
        lam[j] = acc
    for a in range(npr):
        acc = res[pres[a]]
        for i in range(nd):
            acc -= J[rows[i], pres[a]] * lam[i]
        tau[a] = acc
    return True
