"""The description's force elements as one Exudyn object for the whole model (``forces = "compiled"``
of comparisons.builders.exudyn), the fast path beside the connectors of exudyn_forces (the readable
reference: the same equations, one connector per element).

One ObjectGenericODE2 spans every body's node (3 positions + 4 Euler parameters each) with no mass
matrix (empty: a zero one, the same numbers, cost Exudyn ~1.6 us a step on the device's drive, adding
its zeros); its force user function returns the generalized forces of all elements at the coordinates
Newton is trying (implicit, as the connectors). Per call one compiled function generated for the
model (exudyn_codegen) takes Exudyn's coordinates to every element's (x, x') and the bodies' poses
(``arguments``), calls the registry's laws (their states by Heun's method at the step, the
connectors' scheme, exudyn_forces.LawStates) and maps the laws' values to generalized forces
(``forces``); its Jacobian is a compiled forward difference of the same function (Exudyn's would
call the Python function twice per coordinate). So the discrete equations are the connectors' and the two paths agree to Newton's tolerance,
except one detail where this path follows the description's virtual work (and a plane law, which
the connectors take on a joint to the ground only, is here two joint entries, one per slide, on any
joint: its law called once for both, exudyn_codegen): a joint law on a slide
pushes the parent at the child's frame origin (the connector pushes it at the parent's joint point;
the two differ by a moment when the child is off the slide's line, which no joint of the device or
the tests has).

The compiled kernels (poses, arguments, forces) are in exudyn_kernels.
"""
from __future__ import annotations

import numpy as np

import exudyn as exu
from exudyn.itemInterface import ObjectGenericODE2

from comparisons.builders.exudyn_frames import law_axis
from nsd_core.model.description import GROUND
from nsd_core.model.errors import ModelError
from nsd_core.model.laws import PLANE, POINTS


class CompiledForces:
    """All of a Build's force elements as one ObjectGenericODE2 (the module's docstring)."""

    def __init__(self, build, states, predicted: bool = False):
        model, mbs = build.model, build.mbs
        self.bodies = [b.name for b in model.bodies]
        index = {name: i for i, name in enumerate(self.bodies)}
        index[GROUND] = -1
        com = {b.name: np.asarray(b.com, dtype=float) for b in model.bodies}
        com[GROUND] = np.zeros(3)
        pts = [f for f in model.forces if f.law.acts_on == POINTS]
        # joint entries: one per joint law, two per plane law (its slides, x then y; its law called once)
        jts = [(f, k) for f in model.forces if f.law.acts_on != POINTS
               for k in (f.dofs if f.law.acts_on == PLANE else (f.dof,))]
        self.elements = pts + [f for f, _ in jts]
        self.ia = np.array([index[f.body_a] for f in pts], dtype=np.int64)
        self.ib = np.array([index[f.body_b] for f in pts], dtype=np.int64)
        self.pa = np.array([np.asarray(f.point_a, float) - com[f.body_a] for f in pts]).reshape(-1, 3)
        self.pb = np.array([np.asarray(f.point_b, float) - com[f.body_b] for f in pts]).reshape(-1, 3)
        self.e = np.array([np.zeros(3) if f.direction is None else np.asarray(f.direction, float)
                           for f in pts]).reshape(-1, 3)
        cols = []
        for f, dof in jts:
            b = model.body(f.joint)
            k = law_axis(b, dof)
            if k is None:
                raise ModelError(f"forces.{f.name}.joint = {f.joint!r}: the Exudyn builder applies joint laws on slides "
                                 f"and on revolute and planar turns only (this is a turn of a {b.joint.type} joint)")
            J = build.frames[b.name]
            cols.append((index[b.name], index[b.parent], J[:, k % 3], J[:, 0], J[:, 1],
                         np.asarray(b.joint.position, float) - com[b.parent], -com[b.name], k >= 3,
                         build.state.q[(b.name, dof)]))
        self.jc = np.array([c[0] for c in cols], dtype=np.int64)
        self.jp = np.array([c[1] for c in cols], dtype=np.int64)
        self.jax, self.jx, self.jy, self.jpos, self.jorig = (np.array([c[i] for c in cols], float).reshape(-1, 3)
                                                             for i in range(2, 7))
        self.turn = np.array([c[7] for c in cols], dtype=np.bool_)
        self.last = np.array([c[8] for c in cols], float)   # each turn's angle at the last call
        nb = len(self.bodies)
        self.f = np.zeros(7 * nb)   # the generalized forces Exudyn gets back
        self.states = states
        for f in self.elements:
            if f.law.state is not None and f.name not in states.slot:
                states.add(f)
        self.nodes, self.index = [build.node[name] for name in self.bodies], None
        self.ref = np.concatenate([np.asarray(mbs.GetNodeParameter(n, "referenceCoordinates"), float)
                                   for n in self.nodes])
        # one generated module per set of laws: laws and states inside the compiled call (exudyn_codegen)
        from comparisons.builders.exudyn_codegen import module_for, pack, source   # it imports this module
        from comparisons.builders.generated import law_set
        laws = law_set(self.elements)
        self.F, self.I, self.W, sizes, params = pack(self, laws)
        self.gen = module_for(*source(laws))
        self.s_at, self.ns = sizes["s"], len(states.s)
        # the committed states and rates are W's (views): the outputs and the work read them as committed
        states.s, states.r = self.W[self.s_at:self.s_at + self.ns], self.W[self.s_at + self.ns:self.s_at + 2 * self.ns]
        self.J = np.zeros((7 * nb, 7 * nb))
        # load (or compile) the machine code now, not in the timed run's first call; on copies of the states
        z = np.zeros(7 * nb)
        if not predicted:   # the Jacobian only where Newton calls it (0.6-3.3 s to compile per model shape)
            self.gen.jacobian(z, z, self.F, self.I, self.W.copy(), 1.0, 1.0, self.J.copy())
        self.gen.commit(z, z, self.F, self.I, self.W.copy())
        self.gen.advance(z, z, z, np.arange(7 * nb), 0.0, True, self.F, self.I, self.W.copy(), self.f.copy())
        self.predicted = predicted
        if predicted:   # a constant force vector, set before each step (``predict``)
            kw = {"forceVector": np.zeros(7 * nb)}
        else:
            force, jacobian = self.user_functions()
            kw = {"forceUserFunction": force, "jacobianUserFunction": jacobian}
        self.object = mbs.AddObject(ObjectGenericODE2(nodeNumbers=self.nodes,
                                                      **kw))

    def node_index(self, mbs) -> np.ndarray:
        """The nodes' entries in Exudyn's ODE2 vectors (7 each), known once the system is assembled."""
        if self.index is None:
            self.index = np.concatenate([np.arange(i, i + 7) for i in map(mbs.GetNodeODE2Index, self.nodes)])
        return self.index

    def predict(self, mbs, h: float) -> None:
        """forces = "predicted": the forces for the step of size h starting at the converged state, at
        its Taylor-predicted end (q + h q' + h^2/2 q'', q' + h q''; the states by Heun from the
        committed ones, as ``evaluate``), held through the step. The prediction's error is O(h^3) in
        the positions and O(h^2) in the rates, so the forces' error adds O(h^2) to the motion: second
        order, as generalized-alpha (the adapter's per_step scheme, generic here)."""
        sd, ix = mbs.systemData, self.node_index(mbs)
        q, v = np.asarray(sd.GetODE2Coordinates())[ix], np.asarray(sd.GetODE2Coordinates_t())[ix]
        if h > 0.0:
            a = np.asarray(sd.GetODE2Coordinates_tt())[ix]
            q, v = q + h * v + (0.5 * h * h) * a, v + h * a
        mbs.SetObjectParameter(self.object, "forceVector", self.gen.evaluate(q, v, self.F, self.I, self.W, self.f))

    def commit(self, mbs) -> None:
        """The step converged: the laws' states move on at Exudyn's current coordinates (in the compiled
        call; LawStates' s and r are views of them)."""
        self.advance(mbs, 0.0, False)

    def advance(self, mbs, h: float, predict: bool) -> None:
        """The pre-step's work in one compiled call on Exudyn's coordinate vectors: ``commit``, then
        (``predict``) ``predict``'s forces for the step of size h, set as the object's force vector."""
        sd = mbs.systemData
        f = self.gen.advance(np.asarray(sd.GetODE2Coordinates()), np.asarray(sd.GetODE2Coordinates_t()),
                             np.asarray(sd.GetODE2Coordinates_tt()) if predict else self.f, self.node_index(mbs), h, predict,
                             self.F, self.I, self.W, self.f)
        self.states.started = True
        if predict:
            mbs.SetObjectParameter(self.object, "forceVector", f)

    def stepper(self, mbs, h: float, predict: bool):
        """``advance(mbs, h, predict)`` as a closure of no arguments for the pre-step function, run once a
        step: its look-ups done once, the same compiled call on the same numbers. Exudyn's coordinate
        vectors are read through views of its solver's own (``copy=False``): made from the pre-step
        function, once the solver holds them; the caller sets ``states.started``."""
        sd, CT = mbs.systemData, exu.ConfigurationType.Current
        q, q_t = sd.GetODE2Coordinates(CT, False), sd.GetODE2Coordinates_t(CT, False)
        q_tt = sd.GetODE2Coordinates_tt(CT, False) if predict else self.f
        ix, advance, F, I, W, f = self.node_index(mbs), self.gen.advance, self.F, self.I, self.W, self.f
        set_parameter, item = mbs.SetObjectParameter, self.object

        def step():
            if predict:
                set_parameter(item, "forceVector", advance(q, q_t, q_tt, ix, h, True, F, I, W, f))
            else:
                advance(q, q_t, q_tt, ix, h, False, F, I, W, f)
        return step

    def values(self, mbs) -> tuple[np.ndarray, np.ndarray]:
        """Every element's x' and law value at Exudyn's current coordinates and the committed states, in
        ``elements``' order (a plane law's (Q_x, Q_y) in its two entries): exudyn_work's powers at the
        converged steps, in one compiled call (the laws called from Python cost ~30 us a step)."""
        sd, ne, ix = mbs.systemData, len(self.elements), self.node_index(mbs)
        x, xd, T = np.empty(ne), np.empty(ne), np.empty(ne)
        self.gen.values(np.asarray(sd.GetODE2Coordinates())[ix], np.asarray(sd.GetODE2Coordinates_t())[ix],
                        self.F, self.I, self.W, x, xd, T)
        return xd, T

    def values_reader(self, mbs):
        """``values(mbs)`` as a closure of no arguments for the pre-step function (the work's powers at
        every step): Exudyn's coordinate vectors read through views of its solver's own, as ``stepper``
        reads them, into arrays kept between calls; the same compiled call on the same numbers."""
        sd, CT = mbs.systemData, exu.ConfigurationType.Current
        q_all, q_t_all = sd.GetODE2Coordinates(CT, False), sd.GetODE2Coordinates_t(CT, False)
        ix, values, F, I, W = self.node_index(mbs), self.gen.values, self.F, self.I, self.W
        q, q_t = np.empty(len(ix)), np.empty(len(ix))
        take_q, take_q_t = q_all.take, q_t_all.take
        ne = len(self.elements)
        x, xd, T = np.empty(ne), np.empty(ne), np.empty(ne)

        def read() -> tuple[np.ndarray, np.ndarray]:
            take_q(ix, out=q)
            take_q_t(ix, out=q_t)
            values(q, q_t, F, I, W, x, xd, T)
            return xd, T
        return read

    def user_functions(self):
        """Exudyn's force and Jacobian user functions: plain closures around the compiled calls (the
        force function runs ~5 times a step: no attribute look-ups, Exudyn's lists as arrays)."""
        evaluate, jacobian, F, I, W, f, J = self.gen.evaluate, self.gen.jacobian, self.F, self.I, self.W, self.f, self.J
        array = np.array

        def force(mbs, t, item, q, q_t):
            """The generalized forces at (q, q')."""
            return evaluate(array(q), array(q_t), F, I, W, f)

        def jacobian_of(mbs, t, item, q, q_t, fq, fv):
            """-(fq df/dq + fv df/dq'), differentiated in the compiled call."""
            return jacobian(array(q), array(q_t), F, I, W, float(fq), float(fv), J)
        return force, jacobian_of
