"""The Exudyn builder's work outputs (kind ``work``, comparisons.builders.exudyn): each one's power at
every converged step, integrated by the trapezoid over Exudyn's steps (second order, as
generalized-alpha), in the pre-step function: the output step is too coarse for the quadrature.

Powers, at the converged state and time of a step's end (every force path the same, read back as the
outputs read a force: exudyn_outputs.Sampler.law_value, the laws' committed states):
- a force element: a points law's tension T pulls its ends together, power -T x' (x' the rate of
  its distance, or of its offset along its direction); a joint law's Q drives its coordinate, Q q';
- the excitation: the sum over the bodies of -m a_g(t) . v_com (the nodes sit at the centres of mass;
  their velocities are relative to the moving frame, as the load -m a_g(t) is applied: exudyn.Build);
- the drives: each prescribed motion's drive force (Build.drive_force, the locked axis' reaction)
  times q'(t).
"""
from __future__ import annotations

import exudyn as exu
import numpy as np

from nsd_core.model.laws import PLANE, POINTS
from comparisons.builders.exudyn_forces import law_arguments


class Work:
    """The work outputs of one run: ``step(t)`` at every converged state; the sampler records ``work``
    (by ``names``) with each output time's state."""

    def __init__(self, build, sampler):
        self.b, self.sample = build, sampler
        m = build.model
        self.outputs = [o for o in m.outputs if o.kind == "work"]
        self.names = [o.name for o in self.outputs]
        elements = {f.name: f for f in m.forces}
        self.elements = [elements.get(o.element) for o in self.outputs]
        # the joints whose coordinates (continuous angles) the joint laws read
        self.joints = {f.joint for f in self.elements if f is not None and f.law.acts_on != POINTS}
        self.mass = np.array([b.mass for b in m.bodies])
        self.velocity_index = None   # the nodes' velocity entries in Exudyn's ODE2 rates, once assembled
        self.work = np.zeros(len(self.outputs))
        self.power, self.t = None, 0.0
        self.entries = None   # the work elements' entries in the compiled elements (compiled_terms)
        self.plan = None      # the outputs' indices by source (_plan)
        self.ground = None    # the run's exudyn_drive.GroundTable (a_g at the steps' ends), set by the builder
        self.rates = None     # during the solve: Exudyn's ODE2 rates (a view of its vector, read in place)
        self.reader = None    # and the compiled values' reader on its vectors (CompiledForces.values_reader)

    def arguments(self):
        """Each work element's (x, x', committed state), read from the poses as its outputs are (the
        connectors' path; the compiled paths take ``compiled_terms``)."""
        b, states = self.b, self.b.states
        slot = states.slot

        def state(f):   # its committed state (a plane law's: two slots; none: zeros)
            k = slot.get(f.name)
            return tuple(0.0 if k is None else states.s[k + i] for i in range(2 if f.law.acts_on == PLANE else 1))
        P = self.sample.read(self.joints)
        return [None if f is None else (*law_arguments(b, P, self.sample.q, f), *state(f)) for f in self.elements]

    def compiled_terms(self, live: bool) -> np.ndarray:
        """The compiled paths' work elements' powers at the converged state, in ``_plan``'s order: x' and
        the law's value at the committed state of every element in one compiled call (CompiledForces.
        values, or during the solve its reader on Exudyn's own vectors), then per output Q x' (a plane
        law's Q_x x' + Q_y y'; a points law's -T x'): ``element_power``'s arithmetic on arrays."""
        compiled = self.b.compiled
        if self.entries is None:
            at = {}
            for j, f in enumerate(compiled.elements):   # a plane law's first entry (x; y is the next)
                at.setdefault(f.name, j)
            kept = [f for f in self.elements if f is not None]
            self.entries = (np.array([at[f.name] for f in kept], dtype=np.int64),
                            np.array([-1.0 if f.law.acts_on == POINTS else 1.0 for f in kept]),
                            np.array([f.law.acts_on == PLANE for f in kept], dtype=bool))
        j, sign, plane = self.entries
        xd, T = self.reader() if live else compiled.values(self.b.mbs)
        terms = T * xd
        out = sign * terms[j]
        out[plane] += terms[j[plane] + 1]
        return out

    def powers(self, t: float, live: bool = False) -> np.ndarray:
        """Every work output's power at the converged state at t (``live``: during the solve)."""
        b, out = self.b, np.zeros(len(self.outputs))
        if self.plan is None:
            self.plan = self._plan()
        elements, excitation, drives = self.plan
        if live and self.rates is None:   # the first step: Exudyn's vectors as its solver holds them
            self.rates = b.mbs.systemData.GetODE2Coordinates_t(exu.ConfigurationType.Current, False)
            self.reader = b.compiled.values_reader(b.mbs) if b.compiled is not None else None
        if len(elements):
            if b.compiled is not None:
                out[elements] = self.compiled_terms(live)
            else:
                for k, (f, a) in enumerate(zip(self.elements, self.arguments())):
                    if f is not None:
                        out[k] = element_power(f, a)
        if excitation:
            rates = self.rates if live else b.mbs.systemData.GetODE2Coordinates_t()
            a = np.array(self.ground.acceleration(t)) if self.ground is not None else b.excitation.acceleration(t)
            p = -float(a @ (self.mass @ rates[self.velocity_index]))
            for k in excitation:
                out[k] = p
        for k in drives:
            out[k] = sum(b.drive_force(p) * p(t)[1] for p in b.model.prescribed)
        return out

    def _plan(self) -> tuple:
        """The outputs' indices by source, once (the pre-step runs every step): force elements,
        the excitation, the drives; and the nodes' velocity entries in Exudyn's ODE2 rates."""
        b = self.b
        elements = np.array([k for k, f in enumerate(self.elements) if f is not None], dtype=np.int64)
        excitation = [k for k, (o, f) in enumerate(zip(self.outputs, self.elements)) if f is None and o.source == "excitation"]
        drives = [k for k, (o, f) in enumerate(zip(self.outputs, self.elements)) if f is None and o.source != "excitation"]
        if excitation:
            self.velocity_index = np.array([[b.mbs.GetNodeODE2Index(b.node[body.name]) + c for c in range(3)]
                                            for body in b.model.bodies])
        return elements, excitation, drives

    def step(self, t: float, live: bool = True) -> None:
        """The converged state at t: the trapezoid from the last one (``live``: from the pre-step
        function, during the solve; False after it)."""
        now = self.powers(t, live)
        if self.power is not None:
            self.work += 0.5 * (t - self.t) * (self.power + now)
        self.power, self.t = now, t


def element_power(f, args) -> float:
    """A force element's power from its law at (x, x', committed state): Q_x x' + Q_y y' for a plane
    law, -T x' for a points law (its tension pulls the ends together), Q q' for a joint law."""
    if f.law.acts_on == PLANE:
        x, y, xd, yd, sx, sy = args
        qx, qy = f.plane_force(x, y, xd, yd, sx, sy)
        return qx * xd + qy * yd
    x, xd, s = args
    return (-1.0 if f.law.acts_on == POINTS else 1.0) * f.force(x, xd, s) * xd
