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
one ``register`` call) reaches all three engines. This module holds the generic laws; the device
registers its own (rope, SMA wire, push spring, restrainer stop: nsd_core.device.laws) and the
isolated structure the baseline isolators' (nsd_core.structure.isolator_laws), as a user registers a
law, when their package is imported.

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
        hint = "" if "rope" in LAWS else " (the device's and the isolators' laws join when nsd_core.device and nsd_core.structure are imported)"
        raise ModelError(f"{where}.law = {name!r}: unknown; allowed: {', '.join(sorted(LAWS))}{hint}")
    return LAWS[name]


# ---- the laws ---------------------------------------------------------------------------------------

@njit(cache=True, _nrt=False)
def linear_spring_damper(x, xd, p):
    """T = k (L - L0) + c L' + T0: a linear spring of stiffness k [N/m] and free length L0 [m], a
    dashpot c [N s/m] and a preload T0 [N] (as Andrews' spring c0, l0; any strut)."""
    return p[0] * (x - p[2]) + p[1] * xd + p[3]


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
register(Law("constant_force", JOINT, (LawParameter("value", "N or N m", -INF, doc="Q0"),),
             constant_force, constant_force.py_func.__doc__))
register(Law("joint_spring_damper", JOINT, (
    LawParameter("stiffness", "N/m or N m/rad", 0.0), LawParameter("damping", "N s/m or N m s/rad", 0.0, default=0.0),
    LawParameter("neutral", "m or rad", -INF, default=0.0)),
    joint_spring_damper, joint_spring_damper.py_func.__doc__))
