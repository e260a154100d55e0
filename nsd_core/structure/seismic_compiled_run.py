"""The seismic mode's compiled path (nsd_core.structure.compiled_seismic) as a RunResult: the run, its
failures (the device's validity, the rod's reach, the step budget) and the same columns the scipy path
of nsd_core.structure.seismic samples row by row."""
from __future__ import annotations

import math
import time

import numpy as np

from nsd_core import __version__
from nsd_core.device.columns import units_of
from nsd_core.device.drive import DriveError
from nsd_core.device.forces import restrainer_forces, restrainer_stored_scalar
from nsd_core.device.model import _check_lengths
from nsd_core.device.results import RunResult
from nsd_core.engine.integrate import SolverError, check_tolerances
from nsd_core.structure.building import building_columns
from nsd_core.structure.building_tree import BuildingIndex
from nsd_core.structure.isolator_laws import hysteretic_force_scalar

N_ENERGY = 5  # extra states: E_input, E_device, E_supports_dissipated, E_restrainer, E_building_dissipated


def _with_partial(err: DriveError, partial: RunResult | None, t_event: float) -> DriveError:
    """err with what the run computed up to the event (exit 4 keeps the series)."""
    err.partial, err.t_event = partial, float(t_event)
    return err


def _simulate_compiled(system, g, structure, ground, device, y0, t_eval, method, rtol, atol, max_step, first_step,
                       progress, start, fixed_base=False):
    """The seismic run on the compiled path (nsd_core.structure.compiled_seismic): the same columns."""
    from nsd_core.structure import compiled_seismic as cs
    from nsd_core.engine.codegen import evaluation_used, evaluator_for
    from nsd_core.engine.rk import TOO_MANY_STEPS
    check_tolerances(rtol, atol, max_step)  # the bounds of the scipy path, the same way
    model = cs.seismic_model(system, g, structure, ground, device)
    used = evaluation_used(model)   # decided once: the run and its stats name the same evaluation
    res = cs.run(model, system.z_ref, y0, t_eval, method, rtol, atol, max_step, first_step, progress,
                 evaluator_for(model, used))
    keep, error = res["done"], None
    if device:
        try:
            _check_lengths(t_eval[:keep], res["lengths"][:keep], system.forces.device)
        except DriveError as err:  # the first sample outside the laws' validity ends the series
            keep, error = err.sample, _with_partial(err, None, t_eval[err.sample])
    if error is None and res["status"] != 0:
        t_fail, z, q = res["t_fail"], res["z_fail"], res["q_fail"]
        ix = system.forces.ix
        system.last = (t_fail, math.hypot(z[ix["plate_x"]] - q[0], z[ix["plate_y"]] - q[1]))
        if device and (res["status"] == cs.ROD_REACH or system.last[1] > 0.95 * system.reach):
            error = _with_partial(system.reach_error(), None, t_fail)
        elif res["status"] == TOO_MANY_STEPS:
            raise SolverError(f"exceeded {cs.STEPS_PER_SECOND} steps per model second at t = {t_fail:.6g} s of "
                              f"{t_eval[-1]:.6g} s: a stiff or runaway input")
        else:
            raise SolverError(f"{method} (compiled) failed at t = {t_fail:.6g} s: status {res['status']} "
                              "(nsd_core.engine.compiled, nsd_core.engine.rk)")
    stats = {"engine": "semirecursive", "mode": "seismic", "device": device, "fixed_base": fixed_base,
             "version": __version__, "backend": "compiled", "evaluation": used,
             "method": method, "rtol": rtol, "atol": atol, "max_step": max_step, "steps": res["steps"],
             "nfev": res["nfev"], "wall_time": time.perf_counter() - start,
             "model_time": float(t_eval[-1]), "dt_out": float(t_eval[1] - t_eval[0]), "ground": ground.describe(),
             "structure": structure.to_dict()}
    if error is not None:
        error.partial = _compiled_result(res, keep, t_eval, system, g, structure, device, stats) if keep else None
        raise error
    return _compiled_result(res, len(t_eval), t_eval, system, g, structure, device, stats)


def _compiled_result(res, keep, t_eval, system, g, structure, device, stats) -> RunResult:
    """The seismic columns of the first ``keep`` samples of a compiled run (nsd_core.structure.compiled_seismic)."""
    from nsd_core.structure import compiled_seismic as cs
    res = {k: (v[:keep] if isinstance(v, np.ndarray) and v.ndim >= 1 and len(v) == len(t_eval) else v)
           for k, v in res.items()}
    t_eval = t_eval[:keep]
    tab = dict(zip(cs.COLUMNS, res["table"].T))
    s = structure
    x, y, th, vx, vy, thd = tab["x"], tab["y"], tab["theta"], tab["vx"], tab["vy"], tab["theta_rate"]
    cols = {"t": t_eval, "x_g": tab["x_g"], "y_g": tab["y_g"], "ax_g": tab["ax_g"], "ay_g": tab["ay_g"], "x": x,
            "y": y, "theta": th, "vx": vx, "vy": vy, "ax_abs": tab["ax_abs"], "ay_abs": tab["ay_abs"],
            "support_Fx": s.stiffness * x + s.damping * vx, "support_Fy": s.stiffness * y + s.damping * vy,
            "support_torque": s.support_radius ** 2 * (s.stiffness * th + s.damping * thd)}
    if s.isolator is not None and not device:   # its hysteretic part from the integrated z (the shared law)
        zx, zy = res["y"][:, -N_ENERGY - 2], res["y"][:, -N_ENERGY - 1]
        f = np.array([hysteretic_force_scalar(a, b, c, d, *s.isolator.block())[:2] for a, b, c, d in
                      zip(vx, vy, zx, zy)]).reshape(-1, 2)
        cols["support_Fx"], cols["support_Fy"] = cols["support_Fx"] + f[:, 0], cols["support_Fy"] + f[:, 1]
        cols["isolator_zx"], cols["isolator_zy"] = zx, zy
    E_in, E_dev, E_sup_diss, E_res, E_bld = res["y"][:, -N_ENERGY:].T
    cols["device_Fx"], cols["device_Fy"] = tab["device_Fx"], tab["device_Fy"]
    if device:
        dev, nw = system.forces.device, g.n_wires
        extra = res["y"][:, -N_ENERGY - nw - 1:-N_ENERGY]
        zeta = extra[:, nw]
        cols.update({"cap_z": tab["cap_z"], "wall_z": tab["wall_z"], "spring_push": -res["tensions"][:, dev.spring],
                     "spring_zeta": zeta, "closure": tab["closure"]})
        t_rope, t_wire = res["tensions"][:, dev.ropes], res["tensions"][:, dev.wires]
        strain = (res["lengths"][:, dev.wires] - g.wire.natural_length) / g.wire.natural_length
        for i in range(t_rope.shape[1]):
            cols[f"rope{i}_tension"] = t_rope[:, i]
        for j in range(nw):
            cols[f"wire{j}_tension"], cols[f"wire{j}_strain"], cols[f"wire{j}_stress"] = \
                t_wire[:, j], strain[:, j], extra[:, j]
    cols["base_shear_x"] = cols["support_Fx"] + cols["device_Fx"]
    cols["base_shear_y"] = cols["support_Fy"] + cols["device_Fy"]
    stored = 0.5 * s.stiffness * (x * x + y * y) + 0.5 * s.stiffness * s.support_radius ** 2 * th * th
    gravity = tab["height"] - tab["height"][0]
    cols.update({"E_input": E_in, "E_kinetic": tab["kinetic"], "E_gravity": gravity, "E_supports_stored": stored,
                 "E_supports_dissipated": E_sup_diss, "E_device": E_dev})
    if s.restrainer is not None:
        _restrainer_columns(cols, s.restrainer, E_res)
    if s.building is not None:
        cols.update(_compiled_building_columns(res["y"], system, s.building, tab))
        cols["E_building_dissipated"] = E_bld
        stored = stored + cols["E_building_stored"] + E_bld
        if stats.get("fixed_base"):  # the slab is the ground: the base shear is story 1's (docs/building.md)
            cols["base_shear_x"], cols["base_shear_y"] = cols["story_shear1_x"], cols["story_shear1_y"]
    cols["E_residual"] = E_in - (tab["kinetic"] + gravity + stored + E_sup_diss + E_dev + E_res)
    cols["u"] = np.hypot(x, y)
    cols = {k: np.array(v, dtype=float) for k, v in cols.items()}
    return RunResult("semirecursive", cols, units_of(cols), stats)


def _compiled_building_columns(Y, system, building, tab) -> dict:
    """The building's columns from the compiled run's states (the floors are free coordinates; the
    slab's motion and the ground's from the table)."""
    free = list(system.partition.free)
    nf = len(free)
    ix = BuildingIndex(system.m, building)
    pos = np.array([[free.index(i), free.index(j)] for i, j in zip(ix.fx, ix.fy)])
    g = np.array([tab["x_g"], tab["y_g"]])
    gv = np.array([tab["vx_g"], tab["vy_g"]])
    d = Y[:, pos].transpose(1, 2, 0) - g[None]
    v = Y[:, nf + pos].transpose(1, 2, 0) - gv[None]
    d0, v0 = np.array([tab["x"], tab["y"]]), np.array([tab["vx"], tab["vy"]])
    return building_columns(building, d, v, d0, v0)


def _restrainer_columns(cols: dict, r, absorbed) -> None:
    """The restrainer's columns from the sampled relative motion (the shared law) and its absorbed
    work (the integrated state): force, indentation, stored and dissipated energy; base shear += force."""
    fx, fy, F, delta, _ = restrainer_forces(cols["x"], cols["y"], cols["vx"], cols["vy"], r.gap, r.stiffness,
                                            r.exponent, r.damping)
    stored = np.array([restrainer_stored_scalar(d, r.stiffness, r.exponent) for d in delta])
    cols.update({"restrainer_Fx": fx, "restrainer_Fy": fy, "restrainer_F": F, "restrainer_indentation": delta,
                 "E_restrainer_stored": stored, "E_restrainer_dissipated": absorbed - stored})
    cols["base_shear_x"] = cols["base_shear_x"] + fx
    cols["base_shear_y"] = cols["base_shear_y"] + fy
