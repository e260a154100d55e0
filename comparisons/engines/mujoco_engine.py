"""MuJoCo engine: the negative-stiffness device of docs/model.md in drive mode (Table 1, first row).

Model (MJCF generated in code from ``device_geometry(params)``; no XML file):
- world -> ``cap``: three slide joints, ``drive`` along e_psi, ``lateral`` along e_z x e_psi (both
  prescribed: the plate's path p(t) from nsd_core.drive.Drive.plate, projected on the two axes) and
  ``cap_z`` (free: the cap slides vertically in the massless plate);
- world -> ``wall``: slide ``wall_z``; wall -> ``rod``: ball joint at the wall reference point;
- the loop wall -> rod -> cap is closed by an equality ``connect`` at the rod's upper end;
- the base is fixed (the world), gravity is -g along Z.
The rod's spin about its own axis is the one free direction a ball-ball rod has; no moment ever acts
about that axis, so it stays zero; the axial inertia is set to 1e-3 of the transverse one (MuJoCo
rejects zero) and has no effect.

Forces (Eqs. 16-18): ropes (base point -> cap point), SMA wires (cap point -> wall point) and the
push-only Bouc-Wen spring (base origin -> wall reference, along Z) are added to ``qfrc_passive`` by
an ``mjcb_passive`` callback that calls ``nsd_core.forces`` (rope_tension, spring_push; the wire
tension is Eq. 17a, A_w max(sigma, 0), of the committed stress). The callback is installed for the
run only and the previous one is restored afterwards. By default (``passive = "compiled"``,
``step_loop = "native"``) the callback is a C function compiled from the same scalar laws
(mujoco_native) and the whole step loop below runs natively, calling MuJoCo's own mj_step; the
Python callback and loop (``"python"``) remain as the readable form and give the same forces
(tests/test_mujoco_native.py: identical drive force on this machine). Euler, h = 5e-5 s, A = 15 mm,
1 Hz: 1.47 s CPU per cycle with the Python callback and loop, 0.15 s with the C callback, 0.106 s
with the native loop too (loaded 2-core machine). The solver options do not matter here: Newton
tolerance 1e-8..1e-12, 2-20 iterations, implicitfast, commits every 1-50 steps all give the same
error to 3 digits within the timing noise (0.09-0.13 s per cycle).

Hysteretic states (wire stresses sigma_j, spring zeta): never integrated by MuJoCo. After every
``commit_every`` accepted steps (and at every output time) they are advanced along the actual
change of strain / compression since the last commit with ``advance_wire_stress`` /
``advance_spring_zeta`` (RK4 in strain, ``hysteresis_substeps`` substeps). The callback is a pure
function of the stage positions and the committed states: when a stage can differ from the
committed configuration (RK4 stages, or commit_every > 1) it predicts the state to first order,
state_c + slope(direction) * (strain - strain_c), with the two directional slopes
(``sma_stress_slope`` / ``bouc_wen_slope``) evaluated at the commit. This works with every
integrator and never commits anything inside a callback that MuJoCo may call several times a step.

Drive (exact): the driven slides carry a large armature M (a heavy virtual plate) and a
feed-forward force (M + m_c) a - f_prev, where f_prev is the device's force on the drive joint at
the previous step and a is the acceleration that makes the integrator land on u(t_{n+1}) exactly
(Euler: the central difference (u_{n+1} - 2u_n + u_{n-1})/h^2); the driven qpos/qvel are then
reset to the prescribed values every step, so the tracking error is the (reported) drift of one
step, ~1e-15 m. The same holds for the lateral slide. The drive force vector is measured from the
equations of motion of the two driven joints, F_k = m_c a_k - (qfrc_passive + qfrc_constraint -
qfrc_bias)[k], i.e. m_c a minus rod, ropes and wires on the cap along each axis (the rod's share is
the connect's constraint force), rotated back to (F_x, F_y); m_c is read back from the compiled
mjModel, so the force is that of MuJoCo's own model.

Constraint softness: MuJoCo's equality constraints are soft. solref time constant
``solref_factor`` x timestep (2 = the smallest MuJoCo accepts) with solimp d = 0.9999 keeps the loop
closed to ~1e-8 m at h = 1e-5 s (benchmarks/convergence_mujoco.py measures the effect).

Default settings and why (against the in-house model nsd_core.device.simulate(rtol=1e-10), on
the last of 2 cycles: dF = max|dF|/max|F_ref|, dA = relative loop-area difference):
- Euler, h = 1e-5 s, commit every 10 steps, solref 2h, solimp 0.9999: dF 7.3e-5 / dA 2.5e-5
  (1 Hz, A = 0.0255 m), 1.2e-4 / 1.1e-4 (10 Hz, 0.0255), 7.9e-6 / 8.7e-6 (10 Hz, 0.015); about
  45 us CPU a step, 10-11 s CPU per 1 Hz case. Committing every step (3x the cost of a step)
  changes dF by < 3e-5. The timestep dominates the error: at 10 Hz, A = 0.015 m, h = 4e-5, 2e-5,
  1e-5 give dF 8.4e-5, 3.0e-5, 7.9e-6 (about 3x per halving).
- Softness (10 Hz, A = 0.015): solref 4h / 10h: dF 2.2e-5 / 1.1e-4; solimp 0.999 / 0.99: 3.8e-5 /
  3.5e-4. Hence the stiffest: 2h (MuJoCo's floor) and 0.9999.
- RK4 (commit every step) is the accurate option: h = 2.5e-5: dF 1.5e-5 (1 Hz) / 2.7e-5 (10 Hz),
  ~2.5x the CPU of the default; h = 5e-6: 6e-7 (1 Hz, 0.0255), 3e-6 (10 Hz, 0.015), 2.1e-5
  (10 Hz, 0.0255: a residual even in u', in the rod force, left where both models ring).
"""
from __future__ import annotations

import math
import time

import mujoco
import numpy as np

from nsd_core.device.drive import Drive
from nsd_core.device.forces import (advance_spring_zeta, advance_wire_stress, bouc_wen_slope, rope_tension,
                             sma_stress_slope, spring_push, wire_tension)
from nsd_core.device.geometry import DeviceGeometry, device_geometry
from nsd_core.device.outputs import device_columns
from nsd_core.device.params import ParameterError, Params
from nsd_core.device.results import RunResult

from comparisons.engines import mujoco_native
from comparisons.engines.base import DEFAULT_MODEL, EngineError, check_step_count, merged_settings
from comparisons.engines.mujoco_mjcf import wall_rod_loop_mjcf
from comparisons.engines.perturb import perturbed

_EULER_LIKE = ("Euler", "implicit", "implicitfast")


def mirror_symmetric(params: Params, direction_deg: float) -> bool:
    """True when the wire and rope patterns are mirror images of themselves about the drive's line at
    psi, so that a line drive meets no force across it: psi - delta_0 a multiple of 180/n deg for the
    wires and for the ropes (4 wires and ropes: 0 and 45 deg; 6 wires: 0 and 30 deg, not 45)."""
    d = direction_deg - params.wire_first_azimuth_deg
    for n in (params.n_wires, params.n_ropes):
        if n and abs(d * n / 180.0 - round(d * n / 180.0)) > 1e-9:
            return False
    return True


def _check_settings(s: dict) -> None:
    """MuJoCo's own constraints on its settings (types and ranges are checked in base.check_settings)."""
    from nsd_core.device.params import ParameterError
    allowed = _EULER_LIKE + ("RK4",)
    if s["integrator"] not in allowed:
        raise ParameterError(f"mujoco.integrator = {s['integrator']!r}: allowed: {', '.join(allowed)}")
    if s["solref_factor"] < 2.0:
        raise ParameterError(f"mujoco.solref_factor = {s['solref_factor']!r}: must be >= 2 (MuJoCo's minimum)")
    for key, choices in (("passive", ("compiled", "python")), ("step_loop", ("native", "python"))):
        if s[key] not in choices:
            raise ParameterError(f"mujoco.{key} = {s[key]!r}: allowed: {', '.join(choices)}")
    if s["step_loop"] == "native" and s["passive"] != "compiled":
        raise ParameterError("mujoco.step_loop = native needs passive = compiled")


def _f(x) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(x))


def build_mjcf(g: DeviceGeometry, drive: Drive, s: dict, h: float, nuserdata: int = 0) -> str:
    """The MJCF text of the driven device (see the module docstring for bodies and joints); ``nuserdata``
    float64 slots of mjData.userdata hold the compiled callback's element data (mujoco_native)."""
    p = g.params
    e = drive.unit_vector
    lat = np.array([-e[1], e[0], 0.0])
    solref = f"{_f(s['solref_factor'] * h)} {_f(s['solref_dampratio'])}"
    return f"""<mujoco model="nsd_drive">
  <size nuserdata="{nuserdata}"/>
  <option timestep="{_f(h)}" integrator="{s['integrator']}" gravity="0 0 {_f(-p.gravity)}" solver="Newton"
          tolerance="{_f(s['solver_tolerance'])}" iterations="{s['solver_iterations']}" jacobian="dense">
    <flag contact="disable"/>
  </option>
  <worldbody>
    <body name="base" pos="0 0 0"/>
    <body name="cap" pos="0 0 {_f(g.cap_rest_z)}">
      <inertial pos="{_f(g.cap.com)}" mass="{_f(g.cap.mass)}" diaginertia="{_f(np.diag(g.cap.inertia))}"/>
      <joint name="drive" type="slide" axis="{_f(e)}" armature="{_f(s['drive_armature'])}"/>
      <joint name="lateral" type="slide" axis="{_f(lat)}" armature="{_f(s['drive_armature'])}"/>
      <joint name="cap_z" type="slide" axis="0 0 1"/>
    </body>
{wall_rod_loop_mjcf(g, solref, s['solimp'])}</mujoco>
"""


class _Device:
    """Precomputed element data, the committed hysteretic states and the passive callback."""

    def __init__(self, g: DeviceGeometry, drive: Drive, data: mujoco.MjData, predict: bool, substeps: int):
        self.g, self.nr, self.nw = g, g.n_ropes, g.n_wires
        e = drive.unit_vector
        self.e0, self.e1 = float(e[0]), float(e[1])
        self.zc0, self.zw0 = g.cap_rest_z, g.wall_rest_z
        # element vector = cap position + D (- wall z for wires): upper end minus lower end
        self.D = np.vstack([g.rope_offsets, g.wire_offsets])
        self.T = np.zeros(self.nr + self.nw)
        self.data, self.qpos, self.qfrc = data, data.qpos, data.qfrc_passive
        self.predict, self.substeps = predict, substeps
        self._dirs = np.repeat([1.0, -1.0], self.nw)   # one slope call gives both directions
        self.sigma = np.array(g.initial_wire_stress(), dtype=float)
        self.zeta = float(g.spring_zeta0)
        self.eps_c, self.x_c = self.strains(self.qpos)
        self._slopes()

    def geometry(self, q):
        """Cap position, wall height, element vectors (n, 3) and lengths for generalized positions q."""
        q0, q1, q2, q3 = q[0], q[1], q[2], q[3]
        cap = np.array((q0 * self.e0 - q1 * self.e1, q0 * self.e1 + q1 * self.e0, self.zc0 + q2))
        wz = self.zw0 + q3
        v = self.D + cap
        v[self.nr:, 2] -= wz
        return cap, wz, v, np.sqrt(np.einsum("ij,ij->i", v, v))

    def strains(self, q):
        _, wz, _, L = self.geometry(q)
        L0 = self.g.wire.natural_length
        return (L[self.nr:] - L0) / L0, self.g.spring.free_length - wz

    def _slopes(self):
        if self.predict:  # directional slopes at the committed state, for the callback's prediction
            w, sp = self.g.wire, self.g.spring
            both = sma_stress_slope(np.tile(self.eps_c, 2), self._dirs, np.tile(self.sigma, 2), w)
            self.s_up, self.s_dn = both[:self.nw], both[self.nw:]
            self.z_up = float(bouc_wen_slope(self.zeta, 1.0, sp))
            self.z_dn = float(bouc_wen_slope(self.zeta, -1.0, sp))

    def commit(self):
        """Advance the hysteretic states along the strain change since the last commit (accepted states only)."""
        eps, x = self.strains(self.qpos)
        if self.nw:
            self.sigma = advance_wire_stress(self.eps_c, eps, self.sigma, self.g.wire, self.substeps)
        self.zeta = float(advance_spring_zeta(self.x_c, x, self.zeta, self.g.spring, self.substeps))
        self.eps_c, self.x_c = eps, x
        self._slopes()

    def passive(self, m, d):
        """mjcb_passive: add ropes, wires and spring to qfrc_passive. Pure: commits nothing."""
        qfrc = self.qfrc if d is self.data else d.qfrc_passive
        cap, wz, v, L = self.geometry(self.qpos if d is self.data else d.qpos)
        g, nr, T = self.g, self.nr, self.T
        T[:nr] = rope_tension(L[:nr], g.rope_natural_length, g.rope_stiffness)   # Eq. 16
        sigma, zeta = self.sigma, self.zeta
        if self.predict:
            de = (L[nr:] - g.wire.natural_length) / g.wire.natural_length - self.eps_c
            sigma = sigma + np.where(de > 0.0, self.s_up, self.s_dn) * de
            dx = g.spring.free_length - wz - self.x_c
            zeta = zeta + (self.z_up if dx > 0.0 else self.z_dn) * dx
        T[nr:] = wire_tension(sigma, g.wire)                                        # Eq. 17a
        push = spring_push(wz, 0.0, zeta, g.spring)[0]                              # Eq. 18
        w = T / L
        f_cap = -(w @ v)                  # every element pulls the cap towards its lower end
        qfrc[0] += f_cap[0] * self.e0 + f_cap[1] * self.e1
        qfrc[1] += f_cap[1] * self.e0 - f_cap[0] * self.e1
        qfrc[2] += f_cap[2]
        qfrc[3] += float(w[nr:] @ v[nr:, 2]) + float(push)   # wires pull the wall up, spring pushes it


class MujocoEngine:
    name = "mujoco"
    validate_settings = staticmethod(lambda s: _check_settings(s))
    default_settings = {
        "timestep": 1e-5,            # [s] largest step; the step used divides the output interval
        "integrator": "Euler",       # Euler | implicitfast | implicit | RK4
        "solref_factor": 2.0,        # connect time constant = factor x timestep (MuJoCo's minimum is 2)
        "solref_dampratio": 1.0,
        "solimp": [0.9999, 0.9999, 0.001, 0.5, 2.0],
        "drive_armature": 1e4,       # [kg] virtual plate mass on the driven slides
        "commit_every": None,        # accepted steps between commits of the states; None: Euler 10, RK4 1
        "hysteresis_substeps": 1,    # RK4 substeps of advance_wire_stress / advance_spring_zeta
        "solver_tolerance": 1e-12,
        "solver_iterations": 20,
        "closure_limit": 1e-4,       # [m] a larger loop gap is an instability (EngineError)
        "perturb": None,             # a modelling error injected into this model only (engines/perturb.py)
        "passive": "compiled",       # "compiled": C callback (mujoco_native); "python": _Device.passive
        "step_loop": "native",       # "native": compiled loop calling mj_step; "python": one call a step
        "model": DEFAULT_MODEL["mujoco"],          # "described": the builder on the device's description (engines/described.py)
    }

    @property
    def seismic_default_settings(self) -> dict:
        from comparisons.engines.mujoco_seismic import DEFAULTS
        return DEFAULTS

    def run_seismic(self, params: Params, structure, ground, duration=None, dt_out=1e-3,
                    settings: dict | None = None) -> RunResult:
        """The seismic mode (comparisons/engines/mujoco_seismic.py, imported here: it builds on this module)."""
        from comparisons.engines.mujoco_seismic import MujocoSeismic
        return MujocoSeismic().run(params, structure, ground, duration=duration, dt_out=dt_out, settings=settings)

    def run(self, params: Params, drive: Drive, settings: dict | None = None, zero_drive: bool = False) -> RunResult:
        """Run the drive; ``zero_drive`` holds u = 0 (the rest-state check) on the same time grid."""
        s = merged_settings(self.default_settings, settings, self.name)
        if s["integrator"] not in _EULER_LIKE + ("RK4",):
            raise EngineError(f"mujoco: integrator {s['integrator']!r} not supported")
        for key, allowed in (("passive", ("compiled", "python")), ("step_loop", ("native", "python"))):
            if s[key] not in allowed:
                raise ParameterError(f"mujoco.{key} = {s[key]!r}: allowed: {', '.join(allowed)}")
        if s["step_loop"] == "native" and s["passive"] != "compiled":
            raise ParameterError("mujoco.step_loop = native needs passive = compiled")
        compiled = s["passive"] == "compiled"
        drive.check_followable(params)
        g = perturbed(device_geometry(params), s["perturb"])
        t_out = drive.output_times()
        dt_out = float(t_out[1] - t_out[0])
        n_sub = max(1, math.ceil(dt_out / float(s["timestep"]) - 1e-9))
        h = dt_out / n_sub
        euler = s["integrator"] in _EULER_LIKE
        # RK4 stages span the whole step: its first-order stage prediction wants a commit every step
        commit_every = max(1, int(s["commit_every"] or (10 if euler else 1)))
        n_steps = n_sub * (len(t_out) - 1)
        check_step_count(self.name, n_steps)
        try:
            nud = mujoco_native.userdata_size(g.n_ropes, g.n_wires) if compiled else 0
            model = mujoco.MjModel.from_xml_string(build_mjcf(g, drive, s, h, nud))
        except ValueError as exc:
            raise EngineError(f"mujoco: model rejected: {str(exc).splitlines()[0]}") from None
        data = mujoco.MjData(model)
        dev = _Device(g, drive, data, predict=(not euler) or commit_every > 1,
                      substeps=int(s["hysteresis_substeps"]))
        udata = data.userdata
        if compiled:   # the same elements and states, handed to the compiled callback in mjData.userdata
            mujoco_native.pack_userdata(udata, g, drive.unit_vector, dev.sigma, dev.zeta, dev.eps_c, dev.x_c,
                                        dev.predict, dev.substeps)
            callback = mujoco_native.passive_callback().ctypes
            commit = lambda: mujoco_native.commit(data.qpos, udata)  # noqa: E731
            states = lambda: (udata[mujoco_native.sigma_slice(udata)], udata[mujoco_native.ZETA])  # noqa: E731
        else:
            callback, commit, states = dev.passive, dev.commit, lambda: (dev.sigma, dev.zeta)

        # prescribed drive on the step grid (one extra point on each side for the differences):
        # the plate's path in the joints' frame, u along e_psi (slide "drive"), v across (slide "lateral")
        tn = h * np.arange(-1, n_steps + 2)
        e, lat = drive.unit_vector[:2], np.array([-drive.unit_vector[1], drive.unit_vector[0]])
        pos, vel_p, acc_p = drive.plate(tn)
        if zero_drive:
            pos, vel_p, acc_p = (np.zeros_like(pos),) * 3
        u, ud, udd = pos @ e, vel_p @ e, acc_p @ e
        v, vd, vdd = pos @ lat, vel_p @ lat, acc_p @ lat
        if euler:   # semi-implicit Euler lands on u_{n+1} exactly with the central difference
            vel_at = (np.diff(u) / h).tolist()       # vel[n] = (u_n - u_{n-1})/h  (index shift +1)
            acc = (u[2:] - 2 * u[1:-1] + u[:-2]) / (h * h)
            lvel_at = (np.diff(v) / h).tolist()
            lacc = (v[2:] - 2 * v[1:-1] + v[:-2]) / (h * h)
        else:       # RK4: constant acceleration that lands on u_{n+1}; qvel = u'
            acc = 2.0 * (u[2:] - u[1:-1] - h * ud[1:-1]) / (h * h)
            vel_at = ud[1:].tolist()
            lacc = 2.0 * (v[2:] - v[1:-1] - h * vd[1:-1]) / (h * h)
            lvel_at = vd[1:].tolist()
        u_at, acc_at = u[1:].tolist(), acc.tolist()
        v_at, lacc_at = v[1:].tolist(), lacc.tolist()
        tip, cap_id = model.site("rod_tip").id, model.body("cap").id
        m_c, M = float(model.body_mass[cap_id]), float(s["drive_armature"])   # the cap's mass in this model

        n_out = len(t_out)
        cap_pos, wall_z = np.zeros((n_out, 3)), np.zeros(n_out)
        sig, zet, clo, F = np.zeros((n_out, g.n_wires)), np.zeros(n_out), np.zeros(n_out), np.zeros((n_out, 2))
        qpos, qvel, qfa = data.qpos, data.qvel, data.qfrc_applied
        qpas, qcon, qbias = data.qfrc_passive, data.qfrc_constraint, data.qfrc_bias
        track = 0.0
        previous_cb = mujoco.get_mjcb_passive()
        t0, c0 = time.perf_counter(), time.process_time()
        try:
            mujoco.set_mjcb_passive(callback)
            mujoco.mj_forward(model, data)
            # consistent initial velocities: the rod (vertical at the centre) swings with the plate
            qpos[0], qvel[0], qpos[1], qvel[1] = u_at[0], vel_at[0], v_at[0], lvel_at[0]
            v_xy = vel_at[0] * e + lvel_at[0] * lat
            qvel[4:7] = np.array([-v_xy[1], v_xy[0], 0.0]) / params.rod_length
            mujoco.mj_forward(model, data)
            f_prev = qpas[0] + qcon[0] - qbias[0]
            l_prev = qpas[1] + qcon[1] - qbias[1]
            # the native loop drives the ``drive`` slide only and measures the force along it: lines on
            # which the device is mirror-symmetric (no force across the line); any other path or
            # direction takes the Python loop, which measures both components
            native = (s["step_loop"] == "native" and drive.is_line and not zero_drive
                      and mirror_symmetric(params, drive.direction_deg))
            if native:
                F1 = np.zeros(n_out)
                track, failed = mujoco_native.step_loop(
                    *mujoco_native.mujoco_functions(), model._address, data._address, qpos, qvel, qfa, qpas, qcon,
                    qbias, data.xpos, data.site_xpos, udata, np.asarray(u_at), np.asarray(vel_at), np.asarray(acc_at),
                    udd, n_sub, n_steps, commit_every, M + m_c, m_c, cap_id, tip, g.wall_rest_z,
                    float(s["closure_limit"]), F1, cap_pos, wall_z, sig, zet, clo)
                F[:] = F1[:, None] * e[None, :]
                if failed >= 0:
                    raise EngineError(f"mujoco: unstable at t = {t_out[failed]:.6g} s (loop gap {clo[failed]:.3g} m)")
            for n in range(n_steps + 1 if native else 0, n_steps + 1):
                qfa[0] = (M + m_c) * acc_at[n] - f_prev
                qfa[1] = (M + m_c) * lacc_at[n] - l_prev
                if n % n_sub == 0:
                    k = n // n_sub
                    mujoco.mj_forward(model, data)
                    F_u = m_c * udd[n + 1] - (qpas[0] + qcon[0] - qbias[0])
                    F_v = m_c * vdd[n + 1] - (qpas[1] + qcon[1] - qbias[1])
                    F[k] = F_u * e + F_v * lat
                    cap_pos[k] = data.xpos[cap_id]
                    wall_z[k] = g.wall_rest_z + qpos[3]
                    sig[k], zet[k] = states()
                    clo[k] = np.linalg.norm(data.site_xpos[tip] - data.xpos[cap_id])
                    if not (np.isfinite(qpos).all() and clo[k] < s["closure_limit"]):
                        raise EngineError(f"mujoco: unstable at t = {n * h:.6g} s (loop gap {clo[k]:.3g} m)")
                    if n == n_steps:
                        break
                mujoco.mj_step(model, data)
                f_prev = qpas[0] + qcon[0] - qbias[0]
                l_prev = qpas[1] + qcon[1] - qbias[1]
                track = max(track, abs(qpos[0] - u_at[n + 1]), abs(qpos[1] - v_at[n + 1]))
                qpos[0], qvel[0], qpos[1], qvel[1] = u_at[n + 1], vel_at[n + 1], v_at[n + 1], lvel_at[n + 1]
                if (n + 1) % commit_every == 0 or (n + 1) % n_sub == 0:
                    commit()
        finally:
            mujoco.set_mjcb_passive(previous_cb)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        if not np.isfinite(F).all():
            raise EngineError("mujoco: non-finite drive force")
        stats = {"wall_time": wall, "cpu_time": cpu, "steps": n_steps, "timestep": h, "commit_every": commit_every, "tracking_error": track,
                 "closure_max": float(clo.max()), "settings": s, "mujoco_version": mujoco.__version__}
        return device_columns(self.name, g, drive, t_out, cap_pos, wall_z, sig, zet, clo,
                              drive_force=F, stats=stats)
