"""A description's equations of motion derived symbolically: Kane's method (sympy.physics.mechanics)
on the open tree, the loop closures as holonomic constraint equations, and every point a law, a loop
or an output names, each as an expression of the joint coordinates.

What is derived (n joint coordinates q, their rates u = q'; effective field g = (g_x, g_y, g_z), the
gravity less the ground's acceleration, a symbol so that one derivation serves any excitation):
- the tree's mass matrix M(q) and forcing F(q, u, g) from ``KanesMethod``: M u' = F + Q holds for the
  tree, Q every other generalised force (the laws', the loops', the drives');
- the loop closures Phi(q) = 0 (a ``point`` loop: p_a - p_b, three rows in the ground's frame; a
  ``revolute`` loop adds two rows n_i . axis_b, n_1, n_2 perpendicular to axis_a in body a), their
  Jacobian Phi_q and the velocity product gamma = (Phi_q u)_q u, so that Phi'' = Phi_q u' + gamma;
- each named point's position r(q) in the ground's frame, its Jacobian J = r_q (its velocity J u)
  and, for an acceleration output, J' u = (J u)_q u (its acceleration J u' + J' u).

Each body's frame follows the joint's chain of one-coordinate joints (``Joint.dofs``: turns about
axes of the frame turned so far, slides along them), from the parent's frame at the joint's
``position``. Numbers of the description enter as floats (exact doubles); the only symbols are q, u
and g. Nothing here is shared with the in-house engine's kinematics or dynamics.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp
from sympy.physics import mechanics as me

from nsd_core.model.description import GROUND, Model

TINY = 1e-300


def number(x: float):
    """A description's number as sympy holds it: an integer when it is one (clean trigonometry), else a Float."""
    x = float(x)
    return sp.Integer(int(x)) if x == int(x) and abs(x) < 1e15 else sp.Float(x)


def vector(v, frame):
    """Components v in ``frame`` as a sympy vector (zero components left out)."""
    out = sp.S.Zero * frame.x
    for c, e in zip(v, (frame.x, frame.y, frame.z)):
        if float(c) != 0.0:
            out = out + number(c) * e
    return out


@dataclass
class Tree:
    """The sympy objects of a description's tree."""
    N: object                 # the ground's frame
    O: object                 # the ground's origin
    frames: dict              # body -> ReferenceFrame
    origins: dict             # body -> Point (the body frame's origin)
    q: list                   # dynamicsymbols, one per coordinate, in Model.coordinates() order
    u: list
    coordinates: list         # (body, dof) per coordinate


def build_tree(model: Model) -> Tree:
    """Frames and points of every body, from the description's joints."""
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    coords = model.coordinates()
    q = list(me.dynamicsymbols(f"q0:{len(coords)}")) if coords else []
    u = list(me.dynamicsymbols(f"u0:{len(coords)}")) if coords else []
    index = {c: i for i, c in enumerate(coords)}
    frames, origins = {GROUND: N}, {GROUND: O}
    t = me.dynamicsymbols._t
    for b in model.bodies:
        parent = frames[b.parent]
        frame, shift, slide = parent, vector(b.joint.position, parent), sp.S.Zero * parent.x
        for k, (kind, axis) in enumerate(b.joint.dofs()):
            qi = q[index[(b.name, k)]]
            if kind == "P":   # the format's slides come before its turns: along the parent's axes
                shift = shift + qi * vector(axis, frame)
                slide = slide + sp.diff(qi, t) * vector(axis, frame)
            else:
                turned = me.ReferenceFrame(f"F_{len(frames)}_{k}")
                turned.orient_axis(frame, vector(axis, frame), qi)
                frame = turned
        frames[b.name] = frame
        origin = origins[b.parent].locatenew(f"P_{b.name}", shift)
        # the velocity by the rigid parent's transfer (compact expressions in mixed frames, not N's)
        origin.set_vel(parent, slide)
        origin.v1pt_theory(origins[b.parent], N, parent)
        origins[b.name] = origin
    return Tree(N, O, frames, origins, q, u, coords)


def position(tree: Tree, body: str, point) -> sp.Matrix:
    """A body point's position in the ground's frame, a 3-vector of expressions of q."""
    p = tree.origins[body].pos_from(tree.O) + vector(point, tree.frames[body])
    return p.to_matrix(tree.N) if p != 0 else sp.zeros(3, 1)


def kane(model: Model, tree: Tree, g: list) -> tuple[sp.Matrix, sp.Matrix]:
    """The tree's mass matrix and forcing by Kane's method, u = q' (M u' = F)."""
    bodies, loads = [], []
    for b in model.bodies:
        frame = tree.frames[b.name]
        com = tree.origins[b.name].locatenew(f"G_{b.name}", vector(b.com, frame))
        com.v2pt_theory(tree.origins[b.name], tree.N, frame)
        J = np.asarray(b.inertia, dtype=float)
        inertia = me.inertia(frame, number(J[0, 0]), number(J[1, 1]), number(J[2, 2]),
                             number(J[0, 1]), number(J[1, 2]), number(J[0, 2]))
        m = number(b.mass)
        bodies.append(me.RigidBody(f"B_{b.name}", com, frame, m, (inertia, com)))
        loads.append((com, m * (g[0] * tree.N.x + g[1] * tree.N.y + g[2] * tree.N.z)))
    qd = [sp.diff(qi, me.dynamicsymbols._t) for qi in tree.q]
    km = me.KanesMethod(tree.N, q_ind=tree.q, u_ind=tree.u, kd_eqs=[a - b for a, b in zip(qd, tree.u)])
    km.kanes_equations(bodies, loads)
    return km.mass_matrix, km.forcing


def loop_rows(model: Model, tree: Tree) -> list:
    """Phi(q): every loop's closure equations (rows identically zero are left out: a planar loop's
    out-of-plane row)."""
    rows = []
    for lp in model.loops:
        d = position(tree, lp.body_a, lp.point_a) - position(tree, lp.body_b, lp.point_b)
        rows += list(d)
        if lp.type == "revolute":
            a = np.asarray(lp.axis_a, dtype=float) / np.linalg.norm(lp.axis_a)
            e = np.eye(3)[int(np.argmin(np.abs(a)))]
            n1 = np.cross(a, e)
            n1 /= np.linalg.norm(n1)
            n2 = np.cross(a, n1)
            axis_b = vector(lp.axis_b, tree.frames[lp.body_b])
            rows += [vector(n, tree.frames[lp.body_a]).dot(axis_b) for n in (n1, n2)]
    return [r for r in rows if sp.expand(r) != 0]


@dataclass
class Derivation:
    """Every derived expression, in the plain symbols q0.., u0.., gx, gy, gz."""
    n: int
    q: list
    u: list
    g: list
    M: sp.Matrix
    F: sp.Matrix
    Phi: sp.Matrix
    Phi_q: sp.Matrix
    gamma: sp.Matrix
    points: list              # (body, point) in order
    R: list                   # per point: 3-vector r(q)
    J: list                   # per point: 3 x n
    Jdu: list                 # per point: 3-vector J' u, or None where no acceleration is asked
    coordinates: list


def named_points(model: Model) -> tuple[list, set]:
    """Every (body, point) a points law, an output or an energy term needs (centres of mass included),
    and those whose acceleration an output asks."""
    pts = []

    def add(body, point):
        key = (body, tuple(float(c) for c in point))
        if key not in pts:
            pts.append(key)
        return key
    for f in model.forces:
        if f.law.acts_on == "points":
            add(f.body_a, f.point_a)
            add(f.body_b, f.point_b)
    accel = set()
    for o in model.outputs:
        if o.kind in ("point", "point_velocity", "point_acceleration"):
            k = add(o.body, o.point)
            if o.kind == "point_acceleration":
                accel.add(k)
    for b in model.bodies:
        add(b.name, b.com)
    return pts, accel


def derive(model: Model) -> Derivation:
    """The description's equations of motion and kinematics (see the module's docstring)."""
    tree = build_tree(model)
    n = len(tree.q)
    gs = list(sp.symbols("gx gy gz"))
    qs, us = list(sp.symbols(f"q0:{n}")), list(sp.symbols(f"u0:{n}"))
    t = me.dynamicsymbols._t
    plain = {**{sp.diff(a, t): b for a, b in zip(tree.q, us)}, **dict(zip(tree.u, us)), **dict(zip(tree.q, qs))}

    def to_plain(e):
        return sp.Matrix(e).xreplace({k: v for k, v in plain.items() if isinstance(k, sp.Derivative)}).xreplace(
            {k: v for k, v in plain.items() if not isinstance(k, sp.Derivative)})
    M, F = kane(model, tree, gs)
    M, F = to_plain(M), to_plain(F)
    Phi = to_plain(sp.Matrix(loop_rows(model, tree))) if model.loops else sp.zeros(0, 1)
    Phi_q = Phi.jacobian(qs) if Phi.shape[0] else sp.zeros(0, n)
    uv = sp.Matrix(us)
    gamma = (Phi_q * uv).jacobian(qs) * uv if Phi.shape[0] else sp.zeros(0, 1)
    pts, accel = named_points(model)
    R, J, Jdu = [], [], []
    for body, point in pts:
        r = to_plain(position(tree, body, point)) if body != GROUND else sp.Matrix([number(c) for c in point])
        Jp = r.jacobian(qs)
        R.append(r)
        J.append(Jp)
        Jdu.append((Jp * uv).jacobian(qs) * uv if (body, point) in accel else None)
    return Derivation(n, qs, us, gs, M, F, Phi, Phi_q, gamma, pts, R, J, Jdu, tree.coordinates)


def operations(d: Derivation) -> dict:
    """Expression sizes (sympy's operation count) of the derived quantities."""
    def ops(m):
        return int(sum(sp.count_ops(e) for e in m)) if m is not None else 0
    return {"mass_matrix": ops(d.M), "forcing": ops(d.F), "constraints": ops(d.Phi) + ops(d.Phi_q) + ops(d.gamma),
            "points": sum(ops(r) + ops(j) + ops(a) for r, j, a in zip(d.R, d.J, d.Jdu))}
