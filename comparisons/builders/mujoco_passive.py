"""comparisons.builders.mujoco's readable passive path (``passive = "python"``): the mjcb_passive
callback as a Python class. The compiled path (mujoco_codegen, mujoco_kernels) computes the same
numbers in the same order; tests/test_mujoco_codegen.py holds them equal to round-off.

- A points element's two world points and velocities come from MuJoCo's state (mj_jac of each point).
  Along the line (no ``direction``): L = |p_b - p_a|, L' its rate, u the unit vector a -> b, and the
  tension T = ``element.force(L, L')`` gives +T u on a, -T u on b (T > 0 pulls them together).
  Coincident points (L = 0, a stop at rest) have no direction: u = 0, L' = 0, no force applied.
  With a ``direction`` e (ground frame): x = (p_a - p_b) . e, x' its rate, and the law's tension acts
  as -T e on a, +T e on b, i.e. the same arithmetic with u = -e and L = (p_b - p_a) . u.
- A joint element adds ``element.force(q, q')`` to its coordinate; a plane element (two slide
  coordinates of one joint, x and y) adds ``element.plane_force(x, y, x', y', s_x, s_y)``'s (Q_x, Q_y)
  to them, its state in two consecutive activations (advanced as a scalar state is, the pair at once).
- An excitation (the frame translates with the ground) adds -m a_g(t) at every body's centre of
  mass, J_com^T (-m a_g(t)), with t = mjData.time: the passive callback runs at every integrator
  stage with the stage's time (mj_RungeKutta sets it), so the forcing is as accurate as the
  integrator (setting opt.gravity once per step would hold a_g constant over the step, first order).
- Prescribed motions: the heavy virtual drives' feed-forward (comparisons.builders.mujoco says why).
- A law's state (``advance``, Euler): advanced by the callback itself at each evaluation at a later
  time, along the actual change of its element's x since the last one (x linear in time over the
  interval dt, x' = dx/dt: one RK4 step of ``rate(x(tau), x', s)``), before the force uses it; MuJoCo's
  Euler evaluates once per step, at its start, so the state always matches the configuration the
  force sees (comparisons.builders.mujoco says why). Otherwise (RK4) MuJoCo integrates it from the
  rate handed over by ``act_dyn``.
- Work outputs (``work_plan``, ``Passive.powers``): each one's power at the step's first evaluation;
  the step loops integrate it by the trapezoid over the steps (comparisons.builders.mujoco).
"""
from __future__ import annotations

import mujoco
import numpy as np

from comparisons.builders.mujoco_mjcf import joint_name, state_activations
from nsd_core.model.description import GROUND, Model
from nsd_core.model.laws import PLANE, POINTS

EXCITATION, DRIVE = -1, -2   # a work output's load when it is no element (work_plan)


def work_plan(model: Model, m: mujoco.MjModel):
    """The work outputs as the step loops integrate them: (each one's element index in the description,
    or EXCITATION or DRIVE; each element's power sign: a points law's tension T pulls its ends together,
    power -T x', a joint law's Q drives its coordinate, power Q q'; the total mass the excitation loads,
    MuJoCo's own). Its power is then sign value x' (an element), -a_g(t) . (M v_com) of the whole
    mechanism (the excitation: the sum of -m a_g . v_com over the bodies) or the drives' (DRIVE)."""
    index = {f.name: e for e, f in enumerate(model.forces)}
    work_of = np.array([index[o.element] if o.element else (EXCITATION if o.source == "excitation" else DRIVE)
                        for o in model.outputs if o.kind == "work"], dtype=np.int64)
    sign = np.array([-1.0 if f.law.acts_on == POINTS else 1.0 for f in model.forces])
    return work_of, sign, float(m.body_subtreemass[0])


class Passive:
    """The mjcb_passive callback: every force element through its law, the excitation's load, plus the
    drives' feed-forward."""

    def __init__(self, model: Model, m: mujoco.MjModel, drives: list, advance: bool = False):
        self.nv = m.nv
        self.jac = np.zeros((2, 3, m.nv))
        self.points, self.joints, self.planes = [], [], []
        # a law with a state keeps it in an activation of the states actuator (mujoco_mjcf); -1: none
        self.act = state_activations(model, m)
        self.rates = np.zeros(m.na)   # each state's rate at the last evaluation, for mjcb_act_dyn
        self.advance = advance        # the states advanced here (Euler), not by MuJoCo (rates stay 0)
        self.previous = np.zeros(m.na)   # each state's element's x at the last advance ...
        self.t_commit = np.nan           # ... and its time (NaN: none yet)
        for f in model.forces:
            slot = self.act.get(f.name, -1)
            if f.law.acts_on == POINTS:
                ends = tuple((-1 if b == GROUND else m.body(b).id, np.asarray(p, float))
                             for b, p in ((f.body_a, f.point_a), (f.body_b, f.point_b)))
                u = None if f.direction is None else -np.asarray(f.direction, float)
                self.points.append((f, ends, slot, u))
            elif f.law.acts_on == PLANE:   # (element, qposadr x, y, dofadr x, y, first activation)
                ja, jb = (m.joint(joint_name(f.joint, k)) for k in f.dofs)
                self.planes.append((f, int(ja.qposadr[0]), int(jb.qposadr[0]), int(ja.dofadr[0]), int(jb.dofadr[0]),
                                    slot))
            else:
                j = m.joint(joint_name(f.joint, f.dof))
                self.joints.append((f, int(j.qposadr[0]), int(j.dofadr[0]), slot))
        self.forces = model.forces
        self.excitation = model.excitation
        # the bodies the excitation loads: every one with a mass (MuJoCo's own, as its gravity uses)
        self.loaded = [(b, float(m.body_mass[b])) for b in range(1, m.nbody) if m.body_mass[b] > 0.0]
        self.jac_com = np.zeros((3, m.nv))
        self.drives = drives                    # (Prescribed, qposadr, dofadr, armature)
        nd = len(drives)
        self.tau = np.zeros(nd)                 # the drive forces' estimate at t_tau ...
        self.tau_slope = np.zeros(nd)           # ... and its rate [per s]
        self.t_tau = 0.0
        self.feeds: list[np.ndarray] = []       # the feed-forward of each evaluation since the step began

    def point(self, m, d, body: int, p: np.ndarray, jac: np.ndarray):
        """World position and velocity of body point p; ``jac`` gets its 3 x nv Jacobian (ground: 0)."""
        if body < 0:
            jac[:] = 0.0
            return p, np.zeros(3)
        x = d.xpos[body] + d.xmat[body].reshape(3, 3) @ p
        mujoco.mj_jac(m, d, jac, None, x, body)
        return x, jac @ d.qvel

    def element_state(self, m, d, ends, along=None):
        """(x, x', u) of a points element, the force on a being +T u: along the line, (L, L', the unit
        vector a -> b); with a direction e, along = -e: ((p_b - p_a) . along, its rate, along). The
        Jacobians stay in self.jac."""
        (ba, pa), (bb, pb) = ends
        xa, va = self.point(m, d, ba, pa, self.jac[0])
        xb, vb = self.point(m, d, bb, pb, self.jac[1])
        r = xb - xa
        if along is not None:
            return float(r @ along), float(along @ (vb - va)), along
        L = float(np.linalg.norm(r))
        u = r / L if L > 0.0 else np.zeros(3)
        return L, float(u @ (vb - va)), u

    def law(self, d, f, x: float, xd: float, slot: int, dt: float | None = None) -> float:
        """The element's force at (x, x') and its state. From the callback (dt: the time since the last
        advance, NaN before the first), the state is first advanced to this configuration
        (``advance``), or its rate is kept for mjcb_act_dyn; with dt None (outputs) it is only read."""
        if slot < 0:
            return f.force(x, xd)
        s = float(d.act[slot])
        if dt is None:
            pass
        elif self.advance:
            if not dt <= 0.0:   # a later time (NaN before the first: x recorded only)
                if dt > 0.0:
                    s = d.act[slot] = self.step(f, self.previous[slot], x, s, dt)
                self.previous[slot] = x
        else:
            self.rates[slot] = f.rate(x, xd, s)
        return f.force(x, xd, s)

    @staticmethod
    def step(f, x0: float, x1: float, s: float, dt: float) -> float:
        """The state advanced over dt along x linear from x0 to x1: one RK4 step in time (the generated
        ``advance_*`` of mujoco_codegen, the same arithmetic)."""
        xd = (x1 - x0) / dt
        xm = 0.5 * (x0 + x1)
        k1 = f.rate(x0, xd, s)
        k2 = f.rate(xm, xd, s + 0.5 * dt * k1)
        k3 = f.rate(xm, xd, s + 0.5 * dt * k2)
        k4 = f.rate(x1, xd, s + dt * k3)
        return s + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)

    def plane_law(self, d, f, qa, qb, da, db, slot: int, dt: float | None = None) -> tuple[float, float]:
        """A plane element's (Q_x, Q_y) at d's coordinates and its state, the state handled as ``law``
        handles a scalar one (its two components at once)."""
        x, y, xd, yd = d.qpos[qa], d.qpos[qb], d.qvel[da], d.qvel[db]
        if slot < 0:
            return f.plane_force(x, y, xd, yd)
        s = (float(d.act[slot]), float(d.act[slot + 1]))
        if dt is None:
            pass
        elif self.advance:
            if not dt <= 0.0:
                if dt > 0.0:
                    s = self.plane_step(f, self.previous[slot], self.previous[slot + 1], x, y, s, dt)
                    d.act[slot], d.act[slot + 1] = s
                self.previous[slot], self.previous[slot + 1] = x, y
        else:
            self.rates[slot], self.rates[slot + 1] = f.plane_rate(x, y, xd, yd, *s)
        return f.plane_force(x, y, xd, yd, *s)

    @staticmethod
    def plane_step(f, x0, y0, x1, y1, s, dt):
        """``step`` for a plane law: one RK4 step in time along (x, y) linear from (x0, y0) to (x1, y1)."""
        xd, yd = (x1 - x0) / dt, (y1 - y0) / dt
        xm, ym = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
        k1 = f.plane_rate(x0, y0, xd, yd, *s)
        k2 = f.plane_rate(xm, ym, xd, yd, s[0] + 0.5 * dt * k1[0], s[1] + 0.5 * dt * k1[1])
        k3 = f.plane_rate(xm, ym, xd, yd, s[0] + 0.5 * dt * k2[0], s[1] + 0.5 * dt * k2[1])
        k4 = f.plane_rate(x1, y1, xd, yd, s[0] + dt * k3[0], s[1] + dt * k3[1])
        return tuple(s[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]) for i in (0, 1))

    def law_values(self, m, d) -> dict:
        """Each element's force at d's state (tension [N], or generalized force; a plane law's pair)."""
        out = {f.name: self.law(d, f, *self.element_state(m, d, ends, u)[:2], slot) for f, ends, slot, u in self.points}
        out.update({f.name: self.law(d, f, d.qpos[qa], d.qvel[da], slot) for f, qa, da, slot in self.joints})
        out.update({f.name: self.plane_law(d, f, *rest) for f, *rest in self.planes})
        return out

    def powers(self, m, d, work_of, sign, mass) -> np.ndarray:
        """Each work output's power at d's evaluated state (the drives' is left 0: the loop adds each
        step's drive work itself). The laws' states are read, not advanced."""
        rates = {f.name: (*self.element_state(m, d, ends, u)[:2], slot) for f, ends, slot, u in self.points}
        rates.update({f.name: (d.qpos[qa], d.qvel[da], slot) for f, qa, da, slot in self.joints})
        out = np.zeros(len(work_of))
        planes = {f.name: (f, rest) for f, *rest in self.planes}
        for k, e in enumerate(work_of):
            if e == EXCITATION:
                mujoco.mj_subtreeVel(m, d)
                out[k] = -mass * float(self.excitation.acceleration(d.time) @ d.subtree_linvel[0])
            elif e >= 0 and self.forces[e].name in planes:   # Q_x x' + Q_y y'
                f, (qa, qb, da, db, slot) = planes[self.forces[e].name]
                qx, qy = self.plane_law(d, f, qa, qb, da, db, slot)
                out[k] = qx * d.qvel[da] + qy * d.qvel[db]
            elif e >= 0:
                f = self.forces[e]
                x, xd, slot = rates[f.name]
                out[k] = sign[e] * self.law(d, f, x, xd, slot) * xd
        return out

    def act_dyn(self, m, d, actuator: int) -> float:
        """mjcb_act_dyn: the states' rates, computed by this stage's passive call (MuJoCo evaluates the
        passive forces before the actuators), written into act_dot (MuJoCo's rule for an actuator of
        several activations; with one, it takes the value returned)."""
        d.act_dot[:] = self.rates
        return float(self.rates[m.actuator_actadr[actuator]])

    def ground_load(self, m, d, qfrc) -> None:
        """J_com^T (-m a_g(t)) of every body, at this stage's time."""
        a = self.excitation.acceleration(d.time)
        for b, mass in self.loaded:
            mujoco.mj_jacBodyCom(m, d, self.jac_com, None, b)
            qfrc += (-mass * a) @ self.jac_com

    def __call__(self, m, d):
        qfrc = d.qfrc_passive
        dt = d.time - self.t_commit
        for f, ends, slot, along in self.points:
            L, Ld, u = self.element_state(m, d, ends, along)
            qfrc += (self.law(d, f, L, Ld, slot, dt) * u) @ (self.jac[0] - self.jac[1])
        for f, qa, da, slot in self.joints:
            qfrc[da] += self.law(d, f, d.qpos[qa], d.qvel[da], slot, dt)
        for f, qa, qb, da, db, slot in self.planes:
            qx, qy = self.plane_law(d, f, qa, qb, da, db, slot, dt)
            qfrc[da] += qx
            qfrc[db] += qy
        if self.advance and not dt <= 0.0:
            self.t_commit = d.time
        if self.excitation is not None:
            self.ground_load(m, d, qfrc)
        if self.drives:
            t = d.time
            feed = np.array([A * p(t)[2] for p, _, _, A in self.drives]) + self.tau + self.tau_slope * (t - self.t_tau)
            qfrc[[da for _, _, da, _ in self.drives]] += feed
            self.feeds.append(feed)
