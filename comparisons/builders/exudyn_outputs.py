"""The Exudyn builder's outputs (used by comparisons.builders.exudyn): every described quantity read
back from the bodies' world poses at the output times, and the converged arguments of the laws with a
state, committed every step.

During the run an output time only records Exudyn's state (``record``: the ODE2 coordinates and
their rates and accelerations, the algebraic ones, i.e. the multipliers the drive forces are read from, and the laws'
committed states); the outputs are read from them after the run (``replay``: each state set back
into the system, then read as before), as the hand-written adapter records sensors in the run and
builds its columns after it. Reading every output in the pre-step cost as much as the stepping at
the gate's 1 Hz case (an output every second step).
"""
from __future__ import annotations

import exudyn as exu
import numpy as np

from comparisons.builders.exudyn_forces import law_arguments, point
from comparisons.builders.exudyn_frames import Continuous, cross
from nsd_core.model.description import GROUND


class Sampler:
    """Every named output, the largest closure distance and the largest drive tracking error; and,
    every step, the converged arguments of the laws with a state (``commit``)."""

    def __init__(self, build: Build):
        self.b = build
        m = build.model
        rotational = {(b.name, k) for b in m.bodies for k, (kind, _) in enumerate(b.joint.dofs()) if kind == "R"}
        self.continuous = Continuous(build.state.q, rotational)
        self.rows, self.closure, self.tracking = [], 0.0, 0.0
        self.forces = {f.name: f for f in m.forces}
        self.drives = {p.name: p for p in m.prescribed}
        self.stateful = build.states.elements
        self.slot = {f.name: k for k, f in enumerate(self.stateful)}
        self.q = {}
        self.recorded = []
        self.t = 0.0
        self.work = None   # exudyn_work.Work: the work outputs, integrated in the run (set by the builder)

    def record(self, t: float) -> None:
        """The converged state at output time t, for ``replay``."""
        sd = self.b.mbs.systemData
        self.recorded.append((t, sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t(), sd.GetODE2Coordinates_tt(),
                              sd.GetAECoordinates(), list(self.b.states.s),
                              None if self.work is None else dict(zip(self.work.names, self.work.work))))

    def replay(self) -> None:
        """Every output at the recorded states, in time order (angles continuous across samples)."""
        sd, now = self.b.mbs.systemData, exu.ConfigurationType.Current
        for t, q, q_t, q_tt, lam, s, self.works in self.recorded:
            sd.SetODE2Coordinates(q, now)
            sd.SetODE2Coordinates_t(q_t, now)
            sd.SetODE2Coordinates_tt(q_tt, now)
            sd.SetAECoordinates(lam, now)
            self.b.states.s[:] = s
            self(t)
        self.recorded = []

    def read(self, bodies) -> dict:
        """The poses, and the coordinates of ``bodies``' joints into self.q (continuous in time)."""
        P = self.b.poses()
        for body in bodies:
            for k, x in enumerate(self.b.coordinates(P, body)):
                self.q[(body, k)] = self.continuous((body, k), x)
        return P

    def commit(self) -> None:
        """The step converged: the laws' states move on (exudyn_forces.LawStates)."""
        if self.b.compiled is not None:
            self.b.compiled.commit(self.b.mbs)
            return
        P = self.read({f.joint for f in self.stateful if f.joint})
        self.b.states.commit([law_arguments(self.b, P, self.q, f) for f in self.stateful])

    def law_value(self, P, f) -> float:
        k = self.slot.get(f.name)
        return f.force(*law_arguments(self.b, P, self.q, f), 0.0 if k is None else self.b.states.s[k])

    def acceleration(self, P, o) -> np.ndarray:
        """The body point's absolute acceleration: the node's (its centre of mass) from Exudyn's
        accelerations of the converged step (generalized-alpha's q'' that satisfies the equations of
        motion at the step's end, not its algorithmic acceleration), carried to the point,
        a_c + alpha x r + w x (w x r), plus the frame's a_g(t) with an excitation."""
        a = np.zeros(3)
        if o.body != GROUND:
            OV, b = exu.OutputVariableType, self.b.model.body(o.body)
            n = self.b.node[o.body]
            R, _, _, w = P[o.body]
            r = R @ (np.asarray(o.point, dtype=float) - np.asarray(b.com, dtype=float))
            alpha = np.asarray(self.b.mbs.GetNodeOutput(n, OV.AngularAcceleration))
            a = np.asarray(self.b.mbs.GetNodeOutput(n, OV.Acceleration)) + cross(alpha, r) + cross(w, cross(w, r))
        exc = self.b.model.excitation
        return a + exc.acceleration(self.t) if exc is not None else a

    def energy(self, P, term) -> float:
        e = 0.0
        g = np.asarray(self.b.model.gravity, dtype=float)
        for b in self.b.model.bodies:
            R, r, v, w = P[b.name]
            c, vc = point(P, b.name, b.com)
            if term == "kinetic":
                e += 0.5 * b.mass * float(vc @ vc) + 0.5 * float(w @ (R @ b.inertia @ R.T @ w))
            else:
                e -= b.mass * float(g @ c)
        return e

    def __call__(self, t: float) -> None:
        m, self.t = self.b.model, t
        P = self.read({o.body for o in m.outputs if o.kind == "coordinate"} | {f.joint for f in m.forces if f.joint} |
                      {p.joint for p in m.prescribed})
        row = []
        for o in m.outputs:
            if o.kind == "coordinate":
                row.append(self.q[(o.body, o.dof)])
            elif o.kind in ("point", "point_velocity"):
                row.append(float(point(P, o.body, o.point)[o.kind == "point_velocity"][o.component]))
            elif o.kind == "point_acceleration":
                row.append(float(self.acceleration(P, o)[o.component]))
            elif o.kind == "force":
                row.append(self.law_value(P, self.forces[o.element]))
            elif o.kind == "state":   # the committed state its force value uses
                row.append(float(self.b.states.s[self.slot[o.element]]))
            elif o.kind == "drive_force":
                row.append(self.b.drive_force(self.drives[o.element]))
            elif o.kind == "work":   # integrated in the run to this time (exudyn_work), recorded
                row.append(float(self.works[o.name]))
            else:
                row.append(self.energy(P, o.term))
        self.rows.append(row)
        for lp in m.loops:
            gap = point(P, lp.body_a, lp.point_a)[0] - point(P, lp.body_b, lp.point_b)[0]
            self.closure = max(self.closure, float(np.linalg.norm(gap)))
        for p in m.prescribed:
            self.tracking = max(self.tracking, abs(self.q[(p.joint, p.dof)] - p(t)[0]))
