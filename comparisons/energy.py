"""Energy balance over the steady cycle, per engine: the drive's work against what the device did with it.

Power balance of the driven device (constraints do no work; the plate moves the cap in the plane
along its path p(t) = (x, y), a line along psi being the case p = u e_psi):
    F . p' = d/dt (kinetic + gravity) + sum_ropes T L' + sum_wires T L' + P x_s'
so over the steady cycle [t0, t1]
    W_drive = closed integral of F_x dx + F_y dy
            = dKE + dV_g + dU_ropes + d(k_se x_s^2 / 2)             (changes of stored energy)
              + A_w L_w0 sum_wires int sigma+ d eps + int zeta dx_s     (wires and the spring's hysteresis)
The metric is |W_drive - right-hand side| / |W_drive|. Every term is computed from the engine's
output columns (positions, wire stresses, spring zeta) with the nominal geometry of the case, by
trapezoids on the output grid: an engine whose forces, masses or elements differ from what its
states say fails it. Ropes and k_se x^2/2 are elastic: their stored energies are evaluated in closed
form, not integrated.
"""
from __future__ import annotations

import numpy as np

from nsd_core.device.cycle import steady_cycle
from nsd_core.device.geometry import DeviceGeometry
from nsd_core.device.results import RunResult


def _trapz(y, x) -> float:
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


def _plane(r: RunResult, unit_vector):
    """Plate position and drive force in the plane; runs without the vector columns are lines."""
    if "F_x" in r.columns and "x" in r.columns:
        return r["x"], r["y"], r["F_x"], r["F_y"]
    e = np.asarray(unit_vector, dtype=float)
    return r["u"] * e[0], r["u"] * e[1], r["F"] * e[0], r["F"] * e[1]


def energy_terms(r: RunResult, g: DeviceGeometry, frequency: float, unit_vector) -> dict[str, float]:
    """The terms of the balance over the steady cycle [J]."""
    c = steady_cycle(r, frequency)
    p = g.params
    t, zc, zw = r["t"][c], r["cap_z"][c], r["wall_z"][c]
    x, y, Fx, Fy = _plane(r, unit_vector)
    cap = np.column_stack([x[c], y[c], zc])
    rope_v, _ = g.element_vectors(cap, zw)
    rope_l = np.linalg.norm(rope_v, axis=2)
    U_rope = 0.5 * np.sum(g.rope_stiffness * np.maximum(rope_l - g.rope_natural_length, 0.0) ** 2, axis=1)
    x_s = g.spring.free_length - zw
    # kinetic energy: cap (u' along psi and z_c'), wall (z_w'), rod (centre velocity and spin)
    xd, yd, zcd, zwd = (np.gradient(v, r["t"])[c] for v in (x, y, r["cap_z"], r["wall_z"]))
    hd2 = xd ** 2 + yd ** 2  # the cap's horizontal speed squared
    rod_rel2 = hd2 + (zcd - zwd) ** 2
    KE = 0.5 * p.cap_mass * (hd2 + zcd ** 2) + 0.5 * p.wall_mass * zwd ** 2 + 0.5 * p.rod_mass * (
        hd2 / 4 + ((zcd + zwd) / 2) ** 2 + rod_rel2 / 12.0)
    V = p.gravity * (p.cap_mass * zc + p.wall_mass * zw + p.rod_mass * 0.5 * (zc + zw))
    wires = 0.0
    for j in range(g.n_wires):
        sig, eps = np.maximum(r[f"wire{j}_stress"][c], 0.0), r[f"wire{j}_strain"][c]
        wires += g.wire.area * g.wire.natural_length * _trapz(sig, eps)
    terms = {
        "drive_work": _trapz(Fx[c], x[c]) + _trapz(Fy[c], y[c]),
        "wires": wires,
        "spring_hysteresis": _trapz(r["spring_zeta"][c], x_s),
        "stored_change": float((KE[-1] - KE[0]) + (V[-1] - V[0]) + (U_rope[-1] - U_rope[0])
                               + 0.5 * g.spring.kse * (x_s[-1] ** 2 - x_s[0] ** 2)),
    }
    return {k: float(v) for k, v in terms.items()} | {"t_span": float(t[-1] - t[0])}


def energy_balance_rel(r: RunResult, g: DeviceGeometry, frequency: float, unit_vector) -> float:
    """|W_drive - (wires + spring hysteresis + stored change)| / |W_drive| over the steady cycle."""
    e = energy_terms(r, g, frequency, unit_vector)
    rest = e["wires"] + e["spring_hysteresis"] + e["stored_change"]
    return abs(e["drive_work"] - rest) / abs(e["drive_work"]) if e["drive_work"] else float("inf")
