"""MuJoCo on a baseline isolator (issue 33 item 2): the isolated mass on a lead-rubber bearing or a
friction pendulum, without the device, as the in-house ``simulate_seismic(..., device=False)`` runs
it with a structure whose ``isolator`` is set (nsd_core.device.isolators).

Why a separate small model rather than the device's MuJoCo adapter (comparisons/engines/
mujoco_seismic.py): that one always builds the device's bodies and loop; here the plate alone moves.
In the frame that translates with the ground (gravity set to (-a_gx, -a_gy, -g) before each step,
as the device's adapter does): world -> ``plate``: slides ``px``, ``py`` and hinge ``pr`` (mass M,
polar inertia M r_g^2). An ``mjcb_passive`` callback applies the isolator: -(k_d u + c u') and the
hysteretic part -Q z from ``nsd_core.device.isolator_laws.hysteretic_force_scalar`` (the shared law),
its state z advanced after every step along the step's displacement change
(``advance_hysteresis``); the torsional pair k_d r_b^2, c r_b^2. Semi-implicit Euler, fixed step.
No building, no restrainer (the in-house engine runs those).
"""
from __future__ import annotations

import math
import time

import mujoco
import numpy as np

from nsd_core.device.columns import units_of
from nsd_core.device.isolator_laws import advance_hysteresis, hysteretic_force_scalar
from nsd_core.device.params import ParameterError
from nsd_core.device.results import RunResult
from nsd_core.device.seismic import output_times

TIMESTEP = 2e-5   # s: 1e-4 changes the peak displacement of the tests' record by ~1e-3 relative
SUBSTEPS = 4      # midpoint substeps of z's advance per MuJoCo step


def _mjcf(structure, h: float) -> str:
    J = structure.polar_inertia
    return f"""<mujoco model="nsd_isolator">
  <option timestep="{h!r}" integrator="Euler" gravity="0 0 -9.81"><flag contact="disable"/></option>
  <worldbody>
    <body name="plate">
      <inertial pos="0 0 0" mass="{structure.mass!r}" diaginertia="{J / 2!r} {J / 2!r} {J!r}"/>
      <joint name="px" type="slide" axis="1 0 0"/>
      <joint name="py" type="slide" axis="0 1 0"/>
      <joint name="pr" type="hinge" axis="0 0 1"/>
    </body>
  </worldbody>
</mujoco>"""


def run_isolator(structure, ground, duration: float | None = None, dt_out: float = 1e-3,
                 timestep: float = TIMESTEP) -> RunResult:
    """The run without the device on ``structure.isolator`` in MuJoCo: the in-house columns a
    comparison needs (x, y, theta, vx, vy, ax_abs, ay_abs, support_Fx, support_Fy, u)."""
    iso = structure.isolator
    if iso is None or structure.building is not None or structure.restrainer is not None:
        raise ParameterError("mujoco isolator peer: a structure with a baseline isolator, no building, no restrainer")
    duration = ground.duration if duration is None else float(duration)
    t_out = output_times(duration, dt_out)
    n_sub = max(1, math.ceil((t_out[1] - t_out[0]) / timestep - 1e-9))
    h = float(t_out[1] - t_out[0]) / n_sub
    model = mujoco.MjModel.from_xml_string(_mjcf(structure, h))
    data = mujoco.MjData(model)
    k, c, r2 = iso.stiffness, iso.damping, structure.support_radius ** 2
    law = iso.block()
    z = [0.0, 0.0]
    a_g = ground(h * np.arange((len(t_out) - 1) * n_sub + 1))[2]

    def passive(m, d):
        q, v = d.qpos, d.qvel
        fx, fy, _, _, _ = hysteretic_force_scalar(v[0], v[1], z[0], z[1], *law)
        d.qfrc_passive[0] += -k * q[0] - c * v[0] - fx
        d.qfrc_passive[1] += -k * q[1] - c * v[1] - fy
        d.qfrc_passive[2] += -k * r2 * q[2] - c * r2 * v[2]

    rows = []
    previous = mujoco.get_mjcb_passive()
    t0 = time.perf_counter()
    try:
        mujoco.set_mjcb_passive(passive)
        for n in range(len(a_g)):
            model.opt.gravity[:2] = -a_g[n]
            if n % n_sub == 0:
                mujoco.mj_forward(model, data)
                q, v = data.qpos, data.qvel
                fx, fy, _, _, _ = hysteretic_force_scalar(v[0], v[1], z[0], z[1], *law)
                rows.append({"t": t_out[n // n_sub], "x": q[0], "y": q[1], "theta": q[2], "vx": v[0], "vy": v[1],
                             "ax_abs": data.qacc[0] + a_g[n][0], "ay_abs": data.qacc[1] + a_g[n][1],
                             "support_Fx": k * q[0] + c * v[0] + fx, "support_Fy": k * q[1] + c * v[1] + fy,
                             "isolator_zx": z[0], "isolator_zy": z[1]})
                if n == len(a_g) - 1:
                    break
            before = data.qpos[:2].copy()
            mujoco.mj_step(model, data)
            z[0], z[1] = advance_hysteresis(data.qpos[0] - before[0], data.qpos[1] - before[1], z[0], z[1],
                                            law[3], law[4], SUBSTEPS)
    finally:
        mujoco.set_mjcb_passive(previous)
    cols = {key: np.array([r[key] for r in rows], dtype=float) for key in rows[0]}
    cols["u"] = np.hypot(cols["x"], cols["y"])
    cols["base_shear_x"], cols["base_shear_y"] = cols["support_Fx"], cols["support_Fy"]
    stats = {"engine": "mujoco", "mode": "seismic", "device": False, "isolator": iso.kind, "timestep": h,
             "steps": (len(t_out) - 1) * n_sub, "wall_time": time.perf_counter() - t0,
             "mujoco_version": mujoco.__version__}
    return RunResult("mujoco", cols, units_of(cols), stats)


def isolator_metrics(ref, other) -> dict:
    """Differences of the peer's run against the in-house one on the same output times: du, dF (the
    isolator's force vector), da (absolute acceleration) as max|o - r| / max|r| over plan vectors,
    and the relative differences of the peak displacement and acceleration."""
    if len(ref["t"]) != len(other["t"]) or np.max(np.abs(ref["t"] - other["t"])) > 1e-9:
        raise ValueError("isolator_metrics: the runs are not on the same output times")

    def vec(r, a, b):
        return np.column_stack([r[a], r[b]])

    def rel(name_x, name_y):
        a, b = vec(other, name_x, name_y), vec(ref, name_x, name_y)
        return float(np.max(np.linalg.norm(a - b, axis=1)) / max(np.max(np.linalg.norm(b, axis=1)), 1e-300))

    def peak(name_x, name_y):
        a, b = vec(other, name_x, name_y), vec(ref, name_x, name_y)
        pr = np.max(np.linalg.norm(b, axis=1))
        return float((np.max(np.linalg.norm(a, axis=1)) - pr) / max(pr, 1e-300))

    return {"du": rel("x", "y"), "dF": rel("support_Fx", "support_Fy"), "da": rel("ax_abs", "ay_abs"),
            "peak_displacement": peak("x", "y"), "peak_absolute_acceleration": peak("ax_abs", "ay_abs")}
