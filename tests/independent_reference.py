"""An independent quasi-static reference of the driven device, written from docs/model.md alone.

It imports nothing from nsd_core: Table 2 is read from references/paper-data.toml, the assumed
values are copied from docs/model.md (and named so), and the three force laws (Eqs. 16-18) are
written out again here. Where nsd_core.quasistatic closes the loop with a single coordinate and
gets the drive force by virtual work, this one writes Newton's equations body by body:

- cap (free vertically, pushed horizontally by the plate with F along +X), rod (two spherical
  joints, its weight at mid-length), wall (vertical guide) and spring;
- vertical balance of cap + rod + wall fixes the wall height z_w for each plate position u;
- the cap's vertical balance gives the rod's vertical force on the cap, the rod's moment balance
  about its lower joint its horizontal one, and the cap's horizontal balance the drive force
  F = m_c u'' - (ropes + wires + rod on the cap)_x.

Drive along +X (psi = 0) only. Also: ``rod_force_from_wall_balance``, the rod's horizontal force on
the cap recomputed from the wall's vertical balance of an engine's output columns and the rod's own
Newton-Euler equations, a check that shares nothing with the engine's drive-force equation.
"""
from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

_DATA = tomllib.loads((Path(__file__).resolve().parents[1] / "references" / "paper-data.toml").read_text())
T2 = _DATA["table2"]
K_ROPE = _DATA["ropes"]["stiffness"]
F_PRESS = _DATA["table6"]["precompression_force"][-1]   # Table 6's 3800 N column = Table 5's 0.03 m
# assumed in docs/model.md (the paper does not give them)
GRAVITY = 9.81
H_RU = 0.0189                                                             # rope upper end above the cap ref.
H_W = (T2["wire_lower_radius"] - T2["wire_upper_radius"]) / math.tan(math.radians(T2["wire_inclination_deg"]))
WIRE = dict(E=50e9, Y=400e6, alpha=0.03, n=3.0, fT=0.36, a=500.0, Em=25e9, eps_t=0.07, c=300.0)
SPRING = dict(kse=3.44e5, ksd=2.0e5, beta=390.0, gamma=255.0)             # n_s = 1


def exact_zeta_step(zeta: float, dx: float, ksd=SPRING["ksd"], beta=SPRING["beta"], gamma=SPRING["gamma"]) -> float:
    """Eq. 18b with n_s = 1 over one monotonic compression change dx, solved exactly.

    With d = sgn(dx), y = d zeta and X = |dx|: dy/dX = k_sd - (gamma + beta) y for y >= 0 and
    dy/dX = k_sd - (beta - gamma) y for y < 0; both are linear (exponential approach to k_sd/r),
    and the branch changes where y crosses 0, at X = ln(1 - y0/y_inf)/r.
    """
    d = 1.0 if dx >= 0 else -1.0
    y, X = d * zeta, abs(dx)
    if y < 0:
        r = beta - gamma
        y_inf = ksd / r
        X0 = math.log(1.0 - y / y_inf) / r if r != 0 else -y / ksd
        if X < X0:
            return d * (y_inf + (y - y_inf) * math.exp(-r * X) if r != 0 else y + ksd * X)
        y, X = 0.0, X - X0
    r = gamma + beta
    return d * (ksd / r + (y - ksd / r) * math.exp(-r * X))


def exact_zeta(x_path, zeta0: float, **law) -> np.ndarray:
    """zeta along a compression path (piecewise monotonic between samples), exactly (n_s = 1)."""
    out = [zeta0]
    for a, b in zip(x_path[:-1], x_path[1:]):
        out.append(exact_zeta_step(out[-1], b - a, **law))
    return np.array(out)


def sma_slope(eps, d, sigma, w=WIRE):
    """Eq. 17b-d per unit strain for straining in direction d (numpy, elementwise)."""
    unloading = (eps * d < 0).astype(float)          # H(-eps deps), H(0) = 0
    beta = w["E"] * w["alpha"] * (eps - sigma / w["E"] + w["fT"] * np.tanh(w["a"] * eps) * unloading)
    s = 0.5 * (np.tanh(w["c"] * (np.abs(eps) - w["eps_t"])) + 1.0)
    z = sigma - beta
    return (1 - s) * w["E"] * (1 - d * np.sign(z) * np.abs(z / w["Y"]) ** w["n"]) + s * w["Em"]


def sma_step(eps0, eps1, sigma, substeps=2):
    """sigma after the strain goes eps0 -> eps1 (classical RK4 in strain)."""
    d = np.sign(eps1 - eps0)
    h = (eps1 - eps0) / substeps
    for k in range(substeps):
        e = eps0 + k * h
        k1 = sma_slope(e, d, sigma)
        k2 = sma_slope(e + h / 2, d, sigma + h / 2 * k1)
        k3 = sma_slope(e + h / 2, d, sigma + h / 2 * k2)
        k4 = sma_slope(e + h, d, sigma + h * k3)
        sigma = sigma + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return sigma


class Device:
    """The device of docs/model.md at rest, from Table 2 and the assumed values."""

    def __init__(self, wire_lower_radius=T2["wire_lower_radius"]):
        self.ld, self.ls = T2["rod_length"], T2["spring_length_precompressed"]
        self.mc, self.md, self.mw = T2["cap_mass"], T2["rod_mass"], T2["wall_mass"]
        self.W = (self.mc + self.md + self.mw) * GRAVITY
        nr, nw = T2["n_ropes"], T2["n_wires"]
        phr = math.radians(T2["wire_first_azimuth_deg"]) + 2 * math.pi * np.arange(nr) / nr
        phw = math.radians(T2["wire_first_azimuth_deg"]) + 2 * math.pi * np.arange(nw) / nw
        ring = lambda r, ph: np.column_stack([r * np.cos(ph), r * np.sin(ph), np.zeros(len(ph))])  # noqa: E731
        self.rope_low = ring(T2["rope_lower_radius"], phr)                # on the base, z = 0
        self.rope_up = ring(T2["rope_upper_radius"], phr) + [0, 0, H_RU]  # relative to the cap reference
        self.wire_up = ring(T2["wire_upper_radius"], phw) + [0, 0, H_W - self.ld]
        self.wire_low = ring(wire_lower_radius, phw)                      # relative to the wall reference
        self.area = math.pi * T2["wire_diameter"] ** 2 / 4
        # rest: ropes carry F_press - W vertically in total, wires unstressed, spring pushes F_press
        rv, rl = self.ropes(0.0, self.ls + self.ld)
        tension = (F_PRESS - self.W) / np.sum(rv[:, 2] / rl)
        self.rope_L0 = rl - tension / K_ROPE
        self.wire_L0 = self.wires(0.0, self.ls + self.ld, self.ls)[1]
        b = SPRING["beta"] + SPRING["gamma"]
        zeta_of = lambda x: SPRING["ksd"] / b * (1 - math.exp(-b * x))     # noqa: E731  monotonic loading
        self.x_pre = brentq(lambda x: SPRING["kse"] * x + zeta_of(x) - F_PRESS, 0.0, F_PRESS / SPRING["kse"],
                            xtol=1e-16, rtol=1e-15)
        self.zeta0, self.Ls0 = zeta_of(self.x_pre), self.ls + self.x_pre

    def ropes(self, u, zc):
        v = np.array([u, 0.0, zc]) + self.rope_up - self.rope_low
        return v, np.linalg.norm(v, axis=1)

    def wires(self, u, zc, zw):
        v = np.array([u, 0.0, zc - zw]) + self.wire_up - self.wire_low
        return v, np.linalg.norm(v, axis=1)


def quasi_static_force(u, u_ddot=None, device: Device | None = None) -> dict[str, np.ndarray]:
    """F (drive force along +X) and z_w along the path u (u[0] = 0: from rest), quasi-statically."""
    dv = device or Device()
    u = np.asarray(u, dtype=float)
    sigma, zeta = np.zeros(len(dv.wire_L0)), dv.zeta0
    zw = dv.ls
    eps_prev, x_prev = np.zeros(len(dv.wire_L0)), dv.x_pre
    F, ZW = np.zeros(len(u)), np.zeros(len(u))

    def state(uk, z):
        zc = z + math.sqrt(dv.ld ** 2 - uk * uk)
        rv, rl = dv.ropes(uk, zc)
        wv, wl = dv.wires(uk, zc, z)
        eps = (wl - dv.wire_L0) / dv.wire_L0
        sig = sma_step(eps_prev, eps, sigma)
        x = dv.Ls0 - z
        zt = exact_zeta_step(zeta, x - x_prev)
        T_rope = K_ROPE * np.maximum(rl - dv.rope_L0, 0.0)
        T_wire = dv.area * np.maximum(sig, 0.0)
        push = max(SPRING["kse"] * x + zt, 0.0)
        return zc, rv, rl, wv, wl, eps, sig, x, zt, T_rope, T_wire, push

    def vertical(z, uk):   # cap + rod + wall: spring up, ropes down on the cap, weight down
        _, rv, rl, *_r, T_rope, _tw, push = state(uk, z)
        return push - np.sum(T_rope * rv[:, 2] / rl) - dv.W

    for k, uk in enumerate(u):
        if k:
            lo, hi = zw - 2e-3, zw + 2e-3
            while vertical(lo, uk) * vertical(hi, uk) > 0:
                lo, hi = lo - 2e-3, hi + 2e-3
            zw = brentq(vertical, lo, hi, args=(uk,), xtol=1e-15, rtol=1e-15)
        zc, rv, rl, wv, wl, eps, sig, x, zt, T_rope, T_wire, push = state(uk, zw)
        on_cap = -(T_rope[:, None] * rv / rl[:, None]).sum(0) - (T_wire[:, None] * wv / wl[:, None]).sum(0)
        rod_on_cap_z = dv.mc * GRAVITY - on_cap[2]              # cap vertical balance
        cap_on_rod_z = -rod_on_cap_z
        h = zc - zw
        # rod's moments about its lower joint: h f_x - u f_z + (u/2) m_d g = 0, f the cap's force on the rod
        cap_on_rod_x = uk * (cap_on_rod_z - dv.md * GRAVITY / 2) / h
        F[k] = -(on_cap[0] - cap_on_rod_x) + (0.0 if u_ddot is None else dv.mc * u_ddot[k])
        ZW[k] = zw
        sigma, zeta, eps_prev, x_prev = sig, zt, eps, x
    return {"u": u, "F": F, "z_w": ZW}


def rod_force_from_wall_balance(r, n_wires: int = T2["n_wires"]) -> np.ndarray:
    """The rod's contribution to F (drive along +X) from an engine's columns, via the wall.

    Wall, vertically: m_w (z_w'' + g) = P + sum(wire pulls up) + R_z, R the rod's force on the
    wall, so the wall pushes the rod with f_b,z = -R_z. The rod (uniform, mass m_d, length l_d, at
    angle phi = atan(u/h) from the vertical, h = z_c - z_w) then follows from Newton-Euler in the
    drive plane: m_d a_c = f_b + f_t - m_d g e_z and I phi'' = (r/2) x f_t - (r/2) x f_b with
    I = m_d l_d^2/12, a_c = (u''/2, (z_c'' + z_w'')/2); f_t is the cap's force on the rod:
    f_t,x = (I phi'' + h m_d a_c,x / 2 + u (f_t,z - f_b,z)/2) / h. Accelerations by finite
    differences of the output columns. The rod's contribution to F is f_t,x.
    """
    dv = Device()
    t, u, zc, zw = r["t"], r["u"], r["cap_z"], r["wall_z"]
    T = np.column_stack([r[f"wire{j}_tension"] for j in range(n_wires)])
    up = np.zeros(len(t))
    for k in range(len(t)):
        wv, wl = dv.wires(u[k], zc[k], zw[k])
        up[k] = float(T[k] @ (wv[:, 2] / wl))

    def dd(x):
        return np.gradient(np.gradient(x, t), t)

    h = zc - zw
    f_bz = -(dv.mw * (dd(zw) + GRAVITY) - r["spring_push"] - up)
    f_tz = dv.md * (0.5 * (dd(zc) + dd(zw)) + GRAVITY) - f_bz
    inertia = dv.md * dv.ld ** 2 / 12.0
    return (inertia * dd(np.arctan2(u, h)) + 0.5 * h * dv.md * 0.5 * dd(u) + 0.5 * u * (f_tz - f_bz)) / h
