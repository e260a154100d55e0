"""Turn an engine's raw trajectory into the common columns (one home for the output definitions).

An engine supplies, per output time: the cap position, the wall height, the hysteretic states, the
loop-closure violation and its own measure of the drive force and/or the rod's force on the cap.
Everything else (rope and wire tensions, their components along psi, the spring push) is computed
here from the shared force laws, so that the columns mean the same in every engine.
"""
from __future__ import annotations

import numpy as np

from nsd_core.device.drive import Drive
from nsd_core.device.forces import rope_tension, wire_tension
from nsd_core.device.geometry import DeviceGeometry
from nsd_core.device.results import RunResult, column_units


def device_columns(engine: str, g: DeviceGeometry, drive: Drive, t, cap_pos, wall_z, wire_stress,
                   spring_zeta, closure, drive_force=None, rod_force=None, stats=None) -> RunResult:
    """Build a RunResult with the common columns. Give drive_force (the engine's F) or rod_force."""
    t = np.asarray(t, dtype=float)
    n = len(t)
    e = drive.unit_vector
    u, _, u_dd = drive.displacement(t)
    rope_v, wire_v = g.element_vectors(np.atleast_2d(cap_pos), wall_z)
    rope_l = np.linalg.norm(rope_v, axis=2)
    wire_l = np.linalg.norm(wire_v, axis=2)
    rope_t = rope_tension(rope_l, g.rope_natural_length[None], g.rope_stiffness)
    wire_stress = np.asarray(wire_stress, dtype=float).reshape(n, g.n_wires)
    wire_t = wire_tension(wire_stress, g.wire)
    # contribution to F = minus the force on the cap along psi; the force on the cap is -T * unit(v)
    rope_f = rope_t * (rope_v @ e) / rope_l
    wire_f = wire_t * (wire_v @ e) / np.where(wire_l > 0, wire_l, 1.0)
    inertia = g.params.cap_mass * u_dd
    f_ropes, f_wires = rope_f.sum(1), wire_f.sum(1)
    if drive_force is not None:
        F = np.asarray(drive_force, dtype=float)
        f_dev = F - inertia
        f_rod = f_dev - f_ropes - f_wires if rod_force is None else -(np.asarray(rod_force) @ e)
    else:
        f_rod = -(np.asarray(rod_force) @ e)
        f_dev = f_rod + f_ropes + f_wires
        F = f_dev + inertia
    x_s = g.spring.free_length - np.asarray(wall_z, dtype=float)
    cols = {"t": t, "u": u, "F": F, "F_device": f_dev, "F_rod": f_rod, "F_ropes": f_ropes,
            "F_wires": f_wires, "spring_push": np.maximum(g.spring.kse * x_s + spring_zeta, 0.0),
            "spring_zeta": np.asarray(spring_zeta, dtype=float), "cap_z": np.asarray(cap_pos)[:, 2],
            "wall_z": np.asarray(wall_z, dtype=float), "closure": np.asarray(closure, dtype=float)}
    for i in range(g.n_ropes):
        cols[f"rope{i}_tension"], cols[f"rope{i}_F"] = rope_t[:, i], rope_f[:, i]
    strain = (wire_l - g.wire.natural_length) / g.wire.natural_length
    for j in range(g.n_wires):
        cols[f"wire{j}_tension"], cols[f"wire{j}_F"] = wire_t[:, j], wire_f[:, j]
        cols[f"wire{j}_strain"], cols[f"wire{j}_stress"] = strain[:, j], wire_stress[:, j]
    return RunResult(engine, cols, column_units(g.n_ropes, g.n_wires), dict(stats or {}))
