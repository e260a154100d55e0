"""Exudyn in the seismic mode (docs/model.md, "Seismic mode"; Table 1, second row).

In the frame that translates with the ground (the base is the ground; every body carries -m a_g,
docs/model.md allows it for a translating base). Redundant-coordinate rigid bodies on Euler-parameter
nodes, as the drive mode (``exudyn_engine``):
- plate (the isolated mass M, polar inertia M r_g^2): GenericJoint to the ground locking Z and the
  X, Y rotations (free: X, Y and the rotation about Z);
- cap: GenericJoint to the plate locking X, Y (in the plate's frame) and all rotations: it slides
  vertically in the plate and turns with it;
- wall: vertical guide to the ground; rod: spherical joints at both ends.
Loads, constant within a step and set in the pre-step function at the end-of-step state predicted
by a second-order Taylor step from the converged one (as the drive mode's "per_step" forces):
ropes, wires and spring through ``nsd_core.device.forces`` (force and moment on the cap, the cap's
attachment points turning with it; vertical force on the wall), the supports on the plate
(-k_b u - c_b u', torsional pair), the displacement restrainer when the structure has one
(``restrainer_force_scalar``, the shared law, on the plate), and -m a_g(t_end) on every body. Hysteretic states are committed
along the strain change of every converged step and predicted to the step's end.
Energy balance (the in-house seismic mode's, frame of the ground) from Exudyn's own state with the
nominal masses and gravity: E_input = -int a_g . P_rel dt, the elements' absorbed power (their loads at
the converged state times Exudyn's velocities) and the supports' dissipation integrated by trapezoids
over every step; kinetic, gravity and support energy at the output times.
Solver: generalized-alpha (index 3), fixed step, spectral radius 0.8, Newton tolerances 1e-12/1e-14.
"""
from __future__ import annotations

import math
import time

import numpy as np

import exudyn as exu
from exudyn.itemInterface import LoadForceVector, LoadTorqueVector, MarkerNodePosition, MarkerNodeRigid
from exudyn.rigidBodyUtilities import RigidBodyInertia

from comparisons.engines.base import DEFAULT_MODEL, EngineError, check_step_count, merged_settings
from comparisons.engines.exudyn_building import ExudynFloors
from comparisons.engines.exudyn_quiet import quiet_allocation_warning
from comparisons.engines.perturb import perturbed, perturbed_structure
from nsd_core.device.forces import (advance_spring_zeta, advance_wire_stress, restrainer_force_scalar,
                                    restrainer_forces, restrainer_stored_scalar, rope_tension, spring_push,
                                    spring_push_scalar, wire_tension)
from nsd_core.device.geometry import device_geometry
from nsd_core.device.ground import GroundMotion
from nsd_core.device.isolation import Structure
from nsd_core.device.params import Params
from nsd_core.device.results import RunResult
from nsd_core.device.columns import units_of
from nsd_core.device.seismic import output_times

quiet_allocation_warning()

DEFAULTS = {"step_size": 1e-5, "spectral_radius": 0.8, "newton_rel_tol": 1e-12, "newton_abs_tol": 1e-14,
            "rod_axial_inertia": 1e-3, "perturb": None,  # perturb: an error in this model only (engines/perturb.py)
            "model": DEFAULT_MODEL["exudyn"],   # "described": the builder on the device's description (engines/described_seismic.py)
            "builder_forces": "compiled"}   # model = "described" only: the builder's force path (compiled | predicted)


def _cross(a, b):
    """Row-wise a x b of two (n, 3) arrays: numpy.cross's operations (a_1 b_2 - a_2 b_1, ...), the
    same numbers, without its axis handling (a third of this engine's pre-step)."""
    c = np.empty_like(a)
    c[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    c[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    c[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return c


class _Elements:
    """Ropes, wires, spring on the cap (pose: position, rotation about Z) and the wall (height)."""

    def __init__(self, g):
        self.g, self.nr, self.nw = g, g.n_ropes, g.n_wires
        self.cap_pts = np.vstack([g.rope_cap_points, g.wire_cap_points])
        self.low_pts = np.vstack([g.rope_base_points, g.wire_wall_points])
        self.sigma, self.zeta = np.array(g.initial_wire_stress(), dtype=float), float(g.spring_zeta0)
        self._at, self._geometry = None, None
        self.eps, self.x = self.strains(np.array([0.0, 0.0, g.cap_rest_z]), 0.0, g.wall_rest_z)

    def geometry(self, cap, theta, wz):
        """Arms of the cap's attachment points, element vectors and lengths (read-only arrays).

        Kept for the last pose: each step asks twice for the converged pose (commit, energy rates)
        and twice for the predicted one (strains, loads)."""
        at = (cap[0], cap[1], cap[2], theta, wz)
        if at == self._at:
            return self._geometry
        c, s = math.cos(theta), math.sin(theta)
        p = self.cap_pts
        arm = np.empty_like(p)
        arm[:, 0] = c * p[:, 0] - s * p[:, 1]
        arm[:, 1] = s * p[:, 0] + c * p[:, 1]
        arm[:, 2] = p[:, 2]
        low = self.low_pts.copy()
        low[self.nr:, 2] += wz
        v = cap + arm - low
        self._at, self._geometry = at, (arm, v, np.sqrt(np.einsum("ij,ij->i", v, v)))
        return self._geometry

    def strains(self, cap, theta, wz):
        L = self.geometry(cap, theta, wz)[2]
        L0 = self.g.wire.natural_length
        return (L[self.nr:] - L0) / L0, self.g.spring.free_length - wz

    def advance(self, eps0, x0, sigma, zeta, eps1, x1):
        sig = advance_wire_stress(eps0, eps1, sigma, self.g.wire, order=2) if self.nw else sigma
        return sig, float(advance_spring_zeta(x0, x1, zeta, self.g.spring, order=2))

    def commit(self, cap, theta, wz):
        eps, x = self.strains(cap, theta, wz)
        self.sigma, self.zeta = self.advance(self.eps, self.x, self.sigma, self.zeta, eps, x)
        self.eps, self.x = eps, x

    def loads(self, cap, theta, wz, sigma=None, zeta=None):
        """(force on the cap, moment on the cap about its reference, vertical force on the wall)."""
        g, nr = self.g, self.nr
        arm, v, L = self.geometry(cap, theta, wz)
        T = np.concatenate([rope_tension(L[:nr], g.rope_natural_length, g.rope_stiffness),
                            wire_tension(self.sigma if sigma is None else sigma, g.wire)])
        f = -(T / L)[:, None] * v
        push = spring_push_scalar(wz, self.zeta if zeta is None else zeta, g.spring.kse, g.spring.free_length)
        return f.sum(0), _cross(arm, f).sum(0), -float(f[nr:, 2].sum()) + push

    def predicted_loads(self, cap, theta, wz):
        eps, x = self.strains(cap, theta, wz)
        sig, zeta = self.advance(self.eps, self.x, self.sigma, self.zeta, eps, x)
        return self.loads(cap, theta, wz, sig, zeta)


class ExudynSeismic:
    name = "exudyn"
    default_settings = DEFAULTS

    def run(self, params: Params, structure: Structure, ground: GroundMotion, duration: float | None = None,
            dt_out: float = 1e-3, settings: dict | None = None) -> RunResult:
        s = merged_settings(DEFAULTS, settings, "exudyn")
        try:
            g0 = device_geometry(params)
            return self._run(perturbed(g0, s["perturb"], seismic=True), perturbed_structure(structure, s["perturb"]),
                             ground, duration, dt_out, s, g0, structure)
        except EngineError:
            raise
        except Exception as e:  # Exudyn raises RuntimeError/ValueError with multi-line text
            raise EngineError(f"exudyn: {type(e).__name__}: {' '.join(str(e).split())[:300]}") from None

    def _run(self, g, st: Structure, ground, duration, dt_out, s, g0, st0: Structure):
        """g, st: Exudyn's model (an injected error in them); g0, st0: the nominal ones (energy balance)."""
        duration = ground.duration if duration is None else float(duration)
        t_out = output_times(duration, dt_out)  # the in-house run's output times: the last lands on the end
        n_out, dt_out = len(t_out) - 1, float(t_out[1] - t_out[0])
        per_out = max(1, math.ceil(dt_out / float(s["step_size"]) - 1e-9))
        h = dt_out / per_out
        n_steps = n_out * per_out
        check_step_count("exudyn", n_steps)
        grav = list(g.gravity_vector)
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        gnd = mbs.CreateGround(referencePosition=[0.0, 0.0, 0.0])
        cap_z, wall_z, ld = g.cap_rest_z, g.wall_rest_z, g.params.rod_length

        def body(name, mass, inertia, pos):
            d = mbs.CreateRigidBody(name=name, referencePosition=list(pos),
                                    inertia=RigidBodyInertia(mass, inertia, com=[0.0, 0.0, 0.0]), gravity=grav,
                                    nodeType=exu.NodeType.RotationEulerParameters, returnDict=True, show=False)
            return d["nodeNumber"], d["bodyNumber"], mass

        J = st.polar_inertia
        rod_I = np.array(g.rod.inertia, dtype=float)
        rod_I[2, 2] = float(s["rod_axial_inertia"]) * rod_I[0, 0]
        plate = body("plate", st.mass, np.diag([J / 2, J / 2, J]), [0.0, 0.0, 0.0])
        cap = body("cap", g.cap.mass, g.cap.inertia, [0.0, 0.0, cap_z])
        wall = body("wall", g.wall.mass, g.wall.inertia, [0.0, 0.0, wall_z])
        rod = body("rod", g.rod.mass, rod_I, [0.0, 0.0, wall_z + ld / 2])
        mbs.CreateGenericJoint(itemNumbers=[gnd, plate[1]], position=[0.0, 0.0, 0.0],
                               constrainedAxes=[0, 0, 1, 1, 1, 0], show=False)
        mbs.CreateGenericJoint(itemNumbers=[plate[1], cap[1]], position=[0.0, 0.0, cap_z],
                               constrainedAxes=[1, 1, 0, 1, 1, 1], show=False)
        mbs.CreateGenericJoint(itemNumbers=[gnd, wall[1]], position=[0.0, 0.0, wall_z],
                               constrainedAxes=[1, 1, 0, 1, 1, 1], show=False)
        mbs.CreateSphericalJoint(itemNumbers=[wall[1], rod[1]], position=[0.0, 0.0, wall_z], show=False)
        rc_joint = mbs.CreateSphericalJoint(itemNumbers=[rod[1], cap[1]], position=[0.0, 0.0, cap_z], show=False)

        def force_load(node, f=(0.0, 0.0, 0.0)):
            return mbs.AddLoad(LoadForceVector(markerNumber=mbs.AddMarker(MarkerNodePosition(nodeNumber=node)),
                                               loadVector=list(f)))

        def torque_load(node, m=(0.0, 0.0, 0.0)):
            return mbs.AddLoad(LoadTorqueVector(markerNumber=mbs.AddMarker(MarkerNodeRigid(nodeNumber=node)),
                                                loadVector=list(m)))

        # every load starts at its t = 0 value: the solver's initial accelerations are computed with them
        bodies = (plate, cap, wall, rod)
        a_g0 = ground(0.0)[2]
        inertial = [force_load(b[0], (-b[2] * a_g0[0], -b[2] * a_g0[1], 0.0)) for b in bodies]  # -m a_g
        floors = ExudynFloors(mbs, st.building, plate[0], a_g0) if st.building is not None else None
        el = _Elements(g)
        f0, m0, fw0 = el.loads(np.array([0.0, 0.0, cap_z]), 0.0, wall_z)
        cap_f, cap_m, wall_f = force_load(cap[0], f0), torque_load(cap[0], m0), force_load(wall[0], (0.0, 0.0, fw0))
        plate_f, plate_m = force_load(plate[0]), torque_load(plate[0])
        OV = exu.OutputVariableType
        out = []
        counter = [0]
        # energy balance with the nominal bodies: (node, mass, inertia in the body frame)
        J0 = st0.polar_inertia
        rod_I0 = np.array(g0.rod.inertia, dtype=float)
        rod_I0[2, 2] = float(s["rod_axial_inertia"]) * rod_I0[0, 0]
        nominal = [(plate[0], st0.mass, np.diag([J0 / 2, J0 / 2, J0])), (cap[0], g0.cap.mass, np.array(g0.cap.inertia)),
                   (wall[0], g0.wall.mass, np.array(g0.wall.inertia)), (rod[0], g0.rod.mass, rod_I0)]
        energy = {"E": np.zeros(5), "t": None, "last": None, "h0": None}  # + E_building_dissipated
        res = st0.restrainer  # the displacement restrainer (None: none)

        def restrainer(pq, pv):
            """(F_x, F_y, F, delta, delta'): the plate's push on the restrainer (shared law)."""
            if res is None:
                return 0.0, 0.0, 0.0, 0.0, 0.0
            return restrainer_force_scalar(pq[0], pq[1], pv[0], pv[1], res.gap, res.stiffness, res.exponent,
                                           res.damping)

        def energy_rates(t, a_g):
            """Accumulate E_input, E_device, E_supports_dissipated up to the converged state at t."""
            (cq, cth), wz = pose(cap[0]), mbs.GetNodeOutput(wall[0], OV.Position)[2]
            f, m, fw = el.loads(cq, cth, wz)
            P = np.zeros(2)
            for node, mass, _ in nominal:
                P += mass * mbs.GetNodeOutput(node, OV.Velocity)[:2]
            vc = mbs.GetNodeOutput(cap[0], OV.Velocity)
            wc = mbs.GetNodeOutput(cap[0], OV.AngularVelocity)
            applied = float(f @ vc + m @ wc) + fw * mbs.GetNodeOutput(wall[0], OV.Velocity)[2]
            pv = mbs.GetNodeOutput(plate[0], OV.Velocity)
            om = mbs.GetNodeOutput(plate[0], OV.AngularVelocity)[2]
            diss = st0.damping * (pv[0] ** 2 + pv[1] ** 2 + st0.support_radius ** 2 * om ** 2)
            _, _, rF, _, rrate = restrainer(mbs.GetNodeOutput(plate[0], OV.Position), pv)
            bld = 0.0
            if floors is not None:
                P += floors.momentum()
                bld = floors.dissipation()
            now = np.array([-float(np.asarray(a_g)[:2] @ P), -applied, diss, rF * rrate, bld])
            if energy["t"] is not None and t > energy["t"]:
                energy["E"] += 0.5 * (t - energy["t"]) * (now + energy["last"])
            energy["t"], energy["last"] = t, now

        def energy_columns():
            ke = height = 0.0
            for node, mass, inertia in nominal:
                v = mbs.GetNodeOutput(node, OV.Velocity)
                w = mbs.GetNodeOutput(node, OV.AngularVelocity)
                R = mbs.GetNodeOutput(node, OV.RotationMatrix).reshape(3, 3)
                ke += 0.5 * mass * float(v @ v) + 0.5 * float(w @ (R @ inertia @ R.T) @ w)
                height += mass * g0.params.gravity * mbs.GetNodeOutput(node, OV.Position)[2]
            if energy["h0"] is None:
                energy["h0"] = height
            pq, th = pose(plate[0])
            stored = 0.5 * st0.stiffness * (pq[0] ** 2 + pq[1] ** 2 + st0.support_radius ** 2 * th ** 2)
            E = energy["E"]
            row = {"E_input": E[0], "E_kinetic": ke, "E_gravity": height - energy["h0"], "E_supports_stored": stored,
                   "E_supports_dissipated": E[2], "E_device": E[1]}
            if floors is not None:  # the floors' kinetic energy; their stored energy joins at the end
                ke += floors.kinetic()
                row["E_kinetic"], row["E_building_dissipated"] = ke, E[4]
            row["E_residual"] = E[0] - (ke + row["E_gravity"] + stored + E[2] + E[1] + E[3] + E[4])
            if res is not None:
                delta = max(math.hypot(pq[0], pq[1]) - res.gap, 0.0)
                row["E_restrainer_stored"] = restrainer_stored_scalar(delta, res.stiffness, res.exponent)
                row["E_restrainer_dissipated"] = E[3] - row["E_restrainer_stored"]
            return row

        def pose(node):
            q = mbs.GetNodeOutput(node, OV.Position)
            R = mbs.GetNodeOutput(node, OV.RotationMatrix).reshape(3, 3)
            return q, math.atan2(R[1, 0], R[0, 0])

        def record(t, a_g):
            (pq, th), (cq, cth) = pose(plate[0]), pose(cap[0])
            pv, pa = mbs.GetNodeOutput(plate[0], OV.Velocity), mbs.GetNodeOutput(plate[0], OV.Acceleration)
            om = mbs.GetNodeOutput(plate[0], OV.AngularVelocity)[2]
            wz = mbs.GetNodeOutput(wall[0], OV.Position)[2]
            f, _, _ = el.loads(cq, cth, wz)
            rod_on_cap = -np.asarray(mbs.GetObjectOutput(rc_joint, OV.Force))  # the joint's force on body 0 (rod)
            sx, sy = st.stiffness * pq[0] + st.damping * pv[0], st.stiffness * pq[1] + st.damping * pv[1]
            dfx, dfy = -(f[0] + rod_on_cap[0]), -(f[1] + rod_on_cap[1])
            rp = mbs.GetNodeOutput(rod[0], OV.Position)
            ax = mbs.GetNodeOutput(rod[0], OV.RotationMatrix).reshape(3, 3)[:, 2] * (ld / 2)
            row = {"t": t, "x": pq[0], "y": pq[1], "theta": th, "vx": pv[0], "vy": pv[1],
                   "ax_abs": pa[0] + a_g[0], "ay_abs": pa[1] + a_g[1], "support_Fx": sx, "support_Fy": sy,
                   "device_Fx": dfx, "device_Fy": dfy, "base_shear_x": sx + dfx, "base_shear_y": sy + dfy,
                   "cap_z": cq[2], "wall_z": wz, "spring_zeta": el.zeta,
                   "spring_push": float(spring_push(wz, 0.0, el.zeta, g.spring)[0]),
                   "closure": float(np.linalg.norm(rp + ax - cq)), "omega": om}
            for j, sig in enumerate(el.sigma):
                row[f"wire{j}_stress"] = sig
            row.update(energy_columns())
            if floors is not None:
                floors.sample(a_g)
            out.append(row)

        def predict(node, h):
            q, th = pose(node)
            v, a = mbs.GetNodeOutput(node, OV.Velocity), mbs.GetNodeOutput(node, OV.Acceleration)
            w, al = mbs.GetNodeOutput(node, OV.AngularVelocity)[2], mbs.GetNodeOutput(node, OV.AngularAcceleration)[2]
            return q + h * v + 0.5 * h * h * a, th + h * w + 0.5 * h * h * al, v + h * a, w + h * al, q, th

        def pre_step(mbs_, t):
            """t is the END of the step; the state is the converged one at t - h."""
            n = counter[0]
            counter[0] += 1
            cq, cth = pose(cap[0])
            wz = mbs.GetNodeOutput(wall[0], OV.Position)[2]
            if n > 0:
                el.commit(cq, cth, wz)
            energy_rates(t - h, ground(t - h)[2])
            if n % per_out == 0:
                record(t_out[n // per_out], ground(t - h)[2])
            a_g = ground(t)[2]
            for (node, _, m), ld_ in zip(bodies, inertial):
                mbs_.SetLoadParameter(ld_, "loadVector", [-m * a_g[0], -m * a_g[1], 0.0])
            if floors is not None:
                floors.set_inertial(mbs_, a_g)
            cp, cthp, *_ = predict(cap[0], h)
            wzp = wz + h * mbs.GetNodeOutput(wall[0], OV.Velocity)[2] + 0.5 * h * h * mbs.GetNodeOutput(wall[0], OV.Acceleration)[2]
            f, m, fw = el.predicted_loads(cp, cthp, wzp)
            mbs_.SetLoadParameter(cap_f, "loadVector", list(f))
            mbs_.SetLoadParameter(cap_m, "loadVector", list(m))
            mbs_.SetLoadParameter(wall_f, "loadVector", [0.0, 0.0, fw])
            pp, thp, vp, wp, _, _ = predict(plate[0], h)
            kt, ct = st.stiffness * st.support_radius ** 2, st.damping * st.support_radius ** 2
            rx, ry, *_ = restrainer(pp, vp)
            mbs_.SetLoadParameter(plate_f, "loadVector", [-st.stiffness * pp[0] - st.damping * vp[0] - rx,
                                                          -st.stiffness * pp[1] - st.damping * vp[1] - ry, 0.0])
            mbs_.SetLoadParameter(plate_m, "loadVector", [0.0, 0.0, -kt * thp - ct * wp])
            return True

        mbs.SetPreStepUserFunction(pre_step)
        mbs.Assemble()
        ss = exu.SimulationSettings()
        ti = ss.timeIntegration
        ti.numberOfSteps, ti.endTime = n_steps, n_steps * h
        ti.verboseMode = 0
        ti.adaptiveStep = False
        ti.newton.relativeTolerance, ti.newton.absoluteTolerance = float(s["newton_rel_tol"]), float(s["newton_abs_tol"])
        ti.newton.useModifiedNewton = True
        ti.generalizedAlpha.spectralRadius = float(s["spectral_radius"])
        ti.generalizedAlpha.storeInitialAlgebraicCoordinates = True
        ss.solution.file.write = False
        ss.solution.sensors.active = False
        ss.show.statistics = ss.show.computationTime = False
        t0 = time.perf_counter()
        ok = mbs.SolveDynamic(ss, solverType=exu.DynamicSolverType.GeneralizedAlpha)
        if not ok or counter[0] != n_steps:
            raise EngineError(f"exudyn: solver failed in step {counter[0]} of {n_steps} (t = {counter[0] * h:.6g} s)")
        cq, cth = pose(cap[0])
        el.commit(cq, cth, mbs.GetNodeOutput(wall[0], OV.Position)[2])
        energy_rates(n_steps * h, ground(n_steps * h)[2])
        record(t_out[-1], ground(n_steps * h)[2])
        cols = {k: np.array([r[k] for r in out]) for k in out[0]}
        cols["u"] = np.hypot(cols["x"], cols["y"])
        if floors is not None:
            cols.update(floors.columns(cols["x"], cols["y"], cols["vx"], cols["vy"]))
            cols["E_residual"] = cols["E_residual"] - cols["E_building_stored"]
        if res is not None:
            fx, fy, F, delta, _ = restrainer_forces(cols["x"], cols["y"], cols["vx"], cols["vy"], res.gap,
                                                    res.stiffness, res.exponent, res.damping)
            cols.update({"restrainer_Fx": fx, "restrainer_Fy": fy, "restrainer_F": F, "restrainer_indentation": delta})
            cols["base_shear_x"], cols["base_shear_y"] = cols["base_shear_x"] + fx, cols["base_shear_y"] + fy
        stats = {"engine": "exudyn", "mode": "seismic", "wall_time": time.perf_counter() - t0, "steps": n_steps,
                 "step_size": h, "settings": dict(s)}
        return RunResult("exudyn", cols, units_of(cols), stats)
