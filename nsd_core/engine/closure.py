"""Loop closure: Phi (Eq. 13), its Jacobian Phi_z (Eq. 14), the velocity-product term, and the
dependent/independent partition by Gaussian elimination with full pivoting (Eqs. 9-10).

For a point p on body i, d p / d z'_j = b_j,v + b_j,w x p for every joint j on i's path; for a
body-fixed vector a, d a / d z'_j = b_j,w x a. The constraint acceleration is
Phi_z z'' + c(z, z') = 0, and ``closure`` returns c (the terms that do not multiply z'').
"""
from __future__ import annotations

import numpy as np
from numba import njit

from nsd_core.engine.kinematics import SCRATCH_ROWS, Kinematics, cross3, frozen
from nsd_core.engine.mechanism import Mechanism


@njit(cache=True, _nrt=False)
def _global(body, local, A, r, is_point, out):
    for a in range(3):
        if body < 0:
            out[a] = local[a]
        else:
            acc = r[body, a] if is_point else 0.0
            for b in range(3):
                acc += A[body, a, b] * local[b]
            out[a] = acc


@njit(cache=True, _nrt=False)
def closure_kernel(parent, kind, ca, va, cb, vb, A, r, B, Z, vp, with_rates, Phi, J, c, scratch,
                   with_positions=True):
    """Adds Phi, Phi_z (with_positions) and c (with_rates) into the given arrays. scratch: (>= 10, 3)."""
    row = 0
    p, t1, t2, vel = scratch[0], scratch[1], scratch[2], scratch[3]
    av, bv, axb = scratch[4], scratch[5], scratch[6]
    for k in range(kind.shape[0]):
        if kind[k] == 0:  # point coincidence: 3 rows
            for side in range(2):
                body = ca[k] if side == 0 else cb[k]
                sign = 1.0 if side == 0 else -1.0
                _global(body, va[k] if side == 0 else vb[k], A, r, True, p)
                if with_positions:
                    for a in range(3):
                        Phi[row + a] += sign * p[a]
                    j = body  # the ground (-1) has no column
                    while j >= 0:
                        cross3(B[j, 3:], p, t1)
                        for a in range(3):
                            J[row + a, j] += sign * (B[j, a] + t1[a])
                        j = parent[j]
                if body < 0:
                    continue
                if with_rates:
                    cross3(Z[body, 3:], p, t1)
                    for a in range(3):
                        vel[a] = Z[body, a] + t1[a]
                    cross3(vp[body, 3:], p, t1)
                    cross3(Z[body, 3:], vel, t2)
                    for a in range(3):
                        c[row + a] += sign * (vp[body, a] + t1[a] + t2[a])
            row += 3
        else:  # perpendicular body-fixed vectors: 1 row
            _global(ca[k], va[k], A, r, False, av)
            _global(cb[k], vb[k], A, r, False, bv)
            cross3(av, bv, axb)
            if with_positions:
                Phi[row] = av[0] * bv[0] + av[1] * bv[1] + av[2] * bv[2]
                for side in range(2):
                    j = ca[k] if side == 0 else cb[k]
                    sign = 1.0 if side == 0 else -1.0
                    while j >= 0:
                        J[row, j] += sign * (B[j, 3] * axb[0] + B[j, 4] * axb[1] + B[j, 5] * axb[2])
                        j = parent[j]
            if with_rates:
                wa, wb, al = scratch[7], scratch[8], scratch[9]
                wa[:] = 0.0
                wb[:] = 0.0
                al[:] = 0.0
                if ca[k] >= 0:
                    for a in range(3):
                        wa[a] = Z[ca[k], 3 + a]
                        al[a] += vp[ca[k], 3 + a]
                if cb[k] >= 0:
                    for a in range(3):
                        wb[a] = Z[cb[k], 3 + a]
                        al[a] -= vp[cb[k], 3 + a]
                cross3(wa, av, t1)
                cross3(t1, bv, t2)       # (wa x a) x b
                cross3(wb, bv, t1)
                cross3(av, t1, vel)      # a x (wb x b)
                acc = 0.0
                for a in range(3):
                    acc += (t2[a] + vel[a]) * (wa[a] - wb[a]) + axb[a] * al[a]
                c[row] = acc
            row += 1


def closure(m: Mechanism, k: Kinematics, with_rates: bool = False):
    """Phi (nc,), Phi_z (nc, n) and, with rates, the velocity-product term c (nc,)."""
    nc = m.n_constraints
    Phi, J, c = np.zeros(nc), np.zeros((nc, m.n)), np.zeros(nc)
    a = m.arrays
    Z = k.Z if with_rates else np.zeros((m.n, 6))
    vp = k.vp if with_rates else Z
    closure_kernel(*frozen(a.parent, a.cut_kind, a.cut_a, a.cut_va, a.cut_b, a.cut_vb), k.A, k.r, k.B, Z, vp,
                   bool(with_rates), Phi, J, c, np.empty((SCRATCH_ROWS, 3)), True)   # every argument: see frozen
    return Phi, J, (c if with_rates else None)


def full_pivot_elimination(J: np.ndarray, candidates: list[int], rel_tol: float = 1e-9,
                           n_pivots: int | None = None):
    """Gaussian elimination with full pivoting on J[:, candidates].

    Returns (pivot_rows, pivot_cols, pivots): the independent equations, the dependent coordinates
    (the columns where pivots fell) and the pivot magnitudes. Rows whose remaining entries fall
    below rel_tol * (largest first pivot) are redundant (a rank-deficient Phi_z, as in Bricard's
    mechanism) and are left out rather than divided by.

    With ``n_pivots`` the elimination takes exactly that many pivots (fewer only if the rest are
    exactly zero): used when re-partitioning near a singular position, where small pivots are
    genuine (the rank is only lost at the singular point itself) and the number of dependent
    coordinates must stay what it was at a regular configuration.
    """
    A = J[:, candidates].astype(float, copy=True)
    rows = list(range(A.shape[0]))
    cols = list(range(A.shape[1]))
    piv_rows, piv_cols, pivots = [], [], []
    scale = None
    while rows and cols:
        sub = np.abs(A[np.ix_(rows, cols)])
        ri, ci = np.unravel_index(int(np.argmax(sub)), sub.shape)
        pv = sub[ri, ci]
        if scale is None:
            scale = pv if pv > 0 else 1.0
        if (pv <= rel_tol * scale) if n_pivots is None else (len(pivots) >= n_pivots or pv == 0.0):
            break
        r, cc = rows[ri], cols[ci]
        for rr in rows:
            if rr != r:
                A[rr] -= A[rr, cc] / A[r, cc] * A[r]
        piv_rows.append(r)
        piv_cols.append(candidates[cc])
        pivots.append(pv)
        rows.remove(r)
        cols.remove(cc)
    return piv_rows, piv_cols, np.array(pivots)
