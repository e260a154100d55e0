"""Turn an engine's raw trajectory into the common columns (one home for the output definitions).

An engine supplies, per output time: the cap position, the wall height, the hysteretic states, the
loop-closure violation and its own measure of the drive force and/or the rod's force on the cap.
Everything else (rope and wire tensions, their components along psi, the force vector and its projections on
the path's tangent and radial directions, the spring push) is computed
here from the shared force laws, so that the columns mean the same in every engine.
"""
from __future__ import annotations

import numpy as np

from nsd_core.device.drive import Drive
from nsd_core.device.forces import rope_tension, wire_tension
from nsd_core.device.geometry import DeviceGeometry
from nsd_core.device.results import RunResult, column_units


def path_directions(pos: np.ndarray, vel: np.ndarray, acc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit tangent and radial directions (n, 2) of the plate's path.

    Tangent: v/|v|; where the plate stops (|v| below 1e-9 of its largest speed: the start from rest,
    a line's turning points) the acceleration's direction, the way the motion goes on from there.
    Radial: p/|p| from the centre; at the centre itself the tangent.
    """
    speed = np.linalg.norm(vel, axis=1)
    acc_n = np.linalg.norm(acc, axis=1)
    stopped = speed <= 1e-9 * max(float(np.max(speed, initial=0.0)), 1e-300)
    tan = np.where(stopped[:, None], acc / np.where(acc_n > 0, acc_n, 1.0)[:, None],
                   vel / np.where(speed > 0, speed, 1.0)[:, None])
    r = np.linalg.norm(pos, axis=1)
    centre = r <= 1e-12
    rad = np.where(centre[:, None], tan, pos / np.where(centre, 1.0, r)[:, None])
    return tan, rad


def device_columns(engine: str, g: DeviceGeometry, drive: Drive, t, cap_pos, wall_z, wire_stress,
                   spring_zeta, closure, drive_force=None, rod_force=None, stats=None) -> RunResult:
    """Build a RunResult with the common columns.

    Give drive_force, the engine's force vector (n, 2) [F_x, F_y] that the drive applies to the cap,
    or rod_force, the rod's force (n, 3) on the cap. The scalar columns (F and its parts) are
    projections on e_psi, as for the paper's line drive; F_x, F_y, F_tangent and F_radial give the
    whole vector for any path.
    """
    t = np.asarray(t, dtype=float)
    n = len(t)
    e = drive.unit_vector
    e2 = e[:2]
    pos, vel, acc = drive.plate(t)
    u = pos @ e2
    rope_v, wire_v = g.element_vectors(np.atleast_2d(cap_pos), wall_z)
    rope_l = np.linalg.norm(rope_v, axis=2)
    wire_l = np.linalg.norm(wire_v, axis=2)
    rope_t = rope_tension(rope_l, g.rope_natural_length[None], g.rope_stiffness)
    wire_stress = np.asarray(wire_stress, dtype=float).reshape(n, g.n_wires)
    wire_t = wire_tension(wire_stress, g.wire)
    # contribution to F = minus the force on the cap; the force on the cap is -T * unit(v)
    rope_vec = rope_t[:, :, None] * rope_v[:, :, :2] / rope_l[:, :, None]
    wire_vec = wire_t[:, :, None] * wire_v[:, :, :2] / np.where(wire_l > 0, wire_l, 1.0)[:, :, None]
    rope_f, wire_f = rope_vec @ e2, wire_vec @ e2
    inertia = g.params.cap_mass * acc
    f_ropes, f_wires = rope_vec.sum(1), wire_vec.sum(1)
    if drive_force is not None:
        F = np.asarray(drive_force, dtype=float).reshape(n, 2)
        f_dev = F - inertia
        f_rod = f_dev - f_ropes - f_wires if rod_force is None else -np.asarray(rod_force)[:, :2]
    else:
        f_rod = -np.asarray(rod_force, dtype=float)[:, :2]
        f_dev = f_rod + f_ropes + f_wires
        F = f_dev + inertia
    tan, rad = path_directions(pos, vel, acc)
    x_s = g.spring.free_length - np.asarray(wall_z, dtype=float)
    cols = {"t": t, "u": u, "F": F @ e2, "F_device": f_dev @ e2, "F_rod": f_rod @ e2, "F_ropes": f_ropes @ e2,
            "F_wires": f_wires @ e2, "spring_push": np.maximum(g.spring.kse * x_s + spring_zeta, 0.0),
            "spring_zeta": np.asarray(spring_zeta, dtype=float), "cap_z": np.asarray(cap_pos)[:, 2],
            "wall_z": np.asarray(wall_z, dtype=float), "closure": np.asarray(closure, dtype=float),
            "x": pos[:, 0], "y": pos[:, 1], "F_x": F[:, 0], "F_y": F[:, 1],
            "F_tangent": np.einsum("ij,ij->i", F, tan), "F_radial": np.einsum("ij,ij->i", F, rad)}
    for i in range(g.n_ropes):
        cols[f"rope{i}_tension"], cols[f"rope{i}_F"] = rope_t[:, i], rope_f[:, i]
    strain = (wire_l - g.wire.natural_length) / g.wire.natural_length
    for j in range(g.n_wires):
        cols[f"wire{j}_tension"], cols[f"wire{j}_F"] = wire_t[:, j], wire_f[:, j]
        cols[f"wire{j}_strain"], cols[f"wire{j}_stress"] = strain[:, j], wire_stress[:, j]
    return RunResult(engine, cols, column_units(g.n_ropes, g.n_wires), dict(stats or {}), drive.frequency)
