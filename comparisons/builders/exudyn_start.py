"""Exudyn's initial accelerations and multipliers with the prescribed motions' accelerations in them.

Exudyn's generalized-alpha solver computes the initial accelerations from the equations of motion in
acceleration form, [M C_q^T; C_q 0] [q''; lambda] = [f; -(C_q q')_q q'], and neglects the constraints'
explicit time dependence (C_tt = 0; its source says so). A prescribed motion is such a dependence: the
joint's offset is q_drive(t), so its second derivative is missing, the initial accelerations are those
of a drive at rest in acceleration, and the multipliers (the drive forces) at t = 0 are wrong by the
drive's inertial share (a harmonically driven four-bar: 5 % of the peak torque). The inconsistent start
also makes the multipliers ring for a few tens of steps (generalized-alpha damps it by about rho_inf a
step), whatever the step.

``consistent_start`` lets Exudyn compute its initial accelerations and multipliers x0 as it does, then
adds the missing term: the system is linear in its right-hand side, so x = x0 + K^-1 db, with K
Exudyn's own matrix (its mass matrix and constraint Jacobian at t = 0) and db the prescribed offsets'
second derivatives in the drives' constraint rows, scaled as Exudyn's residual responds to an offset
(measured, not assumed). The run then starts from these accelerations (computeInitialAccelerations off,
so that the algorithmic accelerations start from them too), and the multipliers are the t = 0 sample's.
Dense systems only (the sparse solver's matrices are not read back); elsewhere Exudyn's start is kept.
"""
from __future__ import annotations

import exudyn as exu
import numpy as np

# Entries of the initial accelerations, and of the multipliers, below this fraction of the largest are
# round-off (of Exudyn's own solve and of the added term's) and are set to zero. The device's circle:
# 38 of the added term's 48 entries are 1e-32 to 1.7e-14 against a largest of 123, where the exact term
# is zero; driven four-bars of the campaign (seeds 92, 95, 119): 2-5 of 21 initial accelerations from
# Exudyn's own solve, seed 95's at 2.9e-16 of the largest, just above one machine epsilon (hence 1e3
# of them, 2.2e-13, for the threshold). Kept, they decay through the generalized-alpha's algorithmic
# accelerations into subnormal numbers, on which the processor's arithmetic is many times slower: on
# the circle 8 velocities stayed subnormal through the whole run, 1.5x the CPU time (circle_A22mm_f10Hz
# 5.97 -> 3.87 CPU s without them, the same Newton iterations; forces within 5.5e-7 of the peak;
# 2026-11-28).
ROUND_OFF = 1e3 * float(np.finfo(float).eps)
EPS = 1e-6   # the offset step for the residual's response (it is linear in the offset: the step is immaterial)


def _residual(solver, mbs, n2: int) -> np.ndarray:
    solver.ComputeAlgebraicEquations(mbs, False)
    return np.array(solver.GetSystemResidual())[n2:]


def consistent_start(build, ss, offsets) -> np.ndarray | None:
    """Set the initial accelerations of ``build``'s system to those with the drives' accelerations, switch
    ``ss`` to use them, and return the multipliers at t = 0 (None: no drive, or a sparse system).
    ``offsets(slots, t, J, derivative)``: a joint's six offsets (derivative 0) or their second derivative (2)."""
    if not build.driven or ss.linearSolver.solverType != exu.LinearSolverType.EigenDense:
        return None
    mbs, sd, CT = build.mbs, build.mbs.systemData, exu.ConfigurationType
    solver = exu.MainSolverImplicitSecondOrder()
    solver.InitializeSolver(mbs, ss)   # Exudyn's own initial accelerations and multipliers (C_tt = 0)
    a0, lam0 = np.array(sd.GetODE2Coordinates_tt(CT.Current)), np.array(sd.GetAECoordinates(CT.Current))
    n2, n = len(a0), len(a0) + len(lam0)
    solver.ComputeMassMatrix(mbs)
    M = np.array(solver.GetSystemMassMatrix())
    solver.SetSystemJacobian(np.zeros((n, n)))   # ComputeJacobianAE adds to what the matrix holds
    solver.ComputeJacobianAE(mbs, 1.0, 0.0, 1.0, False)
    K = np.array(solver.GetSystemJacobian())
    K[:n2, :n2] += M
    db = np.zeros(n)
    base = _residual(solver, mbs, n2)
    for joint, slots, J in build.driven:
        rows = np.array(sd.GetObjectLTGAE(joint))
        at_rest = offsets(slots, 0.0, J, 0)
        response = np.zeros((len(rows), 6))   # d residual / d offset, column by column
        for k in range(6):
            bumped = list(at_rest)
            bumped[k] += EPS
            mbs.SetObjectParameter(joint, "offsetUserFunctionParameters", bumped)
            response[:, k] = (_residual(solver, mbs, n2)[rows] - base[rows]) / EPS
        mbs.SetObjectParameter(joint, "offsetUserFunctionParameters", at_rest)
        db[n2 + rows] -= response @ np.asarray(offsets(slots, 0.0, J, 2), float)
    solver.FinalizeSolver(mbs, ss)
    dx = np.linalg.lstsq(K, db, rcond=None)[0]
    sd.SetODE2Coordinates_tt(list(without_dust(a0 + dx[:n2])), CT.Initial)
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = False
    ss.timeIntegration.generalizedAlpha.resetAccelerations = False
    return without_dust(lam0 + dx[n2:])


def without_dust(x: np.ndarray) -> np.ndarray:
    """``x`` with its entries below ROUND_OFF of its largest set to zero (see ROUND_OFF)."""
    x = np.array(x, dtype=float)
    x[np.abs(x) < ROUND_OFF * np.max(np.abs(x), initial=0.0)] = 0.0
    return x
