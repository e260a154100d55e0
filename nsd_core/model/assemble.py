"""A description on the in-house engine's terms (the mechanism as parent array and 1-DOF joints), and
the consistent initial state every engine starts from.

Multi-coordinate joints become chains of one-coordinate joints through massless auxiliary bodies
(the paper's Figure 4), named ``body.0``, ``body.1``, ...; the described body is the chain's last
member and carries the mass. Loop closures become cut joints (Eq. 13).

``initial_state`` closes the loops once, at t = 0, from the description's initial coordinates (the
free ones as given, the dependent ones by Newton from the given guess) and makes the velocities
consistent (the free ones as given, the dependent ones from Phi_z z' = 0). Every engine starts from
this state: the initial conditions are input data, shared so that differences between the engines
are differences in their dynamics, not in where they start. A given coordinate or velocity the loops
do not allow is reported as bad input.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from nsd_core.engine.compiled_model import split_state
from nsd_core.engine.elements import AxialElements
from nsd_core.engine.mechanism import Cut, Mechanism, mechanism, revolute_cut
from nsd_core.engine.semirecursive import SemiRecursiveSystem
from nsd_core.model.description import GROUND, JOINT_DOFS, Model
from nsd_core.model.errors import ModelError
from nsd_core.model.laws import JOINT, PLANE, POINTS

ASSEMBLY_TOL = 1e-9   # m or rad: a closure residual above this after Newton means the loops cannot close


@dataclass(frozen=True)
class Tree:
    """The description as the in-house engine's mechanism, with the maps between the two."""
    mech: Mechanism
    coordinate: dict     # (body, dof) -> engine coordinate index
    body: dict           # body name -> engine body index (ground -1)
    prescribed: list     # engine indices of the prescribed coordinates, in the description's order


def to_tree(model: Model) -> Tree:
    rows, coordinate, body_index = [], {}, {GROUND: -1}
    for b in model.bodies:
        dofs = b.joint.dofs()
        parent = body_index[b.parent]   # the parent's last chain member (a described body's own index)
        for k, (kind, axis) in enumerate(dofs):
            last = k == len(dofs) - 1
            row = dict(name=b.name if len(dofs) == 1 else f"{b.name}.{k}", parent=None if parent < 0 else parent,
                       joint=kind, axis=tuple(axis), offset=b.joint.position if k == 0 else (0.0, 0.0, 0.0))
            if last:
                row.update(mass=b.mass, com=b.com, inertia=b.inertia)
            coordinate[(b.name, k)] = len(rows)
            parent = len(rows)
            rows.append(row)
        body_index[b.name] = len(rows) - 1

    def ref(body):
        return body_index[body]
    cuts = []
    for lp in model.loops:
        if lp.type == "point":
            cuts.append(Cut("point", ref(lp.body_a), lp.point_a, ref(lp.body_b), lp.point_b, lp.name))
        else:
            cuts += revolute_cut(ref(lp.body_a), lp.point_a, lp.axis_a, ref(lp.body_b), lp.point_b, lp.axis_b, lp.name)
    mech = mechanism(rows, cuts, gravity=model.gravity)
    return Tree(mech, coordinate, body_index, [coordinate[(p.joint, p.dof)] for p in model.prescribed])


@dataclass(frozen=True)
class InitialState:
    """Where every engine starts: each coordinate and rate, and each described body's world pose."""
    q: dict          # (body, dof) -> coordinate [m or rad]
    qd: dict         # (body, dof) -> rate
    rotation: dict   # body -> 3x3 world rotation of its frame
    origin: dict     # body -> world position of its frame's origin [m]
    velocity: dict   # body -> world velocity of its frame's origin [m/s]
    omega: dict      # body -> world angular velocity [rad/s]


class Forces:
    """The description's force elements on the in-house engine: every law through the registry. The
    states of the laws that have one (``stateful``, in the description's order) are the ODE's extra
    states. A description with an excitation adds -m a_g(t) at every body's centre of mass."""

    def __init__(self, model: Model, tree: Tree):
        pts = [f for f in model.forces if f.law.acts_on == POINTS]
        self.points, self.n = pts, tree.mech.n
        self.joints = [(f, tree.coordinate[(f.joint, f.dof)]) for f in model.forces if f.law.acts_on == JOINT]
        # plane laws: (element, engine index of its x coordinate, of its y coordinate)
        self.planes = [(f, tree.coordinate[(f.joint, f.dofs[0])], tree.coordinate[(f.joint, f.dofs[1])])
                       for f in model.forces if f.law.acts_on == PLANE]
        self.elements = AxialElements([tree.body[f.body_a] for f in pts], [f.point_a for f in pts],
                                      [tree.body[f.body_b] for f in pts], [f.point_b for f in pts], tree.mech.n)
        self.directed = [(j, tree.body[f.body_a], tree.body[f.body_b], np.asarray(f.direction))
                         for j, f in enumerate(pts) if f.direction is not None]
        stateful = [f for f in model.forces if f.law.state is not None]
        self.stateful = [f.name for f in stateful]
        first = np.cumsum([0] + [f.law.state_size for f in stateful])   # a plane law's state takes two slots
        self.slot = {f.name: int(k) for f, k in zip(stateful, first)}
        n_states = int(first[-1])
        # work outputs: quadratures of their power, extra ODE states after the laws' (so the integrator's
        # own error control and dense output hold them); none declared: nothing computed
        self.work = [o for o in model.outputs if o.kind == "work"]
        order = {f.name: j for j, f in enumerate(pts + [f for f, _ in self.joints] + [f for f, _, _ in self.planes])}
        elements = [(n_states + k, order[o.element]) for k, o in enumerate(self.work) if o.element]
        self.work_slots = np.array([k for k, _ in elements], dtype=int)   # the rates an element's power feeds
        self.work_from = np.array([j for _, j in elements], dtype=int)
        self.work_sign = np.array([-1.0 if j < len(pts) else 1.0 for _, j in elements])
        self.excitation_slots = [n_states + k for k, o in enumerate(self.work) if o.source == "excitation"]
        self.work_at = {o.name: n_states + k for k, o in enumerate(self.work)}
        self.drive_work = [n_states + k for k, o in enumerate(self.work) if o.source == "drive"]
        self.initial = np.array([s for f in stateful for s in f.initial_states] + [0.0] * len(self.work))
        self.excitation, self.mech = model.excitation, tree.mech

    def _lengths(self, kin):
        """x and x' of every points element: the distance and its rate, or, for an element with a
        direction e, (p_a - p_b) . e and its rate (its unit vector set to e). A line element whose
        points coincide gets a zero unit vector: its force has no direction there (a stop at rest)."""
        el = self.elements
        L, Ld = el.state(kin)   # coinciding points get a zero unit vector there (elements.element_kinematics)
        for j, a, b, e in self.directed:
            L[j] = (el.P_up[j] - el.P_lo[j]) @ e
            Ld[j] = (kin.point_velocity(a, el.P_up[j]) - kin.point_velocity(b, el.P_lo[j])) @ e
            el.N[j] = e
        return L, Ld

    def _each(self, kin, z, zd, extra):
        """(element, x, x', state slot or -1) for every element."""
        if self.points:
            L, Ld = self._lengths(kin)
            for i, f in enumerate(self.points):
                yield f, L[i], Ld[i], self.slot.get(f.name, -1)
        for f, i in self.joints:
            yield f, z[i], zd[i], self.slot.get(f.name, -1)

    def _plane(self, f, i, j, z, zd, extra):
        """A plane law's (Q_x, Q_y) and its state's rates (or None) at the coordinates (z_i, z_j)."""
        k = self.slot.get(f.name, -1)
        s = (extra[k], extra[k + 1]) if k >= 0 else (0.0, 0.0)
        q = f.plane_force(z[i], z[j], zd[i], zd[j], *s)
        return q, (f.plane_rate(z[i], z[j], zd[i], zd[j], *s) if k >= 0 else None), k

    def values(self, kin, z, zd, extra=()) -> dict:
        """Each element's force: tension [N] of a points law, generalized force of a joint law, the pair
        (Q_x, Q_y) of a plane law."""
        out = {f.name: f.force(x, xd, extra[k] if k >= 0 else 0.0) for f, x, xd, k in self._each(kin, z, zd, extra)}
        out.update({f.name: self._plane(f, i, j, z, zd, extra)[0] for f, i, j in self.planes})
        return out

    def ground_load(self, t, kin, wrench):
        """-m a_g(t) at every body's centre of mass, as wrenches about the origin (the excitation);
        massless auxiliary bodies get nothing (their mass is zero). Returns (a_g(t), the centres)."""
        m = self.mech
        a = self.excitation.acceleration(t)
        f = -m.mass[:, None] * a[None, :]
        com = kin.r + np.einsum("nij,nj->ni", kin.A, m.com)
        wrench[:, :3] += f
        wrench[:, 3:] += np.cross(com, f)
        return a, com

    def excitation_power(self, a, kin, com) -> float:
        """The excitation's power on the mechanism: sum over the bodies of -m a_g(t) . v_com (relative)."""
        return -float(a @ _momentum(self.mech.mass, kin.Z, com))

    def __call__(self, t, kin, z, zd, extra):
        gen = np.zeros(self.n)
        T = np.zeros(len(self.points))
        rates = np.zeros(len(self.initial))
        power = np.zeros(len(self.points) + len(self.joints) + len(self.planes)) if self.work else None
        for j, (f, x, xd, k) in enumerate(self._each(kin, z, zd, extra)):
            value = f.force(x, xd, extra[k] if k >= 0 else 0.0)
            if k >= 0:
                rates[k] = f.rate(x, xd, extra[k])
            if j < len(self.points):
                T[j] = value
            else:
                gen[self.joints[j - len(self.points)][1]] += value
            if power is not None:
                power[j] = value * xd
        for j, (f, i, i2) in enumerate(self.planes):
            (qx, qy), r, k = self._plane(f, i, i2, z, zd, extra)
            gen[i] += qx
            gen[i2] += qy
            if k >= 0:
                rates[k], rates[k + 1] = r
            if power is not None:
                power[len(self.points) + len(self.joints) + j] = qx * zd[i] + qy * zd[i2]
        wrench = self.elements.wrench(T) if self.points else np.zeros((self.n, 6))
        if self.excitation is not None:
            a, com = self.ground_load(t, kin, wrench)
        if power is not None:   # a points law pulls its ends together by T: power -T x'; a joint law Q q'
            rates[self.work_slots] = self.work_sign * power[self.work_from]
            if self.excitation_slots:
                rates[self.excitation_slots] = self.excitation_power(a, kin, com)
            # "drive": the drive force is known after the dynamics are solved (DriveWorkSystem.rhs)
        return wrench, gen, rates


@njit(cache=True)
def _momentum(mass, Z, com):
    """sum of m (v_o + w x r_com) over the bodies: the linear momentum (compiled: in numpy ~8 us a call,
    once per right-hand side)."""
    p = np.zeros(3)
    for i in range(mass.shape[0]):
        w0, w1, w2, c0, c1, c2 = Z[i, 3], Z[i, 4], Z[i, 5], com[i, 0], com[i, 1], com[i, 2]
        p[0] += mass[i] * (Z[i, 0] + w1 * c2 - w2 * c1)
        p[1] += mass[i] * (Z[i, 1] + w2 * c0 - w0 * c2)
        p[2] += mass[i] * (Z[i, 2] + w0 * c1 - w1 * c0)
    return p


class DriveWorkSystem(SemiRecursiveSystem):
    """The in-house system of a description with a work output of its drives: that output's rate, the
    drives' power tau . q'(t), needs the drive forces tau, which the equations of motion give after
    the applied forces; so it is set here, after the solve, in the ODE's right-hand side."""

    def rhs(self, ws, t, y):
        zf, zfd, extra = split_state(y, len(self.partition.free))
        ev = self.rhs_parts(ws, t, zf, zfd, extra)
        rate = ev.extra_rate
        rate[self.forces.drive_work] = float(ev.drive_force @ ev.zd[self.prescribed])
        return np.concatenate([zfd, ev.zdd[self.partition.free], rate])


def system_of(model: Model, tree: Tree | None = None) -> tuple[SemiRecursiveSystem, Tree]:
    """The in-house system of a description (its partition not yet chosen)."""
    tree = tree or to_tree(model)
    drives = model.prescribed

    def motion(t):
        qs = np.array([d(t) for d in drives]).reshape(-1, 3)
        return qs[:, 0].copy(), qs[:, 1].copy(), qs[:, 2].copy()
    prefer = [tree.coordinate[c] for c in model.free]
    forces = Forces(model, tree)
    kind = DriveWorkSystem if forces.drive_work else SemiRecursiveSystem
    system = kind(tree.mech, tree.prescribed, motion, forces, n_extra=len(forces.initial), prefer_free=prefer)
    return system, tree


def guess(model: Model, tree: Tree) -> tuple[np.ndarray, np.ndarray]:
    z = np.zeros(tree.mech.n)
    zd = np.zeros(tree.mech.n)
    for c, v in model.initial_coordinates.items():
        z[tree.coordinate[c]] = v
    for c, v in model.initial_velocities.items():
        zd[tree.coordinate[c]] = v
    for p, i in zip(model.prescribed, tree.prescribed):
        z[i], zd[i], _ = p(0.0)
    return z, zd


def start(model: Model, system: SemiRecursiveSystem, tree: Tree):
    """The system's partition and its consistent initial (z, z', y0) at t = 0 (ModelError when the
    loops cannot be closed from the given coordinates, or a given rate breaks them)."""
    z, zd = guess(model, tree)
    system.choose_partition(z)
    ws = system.workspace(z)
    free = system.partition.free
    try:
        z = system.assemble(ws, 0.0, z[free]).copy()
    except Exception as e:  # noqa: BLE001 (Newton's own failure, said as the description's mistake)
        raise ModelError(f"loops: cannot be closed from [initial].coordinates ({' '.join(str(e).split())})") from None
    extra0 = system.forces.initial
    ev = system.evaluate(system.workspace(z), 0.0, system.state(z, zd, extra0))
    resid = float(np.max(np.abs(ev.Phi))) if ev.Phi.size else 0.0
    if not np.isfinite(resid) or resid > ASSEMBLY_TOL:
        raise ModelError(f"loops: cannot be closed from [initial].coordinates (residual {resid:.3g} after "
                         "Newton): check the joints, the loop points and the initial coordinates")
    names = {i: c for c, i in tree.coordinate.items()}
    for i in system.partition.dependent:
        if names[i] in model.initial_velocities and abs(ev.zd[i] - zd[i]) > 1e-8 * max(1.0, float(np.max(np.abs(ev.zd)))):
            body, k = names[i]
            raise ModelError(f"[initial].velocities.{body} = {float(zd[i])!r} (coordinate {k}): the loops require "
                             f"{ev.zd[i]:.6g}; give the rates of the free coordinates only")
    return z, ev.zd.copy(), system.state(z, ev.zd, extra0), ev


def initial_state(model: Model) -> InitialState:
    """The consistent state at t = 0 every engine starts from (see the module's docstring)."""
    system, tree = system_of(model)
    z, zd, _, ev = start(model, system, tree)
    kin = ev.kin
    q = {c: float(z[i]) for c, i in tree.coordinate.items()}
    qd = {c: float(zd[i]) for c, i in tree.coordinate.items()}
    rot, org, vel, om = {}, {}, {}, {}
    for b in model.bodies:
        i = tree.body[b.name]
        rot[b.name] = kin.A[i].copy()
        org[b.name] = kin.r[i].copy()
        vel[b.name] = kin.point_velocity(i, kin.r[i])
        om[b.name] = kin.Z[i, 3:].copy()
    return InitialState(q, qd, rot, org, vel, om)


def count_dofs(model: Model) -> int:
    return sum(JOINT_DOFS[b.joint.type] for b in model.bodies)
