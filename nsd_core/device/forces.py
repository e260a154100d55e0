"""The three axial force elements every engine calls: rope (Eq. 16), SMA wire (Eq. 17), spring (Eq. 18).

Each is a two-point element: from its current length L, its rate dL/dt and its internal state it
gives a scalar axial force and the state's rate. Every function takes numpy arrays (one entry per
element) or floats, allocates no Python objects per element, and knows nothing of any engine.

The hysteretic laws are rate-independent, so each is written once as a *slope* (d state / d strain
for a given direction of straining); the rate form multiplies the slope by the strain rate, and
``advance_*`` integrates the slope along a finite length change (for engines that commit the
states once per accepted step).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, vectorize


class WireLaw(NamedTuple):
    """Charalampakis-Tsiatas SMA parameters (Eq. 17) plus the wire's area and natural length."""
    E: float
    Y: float
    alpha: float
    n: float
    fT: float
    a: float
    Em: float
    eps_t: float
    c: float
    area: float
    natural_length: float


class SpringLaw(NamedTuple):
    """Bouc-Wen spring parameters (Eq. 18) plus the spring's free length L_s0."""
    kse: float
    ksd: float
    beta: float
    gamma: float
    n: float
    free_length: float


# ---- Scalar laws: the ONE implementation of each law, compiled (numba) -------------------------------
# The array functions below are ufuncs built from these same functions, and compiled callers (MuJoCo's
# C passive callback, compiled engines) call them directly, so every engine evaluates the same code.

@njit(cache=True, _nrt=False)
def rope_tension_scalar(length, natural_length, stiffness):
    """Eq. 16 for one rope: T = k_r (l_r - l_r0) H(l_r - l_r0)."""
    return stiffness * max(length - natural_length, 0.0)


@njit(cache=True, _nrt=False)
def wire_tension_scalar(stress, area):
    """Eq. 17a for one wire: T = sigma A_w H(sigma)."""
    return area * max(stress, 0.0)


@njit(cache=True, _nrt=False)
def power(x, n):
    """x ** n for x >= 0; the whole exponents of the nominal laws (n = 1, 2, 3) by multiplication,
    since a general pow costs several times a right-hand side's other arithmetic on a wire."""
    if n == 1.0:
        return x
    if n == 2.0:
        return x * x
    if n == 3.0:
        return x * x * x
    return x ** n


@njit(cache=True, _nrt=False)
def sma_slope_scalar(eps, d, stress, E, Y, alpha, n, fT, a, Em, eps_t, c):
    """Eq. 17b-d slope d sigma / d eps for one wire straining in direction d (sign taken)."""
    d = 1.0 if d > 0 else (-1.0 if d < 0 else 0.0)
    unloading_towards_zero = 1.0 if eps * d < 0.0 else 0.0  # H(-eps deps), H(0) = 0
    pinch = fT * math.tanh(a * eps) if unloading_towards_zero else 0.0
    beta = E * alpha * (eps - stress / E + pinch)
    over = stress - beta
    sg = 1.0 if over > 0 else (-1.0 if over < 0 else 0.0)
    x = c * (abs(eps) - eps_t)
    s = 0.0 if x < -20.0 else 0.5 * (math.tanh(x) + 1.0)  # tanh(x < -20) is -1.0 in double precision
    return (1.0 - s) * E * (1.0 - d * sg * power(abs(over / Y), n)) + s * Em


@njit(cache=True, _nrt=False)
def bouc_wen_slope_scalar(zeta, direction, ksd, beta, gamma, n):
    """Eq. 18b slope d zeta / d x_s for compressing in ``direction`` (sign taken)."""
    sg = zeta * direction
    sg = 1.0 if sg > 0 else (-1.0 if sg < 0 else 0.0)
    return ksd - (gamma + beta * sg) * power(abs(zeta), n)


@njit(cache=True, _nrt=False)
def spring_push_scalar(length, zeta, kse, free_length):
    """Eq. 18a for the spring: P = max(k_se x_s + zeta, 0), x_s = L_s0 - L (push only)."""
    return max(kse * (free_length - length) + zeta, 0.0)


@njit(cache=True, _nrt=False)
def advance_wire_stress_scalar(strain0, strain1, stress, E, Y, alpha, n, fT, a, Em, eps_t, c, substeps, order):
    """Eq. 17 integrated in strain from strain0 to strain1 (fixed direction): RK4 (order 4) or Heun
    (order 2) in ``substeps`` steps."""
    d = strain1 - strain0
    d = 1.0 if d > 0 else (-1.0 if d < 0 else 0.0)
    h = (strain1 - strain0) / substeps
    y = stress
    for k in range(substeps):
        x = strain0 + k * h
        x_end = strain1 if k == substeps - 1 else x + h
        k1 = sma_slope_scalar(x, d, y, E, Y, alpha, n, fT, a, Em, eps_t, c)
        if order == 2:
            y = y + 0.5 * h * (k1 + sma_slope_scalar(x_end, d, y + h * k1, E, Y, alpha, n, fT, a, Em, eps_t, c))
            continue
        xm = x + 0.5 * h
        k2 = sma_slope_scalar(xm, d, y + 0.5 * h * k1, E, Y, alpha, n, fT, a, Em, eps_t, c)
        k3 = sma_slope_scalar(xm, d, y + 0.5 * h * k2, E, Y, alpha, n, fT, a, Em, eps_t, c)
        k4 = sma_slope_scalar(x_end, d, y + h * k3, E, Y, alpha, n, fT, a, Em, eps_t, c)
        y = y + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return y


@njit(cache=True, _nrt=False)
def advance_spring_zeta_scalar(x0, x1, zeta, ksd, beta, gamma, n, substeps, order):
    """Eq. 18b integrated in the compression from x0 to x1 (fixed direction), as above."""
    d = x1 - x0
    d = 1.0 if d > 0 else (-1.0 if d < 0 else 0.0)
    h = (x1 - x0) / substeps
    y = zeta
    for _ in range(substeps):
        k1 = bouc_wen_slope_scalar(y, d, ksd, beta, gamma, n)
        if order == 2:
            y = y + 0.5 * h * (k1 + bouc_wen_slope_scalar(y + h * k1, d, ksd, beta, gamma, n))
            continue
        k2 = bouc_wen_slope_scalar(y + 0.5 * h * k1, d, ksd, beta, gamma, n)
        k3 = bouc_wen_slope_scalar(y + 0.5 * h * k2, d, ksd, beta, gamma, n)
        k4 = bouc_wen_slope_scalar(y + h * k3, d, ksd, beta, gamma, n)
        y = y + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return y


_F8 = "float64"


class _Ufunc:
    """The scalar law as a numpy ufunc for its one signature, made at its first call.

    Made lazily because numba builds a ufunc's wrapper in every process even when its kernel comes
    from the cache (~0.14 s CPU each: 0.8 s for the six at every import, in the gate's main process
    and in each worker, most of which never call them). The plain ufunc is called, not numba's
    DUFunc wrapper around it: the same machine code, ~0.55 us a call on 4 elements against ~1.7 us
    (the peers' Python callbacks call these laws several times a step)."""

    def __init__(self, scalar_law, *types: str):
        self.law, self.signature, self.ufunc = scalar_law, f"{_F8}({', '.join(types)})", None

    def __call__(self, *args):
        if self.ufunc is None:
            self.ufunc = vectorize([self.signature], cache=True)(self.law.py_func).ufunc
        return self.ufunc(*args)


_sma_slope = _Ufunc(sma_slope_scalar, *[_F8] * 12)
_bouc_wen_slope = _Ufunc(bouc_wen_slope_scalar, *[_F8] * 6)
_advance_wire = _Ufunc(advance_wire_stress_scalar, *[_F8] * 12, "int64", "int64")
_advance_spring = _Ufunc(advance_spring_zeta_scalar, *[_F8] * 7, "int64", "int64")
_rope = _Ufunc(rope_tension_scalar, _F8, _F8, _F8)
_wire = _Ufunc(wire_tension_scalar, _F8, _F8)


# ---- Array forms (numpy arrays, one entry per element, or floats) ----------------------------------

def rope_tension(length, natural_length, stiffness):
    """Eq. 16: T = k_r (l_r - l_r0) H(l_r - l_r0); a rope never pushes."""
    return _rope(np.asarray(length, dtype=float), natural_length, stiffness)


def sma_stress_slope(strain, direction, stress, law: WireLaw):
    """Eq. 17b-d as a slope: d sigma / d epsilon for straining in ``direction`` (+1, -1 or 0).

    beta = E alpha [eps - sigma/E + f_T tanh(a eps) H(-eps deps)] (17c, H(0) = 0),
    s = (tanh(c(|eps| - eps_t)) + 1)/2 (17d), and
    d sigma/d eps = (1 - s) E [1 - sgn(deps) sgn(sigma - beta) |(sigma - beta)/Y|^n] + s E_m (17b).
    """
    return _sma_slope(strain, direction, stress, law.E, law.Y, law.alpha, law.n, law.fT, law.a, law.Em,
                      law.eps_t, law.c)


def sma_wire(length, length_rate, stress, law: WireLaw):
    """Eq. 17: SMA wire tension T = sigma A_w H(sigma) (17a) and the stress rate d sigma/dt (17b).

    The stress evolves as Eq. 17 says even while the wire is slack; only the force is clipped.
    """
    strain = (np.asarray(length, dtype=float) - law.natural_length) / law.natural_length
    strain_rate = np.asarray(length_rate, dtype=float) / law.natural_length
    rate = sma_stress_slope(strain, strain_rate, stress, law) * strain_rate
    return wire_tension(stress, law), rate


def bouc_wen_slope(zeta, direction, law: SpringLaw):
    """Eq. 18b as a slope: d zeta / d x_s = k_sd - (gamma_s + beta_s sgn(zeta dx_s)) |zeta|^n_s."""
    return _bouc_wen_slope(zeta, direction, law.ksd, law.beta, law.gamma, law.n)


def wire_tension(stress, law: WireLaw):
    """Eq. 17a: T = sigma A_w H(sigma); a wire never pushes."""
    return _wire(stress, law.area)


def spring_push(length, length_rate, zeta, law: SpringLaw):
    """Eq. 18: spring push P = k_se x_s + zeta (>= 0: push only) and d zeta/dt.

    x_s = L_s0 - L is the compression. Returns (push, zeta_rate, unclipped push); the unclipped
    value below zero means the spring has lifted off its seat.
    """
    x = law.free_length - np.asarray(length, dtype=float)
    xdot = -np.asarray(length_rate, dtype=float)
    raw = law.kse * x + zeta
    return np.maximum(raw, 0.0), bouc_wen_slope(zeta, xdot, law) * xdot, raw


def _check_order(order: int) -> None:
    if order not in (2, 4):
        raise ValueError(f"order = {order!r}: allowed 2 (Heun) or 4 (RK4)")


def advance_wire_stress(strain0, strain1, stress, law: WireLaw, substeps: int = 1, order: int = 4):
    """Stress after the strain moves from strain0 to strain1 (Eq. 17 integrated in strain along the
    straight increment: ``substeps`` steps of classical RK4 (order 4) or Heun's method (order 2))."""
    _check_order(order)
    return _advance_wire(np.asarray(strain0, dtype=float), np.asarray(strain1, dtype=float),
                         np.asarray(stress, dtype=float), law.E, law.Y, law.alpha, law.n, law.fT, law.a, law.Em,
                         law.eps_t, law.c, int(substeps), int(order))


def advance_spring_zeta(compression0, compression1, zeta, law: SpringLaw, substeps: int = 1, order: int = 4):
    """Hysteretic force after the compression moves from compression0 to compression1 (Eq. 18b,
    integrated as in advance_wire_stress)."""
    _check_order(order)
    return _advance_spring(np.asarray(compression0, dtype=float), np.asarray(compression1, dtype=float),
                           np.asarray(zeta, dtype=float), law.ksd, law.beta, law.gamma, law.n, int(substeps),
                           int(order))


def precompressed_spring(kse, ksd, beta, gamma, n, push) -> tuple[float, float]:
    """Initial spring state: monotonic compression from x = 0, zeta = 0 until k_se x + zeta(x) = push.

    Returns (x_pre, zeta_0). For n_s = 1 zeta(x) = k_sd/(beta+gamma) (1 - exp(-(beta+gamma) x)) in
    closed form; otherwise zeta(x) is integrated in x with fine RK4 steps.
    """
    law = SpringLaw(kse, ksd, beta, gamma, n, 0.0)
    if n == 1.0:
        b = beta + gamma

        def zeta_of(x):
            return ksd / b * (1.0 - math.exp(-b * x))
    else:
        def zeta_of(x):
            return float(advance_spring_zeta(0.0, x, 0.0, law, substeps=2000))
    lo, hi = 0.0, push / kse  # zeta >= 0 on monotonic loading, so x_pre <= push/kse
    for _ in range(200):  # bisection: robust and deterministic
        mid = 0.5 * (lo + hi)
        if kse * mid + zeta_of(mid) < push:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-16:
            break
    x = 0.5 * (lo + hi)
    return x, zeta_of(x)


# ---- The displacement restrainer (docs/seismic.md): the ONE implementation of its contact law -------

@njit(cache=True, _nrt=False)
def restrainer_force_scalar(ux, uy, vx, vy, gap, stiffness, exponent, damping):
    """Radial compression-only contact between plate and base (Hunt and Crossley 1975).

    u = (ux, uy) the plate's displacement relative to the base, v its rate; r = |u|, the
    indentation delta = r - u_gap and its rate delta' = u . v / r. While delta > 0:
        F = max(k delta^n (1 + alpha delta'), 0)   [N], pushing the plate back along -u/r;
    zero otherwise. The force is zero at first touch and at separation (no jump; a Hunt-Crossley
    dashpot cannot pull at separation: the max clips the rare F < 0 when alpha delta' < -1).
    Returns (F_x, F_y, F, delta, delta'): (F_x, F_y) = F u/r, the plate's push on the restrainer
    (the restrainer's force on the plate is its negative), F >= 0 its magnitude."""
    r = math.hypot(ux, uy)
    delta = r - gap
    if delta <= 0.0 or r == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0
    rate = (ux * vx + uy * vy) / r
    F = max(stiffness * delta ** exponent * (1.0 + damping * rate), 0.0)
    return F * ux / r, F * uy / r, F, delta, rate


@njit(cache=True, _nrt=False)
def restrainer_stored_scalar(delta, stiffness, exponent):
    """Elastic energy of the contact at indentation delta: k delta^(n+1) / (n+1) [J] (0 if delta <= 0)."""
    return stiffness * delta ** (exponent + 1.0) / (exponent + 1.0) if delta > 0.0 else 0.0


def restrainer_forces(ux, uy, vx, vy, gap, stiffness, exponent, damping):
    """restrainer_force_scalar over arrays (outputs of a run): (F_x, F_y, F, delta, delta') arrays."""
    ux, uy, vx, vy = (np.asarray(a, dtype=float).ravel() for a in (ux, uy, vx, vy))
    out = np.zeros((5, ux.size))
    for k in range(ux.size):
        out[:, k] = restrainer_force_scalar(ux[k], uy[k], vx[k], vy[k], gap, stiffness, exponent, damping)
    return tuple(out)
