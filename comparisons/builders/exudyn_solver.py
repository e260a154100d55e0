"""Exudyn's solver settings for comparisons.builders.exudyn (the builder's settings dict ``s``), and its
rank test for redundant constraints."""
from __future__ import annotations

import exudyn as exu
import exudyn.solver

MAX_MODIFIED_NEWTON = 3   # modified Newton iterations before a new Jacobian (solver_settings)


def redundant_constraints(mbs, ss) -> int:
    """Exudyn's count of dependent constraint equations at t = 0 (its rank test of the Jacobian)."""
    info = exudyn.solver.ComputeSystemDegreeOfFreedom(mbs, ss, autoAssemble=False)
    return int(info["redundantConstraints"])


def solver_settings(s: dict, n_steps: int, duration: float):
    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    ti.numberOfSteps, ti.endTime, ti.verboseMode, ti.adaptiveStep = n_steps, duration, 0, False
    ti.newton.relativeTolerance, ti.newton.absoluteTolerance = float(s["newton_rel_tol"]), float(s["newton_abs_tol"])
    ti.newton.useModifiedNewton = True
    # a new Jacobian after 3 modified iterations (Exudyn's default 8): the device's drive (h = 2.5e-4 s)
    # converged in 7.0 iterations a step on Jacobians kept from t = 0, in 3.9 with this (361 Jacobians
    # in 8000 steps; 4.6 and 128 at 4; each Jacobian ~80 us, the force object's compiled): 1.6x
    # faster, the same solution to Newton's tolerance (~2e-8 of the peak force)
    ti.newton.maxModifiedNewtonIterations = MAX_MODIFIED_NEWTON
    ti.generalizedAlpha.spectralRadius = float(s["spectral_radius"])
    ti.generalizedAlpha.computeInitialAccelerations = True
    ss.linearSolver.solverType = exu.LinearSolverType.EigenDense
    ss.solution.file.write = False
    ss.solution.sensors.active = False   # outputs are recorded in the pre-step function, never written
    ss.show.statistics = ss.show.computationTime = False
    return ss
