"""An independent quasi-static solution of the driven device, by virtual work in closed form.

It shares only the force laws and the geometry with the multibody engines: no tree, no path matrix,
no Lagrange multipliers. For the plate at u along psi, the cap sits at (u e_psi, z_c), the wall at
z_w and the rod closes the loop, z_c = z_w + sqrt(l_d^2 - u^2). The single free coordinate z_w
moves cap, rod and wall together, so its equilibrium reads P(z_w) + sum(rope pulls on the cap)_z = W
(the wires are internal to that motion). The drive force follows from a virtual displacement du at
fixed z_w: F = m_c u'' - sum(f_on_cap . dr_cap/du) + (m_c + m_d/2) g dz_c/du.
The hysteretic states are advanced along the path with the laws' rate-independent slopes.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from nsd_core.device.forces import advance_spring_zeta, advance_wire_stress, rope_tension, wire_tension
from nsd_core.device.geometry import DeviceGeometry, device_geometry
from nsd_core.device.params import Params


def _element_state(g: DeviceGeometry, e: np.ndarray, u: float, z_w: float):
    """Cap position, element vectors (upper minus lower) and lengths at plate u, wall z_w."""
    z_c = z_w + math.sqrt(g.params.rod_length ** 2 - u * u)
    cap = u * e + np.array([0.0, 0.0, z_c])
    rope_d, wire_d = g.element_vectors(cap, z_w)
    return z_c, rope_d, np.linalg.norm(rope_d, axis=1), wire_d, np.linalg.norm(wire_d, axis=1)


def quasi_static_path(params: Params | DeviceGeometry, u: np.ndarray, direction_deg: float = 0.0,
                      u_ddot: np.ndarray | None = None, substeps: int = 4,
                      stop_at_slack: bool = False) -> dict[str, np.ndarray]:
    """Quasi-static equilibria along the plate displacement path u[0..], starting from rest (u[0] = 0).

    Returns arrays: u, F, F_device, z_w, z_c, spring push, rope tensions (n, n_r), wire stresses;
    with stop_at_slack, only up to the first point where every rope is slack.
    """
    g = params if isinstance(params, DeviceGeometry) else device_geometry(params)
    p = g.params
    e = np.array([math.cos(math.radians(direction_deg)), math.sin(math.radians(direction_deg)), 0.0])
    u = np.asarray(u, dtype=float)
    L0w = g.wire.natural_length
    sigma = g.initial_wire_stress()
    zeta = g.spring_zeta0
    z_w = g.wall_rest_z
    _, _, _, _, wl = _element_state(g, e, 0.0, z_w)
    eps_prev = (wl - L0w) / L0w
    x_prev = g.spring.free_length - z_w
    n = len(u)
    out = {k: np.zeros(n) for k in ("F", "F_device", "z_w", "z_c", "spring_push", "spring_zeta")}
    out["rope_tension"] = np.zeros((n, g.n_ropes))
    out["wire_stress"] = np.zeros((n, g.n_wires))
    out["wire_strain"] = np.zeros((n, g.n_wires))
    out["rope_stretch"] = np.zeros(n)  # max over ropes of L - L_r0 (negative: all slack)

    def states_at(uk, zw):
        z_c, rope_d, rl, wire_d, wl = _element_state(g, e, uk, zw)
        eps = (wl - L0w) / L0w
        sig = advance_wire_stress(eps_prev, eps, sigma, g.wire, substeps) if g.n_wires else sigma
        x = g.spring.free_length - zw
        zt = float(advance_spring_zeta(x_prev, x, zeta, g.spring, substeps))
        return z_c, rope_d, rl, wire_d, wl, eps, sig, x, zt

    def vertical_residual(zw, uk):
        _, rope_d, rl, *_rest, x, zt = states_at(uk, zw)
        push = max(g.spring.kse * x + zt, 0.0)
        t = rope_tension(rl, g.rope_natural_length, g.rope_stiffness)
        return push - np.sum(t * rope_d[:, 2] / rl) - p.carried_weight

    for k, uk in enumerate(u):
        if abs(uk) >= p.rod_length:
            raise ValueError(f"u = {uk}: beyond the rod length {p.rod_length}")
        if k > 0:
            lo, hi = z_w - 2e-3, z_w + 2e-3
            while vertical_residual(lo, uk) * vertical_residual(hi, uk) > 0:
                lo, hi = lo - 2e-3, hi + 2e-3
            z_w = brentq(vertical_residual, lo, hi, args=(uk,), xtol=1e-15, rtol=1e-15, maxiter=200)
        z_c, rope_d, rl, wire_d, wl, eps, sig, x, zt = states_at(uk, z_w)
        t_rope = rope_tension(rl, g.rope_natural_length, g.rope_stiffness)
        t_wire = wire_tension(sig, g.wire)
        f_cap = -(t_rope[:, None] * rope_d / rl[:, None]).sum(0) - (t_wire[:, None] * wire_d / wl[:, None]).sum(0)
        dzc_du = -uk / math.sqrt(p.rod_length ** 2 - uk * uk)
        dr_du = e + np.array([0.0, 0.0, dzc_du])
        f_dev = -float(f_cap @ dr_du) + (p.cap_mass + 0.5 * p.rod_mass) * p.gravity * dzc_du
        acc = 0.0 if u_ddot is None else p.cap_mass * u_ddot[k]
        out["F"][k], out["F_device"][k] = f_dev + acc, f_dev
        out["z_w"][k], out["z_c"][k] = z_w, z_c
        out["spring_push"][k], out["spring_zeta"][k] = max(g.spring.kse * x + zt, 0.0), zt
        out["rope_tension"][k] = t_rope
        out["rope_stretch"][k] = float(np.max(rl - g.rope_natural_length))
        out["wire_stress"][k], out["wire_strain"][k] = sig, eps
        sigma, zeta, eps_prev, x_prev = sig, zt, eps, x
        if stop_at_slack and out["rope_stretch"][k] <= 0.0:  # every rope slack: the path ends here
            out = {key: v[:k + 1] for key, v in out.items()}
            u = u[:k + 1]
            break
    out["u"] = u
    return out


def x_max(params: Params, direction_deg: float = 0.0, step: float = 2e-5) -> float:
    """X_max: the plate displacement, on monotonic loading from rest, at which the ropes go slack.

    Located by stepping outward (the hysteretic states need the path) and then bisecting the last
    step on the total rope tension.
    """
    g = device_geometry(params)
    n = int(params.rod_length * 0.999 / step)
    u = np.linspace(0.0, step * n, n + 1)
    stretch = quasi_static_path(g, u, direction_deg, substeps=2, stop_at_slack=True)["rope_stretch"]
    slack = np.nonzero(stretch <= 0.0)[0]
    if len(slack) == 0:
        return float("nan")
    k = slack[0]  # the stretch is smooth: interpolate linearly inside the last step
    return float(u[k - 1] + step * stretch[k - 1] / (stretch[k - 1] - stretch[k]))


def quasi_static_cycle(params: Params, amplitude: float, points_per_cycle: int = 80, cycles: int = 2,
                       substeps: int = 6) -> dict[str, np.ndarray]:
    """The last of ``cycles`` quasi-static cycles, u = A sin(2 pi s) (the hysteresis is carried).

    Returns the quasi-static path's arrays plus 's' (cycle phase, 0..1) and 'stiffness' on the
    loading quarter (u from 0 to A), used by the qualitative checks of Figures 7-20.
    """
    s = np.linspace(0.0, cycles, cycles * points_per_cycle + 1)
    out = quasi_static_path(params, amplitude * np.sin(2 * np.pi * s), substeps=substeps)
    m = s >= cycles - 1 - 1e-12
    cyc = {k: v[m] for k, v in out.items()}
    cyc["s"] = s[m] - (cycles - 1)
    q = cyc["s"] <= 0.25 + 1e-12
    cyc["loading_u"], cyc["loading_stiffness"] = cyc["u"][q], np.gradient(cyc["F_device"][q], cyc["u"][q])
    return cyc
