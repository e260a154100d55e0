"""The Exudyn builder's outputs at every recorded sample at once (``outputs_from = "coordinates"``, the
compiled force paths' default; comparisons.builders.exudyn_outputs' docstring): a reader for
exudyn_outputs.Sampler.columns whose poses, law arguments, drive forces and node accelerations are
stacks over the samples, computed from the recorded coordinates instead of setting each state back
into Exudyn and reading it through Python (ExudynReader, the reference it equals to round-off).

- Poses: the compiled path's own kernel (exudyn_kernels._poses, the Euler parameters' rotation and G
  matrix) at each sample, one compiled call for all.
- Law arguments (x, x'): the generated force function's kinematics (exudyn_codegen ``series``), one
  compiled call for all samples; the turns' continuity from the initial angles on, sample to sample.
- Drive forces: the locked axis' multiplier from the recorded algebraic coordinates where Exudyn's
  GenericJoint reports it as is: its torques (TorqueLocal is the rotation multipliers) and its forces
  while a translation stays free (the translation multipliers are in the joint frame then, as the
  offsets are: exudyn.Build._tree_joint); with all three translations locked they are global, and
  ForceLocal turns them by the joint frame's pose: those are read through Exudyn, sample by sample.
- Node accelerations: the recorded ODE2 accelerations; the angular one G e'' (G(e') e' = 0 for Euler
  parameters).
"""
from __future__ import annotations

import exudyn as exu
import numpy as np

from comparisons.builders.exudyn_frames import AXIS_OF_DOF, applied, cross
from comparisons.builders.exudyn_kernels import pose_series
from nsd_core.model.description import GROUND
from nsd_core.model.laws import PLANE


class SeriesReader:
    """Every recorded sample at once (the module's docstring)."""

    def __init__(self, build, sampler):
        self.b = build
        mbs = build.mbs
        self.bodies = [b.name for b in build.model.bodies]
        nodes = [build.node[name] for name in self.bodies]
        self.index = np.concatenate([np.arange(i, i + 7) for i in map(mbs.GetNodeODE2Index, nodes)]).astype(np.int64) \
            if nodes else np.zeros(0, np.int64)
        self.ref = np.concatenate([np.asarray(mbs.GetNodeParameter(n, "referenceCoordinates"), float) for n in nodes]) \
            if nodes else np.zeros(0)
        self.recorded = []

    def samples(self, recorded):
        """All of ``recorded`` as one series: yields (t, law states, works) once, each an array over
        the samples (the law states' and works' second axis, by slot and by name)."""
        self.recorded = recorded
        n, nb = len(recorded), len(self.bodies)
        # C order: numpy gives a[:, index] in Fortran order, and its rows ('A' layout to numba) compiled
        # the force call's kinematics (_state) a second time for the series, ~2 s on a cold cache per shape
        self.Q = np.ascontiguousarray(np.array([r[1] for r in recorded])[:, self.index])
        self.Q_t = np.ascontiguousarray(np.array([r[2] for r in recorded])[:, self.index])
        self.Q_tt = np.ascontiguousarray(np.array([r[3] for r in recorded])[:, self.index])
        self.lam = np.array([r[4] for r in recorded]).reshape(n, -1)
        self.R, self.G = np.empty((n, nb, 3, 3)), np.empty((n, nb, 3, 4))
        self.r, self.v, self.w = np.empty((n, nb, 3)), np.empty((n, nb, 3)), np.empty((n, nb, 3))
        pose_series(self.Q, self.Q_t, self.ref, self.R, self.G, self.r, self.v, self.w)
        self.x = None
        t = np.array([r[0] for r in recorded], dtype=float)
        s = np.array([r[5] for r in recorded], dtype=float).reshape(n, -1)
        names = recorded[0][6].keys() if recorded and recorded[0][6] is not None else ()
        yield t, s, {k: np.array([r[6][k] for r in recorded], dtype=float) for k in names}

    def poses(self) -> dict:
        """body -> (R, origin, origin velocity, omega), each a stack over the samples (Build.poses)."""
        out = {GROUND: (np.eye(3), np.zeros(3), np.zeros(3), np.zeros(3))}
        for i, name in enumerate(self.bodies):
            R, w = self.R[:, i], self.w[:, i]
            c = applied(R, np.asarray(self.b.model.body(name).com, dtype=float))
            out[name] = (R, self.r[:, i] - c, self.v[:, i] - cross(w, c), w)
        return out

    def arguments(self, P, f):
        """(x, x') of force element f at every sample (exudyn_codegen's ``series``)."""
        cf = self.b.compiled
        if self.x is None:
            n, ne = len(self.Q), len(cf.elements)
            self.x, self.xd = np.empty((n, ne)), np.empty((n, ne))
            W = cf.W.copy()
            W[:len(cf.last)] = cf.last   # the turns' angles at t = 0, each sample continuing from the last
            cf.gen.series(self.Q, self.Q_t, cf.F, cf.I, W, self.x, self.xd)
            self.at = {}
            for j, e in enumerate(cf.elements):   # a plane law's first entry (x; y is the next)
                self.at.setdefault(e.name, j)
        j = self.at[f.name]
        if f.law.acts_on == PLANE:
            return self.x[:, j], self.x[:, j + 1], self.xd[:, j], self.xd[:, j + 1]
        return self.x[:, j], self.xd[:, j]

    def drive_force(self, p):
        """The drive force of prescribed motion p at every sample (Build.drive_force's sign)."""
        b = self.b
        k = AXIS_OF_DOF[b.model.body(p.joint).joint.type][p.dof]
        joint = b.joints[p.joint]
        if k >= 3 or not all(b.mbs.GetObjectParameter(joint, "constrainedAxes")[:3]):
            lam = self.lam[:, b.mbs.systemData.GetObjectLTGAE(joint)[k]]
            return lam if k >= 3 else -lam
        sd, now, out = b.mbs.systemData, exu.ConfigurationType.Current, []
        for _, q, q_t, _, lam, _, _ in self.recorded:
            sd.SetODE2Coordinates(q, now)
            sd.SetODE2Coordinates_t(q_t, now)
            sd.SetAECoordinates(lam, now)
            out.append(b.drive_force(p))
        return np.array(out)

    def node_acceleration(self, body):
        """The node's acceleration and angular acceleration G e'' at every sample."""
        i = self.bodies.index(body)
        return self.Q_tt[:, 7 * i:7 * i + 3], applied(self.G[:, i], self.Q_tt[:, 7 * i + 3:7 * i + 7])
