"""The symbolic builder: a model description run on equations of motion derived by Kane's method
(sympy.physics.mechanics), generated to code, cached, and integrated by scipy.

Formulation (docs/models.md, "The symbolic engine"): Kane's equations of the open tree, M(q) u' =
F(q, u, g) + Q, with u = q' (comparisons.builders.symbolic_derive), and the loops in the augmented
form with Lagrange multipliers, M u' = F + Q + Phi_q^T lambda, Phi_q u' = -gamma, stabilised by
Baumgarte's terms -2 w Phi' - w^2 Phi (``baumgarte`` = w, 1/s). Why the augmented form and not
Kane's dependent speeds: sympy's dependent-speed form inverts the constraint Jacobian's dependent
block symbolically, whose expressions grow with every loop (Andrews' mechanism: six equations,
Bricard's: a redundant one, which the symbolic inverse cannot take at all), while the augmented form
keeps each derived quantity as small as the tree's and leaves the linear algebra to numbers
(``multipliers``: the range space, lambda by iterated Tikhonov regularisation), where a redundant or
momentarily singular Phi_q (IFToMM A02's singular positions) stays bounded and smooth (u' is unique
while M is positive definite).

Prescribed coordinates are not states: q_p(t), q_p'(t), q_p''(t) are inserted, the remaining rows
are solved for u_f', and the drive's force is the prescribed rows' residual, tau = (M u' - F - Q -
Phi_q^T lambda)_p: positive drives q up (the in-house sign convention). Every law is called through
the registry (comparisons.builders.symbolic_forces); a law's state and each ``work`` output's power
are extra states of the ODE. Gravity and the ground's excitation enter as the effective field
g - a_g(t), a symbol of the derived forcing. The start is this engine's own Newton on its own
closure (comparisons.builders.symbolic_start).

Settings (``default_settings``): ``method`` DOP853 or Radau (scipy.integrate.solve_ivp), ``rtol``,
``atol``, ``max_step`` [s], ``baumgarte`` [1/s], ``regularisation`` and ``refinements`` (the
multipliers' solve). The engine's error estimate is its own tolerance ladder: the run at
``rtol`` against one at rtol x ``comparisons.estimate.TOLERANCE_LADDER``, plus, with loops, the run
against one at the regularisation x ``comparisons.estimate.FORMULATION_COMPANION`` (its bias, which no
tolerance controls; comparisons.model_compare.adaptive_estimate).

Run statistics (``ModelRun.stats``): ``wall_time`` (integration and outputs), ``derive_time`` and
``codegen_time`` of this run (0 when the cache had the equations), ``load_time``, ``cache``,
``steps``, ``nfev``, ``closure_max``, ``tracking_error`` (0: prescribed coordinates are exact).
"""
from __future__ import annotations

import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.linalg import cho_factor, cho_solve

from comparisons.builders.symbolic_codegen import equations
from comparisons.builders.symbolic_forces import Forces
from comparisons.builders.symbolic_start import initial_state
from nsd_core.model.description import Model
from nsd_core.model.errors import ModelError
from nsd_core.model.run import ModelRun, output_times

name = "symbolic"
default_settings = {"method": "DOP853", "rtol": 1e-10, "atol": 1e-12, "max_step": 0.01, "baumgarte": 100.0,
                    "regularisation": 1e-8, "refinements": 50}
METHODS = ("DOP853", "Radau")


def validate_settings(s: dict) -> None:
    """The method one of METHODS; rtol at least 1e-11, so that its tolerance ladder's run stays >= 1e-13;
    the regularisation at most 0.01 of S's largest diagonal entry, so that its estimate's run at x10 stays
    a small perturbation (a regularisation as large as S drops the loops' forces: the loops open)."""
    if s["method"] not in METHODS:
        raise ModelError(f"symbolic.method = {s['method']!r}: allowed: {', '.join(METHODS)}")
    if not s["rtol"] >= 1e-11:
        raise ModelError(f"symbolic.rtol = {s['rtol']!r}: must be >= 1e-11 (its error estimate runs at rtol x 0.01)")
    if not s["regularisation"] <= 0.01:
        raise ModelError(f"symbolic.regularisation = {s['regularisation']!r}: must be <= 0.01 (a fraction of S's "
                         "largest diagonal entry; its error estimate runs at regularisation x 10)")


def check(model: Model) -> None:
    """Every joint, loop, law, drive, excitation and output of the format is built; a model without a
    coordinate has no equations to derive."""
    if not model.coordinates():
        raise ModelError("[[bodies]]: the symbolic engine needs at least one joint coordinate")


class System:
    """One description's derived equations bound to its coordinates, drives, laws and outputs."""

    def __init__(self, model: Model, eqs, meta: dict, settings: dict):
        self.model, self.eqs, self.s = model, eqs, settings
        self.coords = model.coordinates()
        index = {c: i for i, c in enumerate(self.coords)}
        self.n = len(self.coords)
        self.drives = [(index[(p.joint, p.dof)], p) for p in model.prescribed]
        self.p = np.array([i for i, _ in self.drives], dtype=int)
        self.f = np.array([i for i in range(self.n) if i not in set(self.p)], dtype=int)
        self.points = [(b, tuple(p)) for b, p in meta["points"]]
        self.pindex = {k: i for i, k in enumerate(self.points)}
        self.forces = Forces(model, self.coords, self.points)
        self.works = [o for o in model.outputs if o.kind == "work"]
        self.coms = [self.pindex[(b.name, tuple(float(c) for c in b.com))] for b in model.bodies]
        self.mass = np.array([b.mass for b in model.bodies])

    def motion(self, t):
        """(q_p, q_p', q_p'') of every drive at t."""
        if not self.drives:
            return np.zeros(0), np.zeros(0), np.zeros(0)
        v = np.array([p(t) for _, p in self.drives], dtype=float)
        return v[:, 0], v[:, 1], v[:, 2]

    def split(self, t, y):
        nf = len(self.f)
        q, u = np.empty(self.n), np.empty(self.n)
        q[self.f], u[self.f] = y[:nf], y[nf:2 * nf]
        qp, up, ap = self.motion(t)
        q[self.p], u[self.p] = qp, up
        ns = self.forces.n_state
        return q, u, ap, y[2 * nf:2 * nf + ns], y[2 * nf + ns:]

    def evaluate(self, t, y) -> dict:
        """Every quantity at (t, y): accelerations, multipliers, the drives' forces, the laws' values."""
        q, u, ap, s, w = self.split(t, y)
        M, F, Phi, Phi_q, gamma = self.eqs.dynamics(q, u, self.model.gravity_at(t))
        R, J, Jdu = self.eqs.points(q, u)
        Q, rates, values, powers = self.forces(q, u, s, R, J)
        f, p = self.f, self.p
        total = F + Q
        b = total[f] - M[np.ix_(f, p)] @ ap
        A = M[np.ix_(f, f)]
        udot = np.empty(self.n)
        udot[p] = ap
        lam = np.zeros(len(Phi))
        if len(Phi) and len(f):
            C, wb = Phi_q[:, f], self.s["baumgarte"]
            c = -Phi_q[:, p] @ ap - gamma - 2.0 * wb * (Phi_q @ u) - wb * wb * Phi
            udot[f], lam = multipliers(A, b, C, c, self.s)
        elif len(f):
            udot[f] = _solve(A, b)
        tau = (M @ udot - total - Phi_q.T @ lam)[p] if len(p) else np.zeros(0)
        return {"t": t, "q": q, "u": u, "udot": udot, "s": s, "w": w, "M": M, "Phi": Phi, "R": R, "J": J,
                "Jdu": Jdu, "rates": rates, "values": values, "powers": powers, "tau": tau}

    def power(self, ev, out) -> float:
        """A work output's power at one evaluation."""
        if out.element:
            return ev["powers"][out.element]
        if out.source == "drive":
            return float(ev["tau"] @ ev["u"][self.p]) if len(self.p) else 0.0
        if self.model.excitation is None:
            return 0.0
        a = self.model.excitation.acceleration(ev["t"])
        return -float(sum(m * (a @ (ev["J"][k] @ ev["u"])) for m, k in zip(self.mass, self.coms)))

    def rhs(self, t, y):
        ev = self.evaluate(t, y)
        return np.concatenate([ev["u"][self.f], ev["udot"][self.f], ev["rates"],
                               [self.power(ev, o) for o in self.works]])

    def sample(self, ev) -> list[float]:
        return [float(self.one(ev, o)) for o in self.model.outputs]

    def one(self, ev, o):
        if o.kind == "coordinate":
            return ev["q"][self.coords.index((o.body, o.dof))]
        if o.kind in ("point", "point_velocity", "point_acceleration"):
            k = self.pindex[(o.body, tuple(float(c) for c in o.point))]
            if o.kind == "point":
                return ev["R"][k][o.component]
            if o.kind == "point_velocity":
                return (ev["J"][k] @ ev["u"])[o.component]
            a = ev["J"][k] @ ev["udot"] + ev["Jdu"][k]
            if self.model.excitation is not None:
                a = a + self.model.excitation.acceleration(ev["t"])
            return a[o.component]
        if o.kind == "force":
            v = ev["values"][o.element]
            return v[o.component] if isinstance(v, tuple) else v
        if o.kind == "state":
            return ev["s"][self.forces.slot[o.element] + o.component]
        if o.kind == "drive_force":
            return ev["tau"][[p.name for _, p in self.drives].index(o.element)]
        if o.kind == "work":
            return ev["w"][self.works.index(o)]
        if o.term == "kinetic":
            return 0.5 * ev["u"] @ ev["M"] @ ev["u"]
        g = np.asarray(self.model.gravity, dtype=float)
        return -sum(m * (g @ ev["R"][k]) for m, k in zip(self.mass, self.coms))


def multipliers(A, b, C, c, s) -> tuple[np.ndarray, np.ndarray]:
    """u' and lambda of A u' = b + C^T lambda, C u' = c in the range space: u' = A^-1 (b + C^T lambda),
    S lambda = c - C A^-1 b, S = C A^-1 C^T, solved by iterated Tikhonov regularisation (S + mu I, mu =
    ``regularisation`` x S's largest diagonal entry, at most ``refinements`` corrections): exact to round-off
    where S is regular, smooth and bounded where it loses rank (a redundant row, IFToMM A02's singular
    positions), where a plain solve divides by a vanishing pivot and a truncated least squares jumps."""
    X = _solve(A, np.column_stack([b, C.T]))
    S = C @ X[:, 1:]
    r = c - C @ X[:, 0]
    mu = s["regularisation"] * max(float(np.max(np.abs(np.diag(S)))), 1e-300)
    factor = cho_factor(S + mu * np.eye(len(c)))
    lam = cho_solve(factor, r)
    for _ in range(s["refinements"]):   # until a correction no longer changes lambda
        step = cho_solve(factor, r - S @ lam)
        lam += step
        if np.max(np.abs(step)) <= 1e-15 * np.max(np.abs(lam)):
            break
    return X[:, 0] + X[:, 1:] @ lam, lam


def _solve(A, B):
    try:
        return np.linalg.solve(A, B)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(A, B, rcond=None)[0]


def start(system: System) -> np.ndarray:
    """The ODE's state at t = 0: the free coordinates and rates, the laws' states, zero work."""
    zero = np.zeros(3)

    def constraints(q):
        _, _, Phi, Phi_q, _ = system.eqs.dynamics(q, np.zeros(system.n), zero)
        return Phi, Phi_q
    qp, up, _ = system.motion(0.0)
    q, u = initial_state(system.model, system.coords, constraints,
                         {i: (qp[k], up[k]) for k, (i, _) in enumerate(system.drives)})
    return np.concatenate([q[system.f], u[system.f], system.forces.initial, np.zeros(len(system.works))])


def simulate(model: Model, duration: float, dt_out: float, settings: dict | None = None) -> ModelRun:
    s = {**default_settings, **(settings or {})}
    if s["method"] not in METHODS:
        raise ModelError(f"symbolic.method = {s['method']!r}: allowed: {', '.join(METHODS)}")
    check(model)
    eqs, meta = equations(model)
    system = System(model, eqs, meta, s)
    y0 = start(system)
    t_eval = output_times(duration, dt_out)
    begin = time.perf_counter()
    if len(y0):
        sol = solve_ivp(system.rhs, (0.0, float(t_eval[-1])), y0, method=s["method"], rtol=s["rtol"],
                        atol=s["atol"], max_step=s["max_step"], dense_output=True,
                        first_step=min(dt_out, s["max_step"]) / 10)
        if sol.status != 0:
            raise RuntimeError(f"symbolic engine: {sol.message} (t = {sol.t[-1]:.6g} s)")
        Y, steps, nfev = sol.sol(t_eval).T, len(sol.t) - 1, sol.nfev
        Y[0] = y0
    else:   # every coordinate prescribed, no state: kinematics and the drives' forces only
        Y, steps, nfev = np.tile(y0, (len(t_eval), 1)), 0, 0
    rows, closure = [], 0.0
    for t, y in zip(t_eval, Y):
        ev = system.evaluate(float(t), y)
        rows.append(system.sample(ev))
        if len(ev["Phi"]):
            closure = max(closure, float(np.max(np.abs(ev["Phi"]))))
    wall = time.perf_counter() - begin
    data = np.array(rows).reshape(len(t_eval), len(model.outputs))
    stats = {"wall_time": wall, "steps": steps, "nfev": nfev, "closure_max": closure, "tracking_error": 0.0,
             "derive_time": meta["derive_time"], "codegen_time": meta["codegen_time"],
             "load_time": meta["load_time"], "cache": meta["cache"], "derived_in": meta["derived_in"],
             "generated_in": meta["generated_in"], "operations": sum(meta["operations"].values()), **s}
    return ModelRun(name, t_eval, {o.name: data[:, k] for k, o in enumerate(model.outputs)},
                    {o.name: o.unit for o in model.outputs}, stats)
