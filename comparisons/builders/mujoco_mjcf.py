"""The MJCF text of a model description, for comparisons.builders.mujoco (no per-mechanism code).

- Bodies nest as the description's parent tree; a body's frame sits at its joint's ``position`` in
  the parent's frame (``<body pos>``) and its joint becomes one MuJoCo joint per coordinate, in the
  order of ``Joint.dofs()``: ``hinge`` for 'R', ``slide`` for 'P', all anchored at the body's origin.
  MuJoCo applies the joints of one body one after the other, each axis turned by the earlier ones,
  which is exactly the description's convention (universal: q1 then q2 about the turned axis2;
  planar: two slides, then the turn). A spherical joint is three hinges (x, then turned y, then turned
  z), not a ball joint: its coordinates are then the description's own (outputs, joint laws and
  prescribed motions address them directly, no quaternion-to-angle conversion) and the in-house engine
  has the same three-turn chain, with the same singularity at q2 = +-90 deg.
- Inertial: mass at ``com``, the full inertia tensor about it (its principal moments and axes, ``principal``). MuJoCo rejects a
  principal moment below ~1e-15 kg m^2 (a point mass); such a moment is raised to ``inertia_floor``
  [kg m^2] (only those below it; the default 1e-12 changes A01's moment about the pivot, 1 kg m^2, by
  1e-12 relative, far below any step's error). Moments above the floor are passed unchanged.
- Loop closures: a ``point`` loop is an equality ``connect`` between two sites (the two body points,
  a ground point being a world site), which keeps them coincident. A ``revolute`` loop is two
  connects: at the points, and at the points moved by ``arm`` along each body's axis (the axes'
  directions as they are at t = 0, so an axis given opposite on the two sides still pairs). Two
  coincident points on each axis hold exactly the revolute closure's conditions (the point and the
  axis direction); the sixth scalar equation is redundant (turning about the axis), which MuJoCo's
  soft, regularised constraints accept. ``arm`` is the mechanism's size (the largest joint position or
  loop point, at least 1 mm), so the angular condition weighs like the positional one.
- A force law's internal state (``Law.state``: a hysteretic stress, a Bouc-Wen zeta) is an activation
  of one zero-force ``general`` actuator with ``dyntype="user"`` and one activation per state
  (``actdim``): MuJoCo integrates them with the motion (RK4 stages included);
  comparisons.builders.mujoco writes their rates into ``act_dot`` from ``mjcb_act_dyn``.
- Prescribed coordinates get a large ``armature`` (a heavy virtual drive; comparisons.builders.mujoco
  explains the drive); contacts are disabled (a description has no geometry).
"""
from __future__ import annotations

import mujoco
import numpy as np

from nsd_core.model.description import GROUND, Model


def _f(x) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(x))


def joint_name(body: str, dof: int) -> str:
    return f"{body}:{dof}"


def floored_inertia(J: np.ndarray, floor: float) -> np.ndarray:
    """``J`` with its principal moments below ``floor`` raised to it (axes kept)."""
    w, V = np.linalg.eigh(np.asarray(J, dtype=float))
    if w.min() >= floor:
        return np.asarray(J, dtype=float)
    return (V * np.maximum(w, floor)) @ V.T


def principal(J) -> str:
    """A full tensor as its principal moments (on the triangle, ``on_triangle``) and axes (``quat``):
    MuJoCo's own eigen-decomposition of a ``fullinertia`` can put a body whose moments lie on the
    triangle inequality (a thin plate turned in its plane, [1, 1, 2, 0.3, 0, 0]) a rounding outside it,
    and then refuses the model."""
    w, V = np.linalg.eigh(np.asarray(J, float))
    if np.linalg.det(V) < 0:
        V[:, 2] = -V[:, 2]
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, V.flatten())
    return f'diaginertia="{_f(on_triangle(w))}" quat="{_f(quat)}"'


def on_triangle(moments) -> list[float]:
    """Principal moments that meet the triangle inequality up to rounding (a plate written in decimals,
    Izz = Ixx + Iyy, can miss it by 1e-19 kg m^2), moved onto it: MuJoCo rejects A + B < C exactly. A
    real violation (the description's loader allows 1e-12 of the largest) is left for MuJoCo to say."""
    m = [float(x) for x in moments]
    for i, j, k in ((0, 1, 2), (1, 2, 0), (0, 2, 1)):
        if m[i] + m[j] < m[k] <= (m[i] + m[j]) * (1.0 + 1e-12):
            m[k] = m[i] + m[j]
    return m


def mechanism_size(model: Model) -> float:
    """The largest joint offset or loop point [m] (at least 1 mm): the arm of a revolute closure."""
    lengths = [np.linalg.norm(b.joint.position) for b in model.bodies]
    lengths += [np.linalg.norm(p) for lp in model.loops for p in (lp.point_a, lp.point_b)]
    return max([1e-3] + lengths)


def connects(model: Model, rotation: dict) -> list[tuple[str, str, np.ndarray, str, np.ndarray]]:
    """Every equality connect as (name, body_a, point_a, body_b, point_b); ``rotation`` maps a body to
    its world rotation at t = 0 (the initial state), which orients a revolute loop's second pair."""
    out, arm = [], mechanism_size(model)
    for lp in model.loops:
        pa, pb = np.asarray(lp.point_a, float), np.asarray(lp.point_b, float)
        out.append((lp.name, lp.body_a, pa, lp.body_b, pb))
        if lp.type == "revolute":
            ua = np.asarray(lp.axis_a, float) / np.linalg.norm(lp.axis_a)
            ub = np.asarray(lp.axis_b, float) / np.linalg.norm(lp.axis_b)
            Ra = rotation.get(lp.body_a, np.eye(3))
            Rb = rotation.get(lp.body_b, np.eye(3))
            sign = 1.0 if float((Ra @ ua) @ (Rb @ ub)) >= 0.0 else -1.0
            out.append((f"{lp.name}:axis", lp.body_a, pa + arm * ua, lp.body_b, pb + sign * arm * ub))
    return out


STATES = "states"   # the actuator whose activations are the laws' states


def state_slots(model: Model) -> dict[str, int]:
    """Each force element with a state -> its (first) index among the states actuator's activations (a
    plane law's state takes two, x first: Law.state_size)."""
    out, k = {}, 0
    for f in model.forces:
        if f.law.state is not None:
            out[f.name], k = k, k + f.law.state_size
    return out


def n_states(model: Model) -> int:
    """How many activations the states actuator has."""
    return sum(f.law.state_size for f in model.forces)


def state_activations(model: Model, m) -> dict[str, int]:
    """Each force element with a state -> the index of its activation in mjData.act (m: the MjModel)."""
    slots = state_slots(model)
    return {k: int(m.actuator_actadr[m.actuator(STATES).id]) + v for k, v in slots.items()} if slots else {}


def build_mjcf(model: Model, s: dict, h: float, rotation: dict, armature: dict, nuserdata: int = 0) -> str:
    """The MJCF of ``model`` at step ``h`` with settings ``s``; ``armature`` maps a prescribed
    coordinate (body, dof) to its virtual drive inertia [kg or kg m^2]; ``nuserdata`` float64 slots of
    mjData.userdata hold the compiled callback's numbers (comparisons.builders.mujoco_codegen)."""
    children: dict[str, list] = {GROUND: []}
    for b in model.bodies:
        children.setdefault(b.name, [])
        children[b.parent].append(b)
    pairs = connects(model, rotation)
    sites: dict[str, list[str]] = {}
    for name, ba, pa, bb, pb in pairs:
        sites.setdefault(ba, []).append(f'<site name="{name}:a" pos="{_f(pa)}"/>')
        sites.setdefault(bb, []).append(f'<site name="{name}:b" pos="{_f(pb)}"/>')

    def body_xml(b, indent: str) -> list[str]:
        J = floored_inertia(b.inertia, float(s["inertia_floor"]))
        full = (J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2])
        # a diagonal tensor goes as it is written: MuJoCo's eigen-decomposition of a fullinertia can put a
        # plate's Izz = Ixx + Iyy (the description's advice for planar bodies) a rounding below the
        # triangle inequality it then enforces
        given = f'diaginertia="{_f(on_triangle(full[:3]))}"' if not any(full[3:]) else principal(J)
        lines = [f'{indent}<body name="{b.name}" pos="{_f(b.joint.position)}">',
                 f'{indent}  <inertial pos="{_f(b.com)}" mass="{_f(b.mass)}" {given}/>']
        for k, (kind, axis) in enumerate(b.joint.dofs()):
            extra = f' armature="{_f(armature[(b.name, k)])}"' if (b.name, k) in armature else ""
            lines.append(f'{indent}  <joint name="{joint_name(b.name, k)}" type="{"hinge" if kind == "R" else "slide"}" '
                         f'pos="0 0 0" axis="{_f(axis)}"{extra}/>')
        lines += [f"{indent}  {x}" for x in sites.get(b.name, [])]
        for c in children[b.name]:
            lines += body_xml(c, indent + "  ")
        return lines + [f"{indent}</body>"]

    world = [f"    {x}" for x in sites.get(GROUND, [])]
    for b in children[GROUND]:
        world += body_xml(b, "    ")
    solref = f"{_f(s['solref_factor'] * h)} {_f(s['solref_dampratio'])}"
    # the laws' internal states are MuJoCo activations (dyntype "user": their rates come from
    # mjcb_act_dyn), so that MuJoCo's own integrator advances them with the motion; the actuator's force
    # is zero. All of them in one actuator (actdim = their count): five one-state actuators cost the
    # device's mj_forward ~0.5 us of ~4 us; one costs nothing measurable
    na = n_states(model)
    acts = [f'    <general name="{STATES}" joint="{joint_name(model.bodies[0].name, 0)}" dyntype="user" '
            f'actdim="{na}" gaintype="fixed" gainprm="0" biastype="none" actlimited="false"/>'] if na else []
    eq = [f'    <connect name="{name}" site1="{name}:a" site2="{name}:b" solref="{solref}" solimp="{_f(s["solimp"])}"/>'
          for name, *_ in pairs]
    return "\n".join([
        f'<mujoco model="{model.name}">',
        '  <compiler inertiafromgeom="false"/>',
        *([f'  <size nuserdata="{int(nuserdata)}"/>'] if nuserdata else []),
        f'  <option timestep="{_f(h)}" integrator="{s["integrator"]}" gravity="{_f(model.gravity)}" solver="Newton" '
        f'tolerance="{_f(s["solver_tolerance"])}" iterations="{int(s["solver_iterations"])}" jacobian="dense">',
        '    <flag contact="disable"/>',
        '  </option>',
        '  <worldbody>', *world, '  </worldbody>',
        *(['  <equality>', *eq, '  </equality>'] if eq else []),
        *(['  <actuator>', *acts, '  </actuator>'] if acts else []),
        '</mujoco>', ""])
