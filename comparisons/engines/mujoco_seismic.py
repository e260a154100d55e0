"""MuJoCo in the seismic mode (docs/model.md, "Seismic mode"; Table 1, second row).

The model lives in the frame that translates with the ground, where the base is the world and
every body feels -m a_g: MuJoCo's gravity is a uniform field, so setting it to (-a_gx, -a_gy, -g)
before each step is exactly that load (docs/model.md allows it for a translating base).
- world -> ``plate``: slides ``px``, ``py`` and hinge ``pr`` (the isolated mass M, polar inertia
  M r_g^2); plate -> ``cap``: slide ``cap_z``;
- world -> ``wall``: slide ``wall_z``; wall -> ``rod``: ball; the loop is closed by a ``connect``
  (solref 2h, solimp 0.9999, as the drive mode);
- an ``mjcb_passive`` callback adds ropes, wires and the spring (``nsd_core.device.forces``; the cap's
  attachment points turn with the plate), the supports (-k_b u - c_b u', torsional pair) and, when the
  structure has one, the displacement restrainer (``restrainer_force_scalar``, the shared law).
Hysteretic states are advanced along the actual strain change after every step (Euler: the
callback then always sees the committed state; no prediction needed).
Energy balance (the in-house seismic mode's, in the frame of the ground), from MuJoCo's own state with
the nominal masses and gravity (not the model's): E_input = -int a_g . P_rel dt, E_device = int of the
elements' absorbed power (minus their generalized forces times MuJoCo's velocities), the supports'
dissipation, all three integrated by trapezoids over every step; kinetic, gravity and support energy
at the output times. A mass or gravity error in MuJoCo's own model leaves a residual.
Outputs: the in-house seismic columns that a comparison needs (relative x, y, theta, absolute
acceleration, device and support forces, base shear, cap and wall heights, spring and wire states).
``step_loop = "native"`` (the default): the callback and the steps between output samples in compiled
code (mujoco_seismic_native: the same model, laws and order of operations; Python once per output
sample), ~10x cheaper than ``"python"`` (one Python callback and call a step), which stays as the check.
"""
from __future__ import annotations

import math
import time

import mujoco
import numpy as np

from nsd_core.device.forces import (advance_spring_zeta, advance_wire_stress, restrainer_force_scalar,
                                    restrainer_forces, restrainer_stored_scalar, rope_tension, spring_push,
                                    spring_push_scalar, wire_tension)
from nsd_core.device.geometry import device_geometry
from nsd_core.device.ground import GroundMotion
from nsd_core.device.isolation import Structure
from nsd_core.device.params import ParameterError, Params
from nsd_core.device.results import RunResult
from nsd_core.device.columns import units_of
from nsd_core.device.seismic import output_times

from comparisons.engines import mujoco_native, mujoco_seismic_native as native_loop
from comparisons.engines.base import DEFAULT_MODEL, EngineError, check_step_count, merged_settings
from comparisons.engines.mujoco_building import Floors, floors_mjcf, tendons_mjcf
from comparisons.engines.mujoco_mjcf import wall_rod_loop_mjcf
from comparisons.engines.perturb import perturbed, perturbed_structure

DEFAULTS = {"timestep": 1e-5, "solref_factor": 2.0, "solimp": [0.9999, 0.9999, 0.001, 0.5, 2.0],
            "solver_tolerance": 1e-12, "solver_iterations": 20, "closure_limit": 1e-4, "hysteresis_substeps": 1,
            "step_loop": "native", "perturb": None,  # perturb: a modelling error in this model only (engines/perturb.py)
            "model": DEFAULT_MODEL["mujoco"]}   # "described": the builder on the device's description (engines/described_seismic.py)


def _f(x) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(x))


def build_mjcf(g, st: Structure, s: dict, h: float, nuserdata: int = 0) -> str:
    J = st.polar_inertia
    return f"""<mujoco model="nsd_seismic">
  <size nuserdata="{nuserdata}"/>
  <option timestep="{_f(h)}" integrator="Euler" gravity="0 0 {_f(-g.params.gravity)}" solver="Newton"
          tolerance="{_f(s['solver_tolerance'])}" iterations="{s['solver_iterations']}" jacobian="dense">
    <flag contact="disable"/>
  </option>
  <worldbody>
    <body name="plate" pos="0 0 0">
      <inertial pos="0 0 0" mass="{_f(st.mass)}" diaginertia="{_f([J / 2, J / 2, J])}"/>
      <joint name="px" type="slide" axis="1 0 0"/>
      <joint name="py" type="slide" axis="0 1 0"/>
      <joint name="pr" type="hinge" axis="0 0 1"/>
      <body name="cap" pos="0 0 {_f(g.cap_rest_z)}">
        <inertial pos="{_f(g.cap.com)}" mass="{_f(g.cap.mass)}" diaginertia="{_f(np.diag(g.cap.inertia))}"/>
        <joint name="cap_z" type="slide" axis="0 0 1"/>
      </body>
    </body>
{_with_floors(wall_rod_loop_mjcf(g, f"{_f(s['solref_factor'] * h)} 1.0", s['solimp']), st)}</mujoco>
"""


def _with_floors(loop: str, st: Structure) -> str:
    """The building's floors after the device's bodies (qpos and qvel keep the device's indices) and
    its tendons after the worldbody (comparisons.engines.mujoco_building)."""
    if st.building is None:
        return loop
    head, sep, tail = loop.partition("  </worldbody>\n")
    return head + floors_mjcf(st.building) + sep + tail + tendons_mjcf(st.building)


class _Forces:
    """Element forces (shared laws) and supports as qfrc_passive; committed hysteretic states."""
    PX, PY, PR, CZ, WZ = range(5)  # qpos = qvel indices of the plate, cap and wall joints

    def __init__(self, g, st: Structure, substeps: int):
        self.g, self.st, self.nr, self.nw = g, st, g.n_ropes, g.n_wires
        self.cap_pts = np.vstack([g.rope_cap_points, g.wire_cap_points])
        self.low_pts = np.vstack([g.rope_base_points, g.wire_wall_points])
        self.sigma, self.zeta = np.array(g.initial_wire_stress(), dtype=float), float(g.spring_zeta0)
        self.substeps = substeps
        self.T = np.zeros(self.nr + self.nw)
        self.eps_c, self.x_c = None, None
        self.energy = None
        self._at, self._geometry = None, None

    def geometry(self, q):
        """Cap attachment points (world), element vectors and lengths, wall height (read-only arrays).

        Kept for the last configuration: the commit after a step and the passive force of the next
        step see the same coordinates, so each step computes it once."""
        at = (q[self.PX], q[self.PY], q[self.PR], q[self.CZ], q[self.WZ])
        if at == self._at:
            return self._geometry
        c, s = math.cos(at[2]), math.sin(at[2])
        p = self.cap_pts
        cap = np.empty_like(p)
        cap[:, 0] = at[0] + c * p[:, 0] - s * p[:, 1]
        cap[:, 1] = at[1] + s * p[:, 0] + c * p[:, 1]
        cap[:, 2] = self.g.cap_rest_z + at[3] + p[:, 2]
        wz = self.g.wall_rest_z + at[4]
        low = self.low_pts.copy()
        low[self.nr:, 2] += wz
        v = cap - low
        self._at, self._geometry = at, (cap, v, np.sqrt(np.einsum("ij,ij->i", v, v)), wz)
        return self._geometry

    def strains(self, q):
        _, _, L, wz = self.geometry(q)
        L0 = self.g.wire.natural_length
        return (L[self.nr:] - L0) / L0, self.g.spring.free_length - wz

    def commit(self, q):
        eps, x = self.strains(q)
        if self.eps_c is not None:
            if self.nw:
                self.sigma = advance_wire_stress(self.eps_c, eps, self.sigma, self.g.wire, self.substeps)
            self.zeta = float(advance_spring_zeta(self.x_c, x, self.zeta, self.g.spring, self.substeps))
        self.eps_c, self.x_c = eps, x

    def device_on_cap(self, q):
        """(forces of ropes and wires on the cap summed (3,), their moment about the plate axis, the
        wall's vertical load from wires and spring)."""
        g, nr, T = self.g, self.nr, self.T
        cap, v, L, wz = self.geometry(q)
        T[:nr] = rope_tension(L[:nr], g.rope_natural_length, g.rope_stiffness)
        T[nr:] = wire_tension(self.sigma, g.wire)
        f = -(T / L)[:, None] * v  # every element pulls its cap end towards its lower end
        arm = cap[:, :2] - np.array([q[self.PX], q[self.PY]])
        moment = float(np.sum(arm[:, 0] * f[:, 1] - arm[:, 1] * f[:, 0]))
        wall = -float(np.sum(f[nr:, 2])) + spring_push_scalar(wz, self.zeta, g.spring.kse, g.spring.free_length)
        return f.sum(0), moment, wall

    def support(self, q, v):
        st = self.st
        kt, ct = st.stiffness * st.support_radius ** 2, st.damping * st.support_radius ** 2
        return (st.stiffness * q[self.PX] + st.damping * v[self.PX], st.stiffness * q[self.PY] + st.damping * v[self.PY],
                kt * q[self.PR] + ct * v[self.PR])

    def restrainer(self, q, v):
        """(F_x, F_y, F, delta, delta'): the plate's push on the restrainer (nsd_core.device.forces)."""
        r = self.st.restrainer
        if r is None:
            return 0.0, 0.0, 0.0, 0.0, 0.0
        return restrainer_force_scalar(q[self.PX], q[self.PY], v[self.PX], v[self.PY], r.gap, r.stiffness,
                                       r.exponent, r.damping)

    def passive(self, m, d):
        f, moment, wall = self.device_on_cap(d.qpos)
        sx, sy, st = self.support(d.qpos, d.qvel)
        rx, ry, rF, _, rrate = self.restrainer(d.qpos, d.qvel)
        if self.energy is not None:
            v = d.qvel
            applied = f[0] * v[self.PX] + f[1] * v[self.PY] + moment * v[self.PR] + f[2] * v[self.CZ] + wall * v[self.WZ]
            self.energy.rates(m, d, -applied, rF * rrate)
        qf = d.qfrc_passive
        qf[self.PX] += f[0] - sx - rx
        qf[self.PY] += f[1] - sy - ry
        qf[self.PR] += moment - st
        qf[self.CZ] += f[2]
        qf[self.WZ] += wall


class _Energy:
    """The energy balance's integrals and stored energies, from MuJoCo's state with nominal masses."""

    def __init__(self, model, g0, st: Structure):
        self.ids = [model.body(n).id for n in ("plate", "cap", "wall", "rod")]
        J = st.polar_inertia
        self.mass = np.array([st.mass, g0.cap.mass, g0.wall.mass, g0.rod.mass])
        rod_I = np.array(g0.rod.inertia, dtype=float)
        self.inertia = [np.diag([J / 2, J / 2, J]), np.array(g0.cap.inertia, dtype=float),
                        np.array(g0.wall.inertia, dtype=float), rod_I]
        self.gravity, self.st = g0.params.gravity, st
        self.a_g = np.zeros(2)
        self.E = np.zeros(5)           # E_input, E_device, E_supports_dissipated, E_restrainer, E_building_dissipated
        self.floors = None             # the building's floors (mujoco_building.Floors) when there is one
        self.t, self.last = None, None
        self.height0 = None
        self.v6 = np.zeros(6)

    def _velocities(self, m, d):
        out = []
        for b in self.ids:   # (angular, linear) at the body's centre of mass, world axes
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, b, self.v6, 0)
            out.append(self.v6.copy())
        return np.array(out)

    def rates(self, m, d, absorbed, restrainer=0.0):
        vel = self._velocities(m, d)
        P = self.mass @ vel[:, 3:5]
        st, v = self.st, d.qvel
        diss = st.damping * (v[0] ** 2 + v[1] ** 2) + st.damping * st.support_radius ** 2 * v[2] ** 2
        bld = 0.0
        if self.floors is not None:
            P = P + self.floors.momentum(v)
            bld = self.floors.dissipation(v)
        now = np.array([-float(self.a_g @ P), absorbed, diss, restrainer, bld])
        t = float(d.time)
        if self.t is not None and t > self.t:
            self.E += 0.5 * (t - self.t) * (now + self.last)
        self.t, self.last = t, now

    def columns(self, m, d) -> dict:
        vel = self._velocities(m, d)
        ke = 0.0
        for k, b in enumerate(self.ids):
            R = d.xmat[b].reshape(3, 3)
            w = vel[k, :3]
            ke += 0.5 * self.mass[k] * float(vel[k, 3:] @ vel[k, 3:]) + 0.5 * float(w @ (R @ self.inertia[k] @ R.T) @ w)
        height = float(self.mass @ d.xipos[self.ids, 2]) * self.gravity
        if self.height0 is None:
            self.height0 = height
        q, st = d.qpos, self.st
        stored = 0.5 * st.stiffness * (q[0] ** 2 + q[1] ** 2 + st.support_radius ** 2 * q[2] ** 2)
        row = {"E_input": self.E[0], "E_kinetic": ke, "E_gravity": height - self.height0, "E_supports_stored": stored,
               "E_supports_dissipated": self.E[2], "E_device": self.E[1]}
        if self.floors is not None:  # the floors' kinetic energy; their stored energy joins in run()
            row["E_kinetic"] = ke = ke + self.floors.kinetic(d.qvel)
            row["E_building_dissipated"] = self.E[4]
        row["E_residual"] = row["E_input"] - (ke + row["E_gravity"] + stored + self.E[2] + self.E[1] + self.E[3]
                                              + self.E[4])
        if st.restrainer is not None:
            r = st.restrainer
            delta = max(math.hypot(q[0], q[1]) - r.gap, 0.0)
            row["E_restrainer_stored"] = restrainer_stored_scalar(delta, r.stiffness, r.exponent)
            row["E_restrainer_dissipated"] = self.E[3] - row["E_restrainer_stored"]
        return row


class MujocoSeismic:
    name = "mujoco"
    default_settings = DEFAULTS

    def run(self, params: Params, structure: Structure, ground: GroundMotion, duration: float | None = None,
            dt_out: float = 1e-3, settings: dict | None = None) -> RunResult:
        s = merged_settings(DEFAULTS, settings, "mujoco")
        if s["step_loop"] not in ("native", "python"):
            raise ParameterError(f"mujoco.step_loop = {s['step_loop']!r}: allowed 'native', 'python'")
        native = s["step_loop"] == "native"
        g0 = device_geometry(params)
        g = perturbed(g0, s["perturb"], seismic=True)   # an injected modelling error lives in MuJoCo's model only
        model_structure = perturbed_structure(structure, s["perturb"])
        duration = ground.duration if duration is None else float(duration)
        t_out = output_times(duration, dt_out)  # the in-house run's output times: the last lands on the end
        n_out, dt_out = len(t_out) - 1, float(t_out[1] - t_out[0])
        n_sub = max(1, math.ceil(dt_out / float(s["timestep"]) - 1e-9))
        h = dt_out / n_sub
        check_step_count("mujoco", n_out * n_sub)
        n_floors = structure.building.stories if structure.building is not None else 0
        nud = native_loop.userdata_size(g.n_ropes, g.n_wires, n_floors) if native else 0
        model = mujoco.MjModel.from_xml_string(build_mjcf(g, model_structure, s, h, nud))
        data = mujoco.MjData(model)
        dev = _Forces(g, structure, int(s["hysteresis_substeps"]))
        dev.energy = energy = _Energy(model, g0, structure)
        floors = energy.floors = Floors(model, structure.building) if structure.building is not None else None
        dev.commit(data.qpos)
        a_g = np.ascontiguousarray(ground(h * np.arange(n_out * n_sub + 1))[2], dtype=float)
        rows = []
        tip, cap_id = model.site("rod_tip").id, model.body("cap").id
        previous = mujoco.get_mjcb_passive()
        t0 = time.perf_counter()
        ud = data.userdata
        if native:   # the same elements, states and energy integrals, in mjData.userdata
            native_loop.pack(ud, g, structure, dev, model, data, floors)
            callback, step = native_loop.passive_callback().ctypes, mujoco_native.mujoco_functions()[0]
        try:
            mujoco.set_mjcb_passive(callback if native else dev.passive)
            for n in range(0, n_out * n_sub + 1, n_sub) if native else range(n_out * n_sub + 1):
                model.opt.gravity[:2] = -a_g[n]
                energy.a_g = a_g[n]
                if native:
                    ud[native_loop.AGX:native_loop.AGY + 1] = a_g[n]
                if n % n_sub == 0:
                    mujoco.mj_forward(model, data)
                    if native:   # what the samples read: the committed states and the integrals so far
                        dev.sigma, dev.zeta, energy.E[:] = native_loop.states(ud)
                    rows.append(self._row(t_out[n // n_sub], data, dev, a_g[n], tip, cap_id))
                    rows[-1].update(energy.columns(model, data))
                    if floors is not None:
                        floors.sample(data, a_g[n])
                    if not (np.isfinite(data.qpos).all() and rows[-1]["closure"] < s["closure_limit"]):
                        raise EngineError(f"mujoco: unstable at t = {n * h:.6g} s (loop gap {rows[-1]['closure']:.3g} m)")
                    if n == n_out * n_sub:
                        break
                if native:   # the n_sub steps to the next sample
                    native_loop.step_block(step, model._address, data._address, model.opt.gravity, a_g, n, n + n_sub,
                                           h, data.qpos, ud)
                    continue
                mujoco.mj_step(model, data)
                dev.commit(data.qpos)
        finally:
            mujoco.set_mjcb_passive(previous)
        cols = {k: np.array([r[k] for r in rows]) for k in rows[0]}
        cols["u"] = np.hypot(cols["x"], cols["y"])
        if floors is not None:
            cols.update(floors.columns(cols["x"], cols["y"], cols["vx"], cols["vy"]))
            cols["E_residual"] = cols["E_residual"] - cols["E_building_stored"]
        if structure.restrainer is not None:
            r = structure.restrainer
            fx, fy, F, delta, _ = restrainer_forces(cols["x"], cols["y"], cols["vx"], cols["vy"], r.gap, r.stiffness,
                                                    r.exponent, r.damping)
            cols.update({"restrainer_Fx": fx, "restrainer_Fy": fy, "restrainer_F": F, "restrainer_indentation": delta})
            cols["base_shear_x"], cols["base_shear_y"] = cols["base_shear_x"] + fx, cols["base_shear_y"] + fy
        stats = {"engine": "mujoco", "mode": "seismic", "wall_time": time.perf_counter() - t0,
                 "steps": n_out * n_sub, "timestep": h, "settings": s, "mujoco_version": mujoco.__version__}
        return RunResult("mujoco", cols, units_of(cols), stats)

    @staticmethod
    def _row(t, data, dev: _Forces, a_g, tip, cap_id) -> dict:
        q, v, acc = data.qpos, data.qvel, data.qacc
        P = _Forces
        f, _, _ = dev.device_on_cap(q)
        sx, sy, _ = dev.support(q, v)
        rod = data.qfrc_constraint  # the connect's force on the plate's slides is the rod's on the cap
        dfx, dfy = -(f[0] + rod[P.PX]), -(f[1] + rod[P.PY])
        wz = dev.g.wall_rest_z + q[P.WZ]
        row = {"t": t, "x": q[P.PX], "y": q[P.PY], "theta": q[P.PR], "vx": v[P.PX], "vy": v[P.PY],
               "ax_abs": acc[P.PX] + a_g[0], "ay_abs": acc[P.PY] + a_g[1], "support_Fx": sx, "support_Fy": sy,
               "device_Fx": dfx, "device_Fy": dfy, "base_shear_x": sx + dfx, "base_shear_y": sy + dfy,
               "cap_z": data.xpos[cap_id][2], "wall_z": wz, "spring_zeta": dev.zeta,
               "spring_push": float(spring_push(wz, 0.0, dev.zeta, dev.g.spring)[0]),
               "closure": float(np.linalg.norm(data.site_xpos[tip] - data.xpos[cap_id]))}
        for j, sig in enumerate(dev.sigma):
            row[f"wire{j}_stress"] = sig
        return row
