"""The device in Exudyn: redundant-coordinate rigid bodies, joints as constraints, the drive as motion.

Model (docs/model.md, drive mode). Base = ground. Wall, rod and cap are ``ObjectRigidBody`` bodies on
``NodeRigidBodyEP`` nodes (3 positions + 4 Euler parameters each, the Euler-parameter normalisation
an algebraic equation: Exudyn's redundant coordinates). Constraints (index 3, Lagrange multipliers):
- the wall's vertical guide: a GenericJoint ground-wall locking X, Y and the three rotations;
- the rod: a SphericalJoint at each end (lower = wall reference, upper = cap reference). The rod's
  spin about its own axis is free and never excited (axisymmetric inertia: no gyroscopic torque
  about the axis), but it needs a non-zero axial inertia for a regular mass matrix:
  ``rod_axial_inertia`` x the transverse inertia (1e-3, i.e. ~1.3e-9 kg m^2);
- the cap's guide: a GenericJoint ground-cap locking its rotations (the plate holds it level); the
  drive: two CoordinateConstraints on the cap's X and Y coordinates with offsets x(t), y(t), the
  plate's path (nsd_core.drive.Drive.plate_at), set once per step to u(t_end) in a PreStepUserFunction (exact at index 3 with a
  fixed step), or as offset user functions (position and velocity, needed by the index-2 solver).
  The cap's Z is free (it slides in the plate). The initial velocities (the cap's p'(0), the rod
  swinging about its lower joint) are consistent with the drive.
The drive force vector (F_x, F_y) = -(lambda_x, lambda_y) is read from the multipliers of those two
constraints through SensorObject(OutputVariableType.Force) (sign checked against
nsd_core.quasistatic); nsd_core.outputs.device_columns builds the other columns.

Force elements (Eqs. 16-18), all through nsd_core.forces, in one of two ways (``forces``):
- "per_step" (default): a PreStepUserFunction predicts the end-of-step configuration with a
  second-order Taylor step from the converged state (q + h q' + h^2/2 q''; the cap's X, Y exact),
  evaluates all elements there at once (numpy over the elements) and sets two LoadForceVector
  loads (on the cap node and on the wall node), constant within the step. The prediction error is
  O(h^3) per step, so the loads are as good as implicit forces: at 10 Hz the result matches
  "per_iteration" to ~1e-5 of the peak force, at a quarter of the cost (one Python call per step).
  By default (``force_code = "compiled"``) that step is one call of exudyn_native.step, the same
  computation on the shared scalar laws; "python" keeps the numpy form (``_Elements.step``). At the
  1e-4 aim the compiled step halves Exudyn's time per cycle (A = 15 mm, 1 Hz, h = 2.5e-4 s:
  0.69 -> 0.30 s CPU, loaded 2-core machine), and results are unchanged (max|dF| = 0 in the test).
- "per_iteration": one ObjectGenericODE2 on the cap and wall nodes whose forceUserFunction
  evaluates all elements at every Newton residual (implicit; numerical Jacobian).
Forces act at the body reference points: the cap and the wall only translate (rotations locked), so
the moments of the off-centre attachment points go only into the rotation locks' reactions.

Hysteretic states (SMA stress per wire, Eq. 17; Bouc-Wen zeta, Eq. 18). The laws are rate-
independent and each state's driving strain is a scalar, so they are integrated in strain, once per
accepted step, from the committed states (eps_c, sigma_c), (x_c, zeta_c) at the last converged
configuration along the straight increment to the new one, with nsd_core's advance_wire_stress /
advance_spring_zeta: Heun's method by default (order 2, two slope evaluations); "rk4" (order 4)
gives the same loops to < 1e-6, since a step moves the strain < 1e-4.
"per_step" commits the converged step and predicts the next one in one batched call; in
"per_iteration" the force function is pure (it starts from the committed states every residual) so
Newton and its Jacobian see one smooth function, and the states are committed in the pre-step.

Solver options measured (SimulationSettings set by hand on the default model, two runs each,
interleaved; A = 15 mm, 1 Hz, h = 2.5e-4 s, 2 cycles, CPU per cycle, loaded 2-core machine):
Eigen's dense LU ("eigen_dense", kept) 4.6 Newton iterations a step against 5.3 with Exudyn's own
dense solver, ~5-10 % faster, forces within 1e-8 of the peak;
Eigen sparse slower (7.2 iterations); full Newton, a Jacobian per step, a modified-Newton
contractivity of 0.1, at most 3 modified iterations, no initial-residual adaption: within +-7 %
(noise), same error; Newmark (no numerical damping) 60x the error; Newton tolerance 1e-10 the same
error, 1e-8 spikes of 4e-3 (kept 1e-12). Where the time goes then: ~43 us a step in Exudyn's solver,
~32 us in the Python pre-step (node outputs, loads, drive offsets, samples). Since issue 26 the
pre-step is one compiled call (``exudyn_native.pre_step``: three ODE2-vector fetches instead of six
node outputs, the prediction and the plate's path compiled) plus the four parameter sets: A = 25.5 mm,
1 Hz at h = 6.25e-6 s went from 62 to 54 us a step (quiet machine), the same numbers bit for bit.
Solver: generalized-alpha (index 3), fixed step dividing the output interval, spectral radius 0.8
(damps the multipliers' step-to-step oscillation; at 0.9 they are noisy to ~5e-4 of the peak force,
at 0.5 the 250 Hz mode's phase error is 1.5x larger), modified Newton with tight residual
tolerances (rel 1e-12, abs 1e-14: the index-3 multiplier amplifies position residuals by
M/(beta h^2) ~ 1e10). Accuracy is then limited by the phase of the ringing ~250 Hz vertical mode
after the slack events at A = 0.0255 m, second order in h. Measured against nsd_core.device.simulate
(rtol 1e-10), last cycle, max|dF|/peak: 1 Hz 1.3e-4 (A = 0.0255 m, h = 1e-5 s), 5e-7 (A = 0.015 m);
10 Hz 5e-5 (A = 0.0255 m, h = 5e-6 s), 6e-6 (A = 0.015 m); loop areas within 1.3e-5
(benchmarks/convergence_exudyn.py).
"""
from __future__ import annotations

import math
import time

import numpy as np

import exudyn as exu
from exudyn.itemInterface import (LoadForceVector, MarkerNodePosition, ObjectGenericODE2, SensorNode,
                                  SensorObject)
from exudyn.rigidBodyUtilities import RigidBodyInertia

from comparisons.engines import exudyn_native
from comparisons.engines.exudyn_quiet import quiet_allocation_warning
from comparisons.engines.base import DEFAULT_MODEL, EngineError, check_step_count, merged_settings
from nsd_core.device.drive import Drive
from nsd_core.device.forces import advance_spring_zeta, advance_wire_stress, rope_tension, spring_push, wire_tension
from nsd_core.device.geometry import device_geometry
from nsd_core.device.outputs import device_columns
from nsd_core.device.params import ParameterError, Params
from nsd_core.device.results import RunResult
from comparisons.engines.perturb import perturbed

quiet_allocation_warning()


class _Elements:
    """All force elements of the device (Eqs. 16-18) as functions of the cap and wall positions.

    Holds the committed hysteretic states (eps_c, sigma_c) per wire and (x_c, zeta_c) for the spring,
    valid at the last converged configuration.
    """

    def __init__(self, g, integrator="heun", compiled=False):
        self.g = g
        self.order = 2 if integrator == "heun" else 4  # Heun or RK4 along the strain (nsd_core.forces)
        self.compiled = compiled   # step() through exudyn_native (same laws, one compiled call)
        # the compiled step's constants: a stiffness per rope (one value, or a perturbed rope's own)
        k_rope = np.broadcast_to(np.asarray(g.rope_stiffness, dtype=float), (g.n_ropes,)).copy()
        self.consts = (g.rope_offsets, np.asarray(g.rope_natural_length, dtype=float), k_rope,
                       g.wire_offsets, np.array(tuple(g.wire), dtype=float), np.array(tuple(g.spring), dtype=float))
        self._out = np.zeros(6)
        self.sigma = g.initial_wire_stress().astype(float)
        self.zeta = float(g.spring_zeta0)
        self.eps = self.wire_strain(np.array([0.0, 0.0, g.cap_rest_z]), g.wall_rest_z)[1]
        self.x = g.spring.free_length - g.wall_rest_z

    def wire_strain(self, cap, wall_z):
        v = self.g.wire_offsets + (cap - [0.0, 0.0, wall_z])
        L = np.sqrt((v * v).sum(1))
        return v, (L - self.g.wire.natural_length) / self.g.wire.natural_length, L

    def forces_with(self, cap, wall_z, v, L, sigma, zeta):
        """Force on the cap (3) and on the wall (3) for given wire stresses and spring zeta."""
        g = self.g
        r = self.g.rope_offsets + cap
        rl = np.sqrt((r * r).sum(1))
        t_rope = rope_tension(rl, g.rope_natural_length, g.rope_stiffness)          # Eq. 16
        t_wire = wire_tension(sigma, g.wire)                                           # Eq. 17a
        f_wire = ((t_wire / L)[:, None] * v).sum(0)
        f_cap = -((t_rope / rl)[:, None] * r).sum(0) - f_wire
        push = float(spring_push(wall_z, 0.0, zeta, g.spring)[0])                      # Eq. 18, push only
        return f_cap, f_wire + [0.0, 0.0, push]

    def advance_wire(self, eps0, eps1, sigma):
        """Eq. 17 integrated in strain from eps0 to eps1 (one straight, monotonic strain increment)."""
        return advance_wire_stress(eps0, eps1, sigma, self.g.wire, order=self.order)

    def advance_spring(self, x0, x1, zeta):
        """Eq. 18b integrated in the compression x_s from x0 to x1."""
        return advance_spring_zeta(x0, x1, zeta, self.g.spring, order=self.order)

    # ---- "per_iteration": a pure function of the configuration, from the committed states ----
    def states(self, cap, wall_z):
        g = self.g
        v, eps, L = self.wire_strain(cap, wall_z)
        sigma = self.advance_wire(self.eps, eps, self.sigma) if g.n_wires else self.sigma
        x = g.spring.free_length - wall_z
        zeta = float(self.advance_spring(self.x, x, self.zeta))
        return v, eps, L, sigma, x, zeta

    def forces(self, cap, wall_z):
        v, _, L, sigma, _, zeta = self.states(cap, wall_z)
        return self.forces_with(cap, wall_z, v, L, sigma, zeta)

    def commit(self, cap, wall_z):
        _, self.eps, _, self.sigma, self.x, self.zeta = self.states(cap, wall_z)

    # ---- "per_step": commit the converged step and predict the next one in one batched call ----
    def step(self, cap, wall_z, cap_p, wall_p):
        """Commit the states at the converged (cap, wall_z); return the forces at the predicted
        end of the next step (cap_p, wall_p).

        Each law is rate-independent and its strain is a scalar, so its path is an interval: the
        commit (eps_c -> eps_n) and the prediction (eps_c -> eps_p) start from the same committed
        state and run as one vectorised RK4 call (advance_*), twice the rows for the price of one.
        Where the strain turns at eps_n (the next increment runs against the last one) the straight
        path eps_c -> eps_p would miss the turn, so that prediction is redone from (eps_n, sigma_n).
        """
        if self.compiled:
            ro, rl0, rk, wo, wire, spring = self.consts
            self.eps, self.sigma = np.array(self.eps, dtype=float), np.array(self.sigma, dtype=float)
            self.x, self.zeta = exudyn_native.step(np.asarray(cap, dtype=float), float(wall_z), cap_p, float(wall_p),
                                                   self.eps, self.sigma, self.x, self.zeta, ro, rl0, rk, wo, wire,
                                                   spring, self.order, self._out)
            return self._out[0:3].copy(), self._out[3:6].copy()
        g, nw = self.g, self.g.n_wires
        eps_n = self.wire_strain(cap, wall_z)[1]
        v, eps_p, L = self.wire_strain(cap_p, wall_p)
        x_n, x_p = g.spring.free_length - wall_z, g.spring.free_length - wall_p
        if nw:
            s = self.advance_wire(np.concatenate([self.eps, self.eps]), np.concatenate([eps_n, eps_p]),
                                  np.concatenate([self.sigma, self.sigma]))
            sig_n, sig_p = s[:nw], s[nw:]
            rev = (eps_p - eps_n) * (eps_n - self.eps) <= 0.0  # the strain turns (or rests) at eps_n
            if rev.any():
                sig_p = np.where(rev, self.advance_wire(eps_n, eps_p, sig_n), sig_p)
            self.eps, self.sigma = eps_n, sig_n
        z = self.advance_spring(np.array([self.x, self.x]), np.array([x_n, x_p]),
                                np.array([self.zeta, self.zeta]))
        zeta_n, zeta_p = float(z[0]), float(z[1])
        if (x_p - x_n) * (x_n - self.x) <= 0.0:
            zeta_p = float(self.advance_spring(x_n, x_p, zeta_n))
        self.x, self.zeta = x_n, zeta_n
        return self.forces_with(cap_p, wall_p, v, L, sig_p if nw else self.sigma, zeta_p)


CHOICES = {"solver": ("generalized_alpha", "trapezoidal_index2"), "forces": ("per_step", "per_iteration"),
           "force_code": ("compiled", "python"), "linear_solver": ("exudyn_dense", "eigen_dense", "eigen_sparse"),
           "newton_jacobian": ("modified", "per_step", "full"), "state_integrator": ("heun", "rk4"),
           "drive_offsets": ("prestep", "user_function")}
POSITIVE = ("step_size", "min_steps_per_cycle", "spectral_radius", "newton_rel_tol", "newton_abs_tol", "rod_axial_inertia")


def _check_settings(s):
    for k, allowed in CHOICES.items():
        if s[k] not in allowed:
            raise ParameterError(f"exudyn.{k} = {s[k]!r}: allowed: {', '.join(allowed)}")
    for k in POSITIVE:
        if not isinstance(s[k], (int, float)) or not s[k] > 0:
            raise ParameterError(f"exudyn.{k} = {s[k]!r}: must be a number > 0")
    if s["spectral_radius"] > 1 or (s["solver"] == "generalized_alpha" and s["spectral_radius"] == 1):
        raise ParameterError(f"exudyn.spectral_radius = {s['spectral_radius']}: must be < 1 (index-3)")
    if s["solver"] == "trapezoidal_index2" and s["drive_offsets"] != "user_function":
        raise ParameterError("exudyn.solver = trapezoidal_index2 needs drive_offsets = user_function "
                             "(a velocity-level drive needs the offset's time derivative)")


class ExudynEngine:
    name = "exudyn"
    validate_settings = staticmethod(lambda s: _check_settings(s))
    default_settings = {
        "step_size": 1.0e-5,          # largest step [s]; the step used divides the output interval
        "min_steps_per_cycle": 20000,  # and at most 1/(f n): 5e-6 s at 10 Hz, where steps are cheap
        "solver": "generalized_alpha",  # or "trapezoidal_index2" (needs drive_offsets=user_function)
        "spectral_radius": 0.8,       # generalized-alpha rho_inf (index 3 needs < 1)
        "newton_rel_tol": 1e-12,      # 1e-10 leaves isolated multiplier spikes (~2e-4 of the peak
        "newton_abs_tol": 1e-14,      # force at 1 Hz), 1e-8 errors of 2e-3; 1e-12 costs ~10 % more
        "newton_jacobian": "modified",  # "modified" (kept across steps), "per_step", "full"
        "forces": "per_step",         # "per_step": pre-step loads at the predicted end-of-step state;
                                      # "per_iteration": GenericODE2 user function (implicit, ~4x slower)
        "state_integrator": "heun",   # hysteretic states per step in strain: "heun" or "rk4" (advance_*)
        "rod_axial_inertia": 1e-3,    # rod spin inertia / its transverse inertia (must be > 0)
        "drive_offsets": "prestep",   # "prestep": offset = u(t_end) set once per step; "user_function"
        "perturb": None,              # a modelling error injected into this model only (engines/perturb.py)
        "force_code": "compiled",     # per_step loads: "compiled" (exudyn_native.step) or "python" (numpy)
        "linear_solver": "eigen_dense",  # Exudyn's linear solver: exudyn_dense | eigen_dense | eigen_sparse
        "model": DEFAULT_MODEL["exudyn"],            # "described": the builder on the device's description (engines/described.py)
        "builder_forces": "predicted",  # model = "described" only: the builder's force path (predicted: the
                                        # adapter's own scheme, within 1.25x its time; compiled: implicit)
    }

    # a warm-up's tiny run (comparisons.engines._warm_peer) compiles what a run does without the
    # 20000 steps a cycle of the default (2.5 s in each pool worker, for nothing)
    warm_settings = {"min_steps_per_cycle": 100}

    @staticmethod
    def steps_per_output(drive: Drive, settings: dict) -> int:
        """Steps per output interval: the largest step <= min(step_size, 1/(f min_steps_per_cycle))
        that divides the interval."""
        h = min(float(settings["step_size"]), 1.0 / (drive.frequency * float(settings["min_steps_per_cycle"])))
        return max(1, int(math.ceil(1.0 / (drive.frequency * drive.samples_per_cycle * h) - 1e-9)))

    @classmethod
    def step_used(cls, drive: Drive, settings: dict | None = None) -> float:
        s = merged_settings(cls.default_settings, settings, cls.name)
        return 1.0 / (drive.frequency * drive.samples_per_cycle * cls.steps_per_output(drive, s))

    @property
    def seismic_default_settings(self) -> dict:
        from comparisons.engines.exudyn_seismic import DEFAULTS
        return DEFAULTS

    def run_seismic(self, params: Params, structure, ground, duration=None, dt_out=1e-3,
                    settings: dict | None = None) -> RunResult:
        """The seismic mode (comparisons/engines/exudyn_seismic.py, imported here: it builds on this module)."""
        from comparisons.engines.exudyn_seismic import ExudynSeismic
        return ExudynSeismic().run(params, structure, ground, duration=duration, dt_out=dt_out, settings=settings)

    def run(self, params: Params, drive: Drive, settings=None) -> RunResult:
        s = merged_settings(self.default_settings, settings, self.name)
        _check_settings(s)
        drive.check_followable(params)
        g = perturbed(device_geometry(params), s["perturb"])
        try:
            return self._run(g, drive, s, drive.output_times(), self.steps_per_output(drive, s))
        except EngineError:
            raise
        except Exception as e:  # Exudyn raises RuntimeError/ValueError with multi-line text
            msg = " ".join(str(e).split())[:300]
            raise EngineError(f"exudyn: {type(e).__name__}: {msg}") from None

    def _run(self, g, drive, s, t_out, per_out):
        p = g.params
        n_out = len(t_out)
        n_steps = per_out * (n_out - 1)
        check_step_count(self.name, n_steps)
        h = drive.duration / n_steps
        v0 = np.append(drive.plate(0.0)[1], 0.0)  # plate velocity at t = 0: start consistent with the drive
        grav = list(g.gravity_vector)
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        ground = mbs.CreateGround(referencePosition=[0.0, 0.0, 0.0])
        cap_z, wall_z, ld = g.cap_rest_z, g.wall_rest_z, p.rod_length

        def body(name, mass, inertia, pos, vel=(0.0, 0.0, 0.0), omega=(0.0, 0.0, 0.0)):
            d = mbs.CreateRigidBody(name=name, referencePosition=list(pos), initialVelocity=list(vel),
                                    initialAngularVelocity=list(omega),
                                    inertia=RigidBodyInertia(mass, inertia, com=[0.0, 0.0, 0.0]),
                                    gravity=grav, nodeType=exu.NodeType.RotationEulerParameters,
                                    returnDict=True, show=False)
            return d["nodeNumber"], d["bodyNumber"]

        rod_I = np.array(g.rod.inertia, dtype=float)
        rod_I[2, 2] = float(s["rod_axial_inertia"]) * rod_I[0, 0]  # spin inertia: only for a regular M
        wall_n, wall_o = body("wall", g.wall.mass, g.wall.inertia, [0.0, 0.0, wall_z])
        # rod node at its centre of mass (mid-length); at t = 0 it swings about the lower joint
        rod_n, rod_o = body("rod", g.rod.mass, rod_I, [0.0, 0.0, wall_z + ld / 2], vel=0.5 * v0,
                            omega=np.cross([0.0, 0.0, 1.0], v0) / ld)
        cap_n, cap_o = body("cap", g.cap.mass, g.cap.inertia, [0.0, 0.0, cap_z], vel=v0)

        mbs.CreateGenericJoint(itemNumbers=[ground, wall_o], position=[0.0, 0.0, wall_z],
                               constrainedAxes=[1, 1, 0, 1, 1, 1], show=False)   # wall: Z guide
        mbs.CreateGenericJoint(itemNumbers=[ground, cap_o], position=[0.0, 0.0, cap_z],
                               constrainedAxes=[0, 0, 0, 1, 1, 1], show=False)   # cap: held level
        mbs.CreateSphericalJoint(itemNumbers=[wall_o, rod_o], position=[0.0, 0.0, wall_z], show=False)
        mbs.CreateSphericalJoint(itemNumbers=[rod_o, cap_o], position=[0.0, 0.0, cap_z], show=False)

        # the drive: cap X = x(t), cap Y = y(t), the plate's path (coordinate constraints to the ground)
        drives = []
        for k in (0, 1):
            kw = {"offset": 0.0}
            if s["drive_offsets"] == "user_function":
                kw = {"offsetUserFunction": lambda mbs_, t, i, off, k=k: drive.plate_at(t)[k],
                      "offsetUserFunction_t": lambda mbs_, t, i, off, k=k: drive.plate_at(t)[2 + k]}
            drives.append(mbs.CreateCoordinateConstraint(itemNumbers=[None, cap_n], coordinates=[None, k],
                                                         show=False, **kw))

        el = _Elements(g, s["state_integrator"], compiled=s["force_code"] == "compiled")
        cap_ref = np.array([0.0, 0.0, cap_z])
        per_step = s["forces"] == "per_step"
        if per_step:
            f_cap, f_wall = el.forces(cap_ref, wall_z)
            loads = [mbs.AddLoad(LoadForceVector(markerNumber=mbs.AddMarker(MarkerNodePosition(nodeNumber=n)),
                                                 loadVector=list(f))) for n, f in ((cap_n, f_cap), (wall_n, f_wall))]
        else:
            def force_uf(mbs_, t, i, q, q_t):
                f_cap, f_wall = el.forces(cap_ref + q[0:3], wall_z + q[9])
                out = np.zeros(14)
                out[0:3], out[7:10] = f_cap, f_wall
                return out

            mbs.AddObject(ObjectGenericODE2(nodeNumbers=[cap_n, wall_n], massMatrix=np.zeros((14, 14)),
                                            forceUserFunction=force_uf))

        OV = exu.OutputVariableType
        sens_l = [mbs.AddSensor(SensorObject(objectNumber=cc, outputVariableType=OV.Force,
                                                   writeToFile=False)) for cc in drives]
        sens_cap = mbs.AddSensor(SensorNode(nodeNumber=cap_n, outputVariableType=OV.Position, writeToFile=False))
        sens_wall = mbs.AddSensor(SensorNode(nodeNumber=wall_n, outputVariableType=OV.Position, writeToFile=False))
        rec = {"sigma": np.zeros((n_out, g.n_wires)), "zeta": np.zeros(n_out), "closure": np.zeros(n_out),
               "lam": np.zeros((n_out, 2)), "cap": np.zeros((n_out, 3)), "wall": np.zeros(n_out)}
        counter = [0]

        def record(k):
            """Converged state at output time k: sensors, committed states, loop closure."""
            rec["lam"][k] = [float(np.ravel(mbs.GetSensorValues(sl))[0]) for sl in sens_l]
            rec["cap"][k] = mbs.GetSensorValues(sens_cap)
            wp = mbs.GetSensorValues(sens_wall)
            rec["wall"][k] = wp[2]
            rec["sigma"][k], rec["zeta"][k] = el.sigma, el.zeta
            rp = mbs.GetNodeOutput(rod_n, OV.Position)
            ax = mbs.GetNodeOutput(rod_n, OV.RotationMatrix).reshape(3, 3)[:, 2] * (ld / 2)
            rec["closure"][k] = max(np.linalg.norm(rp + ax - rec["cap"][k]), np.linalg.norm(rp - ax - wp),
                                    math.hypot(wp[0], wp[1]))

        native = per_step and el.compiled and s["drive_offsets"] == "prestep"
        if native:  # the whole pre-step in one compiled call: the same numbers as pre_step below
            native = exudyn_native.PreStep(mbs, el, (cap_n, wall_n), [0.0, 0.0, cap_z, wall_z], h, drive.motion_params,
                                           loads, drives, per_out, record, counter)

        def pre_step(mbs_, t):
            """t is the END of the step (Exudyn's convention); the state is the converged one at t - h."""
            n = counter[0]
            counter[0] += 1
            px, py = drive.plate_at(t)[:2]
            cap = mbs_.GetNodeOutput(cap_n, OV.Position)
            wz = mbs_.GetNodeOutput(wall_n, OV.Position)[2]
            if per_step:  # forces at the end-of-step state predicted by a second-order Taylor step
                cv, wv = mbs_.GetNodeOutput(cap_n, OV.Velocity), mbs_.GetNodeOutput(wall_n, OV.Velocity)[2]
                ca, wa = mbs_.GetNodeOutput(cap_n, OV.Acceleration), mbs_.GetNodeOutput(wall_n, OV.Acceleration)[2]
                cap_p = cap + h * cv + 0.5 * h * h * ca
                cap_p[0], cap_p[1] = px, py  # the horizontal end-of-step position is prescribed: exact
                f_cap, f_wall = el.step(cap, wz, cap_p, wz + h * wv + 0.5 * h * h * wa)
                mbs_.SetLoadParameter(loads[0], "loadVector", f_cap)
                mbs_.SetLoadParameter(loads[1], "loadVector", f_wall)
            else:
                el.commit(cap, wz)  # hysteretic states follow the accepted step
            if n % per_out == 0:
                record(n // per_out)
            if s["drive_offsets"] != "user_function":
                for cc, off in zip(drives, (px, py)):
                    mbs_.SetObjectParameter(cc, "offset", off)
            return True

        mbs.SetPreStepUserFunction(native or pre_step)
        mbs.Assemble()
        if native:
            native.assembled()

        ss = exu.SimulationSettings()
        ti = ss.timeIntegration
        ti.numberOfSteps, ti.endTime = n_steps, drive.duration
        ti.verboseMode = 0
        ti.adaptiveStep = False
        nw = ti.newton
        nw.relativeTolerance, nw.absoluteTolerance = float(s["newton_rel_tol"]), float(s["newton_abs_tol"])
        nw.useModifiedNewton = s["newton_jacobian"] != "full"
        nw.modifiedNewtonJacUpdatePerStep = s["newton_jacobian"] == "per_step"
        ti.generalizedAlpha.spectralRadius = float(s["spectral_radius"])
        ti.generalizedAlpha.storeInitialAlgebraicCoordinates = True
        ss.linearSolver.solverType = {"exudyn_dense": exu.LinearSolverType.EXUdense,
                                      "eigen_dense": exu.LinearSolverType.EigenDense,
                                      "eigen_sparse": exu.LinearSolverType.EigenSparse}[s["linear_solver"]]
        ss.solution.file.write = False
        ss.solution.sensors.active = False  # sensors are read in the pre-step function, never written
        ss.show.statistics = ss.show.computationTime = False
        solver = {"generalized_alpha": exu.DynamicSolverType.GeneralizedAlpha,
                  "trapezoidal_index2": exu.DynamicSolverType.TrapezoidalIndex2}[s["solver"]]
        t0, c0 = time.perf_counter(), time.process_time()
        why = "SolveDynamic returned False"
        try:
            ok = mbs.SolveDynamic(ss, solverType=solver)
        except Exception as err:  # Exudyn's solver error carries no detail beyond "terminated"
            ok, why = False, " ".join(str(err).split())[:200]
        wall_time, cpu_time = time.perf_counter() - t0, time.process_time() - c0
        if not ok or counter[0] != n_steps:
            raise EngineError(f"exudyn: solver failed in step {counter[0]} of {n_steps} (t = {counter[0] * h:.6g} s,"
                              f" h = {h:.3g} s): {why}")
        el.commit(mbs.GetNodeOutput(cap_n, OV.Position), mbs.GetNodeOutput(wall_n, OV.Position)[2])
        record(n_out - 1)
        stats = {"wall_time": wall_time, "cpu_time": cpu_time, "steps": n_steps, "step_size": h,
                 "newton_iterations": mbs.sys["dynamicSolver"].it.newtonStepsCount if "dynamicSolver" in mbs.sys else None,
                 "tracking_error": float(np.max(np.linalg.norm(rec["cap"][:, :2] - drive.plate(t_out)[0], axis=1))),
                 "closure_max": float(np.max(rec["closure"])), "settings": dict(s)}
        return device_columns(self.name, g, drive, t_out, rec["cap"], rec["wall"], rec["sigma"], rec["zeta"],
                              rec["closure"], drive_force=-rec["lam"], stats=stats)
