"""The NSD on the generic semirecursive engine: the paper's Figure 4 tree, cap-rod spherical joint cut.

Tree (parent first; massless auxiliary bodies carry multi-DOF joints, as in the paper):
    ground -> plate_x (P, X) -> plate_y (P, Y) -> plate (R, Z) -> cap (P, Z)
    ground -> base_x (P, X) -> base_y (P, Y) -> base (R, Z) -> wall (P, Z) -> rod_x (R, X) -> rod (R, Y)
The cap's reference is the rod's upper joint centre, so the cut spherical joint is the point
constraint cap(0, 0, 0) = rod(0, 0, l_d) (Eq. 13). Parametric drive mode (Table 1, first row): the
plate's X, Y and rotation are driven, the base's planar joint is locked, the cap's height is the
free coordinate and the rod's angles and the wall's height are dependent.
"""
from __future__ import annotations

import time

import numpy as np

from nsd_core import __version__
from nsd_core.device.drive import Drive, DriveError
from nsd_core.device.forces import rope_tension, sma_wire, spring_push
from nsd_core.device.geometry import DeviceGeometry, device_geometry
from nsd_core.engine.integrate import SolverError, integrate
from nsd_core.engine.elements import AxialElements
from nsd_core.engine.mechanism import Cut, Mechanism, mechanism
from nsd_core.device.outputs import device_columns
from nsd_core.device.params import Params
from nsd_core.device.results import RunResult
from nsd_core.engine.semirecursive import ConstraintError, SemiRecursiveSystem

BODY = {name: i for i, name in enumerate(
    ["plate_x", "plate_y", "plate", "cap", "base_x", "base_y", "base", "wall", "rod_x", "rod"])}
DRIVEN = [BODY["plate_x"], BODY["plate_y"], BODY["plate"]]
LOCKED = [BODY["base_x"], BODY["base_y"], BODY["base"]]
X, Y, Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)

MAX_WIRE_STRAIN = 0.2  # beyond it the SMA law (Eq. 17, fitted up to ~8 %) says nothing about a real wire

# The default cases need at most ~1800 accepted steps per cycle (README); about 55x that is a runaway
MAX_STEPS_PER_CYCLE = 100_000
DEFAULT_SOLVER = {"method": "DOP853", "rtol": 1e-7, "atol": 1e-12, "max_step": 1e-3}


def device_mechanism(g: DeviceGeometry) -> Mechanism:
    """The Figure 4 tree as data, from the engine-independent geometry."""
    p = g.params
    bodies = [
        dict(name="plate_x", parent=None, joint="P", axis=X),
        dict(name="plate_y", parent="plate_x", joint="P", axis=Y),
        dict(name="plate", parent="plate_y", joint="R", axis=Z),
        dict(name="cap", parent="plate", joint="P", axis=Z, mass=g.cap.mass, com=g.cap.com, inertia=g.cap.inertia),
        dict(name="base_x", parent=None, joint="P", axis=X),
        dict(name="base_y", parent="base_x", joint="P", axis=Y),
        dict(name="base", parent="base_y", joint="R", axis=Z, mass=g.base.mass, com=g.base.com,
             inertia=g.base.inertia),
        dict(name="wall", parent="base", joint="P", axis=Z, mass=g.wall.mass, com=g.wall.com,
             inertia=g.wall.inertia),
        dict(name="rod_x", parent="wall", joint="R", axis=X),
        dict(name="rod", parent="rod_x", joint="R", axis=Y, mass=g.rod.mass, com=g.rod.com, inertia=g.rod.inertia),
    ]
    cut = Cut("point", "cap", (0.0, 0.0, 0.0), "rod", (0.0, 0.0, p.rod_length), name="cap-rod spherical")
    return mechanism(bodies, [cut], gravity=g.gravity_vector)


def rest_coordinates(g: DeviceGeometry) -> np.ndarray:
    z = np.zeros(len(BODY))
    z[BODY["cap"]] = g.cap_rest_z
    z[BODY["wall"]] = g.wall_rest_z
    return z


class DeviceForces:
    """Ropes, wires and spring as two-point axial elements on the tree (the shared force laws)."""

    def __init__(self, g: DeviceGeometry, n_bodies: int):
        self.g = g
        nr, nw = g.n_ropes, g.n_wires
        cap, base, wall = BODY["cap"], BODY["base"], BODY["wall"]
        self.ropes, self.wires, self.spring = slice(0, nr), slice(nr, nr + nw), nr + nw
        self.elements = AxialElements(
            body_up=[cap] * nr + [cap] * nw + [wall],
            pts_up=np.vstack([g.rope_cap_points, g.wire_cap_points, np.zeros((1, 3))]),
            body_lo=[base] * nr + [wall] * nw + [base],
            pts_lo=np.vstack([g.rope_base_points, g.wire_wall_points, np.zeros((1, 3))]),
            n_bodies=n_bodies)

    def __call__(self, t, kin, z, zd, extra):
        g, nw = self.g, self.g.n_wires
        L, Ld = self.elements.state(kin)
        T = np.empty(len(L))
        T[self.ropes] = rope_tension(L[self.ropes], g.rope_natural_length, g.rope_stiffness)
        T[self.wires], sigma_rate = sma_wire(L[self.wires], Ld[self.wires], extra[:nw], g.wire)
        push, zeta_rate, _ = spring_push(L[self.spring], Ld[self.spring], extra[nw], g.spring)
        T[self.spring] = -push  # the spring pushes its ends apart
        rates = np.empty(nw + 1)
        rates[:nw] = sigma_rate
        rates[nw] = zeta_rate
        return self.elements.wrench(T), None, rates


def check_validity(t: float, kin, forces: DeviceForces) -> None:
    """Stop, with a message, where the device leaves the force laws' validity (never NaNs)."""
    L, _ = forces.elements.state(kin)
    g = forces.g
    if np.any(L <= 0.0):
        raise DriveError(f"t = {t:.6g} s: an element's length reached zero: outside the model's validity")
    if g.n_wires:
        strain = (L[forces.wires] - g.wire.natural_length) / g.wire.natural_length
        if np.max(strain) > MAX_WIRE_STRAIN:  # a shortened wire is merely slack
            raise DriveError(f"t = {t:.6g} s: wire strain {np.max(strain):.3g} beyond "
                             f"{MAX_WIRE_STRAIN}: outside the SMA law's validity")


def device_system(params: Params, drive: Drive) -> tuple[SemiRecursiveSystem, DeviceGeometry]:
    g = device_geometry(params)
    mech = device_mechanism(g)
    e = drive.unit_vector

    def motion(t):
        u, ud, udd = drive.displacement(t)
        return (np.array([u * e[0], u * e[1], 0.0, 0.0, 0.0, 0.0]),
                np.array([ud * e[0], ud * e[1], 0.0, 0.0, 0.0, 0.0]),
                np.array([udd * e[0], udd * e[1], 0.0, 0.0, 0.0, 0.0]))

    system = SemiRecursiveSystem(mech, DRIVEN + LOCKED, motion, DeviceForces(g, mech.n),
                                 n_extra=g.n_wires + 1, prefer_free=[BODY["cap"]])
    system.choose_partition(rest_coordinates(g))
    return system, g


def simulate(params: Params, drive: Drive, method: str = DEFAULT_SOLVER["method"],
             rtol: float = DEFAULT_SOLVER["rtol"], atol: float = DEFAULT_SOLVER["atol"],
             max_step: float = DEFAULT_SOLVER["max_step"], progress=None) -> RunResult:
    """Run the drive on the in-house semirecursive model; returns the common columns.

    Raises DriveError (|u| >= l_d), SolverError (integration failure). The initial state is the
    precompressed rest state (docs/model.md), an exact static equilibrium.
    """
    drive.check_followable(params)
    start = time.perf_counter()
    system, g = device_system(params, drive)
    z0 = rest_coordinates(g)
    extra0 = np.concatenate([g.initial_wire_stress(), [g.spring_zeta0]])
    y0 = system.state(system.assemble(0.0, z0[system.partition.free]), np.zeros(len(z0)), extra0)
    t_eval = drive.output_times()
    rows = []

    def record(t, y):
        ev = system.evaluate(t, y)
        lam = np.zeros(3)
        lam[system.partition.rows] = ev.lam
        cap_pos = ev.kin.r[BODY["cap"]]
        e = drive.unit_vector
        F = ev.drive_force[0] * e[0] + ev.drive_force[1] * e[1]
        check_validity(t, ev.kin, system.forces)
        rows.append((t, cap_pos.copy(), ev.z[BODY["wall"]], y[-g.n_wires - 1:-1].copy(), y[-1],
                     float(np.max(np.abs(ev.Phi))), F, lam))

    try:
        traj = integrate(system, y0, t_eval, method=method, rtol=rtol, atol=atol, max_step=max_step,
                         min_pivot_ratio=0.0, progress=progress, outputs=record,
                         max_steps=MAX_STEPS_PER_CYCLE * drive.cycles)
    except ConstraintError as err:
        raise SolverError(str(err)) from None
    t, cap, wall, sig, zeta, clo, F, lam = (np.array(c) for c in zip(*rows))
    stats = {"engine": "semirecursive", "version": __version__, "method": method, "rtol": rtol,
             "atol": atol, "max_step": max_step, "steps": traj.steps, "nfev": traj.nfev,
             "wall_time": time.perf_counter() - start, "tracking_error": 0.0,
             "closure_max": float(np.max(clo))}
    return device_columns("semirecursive", g, drive, t, cap, wall, sig.reshape(len(t), g.n_wires), zeta, clo,
                          drive_force=F, rod_force=lam, stats=stats)
