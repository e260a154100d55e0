"""The force-law registry: every law a model description can name, written once, used by every engine.

A law maps one scalar coordinate and its rate to one scalar force:
- a *points* law acts along the line between two body points: x = the distance L [m], xd = its rate
  L' [m/s]; it returns the tension T [N] (positive pulls the points together, negative pushes them
  apart);
- a *joint* law acts on one joint coordinate: x = q [m or rad], xd = q' [m/s or rad/s]; it returns
  the generalized force Q [N or N m] on that coordinate (positive drives q up).

Each law is a compiled scalar function ``force(x, xd, p)`` of a float64 array p holding its
parameters in the order of ``Law.parameters``. The in-house builder, MuJoCo's passive callback and
Exudyn's connector user functions all call exactly this function: a law added here (one function and
one ``register`` call) reaches all three engines. Where the device already has a law (the rope of
Eq. 16, the restrainer's Hunt-Crossley contact), the registry calls that one implementation.

A law may carry one internal state s (the SMA wire's stress, the Bouc-Wen spring's zeta): then
``state`` names it (its unit and the parameter holding its value at t = 0), ``force(x, xd, s, p)``
takes it, and ``rate(x, xd, s, p)`` gives ds/dt. Each engine integrates the state along with its own
motion (the in-house engine as extra states of its ODE).

A *plane* law (``PLANE``) acts on two slide coordinates of one joint at once, a planar displacement
(x, y) = (q_i, q_j) [m] with rates (x', y') [m/s], and may carry a two-component state (s_x, s_y): it
is compiled as ``force(x, y, xd, yd, sx, sy, p) -> (Q_x, Q_y)`` [N], the generalized forces on the
two coordinates, and ``rate(x, y, xd, yd, sx, sy, p) -> (s_x', s_y')``. The state of such a law takes
two slots of an engine's state array, consecutive, x first (``Law.state_size``). It exists for laws
whose two directions are coupled (a bidirectional hysteresis: the baseline isolators), which two
scalar joint laws cannot express.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from numba import njit

from nsd_core.device.forces import (bouc_wen_slope_scalar, restrainer_force_scalar, rope_tension_scalar,
                                    sma_slope_scalar, spring_push_scalar, wire_tension_scalar)
from nsd_core.device.isolator_laws import hysteretic_force_scalar

POINTS, JOINT, PLANE = "points", "joint", "plane"


@dataclass(frozen=True)
class LawParameter:
    name: str
    unit: str
    low: float                 # allowed range, inclusive
    high: float = np.inf
    default: float | None = None   # None: required
    doc: str = ""


@dataclass(frozen=True)
class StateSpec:
    """A law's internal state: its name, unit, and the parameter that gives its value at t = 0 (a plane
    law's: two parameters, comma-separated, x first)."""
    name: str
    unit: str
    initial: str


@dataclass(frozen=True)
class Law:
    name: str
    acts_on: str               # POINTS or JOINT
    parameters: tuple[LawParameter, ...]
    force: Callable            # compiled force(x, xd, p) -> float; with a state force(x, xd, s, p)
    doc: str
    state: StateSpec | None = None
    rate: Callable | None = None   # with a state: compiled rate(x, xd, s, p) -> ds/dt

    @property
    def state_size(self) -> int:
        """How many slots the law's state takes in an engine's state array: 0, 1, or 2 (a plane law's)."""
        return 0 if self.state is None else (2 if self.acts_on == PLANE else 1)

    def initial_state(self, packed: np.ndarray) -> float:
        names = [p.name for p in self.parameters]
        return float(packed[names.index(self.state.initial)]) if self.state else 0.0

    def initial_states(self, packed: np.ndarray) -> tuple:
        """The state's components at t = 0, one per slot (``state_size`` of them)."""
        names = [p.name for p in self.parameters]
        return tuple(float(packed[names.index(k)]) for k in self.state.initial.split(",")) if self.state else ()

    def pack(self, given: dict, where: str) -> np.ndarray:
        """The parameters of one element as the array ``force`` takes; bad input raises ModelError."""
        from nsd_core.model.errors import ModelError
        known = {p.name for p in self.parameters}
        for k in given:
            if k not in known:
                raise ModelError(f"{where}.{k}: unknown parameter of law {self.name!r}; "
                                 f"allowed: {', '.join(p.name for p in self.parameters)}")
        out = []
        for p in self.parameters:
            v = given.get(p.name, p.default)
            if v is None:
                raise ModelError(f"{where}.{p.name}: missing; law {self.name!r} needs it [{p.unit}]")
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v) or not p.low <= v <= p.high:
                hi = "" if p.high == np.inf else f", <= {p.high:g}"
                raise ModelError(f"{where}.{p.name} = {v!r}: must be a number >= {p.low:g}{hi} [{p.unit}]")
            out.append(float(v))
        return np.array(out, dtype=np.float64)


LAWS: dict[str, Law] = {}


def register(law: Law) -> Law:
    """Add a law to the registry (a name is registered once)."""
    if law.name in LAWS:
        raise ValueError(f"law {law.name!r} is already registered")
    if law.acts_on not in (POINTS, JOINT, PLANE):
        raise ValueError(f"law {law.name!r}: acts_on must be {POINTS!r}, {JOINT!r} or {PLANE!r}")
    if (law.state is None) != (law.rate is None):
        raise ValueError(f"law {law.name!r}: a state needs a rate, and a rate a state")
    if law.state is not None and (not set(law.state.initial.split(",")) <= {p.name for p in law.parameters}
                                  or len(law.state.initial.split(",")) != law.state_size):
        raise ValueError(f"law {law.name!r}: the state's initial value {law.state.initial!r} is not "
                         f"{law.state_size} parameter(s)")
    LAWS[law.name] = law
    return law


def get_law(name: str, where: str) -> Law:
    from nsd_core.model.errors import ModelError
    if name not in LAWS:
        raise ModelError(f"{where}.law = {name!r}: unknown; allowed: {', '.join(sorted(LAWS))}")
    return LAWS[name]


# ---- the laws ---------------------------------------------------------------------------------------

@njit(cache=True, _nrt=False)
def linear_spring_damper(x, xd, p):
    """T = k (L - L0) + c L' + T0: a linear spring of stiffness k [N/m] and free length L0 [m], a
    dashpot c [N s/m] and a preload T0 [N] (as Andrews' spring c0, l0; any strut)."""
    return p[0] * (x - p[2]) + p[1] * xd + p[3]


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


@njit(cache=True, _nrt=False)
def constant_force(x, xd, p):
    """Q = Q0: a constant generalized force (a motor torque [N m] on a revolute joint, a force [N] on
    a prismatic one; Andrews' driving torque mom)."""
    return p[0]


@njit(cache=True, _nrt=False)
def joint_spring_damper(x, xd, p):
    """Q = -k (q - q0) - c q': a linear spring [N/m or N m/rad] and dashpot [N s/m or N m s/rad] on a
    joint coordinate, neutral at q0 [m or rad]."""
    return -p[0] * (x - p[2]) - p[1] * xd


INF = np.inf
register(Law("linear_spring_damper", POINTS, (
    LawParameter("stiffness", "N/m", 0.0, doc="k"), LawParameter("damping", "N s/m", 0.0, default=0.0, doc="c"),
    LawParameter("free_length", "m", 0.0, doc="L0"), LawParameter("preload", "N", -INF, default=0.0, doc="T0")),
    linear_spring_damper, linear_spring_damper.py_func.__doc__))
register(Law("rope", POINTS, (
    LawParameter("stiffness", "N/m", 0.0, doc="k_r"), LawParameter("free_length", "m", 0.0, doc="l_r0")),
    rope, rope.py_func.__doc__))
register(Law("hunt_crossley_stop", POINTS, (
    LawParameter("gap", "m", 0.0), LawParameter("stiffness", "N/m^n", 0.0),
    LawParameter("exponent", "-", 1.0, 3.0, default=1.5), LawParameter("damping", "s/m", 0.0, default=0.0, doc="alpha")),
    hunt_crossley_stop, hunt_crossley_stop.py_func.__doc__))
register(Law("constant_force", JOINT, (LawParameter("value", "N or N m", -INF, doc="Q0"),),
             constant_force, constant_force.py_func.__doc__))
register(Law("joint_spring_damper", JOINT, (
    LawParameter("stiffness", "N/m or N m/rad", 0.0), LawParameter("damping", "N s/m or N m s/rad", 0.0, default=0.0),
    LawParameter("neutral", "m or rad", -INF, default=0.0)),
    joint_spring_damper, joint_spring_damper.py_func.__doc__))


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


# ---- a plane law: the baseline isolators' bidirectional hysteresis (nsd_core.device.isolator_laws) -----
# p: strength, strength_at_rest, rate, yield_displacement, exponent, initial_zx, initial_zy

@njit(cache=True, _nrt=False)
def bidirectional_hysteresis_force(x, y, xd, yd, sx, sy, p):
    """(Q_x, Q_y) = -Q(|u'|) z [N]: the hysteretic part of a lead-rubber bearing or a friction pendulum
    on the displacement u = (x, y), z = (s_x, s_y) its state (isolator_laws.hysteretic_force_scalar)."""
    fx, fy, _, _, _ = hysteretic_force_scalar(xd, yd, sx, sy, p[0], p[1], p[2], p[3], p[4])
    return -fx, -fy


@njit(cache=True, _nrt=False)
def bidirectional_hysteresis_rate(x, y, xd, yd, sx, sy, p):
    """z' = (u' - H(z . u') |z|^(n - 2) (z . u') z) / D_y [1/s] (Park, Wen and Ang 1986)."""
    _, _, dzx, dzy, _ = hysteretic_force_scalar(xd, yd, sx, sy, p[0], p[1], p[2], p[3], p[4])
    return dzx, dzy


register(Law("bidirectional_hysteresis", PLANE, (
    LawParameter("strength", "N", 0.0, doc="Q at high velocity (Q_d; mu_fast W)"),
    LawParameter("strength_at_rest", "N", 0.0, doc="Q at rest (= strength for a bilinear bearing; mu_slow W)"),
    LawParameter("rate", "s/m", 0.0, default=0.0, doc="a of mu(v) = mu_fast - (mu_fast - mu_slow) exp(-a |v|)"),
    LawParameter("yield_displacement", "m", 1e-12, doc="D_y"),
    LawParameter("exponent", "-", 2.0, 50.0, doc="n"),
    LawParameter("initial_zx", "-", -1.0, 1.0, default=0.0), LawParameter("initial_zy", "-", -1.0, 1.0, default=0.0)),
    bidirectional_hysteresis_force,
    "The baseline isolators' hysteretic part (a lead-rubber bearing: Q = Q_d; a friction pendulum: Q = mu W; "
    "Park, Wen and Ang 1986, evaluated by nsd_core.device.isolator_laws.hysteretic_force_scalar): on the "
    "planar displacement u = (x, y) [m], (Q_x, Q_y) = -Q(|u'|) z [N], D_y z' = u' - H(z . u') |z|^(n-2) "
    "(z . u') z [1/s], Q(v) = Q_fast - (Q_fast - Q_rest) exp(-a v) [N] (a [s/m]; a = 0: Q = Q_rest). A plane "
    "law because z couples the two directions (z_x' depends on z_y and y'): two scalar joint laws cannot "
    "express it",
    StateSpec("z", "-", "initial_zx,initial_zy"), bidirectional_hysteresis_rate))
