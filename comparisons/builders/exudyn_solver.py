"""The Exudyn builder's settings (comparisons.builders.exudyn: ``default_settings``, checked by
``check_settings``), Exudyn's solver settings from them, and its rank test for redundant constraints."""
from __future__ import annotations

import exudyn as exu
import exudyn.solver

from nsd_core.model.description import Model
from nsd_core.model.errors import ModelError

default_settings = {
    "step_size": 1e-4,             # largest step [s]; the step used is dt_out / n, the largest <= this
    "solver": "generalized_alpha",  # index 3; or "trapezoidal_index2" (no prescribed motions: Exudyn's
                                    # GenericJoint has no velocity-level offset)
    "spectral_radius": 0.8,        # generalized-alpha rho_inf: damps the multipliers' step-to-step ringing
    "newton_rel_tol": 1e-12,       # Newton's residual tolerances (relative, absolute); the index-3
    "newton_abs_tol": 1e-12,       # multipliers amplify position residuals by M / (beta h^2). Tight, so that
                                   # Newton's error stays below the step's, which the h, h/2 estimate sees:
                                   # at 1e-10 a ball joint's small angle kept 1.2e-8 of its peak at every step
                                   # (a false "disagrees"), a crank-rocker's drive torque grew as the step fell
                                   # (3.5e-4 of its peak at 2.5e-5 s; 7e-7 at 1e-12). Cost: 1.0-1.6x the steps
    "redundant_constraints": "auto",  # "auto": Exudyn's rank test at t = 0 picks the full-pivot LU when
                                      # it finds any; "ignore": always; "fail": never (singular -> error)
    "on_newton_failure": "relax",  # with closures: "relax" reruns once at RELAXED_REL_TOL; "fail"
    "forces": "compiled",          # the force elements: one object for all, its forces from compiled
                                   # kernels (exudyn_compiled; 2-4x faster), or "connectors": one connector
                                   # each with a Python user function (exudyn_forces, the readable
                                   # reference; the same equations, agreeing to Newton's tolerance);
                                   # "predicted": the compiled forces once a step at the Taylor-predicted
                                   # end of the step, constant in it (the hand-written adapter's scheme:
                                   # no Python in Newton's iterations; explicit in the forces)
    "outputs_from": "coordinates",  # the compiled paths' outputs from the recorded coordinates, all samples
                                    # at once (exudyn_replay), or "exudyn": each state set back into Exudyn
                                    # and read through it (the reference; the connectors always read so)
}
CHOICES = {"solver": ("generalized_alpha", "trapezoidal_index2"), "redundant_constraints": ("auto", "ignore", "fail"),
           "on_newton_failure": ("relax", "fail"), "forces": ("connectors", "compiled", "predicted"),
           "outputs_from": ("coordinates", "exudyn")}
# near a singular position Newton's relative residual stalls above 1e-10 (A02: h = 1e-3 s passes at
# 1e-9 and 1e-8, fails at 1e-10); 1e-8 still leaves A02's error second order in h (module docstring)
RELAXED_REL_TOL = 1e-8
PREDICTED_TOLERANCES = {"newton_rel_tol": 1e-12, "newton_abs_tol": 1e-14}   # forces = "predicted" (check_settings)
POSITIVE = ("step_size", "spectral_radius", "newton_rel_tol", "newton_abs_tol")


def check_settings(settings: dict | None, model: Model) -> dict:
    """Defaults updated by ``settings``; a bad key or value raises ModelError (one line)."""
    settings = settings or {}
    for k in settings:
        if k not in default_settings:
            raise ModelError(f"exudyn.{k}: unknown setting; allowed: {', '.join(default_settings)}")
    s = {**default_settings, **settings}
    if s["forces"] == "predicted":   # the adapter's tolerances, for its reason: at 1e-10 constant loads leave
        # isolated multiplier spikes (the 10 Hz gate case at h = 1.25e-5 s: 1.7e-4 of the peak force; 2.5e-7 here)
        s = {**s, **{k: v for k, v in PREDICTED_TOLERANCES.items() if k not in settings}}
    for k, allowed in CHOICES.items():
        if s[k] not in allowed:
            raise ModelError(f"exudyn.{k} = {s[k]!r}: allowed: {', '.join(allowed)}")
    for k in POSITIVE:
        if isinstance(s[k], bool) or not isinstance(s[k], (int, float)) or not s[k] > 0:
            raise ModelError(f"exudyn.{k} = {s[k]!r}: must be a number > 0")
    if s["solver"] == "generalized_alpha" and s["spectral_radius"] >= 1:
        raise ModelError(f"exudyn.spectral_radius = {s['spectral_radius']!r}: must be < 1 (index 3)")
    if s["solver"] == "trapezoidal_index2" and model.prescribed:
        raise ModelError(f"exudyn.solver = 'trapezoidal_index2': {model.name} has prescribed motions, whose "
                         "velocity-level offset Exudyn's GenericJoint lacks; allowed: generalized_alpha")
    return s


MAX_MODIFIED_NEWTON = 3   # modified Newton iterations before a new Jacobian (solver_settings)


def redundant_constraints(mbs, ss) -> int:
    """Exudyn's count of dependent constraint equations at t = 0 (its rank test of the Jacobian)."""
    info = exudyn.solver.ComputeSystemDegreeOfFreedom(mbs, ss, autoAssemble=False)
    return int(info["redundantConstraints"])


# above this many unknowns (coordinates and multipliers) a system without redundant constraints is solved
# with Eigen's sparse LU (Exudyn advises it above 1000); the full-pivot LU that redundant ones need is dense
SPARSE_ABOVE = 1000


def unknowns(mbs) -> int:
    """The assembled system's unknowns: ODE2 coordinates and algebraic ones (the multipliers)."""
    sd = mbs.systemData
    return len(sd.GetODE2Coordinates()) + len(sd.GetAECoordinates())


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
