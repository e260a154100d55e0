"""The description's force elements as Exudyn connectors (used by comparisons.builders.exudyn), and the
laws' internal states integrated along with Exudyn's motion, nothing here knowing which laws exist.

Connectors. A points law is a CartesianSpringDamper connector (markers: b's point, then a's, so its
displacement is d = p_a - p_b, its velocity d') whose force user function returns the law's tension
T times the element's unit vector: d / |d| for a line element (x = |d|, x' = d . d' / |d|; zero where
the points coincide, a stop at rest, where Exudyn's own SpringDamper would divide by zero), or the
element's fixed ``direction`` e (x = d . e, x' = d' . e). The connector pulls marker 1 (a) by minus
that vector and pushes marker 0 (b) by it: -T e on a, +T e on b, the description's sign. A joint law on a slide (prismatic,
translational, planar u or v) is a linear spring-damper connector along the slide's axis, on a
revolute or planar turn a torsional one about it; its user function returns ``-law.force(q, q', ...)``
(the connector's force opposes its coordinate; the law's drives it up). Exudyn evaluates them at
every Newton iteration and differentiates them numerically (implicit).

Laws with a state (``Law.state``, ds/dt = ``law.rate(x, x', s, p)``): Heun's method (the explicit
trapezoidal rule) with the mechanics' own step h, second order like generalized-alpha, so the
gate's Richardson estimate (order 2 for Exudyn) holds for the coupled solution:
    s_{n+1} = s_n + h/2 (r_n + rate(x_{n+1}, x'_{n+1}, s_n + h r_n)),   r_n = rate(x_n, x'_n, s_n).
The connector's user function evaluates this for the configuration Newton is trying at t_{n+1}, so
the force at the end of the step uses the state at the end of the step, and the state's dependence
on x_{n+1}, x'_{n+1} is in the connector's numerical Jacobian; the pre-step function commits s_{n+1}
and r_{n+1} at the converged configuration (from the bodies' poses). The force is thus an
implicit, pure function of the configuration within a step, as Exudyn's Newton needs. Forces at a
lagged state s_n would be first order (a force shifted by one step); Exudyn's own ODE1
coordinates (ObjectGenericODE1) see only their own coordinates in the right-hand side and their
coupling to the bodies would be outside Exudyn's Jacobian. The hand-written device adapter
(comparisons/engines/exudyn_engine.py) integrates the same laws in strain from committed states
(Heun as well); here the integration runs in time, since a law's rate is a function of (x, x', s).

A plane law (two slide coordinates of one joint, a two-component state: nsd_core.model.laws) is one
CartesianSpringDamper between the parent's joint point and the child's origin (markers: the parent's,
then the child's): x = d . u, y = d . v along the joint's two slide axes, and the returned vector
-(Q_x u + Q_y v) pushes the child by Q_x u + Q_y v. Its state takes two slots, advanced as one by
Heun's method (``at_plane``). The connector reads no rotation of the parent: this path takes a plane
law on a joint to the ground (the compiled paths, exudyn_compiled, take any joint).
"""
from __future__ import annotations

import math

import numpy as np

from exudyn.itemInterface import (NodeGenericData, ObjectConnectorCartesianSpringDamper, ObjectConnectorLinearSpringDamper,
                                  ObjectConnectorTorsionalSpringDamper)

from comparisons.builders.exudyn_frames import cross, joint_rate, law_axis
from nsd_core.model.errors import ModelError
from nsd_core.model.description import GROUND
from nsd_core.model.laws import PLANE, POINTS


class LawStates:
    """The states of the laws that have one, by Heun's method (the module's docstring)."""

    def __init__(self, h: float):
        self.h, self.elements, self.s, self.r = h, [], [], []
        self.of, self.slot = [], {}   # each slot's element; each element's first slot (a plane law takes two)
        self.started = False   # before the first step (the initial accelerations): s = s_0 exactly

    def add(self, f) -> int:
        """A law's state: its first slot."""
        k = len(self.s)
        self.elements.append(f)
        self.slot[f.name] = k
        self.of += [f] * f.law.state_size
        self.s += list(f.initial_states)
        self.r += [0.0] * f.law.state_size
        return k

    def at(self, k: int, x: float, xd: float) -> float:
        """Slot k's state at the end of the step being solved, for the configuration (x, x')."""
        s = self.s[k]
        if not self.started:
            return s
        f, h, r = self.of[k], self.h, self.r[k]
        return s + 0.5 * h * (r + f.law.rate(x, xd, s + h * r, f.parameters))

    def at_plane(self, k: int, x: float, y: float, xd: float, yd: float) -> tuple[float, float]:
        """``at`` for a plane law whose state is in slots k, k + 1."""
        sx, sy = self.s[k], self.s[k + 1]
        if not self.started:
            return sx, sy
        f, h, rx, ry = self.of[k], self.h, self.r[k], self.r[k + 1]
        ax, ay = f.plane_rate(x, y, xd, yd, sx + h * rx, sy + h * ry)
        return sx + 0.5 * h * (rx + ax), sy + 0.5 * h * (ry + ay)

    def commit(self, args) -> None:
        """The step converged: each element's arguments there ((x, x'), a plane law's (x, y, x', y'));
        its state and rate become the start's."""
        for f, a in zip(self.elements, args):
            k = self.slot[f.name]
            if f.law.acts_on == PLANE:
                if self.started:
                    self.s[k], self.s[k + 1] = self.at_plane(k, *a)
                self.r[k], self.r[k + 1] = f.plane_rate(*a, self.s[k], self.s[k + 1])
                continue
            if self.started:
                self.s[k] = self.at(k, *a)
            self.r[k] = f.law.rate(*a, self.s[k], f.parameters)
        self.started = True


def law_function(f, states: LawStates | None, sign: float):
    """A connector's force function of (x, x'): the law's value (times sign), through its state."""
    law, p = f.law.force, f.parameters
    if f.law.state is None:
        return lambda x, xd: sign * law(x, xd, p)
    k = states.add(f)
    return lambda x, xd: sign * law(x, xd, states.at(k, x, xd), p)


def add_force(build, f, states: LawStates):
    """One force element of the description as a connector of ``build`` (a comparisons.builders.exudyn
    Build)."""
    mbs = build.mbs
    if f.law.acts_on == PLANE:
        return add_plane(build, f, states)
    if f.law.acts_on == POINTS:
        tension = law_function(f, states, 1.0)
        e = None if f.direction is None else np.asarray(f.direction, dtype=float)

        def vector(mbs_, t, item, d, d_t, k, c, offset):
            x, xd, n = axial(np.asarray(d), np.asarray(d_t), e)
            return list(tension(x, xd) * n)
        return mbs.AddObject(ObjectConnectorCartesianSpringDamper(
            markerNumbers=[build.marker(f.body_b, f.point_b), build.marker(f.body_a, f.point_a)],
            springForceUserFunction=vector))
    b = build.model.body(f.joint)
    axis = law_axis(b, f.dof)
    if axis is None:
        raise ModelError(f"forces.{f.name}.joint = {f.joint!r}: the Exudyn builder applies joint laws on slides and "
                         f"on revolute and planar turns only (this is a turn of a {b.joint.type} joint)")
    if axis < 3 and _turns(build.model, b.parent):   # its rate and its reaction are taken at the parent's marker,
        # which is not the parent's material point under the child once the slide has moved and the parent turns
        raise ModelError(f"forces.{f.name}.joint = {f.joint!r}: Exudyn's connectors apply a slide's law on a joint "
                         f"whose parent does not turn only (its parent {b.parent!r} turns); forces = \"compiled\" or "
                         "\"predicted\" take any")
    J = build.frames[b.name]
    if axis < 3:   # the linear connector slides along its frame's x: turn J's slide axis onto x
        J = J[:, [axis, (axis + 1) % 3, (axis + 2) % 3]]
    markers = [build.marker(b.parent, b.joint.position, J), build.marker(b.name, (0.0, 0.0, 0.0), J)]
    generalized = law_function(f, states, -1.0)

    def user(mbs_, t, item, q, q_t, k, d, offset):
        return generalized(q, q_t)
    if axis < 3:
        return mbs.AddObject(ObjectConnectorLinearSpringDamper(markerNumbers=markers, springForceUserFunction=user))
    # the data node counts whole turns, so that q reaches the law continuous past +-pi
    q0 = build.state.q[(b.name, f.dof)]
    turns = mbs.AddNode(NodeGenericData(initialCoordinates=[round(q0 / (2 * math.pi))], numberOfDataCoordinates=1))
    return mbs.AddObject(ObjectConnectorTorsionalSpringDamper(markerNumbers=markers, nodeNumber=turns,
                                                              springTorqueUserFunction=user))


def _turns(model, body: str) -> bool:
    """Whether ``body`` can turn: a joint with a turn on its path to the ground."""
    while body != GROUND:
        b = model.body(body)
        if b.joint.type not in ("prismatic", "translational", "planar_translation"):
            return True
        body = b.parent
    return False


def add_plane(build, f, states: LawStates):
    """A plane law as one CartesianSpringDamper (the module's docstring)."""
    b = build.model.body(f.joint)
    if b.parent != GROUND:
        raise ModelError(f"forces.{f.name}.joint = {f.joint!r}: Exudyn's connectors apply a plane law on a joint to "
                         f"the ground only (its parent is {b.parent!r}); forces = \"compiled\" or \"predicted\" take any")
    J = build.frames[b.name]
    u, v = (np.asarray(J[:, law_axis(b, k)], dtype=float) for k in f.dofs)
    k = states.add(f) if f.law.state is not None else -1

    def vector(mbs_, t, item, d, d_t, stiffness, damping, offset):
        d, d_t = np.asarray(d), np.asarray(d_t)
        x, y, xd, yd = float(d @ u), float(d @ v), float(d_t @ u), float(d_t @ v)
        qx, qy = f.plane_force(x, y, xd, yd, *(states.at_plane(k, x, y, xd, yd) if k >= 0 else (0.0, 0.0)))
        return list(-(qx * u + qy * v))
    return build.mbs.AddObject(ObjectConnectorCartesianSpringDamper(
        markerNumbers=[build.marker(GROUND, b.joint.position), build.marker(b.name, (0.0, 0.0, 0.0))],
        springForceUserFunction=vector))


def axial(d, d_t, e):
    """(x, x', unit vector) of a points element from d = p_a - p_b and its rate: along the fixed
    direction e, or along the line (a zero vector where the points coincide: no direction there)."""
    if e is not None:
        return float(d @ e), float(d_t @ e), e
    L = math.sqrt(float(d @ d))
    if L == 0.0:
        return 0.0, 0.0, d * 0.0
    n = d / L
    return L, float(d_t @ n), n


def point(P, body, p):
    """World position and velocity of body point p, from the poses P (Build.poses)."""
    R, r, v, w = P[body]
    x = R @ np.asarray(p, dtype=float)
    return r + x, v + cross(w, x)


def law_arguments(build, P, q, f) -> tuple[float, float]:
    """(x, x') of force element f: the distance (or the offset along its direction) and its rate, or
    the joint coordinate (from q, kept continuous by the caller) and its rate."""
    if f.law.acts_on == POINTS:
        pa, va = point(P, f.body_a, f.point_a)
        pb, vb = point(P, f.body_b, f.point_b)
        x, xd, _ = axial(pa - pb, va - vb, None if f.direction is None else np.asarray(f.direction, dtype=float))
        return x, xd
    b = build.model.body(f.joint)
    Rp, rp, vp, wp = P[b.parent]
    _, rc, vc, wc = P[b.name]
    if f.law.acts_on == PLANE:   # (x, y, x', y')
        i, j = f.dofs
        return (q[(b.name, i)], q[(b.name, j)], joint_rate(b, i, build.frames[b.name], Rp, rp, vp, wp, rc, vc, wc),
                joint_rate(b, j, build.frames[b.name], Rp, rp, vp, wp, rc, vc, wc))
    return q[(b.name, f.dof)], joint_rate(b, f.dof, build.frames[b.name], Rp, rp, vp, wp, rc, vc, wc)
