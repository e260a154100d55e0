"""A mechanism described as data: bodies on a tree of joints, loop closures, force elements whose laws
come from one registry (nsd_core.model.laws), prescribed motions, and named outputs.

The conventions every builder follows (docs/models.md):
- each body hangs on its parent ("ground" or another body) by one joint; the body's frame sits at the
  joint's ``position`` (given in the parent's frame) and is parallel to the parent's frame when the
  joint's coordinates are zero. Centres of mass, inertias and points are in the body's frame;
- a joint's coordinates, in order: revolute q about ``axis``; prismatic q along ``axis``; universal
  q1 about ``axis``, then q2 about ``axis2`` (turned by q1); spherical three turns about x, then the
  turned y, then the turned z; planar two slides along u, v (u, v, normal right-handed), then a turn
  about ``normal``; planar_translation the two slides alone (u: the parent's x projected onto the
  plane, its y when the normal is along x; v = normal x u); translational three slides along the
  parent's x, y, z;
- a loop closure (``point``: two body points coincide; ``revolute``: they coincide and two body axes
  stay parallel) cuts a closed chain; ``ground`` can be either side;
- a points force element acts along the line between its points, or, with a ``direction`` e (in the
  ground's frame), along e: x = (p_a - p_b) . e, its rate likewise, and the tension T pulls a by -T e
  and b by +T e (a per-direction spring: a shear building's story);
- a plane force element (a law acting on a planar displacement) acts on two slide coordinates of one
  joint, ``dofs = [i, j]``: x = q_i, y = q_j, and returns the generalized forces on both; its state
  (when it has one) has two components, x first;
- an excitation (``[excitation]``, nsd_core.model.excitation) moves the frame with the ground: every
  body feels -m a_g(t) besides gravity, i.e. the uniform field g - a_g(t);
- outputs are in the file's frame (relative to the ground when it moves), except
  ``point_acceleration``: the absolute (inertial) acceleration, the frame's relative one plus a_g(t);
- ``work``: the work done on the mechanism since t = 0, integral of the power over the run: of a force
  element (a points law: -T x', its tension against its x's rate; a joint law: Q q'), of the excitation
  (sum over the bodies of -m a_g(t) . v_com, v relative to the moving frame) or of the drives (each
  prescribed motion's drive force times q'(t)); kinetic + gravity energy less every work is constant;
- SI units everywhere: m, kg, kg m^2, s, rad, N, N m.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nsd_core.model.errors import ModelError
from nsd_core.model.laws import JOINT, POINTS, Law

GROUND = "ground"
JOINT_DOFS = {"revolute": 1, "prismatic": 1, "universal": 2, "spherical": 3, "planar": 3, "planar_translation": 2,
              "translational": 3}
OUTPUT_KINDS = ("coordinate", "point", "point_velocity", "point_acceleration", "force", "drive_force", "energy",
                "state", "work")
WORK_SOURCES = ("excitation", "drive")   # a work output's loads other than a force element's
MOTION_KINDS = {"constant_speed": ("start", "speed"), "harmonic": ("centre", "amplitude", "frequency", "phase")}
MOTION_PARSERS: dict = {}   # a registered motion kind's parse(where, table) -> values (register_motion)
COMPONENTS = {"x": 0, "y": 1, "z": 2}


def register_motion(kind: str, fields: tuple, parse) -> None:
    """Add a prescribed-motion kind (the device registers its plate path, "device_path"): ``fields``
    are its table's keys; ``parse(where, table)`` checks them (ModelError naming the field) and returns
    the motion's values, whose ``"motion"`` is q(t) -> (q, q', q'') [the joint's units], with
    ``table(times)`` -> 3 x len(times) for many times at once."""
    if kind in MOTION_KINDS:
        raise ValueError(f"motion {kind!r} is already registered")
    MOTION_KINDS[kind] = fields
    MOTION_PARSERS[kind] = parse


def unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


@dataclass(frozen=True)
class Joint:
    type: str
    position: tuple          # the child's frame origin, in the parent's frame [m]
    axis: tuple = (0.0, 0.0, 1.0)   # revolute, prismatic, universal's first axis, planar's normal
    axis2: tuple = (0.0, 1.0, 0.0)  # universal's second axis

    def dofs(self) -> list[tuple[str, np.ndarray]]:
        """The joint as a chain of one-coordinate joints: ('R' or 'P', unit axis in the frame turned by
        the earlier ones), in coordinate order."""
        a = unit(self.axis)
        if self.type == "revolute":
            return [("R", a)]
        if self.type == "prismatic":
            return [("P", a)]
        if self.type == "universal":
            return [("R", a), ("R", unit(self.axis2))]
        if self.type == "spherical":
            return [("R", np.eye(3)[0]), ("R", np.eye(3)[1]), ("R", np.eye(3)[2])]
        if self.type == "translational":
            return [("P", np.eye(3)[0]), ("P", np.eye(3)[1]), ("P", np.eye(3)[2])]
        u, v = plane_axes(a)
        if self.type == "planar_translation":
            return [("P", u), ("P", v)]
        return [("P", u), ("P", v), ("R", a)]   # planar


def plane_axes(normal) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) of a plane: u the x axis projected onto it (y when the normal is along x), v = n x u;
    a plane normal to z has u = x, v = y."""
    n = unit(normal)
    e = np.eye(3)[0] if abs(n[0]) < 0.9 else np.eye(3)[1]
    u = e - (e @ n) * n
    u /= np.linalg.norm(u)
    return u, np.cross(n, u)


@dataclass(frozen=True)
class Body:
    name: str
    parent: str
    joint: Joint
    mass: float              # kg
    com: tuple               # m, body frame
    inertia: np.ndarray      # 3x3 about the centre of mass, body axes [kg m^2]
    source: str = ""


@dataclass(frozen=True)
class Loop:
    name: str
    type: str                # "point" or "revolute"
    body_a: str
    point_a: tuple
    body_b: str
    point_b: tuple
    axis_a: tuple = (0.0, 0.0, 1.0)
    axis_b: tuple = (0.0, 0.0, 1.0)


@dataclass(frozen=True)
class ForceElement:
    name: str
    law: Law
    parameters: np.ndarray   # packed in the law's order
    given: dict              # as written, with units from the law
    body_a: str = GROUND     # points laws: from point_a on body_a to point_b on body_b
    point_a: tuple = (0.0, 0.0, 0.0)
    body_b: str = GROUND
    point_b: tuple = (0.0, 0.0, 0.0)
    joint: str = ""          # joint laws: the body whose joint, and which of its coordinates
    dof: int = 0
    direction: tuple | None = None   # points laws: act along this unit vector (ground frame), not the line
    dofs: tuple = ()         # plane laws: the joint's two slide coordinates (x, y), dof = dofs[0]

    def force(self, x: float, xd: float, s: float = 0.0) -> float:
        """The law's force at (x, x') (and its state s, for a law with one)."""
        if self.law.state is None:
            return float(self.law.force(float(x), float(xd), self.parameters))
        return float(self.law.force(float(x), float(xd), float(s), self.parameters))

    def rate(self, x: float, xd: float, s: float) -> float:
        """ds/dt of the law's state (a law with a state only)."""
        return float(self.law.rate(float(x), float(xd), float(s), self.parameters))

    @property
    def initial_state(self) -> float:
        return self.law.initial_state(self.parameters)

    @property
    def initial_states(self) -> tuple:
        """The state's components at t = 0 (a plane law's two, x first)."""
        return self.law.initial_states(self.parameters)

    def plane_force(self, x, y, xd, yd, sx=0.0, sy=0.0) -> tuple[float, float]:
        """A plane law's generalized forces (Q_x, Q_y) at the displacement (x, y), its rate and its state."""
        qx, qy = self.law.force(float(x), float(y), float(xd), float(yd), float(sx), float(sy), self.parameters)
        return float(qx), float(qy)

    def plane_rate(self, x, y, xd, yd, sx, sy) -> tuple[float, float]:
        """d(s_x, s_y)/dt of a plane law's state."""
        rx, ry = self.law.rate(float(x), float(y), float(xd), float(yd), float(sx), float(sy), self.parameters)
        return float(rx), float(ry)


@dataclass(frozen=True)
class Prescribed:
    """A joint coordinate moved as a function of time (the drive): q(t), q'(t), q''(t)."""
    name: str
    joint: str
    dof: int
    kind: str
    values: dict

    def __call__(self, t: float) -> tuple[float, float, float]:
        v = self.values
        if "motion" in v:   # a registered kind (register_motion)
            return v["motion"](t)
        if self.kind == "constant_speed":
            return v["start"] + v["speed"] * t, v["speed"], 0.0
        w = 2.0 * math.pi * v["frequency"]
        s, c = math.sin(w * t + v["phase"]), math.cos(w * t + v["phase"])
        return v["centre"] + v["amplitude"] * s, v["amplitude"] * w * c, -v["amplitude"] * w * w * s

    def table(self, times) -> np.ndarray:
        """(q, q', q'') at every time of ``times``: 3 x len(times), at each time the floats of the call
        at that time (a registered motion's own ``table``; the closed forms time by time)."""
        motion = self.values.get("motion")
        if motion is not None and hasattr(motion, "table"):
            return motion.table(np.asarray(times, dtype=float))
        return np.array([self(t) for t in np.asarray(times, dtype=float).tolist()], dtype=float).reshape(-1, 3).T


@dataclass(frozen=True)
class Output:
    name: str
    kind: str
    body: str = ""
    point: tuple = (0.0, 0.0, 0.0)
    component: int = 0
    dof: int = 0
    element: str = ""        # force, state, work: a force element; drive_force: a prescribed motion
    source: str = ""         # work: "excitation" or "drive" (every prescribed motion's) instead of an element
    term: str = ""           # energy: kinetic or gravity
    tolerance: float = 1e-3  # engineering tolerance, a fraction of the scale
    scale: float = 0.0       # the quantity's scale [its unit]; 0: the reference's peak |value|
    unit: str = ""


@dataclass(frozen=True)
class Model:
    name: str
    source: str
    gravity: tuple
    bodies: tuple[Body, ...]
    loops: tuple[Loop, ...]
    forces: tuple[ForceElement, ...]
    prescribed: tuple[Prescribed, ...]
    outputs: tuple[Output, ...]
    initial_coordinates: dict = field(default_factory=dict)   # (body, dof) -> value
    initial_velocities: dict = field(default_factory=dict)
    free: tuple = ()                                         # (body, dof) kept independent
    path: str = ""
    excitation: object = None    # nsd_core.model.excitation.Excitation, or None: the frame is inertial

    def gravity_at(self, t: float) -> np.ndarray:
        """The uniform field every body feels at t [m/s^2]: gravity, less the ground's acceleration."""
        if self.excitation is None:
            return np.asarray(self.gravity, dtype=float)
        return self.excitation.gravity(self.gravity, t)

    def body(self, name: str) -> Body:
        return next(b for b in self.bodies if b.name == name)

    def coordinates(self) -> list[tuple[str, int]]:
        """Every joint coordinate (body, dof), bodies in file order (parents first)."""
        return [(b.name, k) for b in self.bodies for k in range(JOINT_DOFS[b.joint.type])]

    def coordinate_unit(self, body: str, dof: int) -> str:
        return "rad" if self.body(body).joint.dofs()[dof][0] == "R" else "m"
