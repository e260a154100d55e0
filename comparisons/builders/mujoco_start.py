"""MuJoCo's drive forces and accelerations at t = 0 with its loop constraints taken as rigid.

MuJoCo's loop closures are soft: the constraint solver drives each connect's gap toward zero through
a reference acceleration -b v - k r, which has no term for the velocity product J' q' that a moving
closed loop needs (the rigid constraint's acceleration is J q'' = -J' q'). The consistent start
(r = 0, v = 0, shared by every engine) therefore begins with a transient of a few solref time
constants in which the loop's constraint forces miss that term; afterwards the gap r settles where k r
supplies it. The transient's length is a fixed number of steps (the time constant is a multiple of the
step), so the first output's drive force, reconstructed from the first steps' averages, carries an
error that does not shrink with the step (a driven crank-rocker: 1.9e-5 of the peak torque at every
timestep from 1e-4 to 2.5e-6 s; every later sample converges).

At t = 0 the state is exact, and MuJoCo's own model gives every term of the rigid equations of
motion: the mass matrix (mj_fullM, less the virtual drives' armature), the smooth forces
(qfrc_smooth: bias, gravity, the laws' passive forces, less the drives' feed-forward), each
connect's point Jacobians and their rates (mj_jac, mj_jacDot). Solving

    M q'' - J^T lambda - S tau = f,   J q'' = -J' q',   S^T q'' = q_drive''(t)

gives the accelerations and drive forces the soft constraint settles to as the step goes to zero,
which is what the later samples converge to. Redundant closure rows (a planar loop's out-of-plane
rows) are handled by a least-squares solve of the consistent system.
"""
from __future__ import annotations

import mujoco
import numpy as np


def rigid_start(m, d, drives: list, feeds: np.ndarray, pairs: list, acc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(q'', drive forces) at d's state with rigid loop closures. ``drives``: (Prescribed, qposadr, dofadr,
    armature); ``feeds``: each drive's feed-forward in d.qfrc_smooth (the callback's last evaluation);
    ``pairs``: the connects' (site a, site b) ids; ``acc``: each driven coordinate's prescribed q''(t).
    d must have been through mj_forward at this state."""
    nv, nd = m.nv, len(drives)
    M = np.zeros((nv, nv))
    mujoco.mj_fullM(m, d, M)
    f = np.array(d.qfrc_smooth, dtype=float)
    S = np.zeros((nv, nd))
    for i, (_, _, da, A) in enumerate(drives):
        M[da, da] -= A
        f[da] -= feeds[i]
        S[da, i] = 1.0
    rows, rates = [], []
    jp, jr = np.zeros((3, nv)), np.zeros((3, nv))
    for a, b in pairs:
        J, Jdot = np.zeros((3, nv)), np.zeros((3, nv))
        for site, sign in ((a, 1.0), (b, -1.0)):
            body, point = int(m.site_bodyid[site]), np.array(d.site_xpos[site])
            mujoco.mj_jac(m, d, jp, jr, point, body)
            J += sign * jp
            mujoco.mj_jacDot(m, d, jp, jr, point, body)
            Jdot += sign * jp
        rows.append(J)
        rates.append(-Jdot @ d.qvel)
    nc = 3 * len(pairs)
    J = np.vstack(rows) if rows else np.zeros((0, nv))
    K = np.zeros((nv + nc + nd, nv + nc + nd))
    K[:nv, :nv], K[:nv, nv:nv + nc], K[:nv, nv + nc:] = M, -J.T, -S
    K[nv:nv + nc, :nv], K[nv + nc:, :nv] = J, S.T
    rhs = np.concatenate([f, np.concatenate(rates) if rates else np.zeros(0), np.asarray(acc, float)])
    x = np.linalg.lstsq(K, rhs, rcond=1e-13)[0]
    return x[:nv], x[nv + nc:]
