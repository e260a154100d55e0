"""The in-house builder: a model description run on the two-step semirecursive engine.

``simulate(model, duration, dt_out, settings)`` builds the mechanism (nsd_core.model.assemble),
starts from the shared consistent initial state, integrates with an adaptive embedded Runge-Kutta
method (nsd_core.engine.integrate) and samples every named output. No line here knows which
mechanism it runs. A ``work`` output is an extra state of the ODE, the quadrature of its power
(nsd_core.model.assemble.Forces), under the integrator's error control and dense output like the
motion: the energy balance holds to the tolerance (nsd_seismic ~1e-15, fourbar_spring 1.4e-10 of the
peak work at rtol 1e-10), at the cost of the steps those states add to the control.
"""
from __future__ import annotations

import time

import numpy as np

from nsd_core.engine.dynamics import kinetic_energy, potential_energy_gravity
from nsd_core.engine.integrate import integrate
from nsd_core.model.assemble import start, system_of
from nsd_core.model.description import Model
from nsd_core.model.run import ModelRun, output_times

name = "semirecursive"
MAX_STEPS = 20_000_000   # a runaway or a needlessly long case stops with a SolverError (its case's failure)
default_settings = {"method": "DOP853", "rtol": 1e-10, "atol": 1e-12, "max_step": 0.01}


def sampler(model: Model, system, tree):
    """A function of one Evaluation giving every named output's value, in the description's order."""
    forces = system.forces
    drive_pos = {p.name: k for k, p in enumerate(model.prescribed)}
    parent = system.m.arrays.parent

    def acceleration(ev, out):
        """The body point's absolute acceleration: Z'_i = sum over i's path of b_j z''_j plus the
        velocity products vp_i (Eq. 5), then d/dt (s' + w x p) = s'' + w' x p + w x v_p; with an
        excitation the frame's own acceleration a_g(t) is added (outputs are otherwise relative)."""
        kin, i = ev.kin, tree.body[out.body]
        if i < 0:
            a = np.zeros(3)
        else:
            Zd, j = kin.vp[i].copy(), i
            while j >= 0:
                Zd += kin.B[j] * ev.zdd[j]
                j = parent[j]
            p = kin.point(i, out.point)
            a = Zd[:3] + np.cross(Zd[3:], p) + np.cross(kin.Z[i, 3:], kin.point_velocity(i, p))
        return a + model.excitation.acceleration(ev.t) if model.excitation is not None else a

    def one(ev, out, law_values, extra):
        kin = ev.kin
        if out.kind == "coordinate":
            return ev.z[tree.coordinate[(out.body, out.dof)]]
        if out.kind == "point":
            return kin.point(tree.body[out.body], out.point)[out.component]
        if out.kind == "point_velocity":
            i = tree.body[out.body]
            return kin.point_velocity(i, kin.point(i, out.point))[out.component]
        if out.kind == "point_acceleration":
            return acceleration(ev, out)[out.component]
        if out.kind == "force":   # a plane law's value is its pair (Q_x, Q_y)
            v = law_values[out.element]
            return v[out.component] if isinstance(v, tuple) else v
        if out.kind == "state":   # a plane law's state takes two slots, x first
            return extra[forces.slot[out.element] + out.component]
        if out.kind == "drive_force":
            return ev.drive_force[drive_pos[out.element]]
        if out.kind == "work":   # its quadrature state (nsd_core.model.assemble.Forces)
            return extra[forces.work_at[out.name]]
        if out.term == "kinetic":
            return kinetic_energy(system.m, kin)
        return potential_energy_gravity(system.m, kin)

    def sample(ev, extra=()):
        law_values = forces.values(ev.kin, ev.z, ev.zd, extra) if model.forces else {}
        return [float(one(ev, o, law_values, extra)) for o in model.outputs]
    return sample


def simulate(model: Model, duration: float, dt_out: float, settings: dict | None = None) -> ModelRun:
    s = {**default_settings, **(settings or {})}
    system, tree = system_of(model)
    _, _, y0, _ = start(model, system, tree)
    t_eval = output_times(duration, dt_out)
    sample = sampler(model, system, tree)
    rows, closure, tracking = [], [0.0], [0.0]
    prescribed = tree.prescribed

    def record(t, y):
        ev = system.evaluate(ws, t, y)
        rows.append(sample(ev, y[len(y) - system.n_extra:] if system.n_extra else ()))
        if ev.Phi.size:
            closure[0] = max(closure[0], float(np.max(np.abs(ev.Phi))))
        if len(prescribed):
            q = system.motion(t)[0]
            tracking[0] = max(tracking[0], float(np.max(np.abs(ev.z[prescribed] - q))))

    ws = system.workspace()
    begin = time.perf_counter()
    if len(y0) == 0:   # every coordinate prescribed or dependent: kinematics only, nothing to integrate
        for t in t_eval:
            record(t, y0)
        steps, nfev, parts = 0, len(t_eval), 0
    else:
        traj = integrate(system, ws, y0, t_eval, method=s["method"], rtol=s["rtol"], atol=s["atol"],
                         max_step=s["max_step"], outputs=record, first_step=min(dt_out, s["max_step"]) / 10,
                         max_steps=MAX_STEPS)
        steps, nfev, parts = traj.steps, traj.nfev, len(traj.partitions) - 1
    wall = time.perf_counter() - begin
    data = np.array(rows).reshape(len(t_eval), len(model.outputs))
    return ModelRun(name, t_eval, {o.name: data[:, k] for k, o in enumerate(model.outputs)},
                    {o.name: o.unit for o in model.outputs},
                    {"wall_time": wall, "steps": steps, "nfev": nfev, "closure_max": closure[0],
                     "tracking_error": tracking[0], "repartitions": parts, **s})
