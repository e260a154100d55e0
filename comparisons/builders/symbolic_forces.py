"""The force elements of a description applied to the symbolic engine's equations as generalised
forces, each law called through the registry (nsd_core.model.laws), numerically, at run time.

A points law acts along d = p_a - p_b (p from the derived positions, J_d = J_a - J_b from the derived
Jacobians): x = |d| (or d . e with a ``direction`` e), x' = (d . J_d u) / x (or e . J_d u), and the
law's tension T gives Q = -T x_q, x_q = d^T J_d / x (or e^T J_d): a tension pulls the points together
(where the two points coincide the line has no direction and the force is zero). A joint law's Q acts
on its coordinate; a plane law's (Q_x, Q_y) on its two. A law with a state adds its rate; each
``work`` output adds its power (a points law -T x', a joint law Q q', a plane law Q_x x' + Q_y y').
"""
from __future__ import annotations

import numpy as np

from nsd_core.model.laws import JOINT, POINTS


class Forces:
    """The elements of one model, bound to the symbolic engine's coordinate and point order."""

    def __init__(self, model, coordinates: list, points: list):
        self.model = model
        index = {c: i for i, c in enumerate(coordinates)}
        pidx = {(b, tuple(float(c) for c in p)): k for k, (b, p) in enumerate(points)}
        self.items, self.slot, n_state = [], {}, 0
        for f in model.forces:
            item = {"f": f, "kind": f.law.acts_on}
            if f.law.acts_on == POINTS:
                item["a"] = pidx[(f.body_a, tuple(float(c) for c in f.point_a))]
                item["b"] = pidx[(f.body_b, tuple(float(c) for c in f.point_b))]
                item["e"] = None if f.direction is None else np.asarray(f.direction, dtype=float)
            elif f.law.acts_on == JOINT:
                item["i"] = index[(f.joint, f.dof)]
            else:
                item["i"], item["j"] = index[(f.joint, f.dofs[0])], index[(f.joint, f.dofs[1])]
            if f.law.state_size:
                self.slot[f.name] = n_state
                item["s"] = n_state
                n_state += f.law.state_size
            self.items.append(item)
        self.n_state = n_state
        self.initial = np.array([v for f in model.forces for v in f.initial_states], dtype=float)

    def __call__(self, q, u, s, R, J):
        """(Q, state rates, {element: value}, {element: power}) at one state."""
        Q, rates = np.zeros(len(q)), np.zeros(self.n_state)
        values, powers = {}, {}
        for it in self.items:
            f = it["f"]
            if it["kind"] == POINTS:
                d, Jd = R[it["a"]] - R[it["b"]], J[it["a"]] - J[it["b"]]
                if it["e"] is None:
                    x = float(np.sqrt(d @ d))
                    xq = (d @ Jd) / x if x > 0.0 else np.zeros(len(q))
                else:
                    x, xq = float(d @ it["e"]), it["e"] @ Jd
                xd = float(xq @ u)
                st = s[it["s"]] if "s" in it else 0.0
                T = f.force(x, xd, st) if x > 0.0 or it["e"] is not None else 0.0
                Q -= T * xq
                values[f.name], powers[f.name] = T, -T * xd
                if "s" in it:
                    rates[it["s"]] = f.rate(x, xd, st)
            elif it["kind"] == JOINT:
                i = it["i"]
                st = s[it["s"]] if "s" in it else 0.0
                v = f.force(q[i], u[i], st)
                Q[i] += v
                values[f.name], powers[f.name] = v, v * u[i]
                if "s" in it:
                    rates[it["s"]] = f.rate(q[i], u[i], st)
            else:   # a plane law
                i, j = it["i"], it["j"]
                sx, sy = (s[it["s"]], s[it["s"] + 1]) if "s" in it else (0.0, 0.0)
                qx, qy = f.plane_force(q[i], q[j], u[i], u[j], sx, sy)
                Q[i] += qx
                Q[j] += qy
                values[f.name], powers[f.name] = (qx, qy), qx * u[i] + qy * u[j]
                if "s" in it:
                    rates[it["s"]], rates[it["s"] + 1] = f.plane_rate(q[i], q[j], u[i], u[j], sx, sy)
        return Q, rates, values, powers

