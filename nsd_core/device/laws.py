"""The device's force laws in the registry (nsd_core.model.laws): the rope (Eq. 16), the restrainer's
Hunt-Crossley stop, the SMA wire (Eq. 17) and the push spring (Eq. 18), each calling the device's
own implementation in nsd_core.device.forces. Registered when nsd_core.device is imported, the way a
user registers a law of their own."""
from __future__ import annotations

from numba import njit

from nsd_core.device.forces import (bouc_wen_slope_scalar, restrainer_force_scalar, rope_tension_scalar,
                                    sma_slope_scalar, spring_push_scalar, wire_tension_scalar)
from nsd_core.model.laws import INF, POINTS, Law, LawParameter, StateSpec, register


@njit(cache=True, _nrt=False)
def rope(x, xd, p):
    """Eq. 16 of the paper: T = k (L - L0) H(L - L0), tension only (the device's rope law)."""
    return rope_tension_scalar(x, p[1], p[0])


@njit(cache=True, _nrt=False)
def hunt_crossley_stop(x, xd, p):
    """A stop that holds the points within a distance gap [m]: past it, delta = L - gap > 0 and
    T = max(k delta^n (1 + alpha delta'), 0) pulls them together (the device's restrainer law,
    Hunt and Crossley 1975, evaluated by the restrainer's own function)."""
    return restrainer_force_scalar(x, 0.0, xd, 0.0, p[0], p[1], p[2], p[3])[2]


register(Law("rope", POINTS, (
    LawParameter("stiffness", "N/m", 0.0, doc="k_r"), LawParameter("free_length", "m", 0.0, doc="l_r0")),
    rope, rope.py_func.__doc__))
register(Law("hunt_crossley_stop", POINTS, (
    LawParameter("gap", "m", 0.0), LawParameter("stiffness", "N/m^n", 0.0),
    LawParameter("exponent", "-", 1.0, 3.0, default=1.5), LawParameter("damping", "s/m", 0.0, default=0.0, doc="alpha")),
    hunt_crossley_stop, hunt_crossley_stop.py_func.__doc__))


# ---- laws with a hysteretic state: the device's SMA wire (Eq. 17) and push spring (Eq. 18) --------------
# p: area, natural_length, E, Y, alpha, n, fT, a, Em, eps_t, c, initial_stress

@njit(cache=True, _nrt=False)
def sma_wire_tension(x, xd, s, p):
    """Eq. 17a: T = sigma A_w H(sigma), sigma the wire's stress (its state); a wire never pushes."""
    return wire_tension_scalar(s, p[0])


@njit(cache=True, _nrt=False)
def sma_wire_rate(x, xd, s, p):
    """Eq. 17b-d: d sigma/dt = (d sigma/d eps)(eps, sgn eps', sigma) eps', eps = (L - L0)/L0; the stress
    evolves as Eq. 17 says even while the wire is slack (only the force is clipped)."""
    eps, eps_rate = (x - p[1]) / p[1], xd / p[1]
    return sma_slope_scalar(eps, eps_rate, s, p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9], p[10]) * eps_rate


# p: kse, ksd, beta, gamma, n, free_length, initial_zeta

@njit(cache=True, _nrt=False)
def push_spring_tension(x, xd, s, p):
    """Eq. 18a: the spring pushes with P = max(k_se x_s + zeta, 0), x_s = L_s0 - L: T = -P."""
    return -spring_push_scalar(x, s, p[0], p[5])


@njit(cache=True, _nrt=False)
def push_spring_rate(x, xd, s, p):
    """Eq. 18b: d zeta/dt = (k_sd - (gamma + beta sgn(zeta x_s')) |zeta|^n) x_s', x_s' = -L'."""
    return bouc_wen_slope_scalar(s, -xd, p[1], p[2], p[3], p[4]) * (-xd)


register(Law("sma_wire", POINTS, (
    LawParameter("area", "m^2", 0.0, doc="A_w"), LawParameter("natural_length", "m", 0.0, doc="l_w0"),
    LawParameter("E", "Pa", 0.0), LawParameter("Y", "Pa", 0.0), LawParameter("alpha", "-", 0.0),
    LawParameter("n", "-", 0.0), LawParameter("fT", "-", -INF), LawParameter("a", "-", -INF),
    LawParameter("Em", "Pa", 0.0), LawParameter("eps_t", "-", 0.0), LawParameter("c", "-", 0.0),
    LawParameter("initial_stress", "Pa", -INF, default=0.0)),
    sma_wire_tension, "SMA wire, Eq. 17 of the paper (Bouc-Wen-type stress-strain law with pinching)",
    StateSpec("stress", "Pa", "initial_stress"), sma_wire_rate))
register(Law("push_spring", POINTS, (
    LawParameter("kse", "N/m", 0.0), LawParameter("ksd", "N/m", 0.0), LawParameter("beta", "1/N^n", -INF),
    LawParameter("gamma", "1/N^n", -INF), LawParameter("n", "-", 0.0), LawParameter("free_length", "m", 0.0),
    LawParameter("initial_zeta", "N", -INF, default=0.0)),
    push_spring_tension, "Push-only Bouc-Wen spring, Eq. 18 of the paper",
    StateSpec("zeta", "N", "initial_zeta"), push_spring_rate))
