"""The Exudyn builder: a model description (nsd_core.model) run in Exudyn, with no per-mechanism code.

``simulate(model, duration, dt_out, settings) -> ModelRun``. Exudyn shares no formulation with the
in-house engine (minimal coordinates, recursive): here every described body is one rigid body on
redundant coordinates (the centre of mass and four Euler parameters, their normalisation an algebraic
equation), placed at its pose and velocity of ``initial_state(model)``, the state every engine
starts from; joints and loop closures are constraints with Lagrange multipliers (index 3).
- A tree joint is one GenericJoint between parent and child that locks the axes of the joint's frame
  the joint does not free (comparisons.builders.exudyn_frames); a prescribed coordinate locks its axis
  too, the offset following q(t) exactly (offsetUserFunction).
- A ``point`` closure locks the three translations, a ``revolute`` one also the two rotations
  across its axis. In a planar mechanism (``exudyn_frames.planar_normal``) a closure's out-of-plane
  equations repeat the tree's and make the Jacobian singular: only the two in-plane translations are
  locked. A spatial mechanism whose closures are still redundant (Bricard's, IFToMM A04: a revolute
  closure of which one equation follows from the others) is found by Exudyn's own rank test of the
  constraint Jacobian at t = 0 (``exudyn.solver.ComputeSystemDegreeOfFreedom``); it is then solved
  with Exudyn's option for redundant constraints, Eigen's full-pivoting LU
  (``linearSolver.ignoreSingularJacobian``), which gives the dependent multipliers a least-squares
  share and leaves the motion unique. The number found is ``stats["redundant_found"]``.
- Force elements, every law through the registry (nsd_core.model.laws), nothing here knowing which
  laws exist, evaluated at every Newton iteration (implicit): by default one ObjectGenericODE2 over all
  nodes whose force function is one compiled call generated for the model (exudyn_compiled,
  exudyn_codegen; a compiled Jacobian); ``forces = "connectors"``: one connector per element whose
  user function calls the law (exudyn_forces), the readable reference (the same equations, apart by
  Newton's tolerance); ``forces = "predicted"``: the compiled forces once a step at the Taylor-
  predicted end of the step, held through it (the hand-written adapter's scheme: second order, but
  explicit in the forces: on the device stable at the gate's 2.5e-4 s, not at 1e-3 s). A law's
  internal state (the SMA wire's stress, the Bouc-Wen zeta) is integrated with the motion by Heun's
  method at Exudyn's step, second order as generalized-alpha is: the force sees the state at the end
  of the step for the configuration Newton tries, the pre-step function commits it (exudyn_forces).
  What it costs and which step each benchmark mechanism needs: docs/models.md ("Exudyn's cost and
  steps").
- Prescribed motions: the joint's offset is a symbolic user function returning its parameters (run in
  C++), set to q(t_end) before each step: generalized-alpha (index 3) evaluates the constraint at the
  step's end only, so this is exact.
- Singular positions (IFToMM A02: all cranks aligned, the closures' Jacobian loses rank for an
  instant): Newton's relative residual stalls above 1e-10 near them and the step fails. With
  closures, a failed run is rerun once at newton_rel_tol = RELAXED_REL_TOL = 1e-8
  (``on_newton_failure = "relax"``, the default; "fail" keeps the error); ``stats
  ["newton_relaxed_after"]`` says where the first run failed, ``wall_time`` includes it. The
  relaxed tolerance is not the default: the drive forces are multipliers, which it leaves noisier.
- An excitation (``[excitation]``): -m a_g(t) on every body, a mass-proportional load set to
  -a_g(t_end) before each step (generalized-alpha's equations hold at the step's end): second order
  (tests/test_model_exudyn_seismic.py: a forced oscillator's error falls 4.0x per halving).
Outputs are read from the bodies' world poses at the output times (recorded by the pre-step function,
read after the run, by default from the recorded coordinates, all samples at once: exudyn_outputs,
exudyn_replay; ``wall_time`` is the stepping, ``output_time`` the reading; the step divides the
output interval): joint coordinates (angles continuous across +-pi), points and their
velocities, the laws' values (at the committed states), the drive's generalized force (the locked
axis' reaction; the sign of the in-house ``Evaluation.drive_force``: positive drives the coordinate
up), kinetic and gravity
energy (-sum m g . r_com, as nsd_core.engine.dynamics), work (exudyn_work: powers by the trapezoid).
"""
from __future__ import annotations

import math
import time

import numpy as np

import exudyn as exu
from exudyn.advancedUtilities import CreateSymbolicUserFunction
from exudyn.itemInterface import (LoadMassProportional, MarkerBodyMass, MarkerBodyRigid, ObjectGround,
                                  ObjectJointGeneric)
from exudyn.rigidBodyUtilities import RigidBodyInertia

from comparisons.builders.exudyn_compiled import CompiledForces
from comparisons.builders.exudyn_drive import DriveTable, GroundTable, offsets as _offsets
from comparisons.builders.exudyn_forces import LawStates, add_force
from comparisons.builders.exudyn_frames import (AXIS_OF_DOF, constrained_axes, cross, frame_with_z, joint_coordinates,
                                                joint_frame, law_axis, planar_normal)
from comparisons.builders.exudyn_outputs import Sampler
from comparisons.builders.exudyn_replay import SeriesReader
from comparisons.builders.exudyn_start import consistent_start
from comparisons.builders.subnormals import flushed
from comparisons.builders.exudyn_solver import (CHOICES, RELAXED_REL_TOL, check_settings, default_settings,  # noqa: F401
                                                SPARSE_ABOVE, redundant_constraints, solver_settings, unknowns)
from comparisons.builders.exudyn_work import Work
from comparisons.engines.base import EngineError, check_step_count
from comparisons.builders.exudyn_quiet import quiet_allocation_warning
from nsd_core.model.assemble import initial_state
from nsd_core.model.description import GROUND, Model
from nsd_core.model.laws import PLANE, POINTS
from nsd_core.model.errors import ModelError
from nsd_core.model.run import ModelRun, output_times

quiet_allocation_warning()

name = "exudyn"


def _local_frame(R_body_world, axis_world) -> np.ndarray:
    return frame_with_z(R_body_world.T @ axis_world)


class Build:
    """One description as an Exudyn system, with what the outputs need to read it back."""

    def __init__(self, model: Model, s: dict, h: float):
        self.model, self.s = model, s
        st = self.state = initial_state(model)
        self.SC = exu.SystemContainer()
        mbs = self.mbs = self.SC.AddSystem()
        self.ground = mbs.AddObject(ObjectGround())
        self.node, self.obj = {}, {GROUND: self.ground}
        grav = list(model.gravity)
        for b in model.bodies:
            R, c = st.rotation[b.name], np.asarray(b.com, dtype=float)
            com_w = st.origin[b.name] + R @ c
            d = mbs.CreateRigidBody(name=b.name, referencePosition=list(com_w), referenceRotationMatrix=R,
                                    initialVelocity=list(st.velocity[b.name] + np.cross(st.omega[b.name], R @ c)),
                                    initialAngularVelocity=list(st.omega[b.name]),
                                    inertia=RigidBodyInertia(b.mass, np.asarray(b.inertia, dtype=float), com=[0.0, 0.0, 0.0]),
                                    gravity=grav, nodeType=exu.NodeType.RotationEulerParameters,
                                    returnDict=True, show=False)
            self.node[b.name], self.obj[b.name] = d["nodeNumber"], d["bodyNumber"]
        self.excitation = model.excitation
        self.ground_loads = [self._ground_load(b.name) for b in model.bodies] if model.excitation is not None else []
        self.frames = {b.name: joint_frame(b) for b in model.bodies}
        self.symbolic, self.driven = [], []
        self.joints = {b.name: self._tree_joint(b) for b in model.bodies}
        self.normal = planar_normal(model, st) if model.loops else None
        for lp in model.loops:
            self._closure(lp)
        self.states = LawStates(h)
        if s["forces"] != "connectors" and model.forces:   # no elements: no object (its calls cost)
            self.connectors = []
            self.compiled = CompiledForces(self, self.states, predicted=s["forces"] == "predicted")
        else:
            self.connectors, self.compiled = [add_force(self, f, self.states) for f in model.forces], None

    def _ground_load(self, body: str):
        """-m a_g at the body's centre of mass (the excitation): a mass-proportional load, set to
        -a_g(t) at the end of every step (exudyn_drive.GroundTable: generalized-alpha solves the equations
        of motion at the step's end, its alpha averaging acting on the accelerations, not the loads, so
        a load that depends on time alone is exact there, set once a step); it starts at a_g(0), which
        the initial accelerations see."""
        marker = self.mbs.AddMarker(MarkerBodyMass(bodyNumber=self.obj[body]))
        return self.mbs.AddLoad(LoadMassProportional(markerNumber=marker,
                                                     loadVector=list(-self.excitation.acceleration(0.0))))

    def marker(self, body: str, point, frame=np.eye(3)):
        """A rigid marker at ``point`` of ``body`` (in the body's frame), axes ``frame`` (its columns
        in the body's frame); bodies' nodes sit at their centres of mass."""
        p = np.asarray(point, dtype=float) - (0.0 if body == GROUND else np.asarray(self.model.body(body).com))
        HT = np.eye(4)
        HT[:3, :3], HT[:3, 3] = frame, p
        return self.mbs.AddMarker(MarkerBodyRigid(bodyNumber=self.obj[body], localHT=HT))

    def _tree_joint(self, b):
        J = self.frames[b.name]
        axes = constrained_axes(b)
        drives = [p for p in self.model.prescribed if p.joint == b.name]
        kw = {}
        if drives:
            slots = {AXIS_OF_DOF[b.joint.type][p.dof]: p for p in drives}
            for k in slots:
                axes[k] = 1
            # Exudyn takes the translation offsets in the joint frame J0 while a translation stays free,
            # but in global coordinates once all three are locked (its GenericJoint equations): then
            # they are turned by J here, which is exact on the ground only (a moving parent's J0 turns)
            global_offsets = all(axes[:3]) and any(k < 3 for k in slots)
            if global_offsets and b.parent != GROUND:
                raise ModelError(f"prescribed.{next(p.name for p in drives if AXIS_OF_DOF[b.joint.type][p.dof] < 3)}: "
                                 f"the Exudyn builder drives a slide of {b.name}'s {b.joint.type} joint on the ground "
                                 f"or beside a free slide only (its parent {b.parent} moves, and Exudyn's joint then "
                                 "takes the offset in global coordinates)")
            J_offsets = J if global_offsets else None
            # the offset is its parameters, set to q(t_end) before each step (``drive``): generalized-
            # alpha (index 3) evaluates the constraint at the step's end only, so this is exact, and
            # the symbolic function runs in C++ (a Python offset function cost ~2 calls an iteration)
            sym = CreateSymbolicUserFunction(self.mbs, _offset, "offsetUserFunction", itemTypeName="ObjectJointGeneric")
            self.symbolic.append(sym)   # its expression tree must outlive the run
            kw = {"offsetUserFunction": sym, "offsetUserFunctionParameters": _offsets(slots, 0.0, J_offsets)}
        m0 = self.marker(b.parent, b.joint.position, J)
        m1 = self.marker(b.name, (0.0, 0.0, 0.0), J)
        joint = self.mbs.AddObject(ObjectJointGeneric(markerNumbers=[m0, m1], constrainedAxes=axes, **kw))
        if drives:
            self.driven.append((joint, slots, J_offsets))
        return joint

    def drive(self, t: float) -> None:
        """The prescribed offsets for the step ending at t (``_tree_joint``)."""
        for joint, slots, J in self.driven:
            self.mbs.SetObjectParameter(joint, "offsetUserFunctionParameters", _offsets(slots, t, J))

    def _rotation(self, body):
        return np.eye(3) if body == GROUND else self.state.rotation[body]

    def _closure(self, lp):
        Ra, Rb = self._rotation(lp.body_a), self._rotation(lp.body_b)
        if self.normal is not None:        # planar: the in-plane translations only
            Ja = _local_frame(Ra, self.normal)
            axes = [1, 1, 0, 0, 0, 0]
        elif lp.type == "revolute":
            Ja = _local_frame(Ra, Ra @ np.asarray(lp.axis_a, dtype=float))
            axes = [1, 1, 1, 1, 1, 0]
        else:
            Ja, axes = np.eye(3), [1, 1, 1, 0, 0, 0]
        Jb = Rb.T @ Ra @ Ja   # the same world axes at t = 0: the relative rotation starts at zero
        m0, m1 = self.marker(lp.body_a, lp.point_a, Ja), self.marker(lp.body_b, lp.point_b, Jb)
        self.mbs.AddObject(ObjectJointGeneric(markerNumbers=[m0, m1], constrainedAxes=axes))

    # ---- reading the description's quantities back -------------------------------------------------
    def poses(self) -> dict:
        """body -> (R, origin, origin velocity, omega) in the world, from the nodes (at the centres of
        mass); the ground's frame is the world's."""
        OV, mbs = exu.OutputVariableType, self.mbs
        out = {GROUND: (np.eye(3), np.zeros(3), np.zeros(3), np.zeros(3))}
        for b in self.model.bodies:
            n = self.node[b.name]
            R = np.asarray(mbs.GetNodeOutput(n, OV.RotationMatrix)).reshape(3, 3)
            w = np.asarray(mbs.GetNodeOutput(n, OV.AngularVelocity))
            c = R @ np.asarray(b.com, dtype=float)
            out[b.name] = (R, mbs.GetNodeOutput(n, OV.Position) - c,
                           mbs.GetNodeOutput(n, OV.Velocity) - cross(w, c), w)
        return out

    def coordinates(self, P: dict, body: str) -> list[float]:
        b = self.model.body(body)
        Rp, rp = P[b.parent][:2]
        Rc, rc = P[body][:2]
        return joint_coordinates(b, self.frames[body], Rp, rp, Rc, rc)

    def drive_force(self, p) -> float:
        """The generalized force of prescribed motion ``p``: the reaction of its locked axis, in the
        joint's frame. Exudyn's GenericJoint reports the torque on the child's marker (it drives the
        coordinate up) but the force on the parent's: a slide's reaction changes sign (measured
        against the in-house engine: a held slider pushed by a constant force or by gravity on
        prismatic and translational joints, a held crank under a constant torque)."""
        k = AXIS_OF_DOF[self.model.body(p.joint).joint.type][p.dof]
        OV = exu.OutputVariableType
        v = self.mbs.GetObjectOutput(self.joints[p.joint], OV.ForceLocal if k < 3 else OV.TorqueLocal)
        return float(v[k % 3]) if k >= 3 else -float(v[k])


def _offset(mbs, t, itemNumber, offsetUserFunctionParameters):
    """A GenericJoint's offset: its parameters (made a symbolic user function, evaluated in C++)."""
    return offsetUserFunctionParameters


def _run(model: Model, s: dict, duration: float, dt_out: float) -> ModelRun:
    t_out = output_times(duration, dt_out)
    per_out = max(1, int(math.ceil((t_out[1] - t_out[0]) / s["step_size"] - 1e-9)))
    n_steps = per_out * (len(t_out) - 1)
    build = Build(model, s, duration / n_steps)
    sample = Sampler(build)
    work = sample.work = Work(build, sample) if any(o.kind == "work" for o in model.outputs) else None
    counter = [0]
    h, compiled = duration / n_steps, build.compiled
    predicted = compiled is not None and compiled.predicted
    advance = compiled is not None and (predicted or bool(sample.stateful))

    start_lambda, step = None, None
    drive = DriveTable(build, h, n_steps).set if build.driven else None
    ground = GroundTable(build, h, n_steps) if build.ground_loads else None
    excite = ground.set if ground is not None else None
    if work is not None:
        work.ground = ground

    def pre_step(mbs, t):
        """t is the END of the step (Exudyn's convention); the state is the converged one at t - h."""
        nonlocal step
        n = counter[0]
        counter[0] = n + 1
        if excite is not None:
            excite(n, t)
        if drive is not None:
            drive(n, t)
        if step is not None:   # the laws' commit, and the predicted forces: one compiled call
            step()
        elif advance:   # the first step: Exudyn's vectors as its solver holds them (CompiledForces.stepper)
            step = compiled.stepper(mbs, h, predicted)
            step()
            build.states.started = True
        elif sample.stateful:
            sample.commit()
        if work is not None:   # the converged state at t - h, the states committed (no state moves after)
            work.step(t - h)
        if n == 0 and start_lambda is not None:   # Exudyn zeroes them when it does not compute its own
            build.mbs.systemData.SetAECoordinates(list(start_lambda), exu.ConfigurationType.Current)
        if n % per_out == 0:
            sample.record(t_out[n // per_out])
        return True

    build.mbs.SetPreStepUserFunction(pre_step)
    build.mbs.Assemble()
    if predicted:   # the initial accelerations see the forces at the initial state
        build.compiled.predict(build.mbs, 0.0)
    ss, redundant = _solver(build, model, s, n_steps, duration)
    # the drives' accelerations in the initial accelerations and multipliers (exudyn_start)
    start_lambda = consistent_start(build, ss, _offsets) if s["solver"] == "generalized_alpha" else None
    solver = {"generalized_alpha": exu.DynamicSolverType.GeneralizedAlpha,
              "trapezoidal_index2": exu.DynamicSolverType.TrapezoidalIndex2}[s["solver"]]
    why = "SolveDynamic returned False"
    try:
        with flushed():   # as MuJoCo's step loop (comparisons.builders.subnormals)
            begin = time.perf_counter()
            ok = build.mbs.SolveDynamic(ss, solverType=solver)
    except Exception as err:  # noqa: BLE001 (Exudyn's multi-line solver text, said on one line)
        ok, why = False, " ".join(str(err).split())[:200]
    if not ok or counter[0] != n_steps:
        raise EngineError(f"exudyn: {model.name}: solver failed in step {counter[0]} of {n_steps} "
                          f"(t = {counter[0] * duration / n_steps:.6g} s): {why}")
    if sample.stateful:
        sample.commit()
    if work is not None:
        work.step(duration, live=False)
    sample.record(t_out[-1])
    wall = time.perf_counter() - begin
    begin = time.perf_counter()
    series = s["outputs_from"] == "coordinates" and s["forces"] != "connectors"
    columns = sample.replay(SeriesReader(build, sample) if series else None)   # exudyn_outputs' docstring
    reading = time.perf_counter() - begin
    return ModelRun(name, t_out, columns,
                    {o.name: o.unit for o in model.outputs},
                    {"wall_time": wall, "output_time": reading, "steps": n_steps,
                     "closure_max": sample.closure, "tracking_error": sample.tracking,
                     **s, "step_size": duration / n_steps,   # the step used (the setting is its largest)
                     "redundant_found": redundant, "newton_relaxed_after": None,
                     "linear_solver": "sparse" if ss.linearSolver.solverType == exu.LinearSolverType.EigenSparse
                     else "dense"})


def _solver(build, model: Model, s: dict, n_steps: int, duration: float):
    """Exudyn's simulation settings for the run and the redundant constraints found (the full-pivot LU for
    them; Eigen's sparse LU above SPARSE_ABOVE unknowns)."""
    ss = solver_settings(s, n_steps, duration)
    redundant = redundant_constraints(build.mbs, ss) if model.loops and build.normal is None and s["redundant_constraints"] == "auto" else 0
    if redundant or s["redundant_constraints"] == "ignore":
        ss.linearSolver.ignoreSingularJacobian = True
    elif unknowns(build.mbs) > SPARSE_ABOVE:   # dense LU grows as n^3: A02 with N = 40 (1.3k unknowns) 118 ms a
        ss.linearSolver.solverType = exu.LinearSolverType.EigenSparse   # step dense, 1.8 ms sparse, the same to 2e-11
    return ss, redundant


def check(model: Model) -> None:
    """What this builder cannot build, said before any run (ModelError, one line): a joint law on a turn of
    a universal or spherical joint (Tait-Bryan angles no connector measures), a universal joint whose
    axes are not perpendicular, a prescribed slide of a joint whose parent moves with every translation
    locked (Exudyn then takes the offset in global coordinates)."""
    for b in model.bodies:
        joint_frame(b)
    for f in model.forces:
        if f.law.acts_on != POINTS:
            b = model.body(f.joint)
            for dof in (f.dofs if f.law.acts_on == PLANE else (f.dof,)):
                if law_axis(b, dof) is None:
                    raise ModelError(f"forces.{f.name}.joint = {f.joint!r}: the Exudyn builder applies joint laws on "
                                     f"slides and on revolute and planar turns only (this is a turn of a "
                                     f"{b.joint.type} joint)")
    for p in model.prescribed:
        b = model.body(p.joint)
        axes = constrained_axes(b)
        slots = [AXIS_OF_DOF[b.joint.type][q.dof] for q in model.prescribed if q.joint == b.name]
        for k in slots:
            axes[k] = 1
        if all(axes[:3]) and AXIS_OF_DOF[b.joint.type][p.dof] < 3 and b.parent != GROUND:
            raise ModelError(f"prescribed.{p.name}: the Exudyn builder drives a slide of {b.name}'s {b.joint.type} "
                             f"joint on the ground or beside a free slide only (its parent {b.parent} moves, and "
                             "Exudyn's joint then takes the offset in global coordinates)")


def simulate(model: Model, duration: float, dt_out: float, settings: dict | None = None) -> ModelRun:
    """The run; with closures, a Newton failure (a singular position, as A02's) is retried once at
    newton_rel_tol = RELAXED_REL_TOL (``on_newton_failure``; the module's docstring)."""
    s = check_settings(settings, model)
    t_out = output_times(duration, dt_out)   # a runaway step count fails its case before anything is built
    per_out = max(1, int(math.ceil((t_out[1] - t_out[0]) / s["step_size"] - 1e-9)))
    check_step_count("exudyn", per_out * (len(t_out) - 1))
    retry = bool(model.loops) and s["on_newton_failure"] == "relax" and s["newton_rel_tol"] < RELAXED_REL_TOL
    begin = time.perf_counter()
    exu.config.printToConsole = not retry   # a failure that is retried is no news: Exudyn's banner is kept off
    try:
        return _run(model, s, duration, dt_out)
    except EngineError as err:
        if not retry:
            raise
        first = str(err).split(": ", 2)[2]   # "solver failed in step ... (t = ...): why"
    finally:
        exu.config.printToConsole = True
    lost = time.perf_counter() - begin
    try:
        run = _run(model, {**s, "newton_rel_tol": RELAXED_REL_TOL}, duration, dt_out)
    except EngineError as err:
        raise EngineError(f"{err} (newton_rel_tol relaxed to {RELAXED_REL_TOL:g}; at {s['newton_rel_tol']:g}: "
                          f"{first})") from None
    run.stats["newton_relaxed_after"] = first
    run.stats["wall_time"] += lost   # the failed attempt counts: it is what the relaxed run cost
    return run
