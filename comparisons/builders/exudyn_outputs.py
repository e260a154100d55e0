"""The Exudyn builder's outputs (used by comparisons.builders.exudyn): every described quantity read
back from the bodies' world poses at the output times, and the converged arguments of the laws with a
state, committed every step.

During the run an output time only records Exudyn's state (``record``: the ODE2 coordinates and
their rates and accelerations, the algebraic ones, i.e. the multipliers the drive forces are read from, and the laws'
committed states); the outputs are read from them after the run, as the hand-written adapter records
sensors in the run and builds its columns after it. Reading every output in the pre-step cost as much
as the stepping at the gate's 1 Hz case (an output every second step).

The outputs' formulas (``columns``) take the poses of one sample or of all samples at once (stacks
over the samples, the first axis), from one of two readers:
- ``ExudynReader`` (here; ``outputs_from = "exudyn"``, and always with the connectors): each recorded
  state set back into the system and read through Exudyn's output variables, sample by sample, the
  readable reference;
- exudyn_replay.SeriesReader (``outputs_from = "coordinates"``, the compiled paths' default): every
  sample at once from the recorded coordinates, the poses and the laws' arguments by the compiled
  force path's own kinematics: ~12x cheaper (the device's 4001 samples: 0.28 -> 0.024 s CPU, most of
  what is left the laws' values and the drives' q(t) for the tracking error, called per sample), the
  same numbers to round-off (tests/test_exudyn_builder_speed.py).
"""
from __future__ import annotations

import exudyn as exu
import numpy as np

from comparisons.builders.exudyn_forces import law_arguments, point
from comparisons.builders.exudyn_frames import Continuous, applied, cross, transposed
from nsd_core.model.description import GROUND
from nsd_core.model.laws import PLANE


def _dot(a, b):
    """a . b of two vectors, or of each pair of two stacks of them."""
    return (a * b).sum(-1)


def _each(fn, *args):
    """A scalar function at one sample, or at each of a series of samples (arrays over them)."""
    if np.ndim(args[0]) == 0:
        return fn(*args)
    return np.array([fn(*a) for a in zip(*(np.broadcast_to(x, np.shape(args[0])).tolist() for x in args))])


class ExudynReader:
    """One recorded sample at a time, set back into Exudyn and read through its output variables."""

    def __init__(self, build, sampler):
        self.b, self.sampler = build, sampler

    def samples(self, recorded):
        """Each recorded sample set into the system in turn: yields (t, law states, works)."""
        sd, now = self.b.mbs.systemData, exu.ConfigurationType.Current
        for t, q, q_t, q_tt, lam, s, works in recorded:
            sd.SetODE2Coordinates(q, now)
            sd.SetODE2Coordinates_t(q_t, now)
            sd.SetODE2Coordinates_tt(q_tt, now)
            sd.SetAECoordinates(lam, now)
            self.b.states.s[:] = s
            yield t, np.asarray(s, dtype=float), works

    def poses(self) -> dict:
        return self.b.poses()

    def arguments(self, P, f):
        return law_arguments(self.b, P, self.sampler.q, f)

    def drive_force(self, p):
        return self.b.drive_force(p)

    def node_acceleration(self, body):
        """The node's (centre of mass') acceleration and angular acceleration."""
        OV, n = exu.OutputVariableType, self.b.node[body]
        return (np.asarray(self.b.mbs.GetNodeOutput(n, OV.Acceleration)),
                np.asarray(self.b.mbs.GetNodeOutput(n, OV.AngularAcceleration)))


class Sampler:
    """Every named output, the largest closure distance and the largest drive tracking error; and,
    every step, the converged arguments of the laws with a state (``commit``)."""

    def __init__(self, build: Build):
        self.b = build
        m = build.model
        rotational = {(b.name, k) for b in m.bodies for k, (kind, _) in enumerate(b.joint.dofs()) if kind == "R"}
        self.continuous = Continuous(build.state.q, rotational)
        self.closure, self.tracking = 0.0, 0.0
        self.forces = {f.name: f for f in m.forces}
        self.drives = {p.name: p for p in m.prescribed}
        self.stateful = build.states.elements
        self.slot = build.states.slot   # each element's first slot (a plane law's state takes two)
        self.q = {}
        self.recorded = []
        self.work = None   # exudyn_work.Work: the work outputs, integrated in the run (set by the builder)
        # the joints whose coordinates the outputs read (the coordinates, the joint laws, the drives)
        self.joints = ({o.body for o in m.outputs if o.kind == "coordinate"} | {f.joint for f in m.forces if f.joint} |
                       {p.joint for p in m.prescribed})

    def record(self, t: float) -> None:
        """The converged state at output time t, for ``replay``."""
        sd = self.b.mbs.systemData
        self.recorded.append((t, sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t(), sd.GetODE2Coordinates_tt(),
                              sd.GetAECoordinates(), list(self.b.states.s),
                              None if self.work is None else dict(zip(self.work.names, self.work.work))))

    def replay(self, reader=None) -> dict:
        """Every output at the recorded states, in time order (angles continuous across samples): name
        -> array over the samples. ``reader``: ExudynReader (the default) or exudyn_replay.SeriesReader
        (the module's docstring)."""
        reader = reader or ExudynReader(self.b, self)
        outputs = self.b.model.outputs
        parts = [[] for _ in outputs]
        for t, s, works in reader.samples(self.recorded):
            for part, value in zip(parts, self.columns(reader, t, s, works)):
                part.append(np.broadcast_to(value, np.shape(t)))   # a constant output: one value a sample
        self.recorded = []
        return {o.name: np.concatenate([np.atleast_1d(v) for v in part]).astype(float) for o, part in zip(outputs, parts)}

    def read(self, bodies) -> dict:
        """The poses, and the coordinates of ``bodies``' joints into self.q (continuous in time)."""
        return self.coordinates(self.b.poses(), bodies)

    def coordinates(self, P, bodies) -> dict:
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

    def law_value(self, reader, P, f, s, component=0):
        k = self.slot.get(f.name)
        if f.law.acts_on == PLANE:   # (Q_x, Q_y): the output's component
            z = (0.0, 0.0) if k is None else (s[..., k], s[..., k + 1])
            return _each(lambda *a: f.plane_force(*a)[component], *reader.arguments(P, f), *z)
        return _each(f.force, *reader.arguments(P, f), 0.0 if k is None else s[..., k])

    def acceleration(self, reader, P, o, t):
        """The body point's absolute acceleration: the node's (its centre of mass) from Exudyn's
        accelerations of the converged step (generalized-alpha's q'' that satisfies the equations of
        motion at the step's end, not its algorithmic acceleration), carried to the point,
        a_c + alpha x r + w x (w x r), plus the frame's a_g(t) with an excitation."""
        a = np.zeros(3)
        if o.body != GROUND:
            b = self.b.model.body(o.body)
            R, _, _, w = P[o.body]
            r = applied(R, np.asarray(o.point, dtype=float) - np.asarray(b.com, dtype=float))
            a_c, alpha = reader.node_acceleration(o.body)
            a = a_c + cross(alpha, r) + cross(w, cross(w, r))
        exc = self.b.model.excitation
        if exc is None:
            return a
        return a + (exc.acceleration(t) if np.ndim(t) == 0 else np.array([exc.acceleration(x) for x in t]))

    def energy(self, P, term):
        e = 0.0
        g = np.asarray(self.b.model.gravity, dtype=float)
        for b in self.b.model.bodies:
            R, r, v, w = P[b.name]
            c, vc = point(P, b.name, b.com)
            if term == "kinetic":
                e = e + 0.5 * b.mass * _dot(vc, vc) + 0.5 * _dot(w, applied(R @ b.inertia @ transposed(R), w))
            else:
                e = e - b.mass * _dot(g, c)
        return e

    def columns(self, reader, t, s, works) -> list:
        """Every output at time(s) t from ``reader``'s poses (one sample, or stacks over samples), s the
        committed law states (their last axis), ``works`` the work outputs recorded there."""
        m = self.b.model
        P = self.coordinates(reader.poses(), self.joints)
        row = []
        for o in m.outputs:
            if o.kind == "coordinate":
                row.append(self.q[(o.body, o.dof)])
            elif o.kind in ("point", "point_velocity"):
                row.append(point(P, o.body, o.point)[o.kind == "point_velocity"][..., o.component])
            elif o.kind == "point_acceleration":
                row.append(self.acceleration(reader, P, o, t)[..., o.component])
            elif o.kind == "force":
                row.append(self.law_value(reader, P, self.forces[o.element], s, o.component))
            elif o.kind == "state":   # the committed state its force value uses
                row.append(s[..., self.slot[o.element] + o.component])
            elif o.kind == "drive_force":
                row.append(reader.drive_force(self.drives[o.element]))
            elif o.kind == "work":   # integrated in the run to this time (exudyn_work), recorded
                row.append(works[o.name])
            else:
                row.append(self.energy(P, o.term))
        for lp in m.loops:
            gap = point(P, lp.body_a, lp.point_a)[0] - point(P, lp.body_b, lp.point_b)[0]
            self.closure = max(self.closure, float(np.max(np.sqrt(_dot(gap, gap)))))
        for p in m.prescribed:
            self.tracking = max(self.tracking, float(np.max(np.abs(self.q[(p.joint, p.dof)] - _each(lambda x: p(x)[0], t)))))
        return row
