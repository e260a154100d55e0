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
from nsd_core.engine.integrate import SolverError, check_tolerances, integrate
from nsd_core.engine.elements import AxialElements
from nsd_core.engine.mechanism import Cut, Mechanism, mechanism
from nsd_core.engine.rk import METHODS
from nsd_core.device.outputs import device_columns
from nsd_core.device.params import ParameterError, Params
from nsd_core.device.results import RunResult
from nsd_core.engine.timing import warm_and_time
from nsd_core.engine.compiled_model import split_state
from nsd_core.engine.semirecursive import ConstraintError, SemiRecursiveSystem

BODY = {name: i for i, name in enumerate(
    ["plate_x", "plate_y", "plate", "cap", "base_x", "base_y", "base", "wall", "rod_x", "rod"])}
DRIVEN = [BODY["plate_x"], BODY["plate_y"], BODY["plate"]]
LOCKED = [BODY["base_x"], BODY["base_y"], BODY["base"]]
X, Y, Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)

MAX_WIRE_STRAIN = 0.2  # beyond it the SMA law (Eq. 17, fitted up to ~8 %) says nothing about a real wire

# DOP853, rtol 1e-7, atol 1e-12, max_step 1e-3 (measured, benchmarks/integrators.py, on the four
# Figure 6 cases against rtol 1e-10: max|dF|/max|F| <= 1e-5, aim 1e-4). Looser settings pass the
# smooth cases but not reliably the rope-slack ones (the laws' kinks make the error erratic:
# rtol 3e-6 gave 1.1e-4 on A = 25.5 mm, 10 Hz), rtol 1e-6 breaks the four-fold symmetry at 4e-6,
# and atol above 1e-12 lets round-off ring at rest. The step is limited by the stability of the
# lightly damped ~255 Hz vertical mode (h omega ~ 4.8 at 3 ms): a cap of 1e-3 s below that limit
# costs fewer right-hand sides than none (39k instead of 48k per two 1 Hz cycles: no rejected
# steps). max_step None: no limit.
# The default cases need at most ~1800 accepted steps per cycle (docs/performance.md); about 55x that is a runaway
MAX_STEPS_PER_CYCLE = 100_000
DEFAULT_SOLVER = {"method": "DOP853", "rtol": 1e-7, "atol": 1e-12, "max_step": 1e-3, "backend": "auto"}
BACKENDS = ("auto", "compiled", "scipy", "numpy")  # auto: compiled where it offers the method
COMPILED_METHODS = METHODS   # the compiled step loop's pairs (nsd_core.engine.rk)


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


def rest_state(system: SemiRecursiveSystem, g: DeviceGeometry, ws) -> tuple[np.ndarray, np.ndarray]:
    """The precompressed rest state every drive starts from (docs/model.md), assembled in ``ws``:
    the full configuration and the state y0 = [z_f, 0, wire stresses, spring zeta]."""
    z0 = rest_coordinates(g)
    z_rest = system.assemble(ws, 0.0, z0[system.partition.free]).copy()
    extra0 = np.concatenate([g.initial_wire_stress(), [g.spring_zeta0]])
    return z_rest, system.state(z_rest, np.zeros(len(z0)), extra0)


def device_system(params: Params, drive: Drive) -> tuple[SemiRecursiveSystem, DeviceGeometry]:
    g = device_geometry(params)
    mech = device_mechanism(g)

    def motion(t):  # the plate's X and Y follow the drive's path; its rotation and the base stay 0
        x, y, xd, yd, xdd, ydd = drive.plate_at(t)
        return (np.array([x, y, 0.0, 0.0, 0.0, 0.0]), np.array([xd, yd, 0.0, 0.0, 0.0, 0.0]),
                np.array([xdd, ydd, 0.0, 0.0, 0.0, 0.0]))

    system = SemiRecursiveSystem(mech, DRIVEN + LOCKED, motion, DeviceForces(g, mech.n),
                                 n_extra=g.n_wires + 1, prefer_free=[BODY["cap"]])
    system.choose_partition(rest_coordinates(g))
    return system, g


@warm_and_time("drive")  # compilation recorded apart, never in wall_time (docs/report.md, compile_time)
def simulate(params: Params, drive: Drive, method: str = DEFAULT_SOLVER["method"],
             rtol: float = DEFAULT_SOLVER["rtol"], atol: float = DEFAULT_SOLVER["atol"],
             max_step: float | None = DEFAULT_SOLVER["max_step"], progress=None,
             backend: str = DEFAULT_SOLVER["backend"]) -> RunResult:
    """Run the drive on the in-house semirecursive model; returns the common columns.

    backend "auto" (default): "compiled" for the methods it offers, else "scipy". "compiled": the
    compiled right-hand side and step loop (nsd_core.device.compiled; methods RK45, DOP853);
    "scipy": SemiRecursiveSystem (compiled kernels, the force laws through numpy) driven by scipy's
    solvers (any method of nsd_core.engine.integrate); "numpy": the same on the readable numpy
    specification of every step. Raises DriveError (|u| >= l_d), SolverError (integration failure).
    The initial state is the precompressed rest state (docs/model.md), an exact static equilibrium.
    """
    drive.check_followable(params)
    if backend not in BACKENDS:
        raise ParameterError(f"backend = {backend!r}: allowed {', '.join(BACKENDS)}")
    if backend == "auto":  # every path runs compiled (the motion callback is the Drive's plate_motion)
        backend = "compiled" if method in COMPILED_METHODS else "scipy"
    if backend == "compiled" and method not in COMPILED_METHODS:
        raise ParameterError(f"method = {method!r}: the compiled backend offers {', '.join(COMPILED_METHODS)}")
    step_cap = np.inf if max_step is None else max_step
    start = time.perf_counter()
    system, g = device_system(params, drive)
    system.fast = backend != "numpy"
    ws = system.workspace()
    z_rest, y0 = rest_state(system, g, ws)
    t_eval = drive.output_times()
    if backend == "compiled":
        return _simulate_compiled(system, g, drive, z_rest, y0, t_eval, method, rtol, atol, step_cap, start)
    rows = []

    def record(t, y):
        ev = system.evaluate(ws, t, y)
        lam = np.zeros(3)
        lam[system.partition.rows] = ev.lam
        cap_pos = ev.kin.r[BODY["cap"]]
        F = (float(ev.drive_force[0]), float(ev.drive_force[1]))  # the multipliers of the plate's X and Y
        check_validity(t, ev.kin, system.forces)
        extra = split_state(y, len(system.partition.free)).extra
        rows.append((t, cap_pos.copy(), ev.z[BODY["wall"]], extra[:g.n_wires].copy(), extra[g.n_wires],
                     float(np.max(np.abs(ev.Phi))), F, lam))

    try:
        traj = integrate(system, ws, y0, t_eval, method=method, rtol=rtol, atol=atol, max_step=step_cap,
                         min_pivot_ratio=0.0, progress=progress, outputs=record,
                         max_steps=MAX_STEPS_PER_CYCLE * drive.cycles)
    except ConstraintError as err:
        raise SolverError(str(err)) from None
    t, cap, wall, sig, zeta, clo, F, lam = (np.array(c) for c in zip(*rows))
    stats = {"engine": "semirecursive", "version": __version__, "method": method, "backend": backend, "rtol": rtol,
             "atol": atol, "max_step": max_step, "steps": traj.steps, "nfev": traj.nfev,
             "wall_time": time.perf_counter() - start, "tracking_error": 0.0,
             "closure_max": float(np.max(clo))}
    return device_columns("semirecursive", g, drive, t, cap, wall, sig.reshape(len(t), g.n_wires), zeta, clo,
                          drive_force=F, rod_force=lam, stats=stats)


def _check_lengths(t, lengths, forces: DeviceForces) -> None:
    """check_validity on recorded element lengths (samples, elements): the first bad sample raises."""
    g = forces.g
    bad = np.any(lengths <= 0.0, axis=1)
    if g.n_wires:
        strain = (lengths[:, forces.wires] - g.wire.natural_length) / g.wire.natural_length
        bad |= np.max(strain, axis=1) > MAX_WIRE_STRAIN
    if np.any(bad):
        k = int(np.argmax(bad))
        L = lengths[k]
        if np.any(L <= 0.0):
            err = DriveError(f"t = {t[k]:.6g} s: an element's length reached zero: outside the model's validity")
        else:
            err = DriveError(f"t = {t[k]:.6g} s: wire strain {np.max(strain[k]):.3g} beyond "
                             f"{MAX_WIRE_STRAIN}: outside the SMA law's validity")
        err.sample = k  # the first sample outside validity (the seismic mode keeps those before it)
        raise err


def _simulate_compiled(system, g, drive, z_rest, y0, t_eval, method, rtol, atol, max_step, start):
    check_tolerances(rtol, atol, max_step)  # the bounds of the scipy path, the same way
    from nsd_core.device.compiled import compiled_model, run
    from nsd_core.engine.codegen import evaluation_used, evaluator_for
    from nsd_core.engine.rk import TOO_MANY_STEPS
    model = compiled_model(system, g, drive, system.forces.elements)
    used = evaluation_used(model)   # decided once: the run and its stats name the same evaluation
    out, (steps, nfev, status, n_done) = run(model, z_rest, y0, t_eval, method, rtol, atol, max_step,
                                             MAX_STEPS_PER_CYCLE * drive.cycles, evaluator_for(model, used))
    _check_lengths(t_eval[:n_done], out.lengths[:n_done], system.forces)
    if status == TOO_MANY_STEPS:
        raise SolverError(f"exceeded {MAX_STEPS_PER_CYCLE * drive.cycles} steps at t = "
                          f"{t_eval[min(n_done, len(t_eval) - 1)]:.6g} s of {t_eval[-1]:.6g} s: "
                          "a stiff or runaway input")
    if status != 0:
        raise SolverError(f"{method} (compiled) failed at t = {t_eval[min(n_done, len(t_eval) - 1)]:.6g} s "
                          f"or before: status {status} (nsd_core.engine.compiled, nsd_core.engine.rk)")
    parts = split_state(out.y, len(system.partition.free))
    lam = np.zeros((len(t_eval), 3))
    lam[:, system.partition.rows] = out.lam
    F = out.tau[:, :2]  # the multipliers of the plate's X and Y: the force vector
    stats = {"engine": "semirecursive", "version": __version__, "method": method, "backend": "compiled",
             "evaluation": used,
             "rtol": rtol, "atol": atol, "max_step": None if max_step == np.inf else max_step,
             "steps": int(steps), "nfev": int(nfev),
             "wall_time": time.perf_counter() - start, "tracking_error": 0.0,
             "closure_max": float(np.max(out.closure))}
    return device_columns("semirecursive", g, drive, t_eval, out.r[:, BODY["cap"]], out.z[:, BODY["wall"]],
                          parts.extra[:, :g.n_wires], parts.extra[:, g.n_wires], out.closure,
                          drive_force=F, rod_force=lam, stats=stats)
