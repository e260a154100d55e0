"""The seismic mode on the in-house engine: Table 1, second row (docs/model.md, "Seismic mode").

The same Figure 4 tree as the drive mode (``nsd_core.device.model``); only the choice of prescribed
and free coordinates changes, so the generic engine needs no special case:
    prescribed: the base's planar joint (base_x, base_y, base) follows the ground x_g, y_g, rotation 0;
    free: the plate's X, Y and rotation (plate_x, plate_y, plate) and the cap's height (cap);
    dependent: the wall's height and the rod's two angles (the cut spherical joint, Eq. 13).
The plate carries the isolated mass M (polar inertia M r_g^2); the supports act between plate and
base as joint forces on the plate's coordinates: -k_b u - c_b u' in X and Y (u relative to the
base) and -k_b r_b^2 theta - c_b r_b^2 theta' about Z. With ``device=False`` the tree is the plate
and the base alone: the supports-alone structure of the same input (the isolation effect's
reference and a closed-form check).

Energy balance in the frame that translates with the ground, where every body feels -m a_g:
    E_input = -int a_g . P_rel dt = E_kinetic(rel) + E_gravity + E_supports_stored
              + E_supports_dissipated + E_device,
with P_rel the bodies' horizontal momentum relative to the base and E_device = int sum T dL/dt the
work absorbed by ropes, wires and spring (stored and dissipated). E_input, E_device,
E_supports_dissipated and E_restrainer (the work the displacement restrainer absorbs, stored +
dissipated; nsd_core.structure.restrainer) are integrated with the motion (four extra states), so the
residual measures the mechanics, not an output quadrature.

Output times: ``output_times`` (every engine's): n = ceil(duration / dt_out) equal intervals, so the
last sample lands on the window's end and the interval is at most dt_out. A run stopped by the
device's failure (RodReachError, DriveError; exit 4) carries what it computed up to the event as
``error.partial`` (a RunResult) and the event's time as ``error.t_event``.
"""
from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from nsd_core import __version__
from nsd_core.device.drive import DriveError
from nsd_core.device.forces import restrainer_force_scalar, restrainer_stored_scalar, rope_tension, wire_tension
from nsd_core.device.geometry import device_geometry
from nsd_core.structure.building import building_columns, building_dissipation_rate
from nsd_core.device.columns import units_of
from nsd_core.structure.building_tree import BuildingIndex, floor_names, with_floors
from nsd_core.ground.motions import GroundMotion
from nsd_core.structure.isolation import Structure
from nsd_core.structure.isolator_laws import hysteretic_force_scalar
from nsd_core.device.model import (BODY, COMPILED_METHODS, DEFAULT_SOLVER, DeviceForces, check_validity,
                                   device_mechanism, rest_coordinates)
from nsd_core.device.params import ParameterError, Params
from nsd_core.device.results import RunResult
from nsd_core.engine.timing import warm_and_time
from nsd_core.structure.seismic_summary import peaks_at_last_sample, seismic_summary  # noqa: F401 (this module's API)
from nsd_core.engine.integrate import SolverError, integrate
from nsd_core.engine.kinematics import cross_rows
from nsd_core.engine.mechanism import mechanism
from nsd_core.engine.semirecursive import ConstraintError, SemiRecursiveSystem
from nsd_core.structure.seismic_compiled_run import N_ENERGY, _simulate_compiled, _with_partial

GROUND_DRIVEN = ["base_x", "base_y", "base"]
FREE = ["plate_x", "plate_y", "plate", "cap"]
FIXED_BASE = ["plate_x", "plate_y", "plate"]  # prescribed too in a fixed-base run: the slab follows the ground


def output_times(duration: float, dt_out: float) -> np.ndarray:
    """The output times of a seismic run in every engine: n = ceil(duration / dt_out) equal intervals
    from 0 to ``duration`` (the last sample lands on the end; the interval is duration / n <= dt_out)."""
    n = max(1, math.ceil(duration / dt_out * (1.0 - 1e-12)))
    return np.linspace(0.0, duration, n + 1)


class RodReachError(DriveError):
    """|u| >= l_d: the rod cannot reach across the relative displacement (exit code 4)."""


def _plate_body(structure: Structure) -> dict:
    J = structure.polar_inertia
    return dict(mass=structure.mass, com=(0.0, 0.0, 0.0), inertia=(J / 2.0, J / 2.0, J))  # a thin slab


def seismic_mechanism(params: Params, structure: Structure, device: bool = True):
    """The Figure 4 tree with the isolated mass on the plate (device=False: plate and base alone),
    and the structure's building's floors (nsd_core.structure.building_tree) when it has one."""
    mech, g = _slab_mechanism(params, structure, device)
    if structure.building is not None:
        mech = with_floors(mech, structure.building)
    return mech, g


def _slab_mechanism(params: Params, structure: Structure, device: bool):
    g = device_geometry(params)
    if device:
        mech = device_mechanism(g)
        plate = BODY["plate"]
        mass, com, inertia = mech.mass.copy(), mech.com.copy(), mech.inertia.copy()
        body = _plate_body(structure)
        mass[plate], com[plate], inertia[plate] = body["mass"], body["com"], np.diag(body["inertia"])
        return dataclasses.replace(mech, mass=mass, com=com, inertia=inertia), g
    X, Y, Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
    bodies = [dict(name="plate_x", parent=None, joint="P", axis=X),
              dict(name="plate_y", parent="plate_x", joint="P", axis=Y),
              dict(name="plate", parent="plate_y", joint="R", axis=Z, **_plate_body(structure)),
              dict(name="base_x", parent=None, joint="P", axis=X),
              dict(name="base_y", parent="base_x", joint="P", axis=Y),
              dict(name="base", parent="base_y", joint="R", axis=Z, mass=g.base.mass, inertia=g.base.inertia)]
    return mechanism(bodies, [], gravity=g.gravity_vector), g


class SeismicForces:
    """The device's elements (shared laws, via DeviceForces) plus the supports and energy rates."""

    def __init__(self, mech, g, structure: Structure, device: bool, ground_cache: dict):
        self.m, self.g, self.s = mech, g, structure
        self.ix = {n: mech.names.index(n) for n in FREE[:3] + GROUND_DRIVEN}
        self.device = DeviceForces(g, mech.n) if device else None
        self.n_dev = (g.n_wires + 1) if device else 0
        self.ground = ground_cache
        self.massive = np.flatnonzero(mech.mass > 0)
        self.building = BuildingIndex(mech, structure.building) if structure.building is not None else None
        # a baseline isolator (runs without the device): its hysteretic state z (2 extra states, after the device's)
        self.iso = structure.isolator if not device else None
        self.n_iso = 2 if self.iso is not None else 0

    def relative(self, z, zd):
        """Plate relative to base: (u (2,), u' (2,), theta, theta')."""
        i = self.ix
        u = np.array([z[i["plate_x"]] - z[i["base_x"]], z[i["plate_y"]] - z[i["base_y"]]])
        ud = np.array([zd[i["plate_x"]] - zd[i["base_x"]], zd[i["plate_y"]] - zd[i["base_y"]]])
        return u, ud, z[i["plate"]] - z[i["base"]], zd[i["plate"]] - zd[i["base"]]

    def relative_momentum(self, kin, v_g):
        """Horizontal momentum of all bodies relative to the ground frame."""
        b = self.massive
        com = kin.r[b] + np.einsum("kij,kj->ki", kin.A[b], self.m.com[b])
        v = kin.Z[b, :3] + cross_rows(kin.Z[b, 3:], com)
        return self.m.mass[b] @ v[:, :2] - self.m.mass[b].sum() * v_g[:2]

    def __call__(self, t, kin, z, zd, extra):
        n, s, i = self.m.n, self.s, self.ix
        if self.device is not None:
            wrench, _, dev_rates = self.device(t, kin, z, zd, extra[:self.n_dev])
            # elements are internal (no end on the ground): their power on the bodies is frame-free
            absorbed = -float(np.sum(wrench * kin.Z))
        else:
            wrench, dev_rates, absorbed = np.zeros((n, 6)), np.zeros(0), 0.0
        u, ud, th, thd = self.relative(z, zd)
        kt = s.stiffness * s.support_radius ** 2
        ct = s.damping * s.support_radius ** 2
        gen = np.zeros(n)
        gen[i["plate_x"]], gen[i["plate_y"]] = -s.stiffness * u - s.damping * ud
        gen[i["plate"]] = -kt * th - ct * thd
        e_sup = s.damping * float(ud @ ud) + ct * thd * thd
        iso_rates = np.zeros(self.n_iso)
        if self.iso is not None:  # the baseline isolator's hysteretic part (nsd_core.structure.isolator_laws)
            zx, zy = extra[self.n_dev], extra[self.n_dev + 1]
            fx, fy, iso_rates[0], iso_rates[1], power = hysteretic_force_scalar(ud[0], ud[1], zx, zy,
                                                                                *self.iso.block())
            gen[i["plate_x"]] -= fx
            gen[i["plate_y"]] -= fy
            e_sup += power  # its work counts with the supports' dissipation (its stored part is < Q D_y)
        e_res = 0.0
        if s.restrainer is not None:  # the plate pushes the restrainer with (F_x, F_y); it pushes back
            r = s.restrainer
            fx, fy, F, _, rate = restrainer_force_scalar(u[0], u[1], ud[0], ud[1], r.gap, r.stiffness, r.exponent,
                                                         r.damping)
            gen[i["plate_x"]] -= fx
            gen[i["plate_y"]] -= fy
            e_res = F * rate
        e_bld = 0.0
        if self.building is not None:
            self.building.add_forces(gen, z, zd)
            _, v, _, v0 = self.building.motion(z, zd)
            e_bld = building_dissipation_rate(self.building.b, v, v0)
        _, v_g, a_g = self.ground["now"]
        e_in = -float(a_g[:2] @ self.relative_momentum(kin, v_g))
        return wrench, gen, np.concatenate([dev_rates, iso_rates, [e_in, absorbed, e_sup, e_res, e_bld]])


class SeismicSystem(SemiRecursiveSystem):
    """The generic system, stopping with RodReachError where |u| >= l_d (the rod lies flat)."""
    reach = math.inf
    last = (0.0, 0.0)  # (t, |u|) of the last evaluation

    def rhs_parts(self, ws, t, zf, zfd, extra):
        q = self.motion(t)[0]
        u = math.hypot(zf[0] - q[0], zf[1] - q[1])
        self.last = (t, u)
        if u >= self.reach:
            raise self.reach_error()
        return super().rhs_parts(ws, t, zf, zfd, extra)

    def reach_error(self) -> RodReachError:
        t, u = self.last
        return RodReachError(f"t = {t:.6g} s: |u| = {u:.6g} m >= rod_length = {self.reach} m: the rod cannot "
                             f"reach" if u >= self.reach else f"t = {t:.6g} s: |u| = {u:.6g} m: the loop cannot "
                             f"close as the rod nears the horizontal (rod_length = {self.reach} m): the rod cannot reach")


def _rest(g, mech, device: bool) -> np.ndarray:
    """The rest configuration: the device's (or zeros), the floors (appended) at zero."""
    z = np.zeros(mech.n)
    if device:
        rest = rest_coordinates(g)
        z[:len(rest)] = rest
    return z


def seismic_system(params: Params, structure: Structure, ground: GroundMotion, device: bool = True,
                   fixed_base: bool = False):
    """(system, geometry, forces) for the seismic mode. fixed_base (without the device): the plate
    (the slab) is prescribed to follow the ground too."""
    if fixed_base and device:
        raise ParameterError("fixed base: the slab is held to the ground, so the run has no device")
    mech, g = seismic_mechanism(params, structure, device)
    cache = {}
    copies = 2 if fixed_base else 1

    def motion(t):
        if cache.get("t") == t:  # the reach check and the engine ask for the same t in turn
            return cache["now"]
        d, v, a = ground(t)
        q = (np.array([d[0], d[1], 0.0]), np.array([v[0], v[1], 0.0]), np.array([a[0], a[1], 0.0]))
        cache["t"], cache["now"] = t, q
        if copies == 2:
            cache["now"] = tuple(np.concatenate([x, x]) for x in q)
            cache["now_ground"] = q
        return cache["now"]

    forces = SeismicForces(mech, g, structure, device, cache)
    driven = GROUND_DRIVEN + (FIXED_BASE if fixed_base else [])
    prescribed = [mech.names.index(n) for n in driven]
    free = [mech.names.index(n) for n in FREE if n in mech.names and n not in driven]
    if structure.building is not None:
        free += [mech.names.index(n) for n in floor_names(structure.building.stories)]
    system = SeismicSystem(mech, prescribed, motion, forces, n_extra=forces.n_dev + forces.n_iso + N_ENERGY,
                           prefer_free=free)
    if device:
        system.reach = params.rod_length
    z0 = _rest(g, mech, device)
    system.choose_partition(z0)
    if sorted(system.partition.free) != sorted(free):
        raise SolverError(f"seismic partition: free {system.partition.free}, expected {free}")  # pragma: no cover
    return system, g, forces


def _kinetic_and_height(mech, kin, v_g):
    """Kinetic energy relative to the ground frame and sum(m g z_com) of the massive bodies."""
    b = np.flatnonzero(mech.mass > 0)
    A = kin.A[b]
    com = kin.r[b] + np.einsum("kij,kj->ki", A, mech.com[b])
    w = kin.Z[b, 3:]
    v = kin.Z[b, :3] + cross_rows(w, com)
    v[:, :2] -= v_g[None, :2]
    Jw = np.einsum("kij,kjl,kml,km->ki", A, mech.inertia[b], A, w)  # (A J A^T) w
    kinetic = 0.5 * float(np.sum(mech.mass[b] * np.sum(v * v, axis=1)) + np.sum(w * Jw))
    return kinetic, float(np.sum(mech.mass[b] * com[:, 2])) * -mech.gravity[2]


def _sample_row(system, ws, forces, structure, g, device, fixed_base, height0, t, y) -> dict:
    """One output sample of the scipy path: the ground, the plate's relative motion, the forces and the energy
    balance (height0: the first sample's potential energy, set by the first call)."""
    ev = system.evaluate(ws, t, y)
    d_g, v_g, a_g = forces.ground["now"]
    u, ud, th, thd = forces.relative(ev.z, ev.zd)
    s, ix = structure, forces.ix
    row = {"t": t, "x_g": d_g[0], "y_g": d_g[1], "ax_g": a_g[0], "ay_g": a_g[1], "x": u[0], "y": u[1],
           "theta": th, "vx": ud[0], "vy": ud[1], "ax_abs": ev.zdd[ix["plate_x"]], "ay_abs": ev.zdd[ix["plate_y"]],
           "support_Fx": s.stiffness * u[0] + s.damping * ud[0], "support_Fy": s.stiffness * u[1] + s.damping * ud[1],
           "support_torque": s.support_radius ** 2 * (s.stiffness * th + s.damping * thd)}
    if forces.iso is not None:
        fx, fy, _, _, _ = hysteretic_force_scalar(ud[0], ud[1], y[-N_ENERGY - 2], y[-N_ENERGY - 1], *forces.iso.block())
        row["support_Fx"] += fx
        row["support_Fy"] += fy
        row["isolator_zx"], row["isolator_zy"] = y[-N_ENERGY - 2], y[-N_ENERGY - 1]
    E_in, E_dev, E_sup_diss, E_res, E_bld = y[-N_ENERGY:]
    kinetic, height = _kinetic_and_height(system.m, ev.kin, v_g)
    if not height0:
        height0.append(height)
    if device:
        try:
            _device_outputs(row, ev, y, g, forces, system)
        except DriveError as err:
            err.t_event = float(t)
            raise
    else:
        row["device_Fx"] = row["device_Fy"] = 0.0
    row["base_shear_x"] = row["support_Fx"] + row["device_Fx"]
    row["base_shear_y"] = row["support_Fy"] + row["device_Fy"]
    stored = 0.5 * s.stiffness * float(u @ u) + 0.5 * s.stiffness * s.support_radius ** 2 * th * th
    row.update({"E_input": E_in, "E_kinetic": kinetic, "E_gravity": height - height0[0],
                "E_supports_stored": stored, "E_supports_dissipated": E_sup_diss, "E_device": E_dev})
    res_stored = 0.0
    if s.restrainer is not None:
        r = s.restrainer
        fx, fy, F, delta, _ = restrainer_force_scalar(u[0], u[1], ud[0], ud[1], r.gap, r.stiffness, r.exponent,
                                                      r.damping)
        res_stored = restrainer_stored_scalar(delta, r.stiffness, r.exponent)
        row.update({"restrainer_Fx": fx, "restrainer_Fy": fy, "restrainer_F": F, "restrainer_indentation": delta,
                    "E_restrainer_stored": res_stored, "E_restrainer_dissipated": E_res - res_stored})
        row["base_shear_x"] += fx
        row["base_shear_y"] += fy
    if forces.building is not None:
        d, v, d0, v0 = forces.building.motion(ev.z, ev.zd)
        cols = building_columns(structure.building, d[:, :, None], v[:, :, None], d0[:, None], v0[:, None])
        row.update({k: float(val[0]) for k, val in cols.items()})
        row["E_building_dissipated"] = E_bld
        stored += row["E_building_stored"] + E_bld
        if fixed_base:  # the slab is the ground: the base shear is story 1's (docs/building.md)
            row["base_shear_x"], row["base_shear_y"] = row["story_shear1_x"], row["story_shear1_y"]
    row["E_residual"] = E_in - (kinetic + row["E_gravity"] + stored + E_sup_diss + E_dev + E_res)
    return row


@warm_and_time("seismic")  # compilation recorded apart, never in wall_time (docs/report.md, compile_time)
def simulate_seismic(params: Params, structure: Structure, ground: GroundMotion, duration: float | None = None,
                     dt_out: float = 1e-3, device: bool = True, method: str = DEFAULT_SOLVER["method"],
                     rtol: float = DEFAULT_SOLVER["rtol"], atol: float = DEFAULT_SOLVER["atol"],
                     max_step: float = DEFAULT_SOLVER["max_step"], progress=None,
                     backend: str = DEFAULT_SOLVER["backend"], fixed_base: bool = False) -> RunResult:
    """The seismic response from relative rest at t = 0, sampled every ``dt_out`` up to ``duration``
    (default: the ground motion's; longer: free vibration after it). Raises RodReachError (exit 4),
    DriveError (outside the laws' validity), SolverError (exit 3). backend: "compiled" the compiled
    right-hand side and step loop (nsd_core.structure.compiled_seismic; methods RK45, DOP853); "auto"
    (default) that for the methods it offers, else "scipy": SemiRecursiveSystem under scipy's
    solvers; "numpy" the same on the numpy specification. The compiled path restarts its step loop
    every compiled_seismic.CHUNK model seconds (progress, Ctrl-C), so it follows scipy's path step for
    step over the first chunk and within the tolerance after. fixed_base (device=False): the slab
    follows the ground (the building's fixed-base reference; nsd_core.structure.building)."""
    if backend not in ("auto", "compiled", "scipy", "numpy"):
        raise ParameterError(f"backend = {backend!r}: the seismic mode offers auto, compiled, scipy, numpy")
    if backend == "auto":
        backend = "compiled" if method in COMPILED_METHODS else "scipy"
    if backend == "compiled" and method not in COMPILED_METHODS:
        raise ParameterError(f"method = {method!r}: the compiled backend offers {', '.join(COMPILED_METHODS)}")
    duration = ground.duration if duration is None else float(duration)
    if not (math.isfinite(duration) and duration > 0):
        raise ParameterError(f"duration = {duration!r}: must be > 0 s")
    if not (math.isfinite(dt_out) and 0 < dt_out <= duration):
        raise ParameterError(f"dt_out = {dt_out!r}: must be in (0, duration]")
    start = time.perf_counter()
    if not device:  # a baseline isolator's linear part takes the supports' place (nsd_core.structure.isolators)
        structure = structure.on_isolator()
    system, g, forces = seismic_system(params, structure, ground, device, fixed_base)
    system.fast = backend != "numpy"
    mech = system.m
    z0 = _rest(g, mech, device)
    extra0 = np.concatenate([g.initial_wire_stress(), [g.spring_zeta0]]) if device else np.zeros(0)
    ws = system.workspace()
    y0 = system.state(system.assemble(ws, 0.0, z0[system.partition.free]).copy(), np.zeros(mech.n),
                      np.concatenate([extra0, np.zeros(forces.n_iso + N_ENERGY)]))
    t_eval = output_times(duration, dt_out)
    first_step = min(max_step, 1e-4, duration)  # the ground moves: start small
    if backend == "compiled":
        return _simulate_compiled(system, g, structure, ground, device, y0, t_eval, method, rtol, atol, max_step,
                                  first_step, progress, start, fixed_base)
    return _simulate_scipy(system, ws, backend, g, structure, ground, device, y0, t_eval, method, rtol, atol, max_step,
                           first_step, progress, start, fixed_base)


def _simulate_scipy(system, ws, backend, g, structure, ground, device, y0, t_eval, method, rtol, atol, max_step,
                    first_step, progress, start, fixed_base) -> RunResult:
    """The seismic run under scipy's solvers (backend "scipy" or "numpy"): one row per output time."""
    rows, height0 = [], []

    def record(t, y):
        rows.append(_sample_row(system, ws, system.forces, structure, g, device, fixed_base, height0, t, y))

    def stats(steps, nfev):
        return {"engine": "semirecursive", "mode": "seismic", "device": device, "fixed_base": fixed_base,
                "version": __version__, "backend": backend, "method": method, "rtol": rtol, "atol": atol, "max_step": max_step,
                "steps": steps, "nfev": nfev, "wall_time": time.perf_counter() - start,
                "model_time": float(t_eval[-1]), "dt_out": float(t_eval[1] - t_eval[0]),
                "ground": ground.describe(), "structure": structure.to_dict()}

    def result(st):
        cols = {k: np.array([r[k] for r in rows]) for k in rows[0]}
        cols["u"] = np.hypot(cols["x"], cols["y"])  # radial relative displacement (events use it)
        return RunResult("semirecursive", cols, units_of(cols), st)

    try:
        try:
            traj = integrate(system, ws, y0, t_eval, method=method, rtol=rtol, atol=atol, max_step=max_step,
                             min_pivot_ratio=0.0, progress=progress, outputs=record, first_step=first_step)
        except ConstraintError as err:
            if system.last[1] > 0.95 * system.reach:
                raise system.reach_error() from None
            raise SolverError(str(err)) from None
    except DriveError as err:
        # rows holds every sample recorded before the event (a sample outside validity raised in record)
        raise _with_partial(err, result(stats(None, None)) if rows else None,
                            getattr(err, "t_event", system.last[0])) from None
    return result(stats(traj.steps, traj.nfev))


def _device_outputs(row, ev, y, g, forces, system):
    """Element forces, device_F, cap and wall heights. device_F has the drive mode's sign: the force
    the plate applies to the device, -(rod + ropes + wires on the cap), horizontal; the device's
    force on the plate is its negative."""
    dev = forces.device
    check_validity(row["t"], ev.kin, dev)
    L, _ = dev.elements.state(ev.kin)
    N = dev.elements.N
    nw = g.n_wires
    sigma = y[-N_ENERGY - nw - 1:-N_ENERGY - 1]
    zeta = y[-N_ENERGY - 1]
    t_rope = rope_tension(L[dev.ropes], g.rope_natural_length, g.rope_stiffness)
    t_wire = wire_tension(sigma, g.wire)
    lam = np.zeros(3)
    lam[system.partition.rows] = ev.lam  # the rod's force on the cap (the cut's multiplier)
    on_cap = lam - (t_rope[:, None] * N[dev.ropes]).sum(0) - (t_wire[:, None] * N[dev.wires]).sum(0)
    row["device_Fx"], row["device_Fy"] = -on_cap[0], -on_cap[1]
    x_s = g.spring.free_length - ev.z[BODY["wall"]]
    row.update({"cap_z": ev.kin.r[BODY["cap"]][2], "wall_z": ev.z[BODY["wall"]],
                "spring_push": max(g.spring.kse * x_s + zeta, 0.0), "spring_zeta": zeta,
                "closure": float(np.max(np.abs(ev.Phi)))})
    strain = (L[dev.wires] - g.wire.natural_length) / g.wire.natural_length
    for i, T in enumerate(t_rope):
        row[f"rope{i}_tension"] = T
    for j in range(nw):
        row[f"wire{j}_tension"], row[f"wire{j}_strain"], row[f"wire{j}_stress"] = t_wire[j], strain[j], sigma[j]
