"""The two-step semirecursive equations of motion (Eqs. 9-12) with driven and locked coordinates.

The coordinates z split into prescribed (driven, or locked at a constant: Table 1), dependent
(one per independent loop equation, chosen by full-pivot elimination, Eq. 9) and free (the rest).
Positions of the dependent coordinates are solved by Newton from Phi(z) = 0 and velocities from
Phi_z z' = 0 at every evaluation, so only the free coordinates are integrated and the constraint
drift stays at round-off. With z' = R_z z'_f + (prescribed part) (Eq. 10) and
z'' = R_z z''_f + z''_0, Eq. 12 becomes
    R_z^T (R_d^T M^S R_d) R_z z''_f = R_z^T [R_d^T (Q^S - P^S) - (R_d^T M^S R_d) z''_0],
where z''_0 holds the prescribed accelerations and the dependent response to them and to the
velocity-product term. Reactions follow from the full residual: Phi_z^T lambda on the loop
equations and the drive forces on the prescribed coordinates.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from nsd_core.engine.compile_once import DONE, compile_once
from nsd_core.engine.compiled import DYNAMICS, OK, VELOCITIES, reduced_dynamics, velocities_and_predictor
from nsd_core.engine.compiled import assemble as assemble_kernel
from nsd_core.engine.compiled_model import SystemModel, Workspace, build_model, make_workspace, split_state
from nsd_core.engine.closure import closure, full_pivot_elimination
from nsd_core.engine.dynamics import tree_equations
from nsd_core.engine.kinematics import Kinematics, positions, velocities
from nsd_core.common.errors import ConstraintError
from nsd_core.engine.mechanism import Mechanism

# forces(t, kin, z, zd, extra) -> (wrench (n,6) about the origin, joint forces (n,) or None, extra rates)
ForceFn = Callable[[float, Kinematics, np.ndarray, np.ndarray, np.ndarray], tuple]
# motion(t) -> (q, q', q'') of the prescribed coordinates, in the order of ``prescribed``
MotionFn = Callable[[float], tuple[np.ndarray, np.ndarray, np.ndarray]]


def _solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """LU solve; at an exactly singular block (a singular position hit dead on) the minimum-norm
    least-squares step instead of an exception: the predictor has already put z on the branch."""
    try:
        return np.linalg.solve(A, b)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(A, b, rcond=None)[0]


def _inverse(A: np.ndarray) -> np.ndarray:
    try:
        return np.linalg.inv(A)
    except np.linalg.LinAlgError:
        return np.linalg.pinv(A)


@dataclass(frozen=True)
class Partition:
    free: np.ndarray
    dependent: np.ndarray
    rows: np.ndarray        # independent loop equations (redundant ones left out)
    pivot_ratio: float      # smallest / largest pivot: how well-conditioned the choice is


@dataclass
class Evaluation:
    """Everything computed at one (t, state): for outputs and diagnostics."""
    t: float
    z: np.ndarray
    zd: np.ndarray
    zdd: np.ndarray
    kin: Kinematics
    extra_rate: np.ndarray
    lam: np.ndarray          # multipliers of the independent loop equations
    drive_force: np.ndarray  # generalized force the drive applies on each prescribed coordinate
    Phi: np.ndarray
    info: dict = field(default_factory=dict)


class SemiRecursiveSystem:
    """A mechanism, its prescribed coordinates and its applied forces, as an ODE in the free ones.

    The system is the model: the mechanism, the partition (and the configuration it was chosen at,
    which fixes the assembly branch) and the compiled arrays of both (``model``). What a run
    changes (the Newton warm start, the predictor, every scratch array) lives in a ``Workspace``
    (nsd_core.engine.compiled_model) that the caller makes with ``workspace()`` and passes in.
    """

    def __init__(self, mech: Mechanism, prescribed: list[int], motion: MotionFn, forces: ForceFn,
                 n_extra: int = 0, prefer_free: list[int] | None = None, newton_tol: float = 1e-13,
                 fast: bool = True):
        self.m = mech
        self.prescribed = np.array(prescribed, dtype=int)
        self.motion = motion
        self.forces = forces
        self.n_extra = n_extra
        self.prefer_free = list(prefer_free or [])
        self.newton_tol = newton_tol
        self.fast = fast  # compiled kernels (nsd_core.engine.compiled); False: the numpy specification
        self.partition: Partition | None = None
        self.model: SystemModel | None = None
        self.z_ref: np.ndarray | None = None  # configuration the partition was chosen at

    # ---- partition (Eq. 9) ----
    def choose_partition(self, z: np.ndarray, n_dependent: int | None = None) -> Partition:
        """Eq. 9 at z. ``n_dependent`` forces that many dependent coordinates (re-partitioning)."""
        k = positions(self.m, z)
        _, J, _ = closure(self.m, k)
        others = [i for i in range(self.m.n) if i not in set(self.prescribed)]
        # redundant equations (rank-deficient Phi_z) are left out by the elimination
        rows, dep, piv = full_pivot_elimination(J, others, n_pivots=n_dependent) if J.shape[0] else ([], [], np.ones(1))
        # coordinates the user prefers free stay free whenever the others alone reach the same rank
        # (Table 1: the same tree is driven at the plate or at the base, free elsewhere); else, and
        # when re-partitioning near a singular position (n_dependent given), they are offered as
        # pivots last
        if self.prefer_free and J.shape[0]:
            rest = [i for i in others if i not in self.prefer_free]
            pick = full_pivot_elimination(J, rest) if rest and n_dependent is None else ([], [], np.ones(0))
            if len(pick[1]) < len(dep):
                pick = full_pivot_elimination(J, rest + [i for i in others if i in self.prefer_free],
                                              n_pivots=n_dependent)
            rows, dep, piv = pick
        free = np.array([i for i in others if i not in dep], dtype=int)
        ratio = float(piv.min() / piv.max()) if len(piv) else 1.0
        self._set_partition(Partition(free, np.array(dep, dtype=int), np.array(rows, dtype=int), ratio), z)
        return self.partition

    def _set_partition(self, partition: Partition, z: np.ndarray) -> None:
        self.partition = partition
        self.z_ref = np.array(z, dtype=float)
        self.model = build_model(self.m, partition, self.prescribed, n_extra=self.n_extra,
                                 newton_tol=self.newton_tol)

    def workspace(self, z: np.ndarray | None = None) -> Workspace:
        """A fresh per-run workspace; Newton starts from z (default: where the partition was chosen)."""
        return make_workspace(self.model, self.z_ref if z is None else z)

    # ---- positions and velocities on the constraint manifold ----
    def assemble(self, ws: Workspace, t: float, zf: np.ndarray, q: np.ndarray | None = None) -> np.ndarray:
        """Full configuration on the loop manifold for free coordinates zf at time t (q: the prescribed
        positions at t, when the caller already has them). Returns ws.z."""
        P = self.partition
        if q is None:
            q = self.motion(t)[0]
        if self.fast:
            ws.q[:] = q
            z_before = ws.z.copy()
            if assemble_kernel(self.model, ws, t, np.ascontiguousarray(zf, dtype=float)) == OK:
                return ws.z
            ws.z[:] = z_before  # a singular block or no convergence: the specification copes or says why
        ws.kin_current[0] = 0
        z = ws.z.copy()
        z[self.prescribed] = q
        z[P.free] = zf
        if len(P.dependent) == 0:
            ws.z[:] = z
            return ws.z
        pred = None
        if ws.has_lin[0]:
            # first-order predictor along the constraint manifold, z_dep + S dz (S = -Jd^-1 Jr from
            # the last evaluation). With large steps (loose tolerances, or across a singular
            # position where two assembly branches meet) Newton from the plain warm start can land
            # on another branch, or on the same one shifted by 2 pi; the predictor tells which.
            dz = z - ws.z_lin
            dz[P.dependent] = 0.0
            pred = ws.z_lin[P.dependent] + ws.S @ dz
            move = float(np.max(np.abs(pred - ws.z_lin[P.dependent])))
        z_start = z.copy()
        try:
            z = self._newton(t, z)
        except ConstraintError:
            if pred is None:
                raise
            z = None
        if pred is not None:
            dev = np.inf if z is None else float(np.max(np.abs(z[P.dependent] - pred)))
            # the predictor's own error is second order in the move; a larger gap may be a jump to
            # another branch: solve again from the predictor and keep that answer only if it is a
            # genuinely different solution (not the same one to round-off) closer to the predictor
            if dev > 0.02 * move + 1e-10:
                z_alt = z_start
                z_alt[P.dependent] = pred
                try:
                    z_alt = self._newton(t, z_alt)
                except ConstraintError:
                    if z is None:
                        raise
                    z_alt = None
                if z_alt is not None and (z is None or (
                        float(np.max(np.abs(z_alt[P.dependent] - z[P.dependent]))) > 1e-8
                        and float(np.max(np.abs(z_alt[P.dependent] - pred))) < dev)):
                    z = z_alt
        ws.z[:] = z
        return ws.z

    def _newton(self, t: float, z: np.ndarray) -> np.ndarray:
        """Newton on the independent loop equations for the dependent coordinates (in place)."""
        P = self.partition
        for _ in range(30):
            k = positions(self.m, z)
            Phi, J, _ = closure(self.m, k)
            if np.max(np.abs(Phi[P.rows])) <= 4e-16 * max(1.0, np.max(np.abs(k.r))):
                break  # closed to round-off (near a singular position the step cannot shrink further)
            step = _solve(J[P.rows][:, P.dependent], Phi[P.rows])
            z[P.dependent] -= step
            if np.max(np.abs(step)) < self.newton_tol * (1.0 + np.max(np.abs(z[P.dependent]))):
                break
        else:
            raise ConstraintError(f"t = {t:.6g} s: Newton on the loop equations did not converge "
                                  f"(|Phi| = {np.max(np.abs(Phi)):.3g})")
        return z

    def rhs_parts(self, ws: Workspace, t: float, zf: np.ndarray, zfd: np.ndarray, extra: np.ndarray) -> Evaluation:
        q, qd, qdd = self.motion(t)
        z = self.assemble(ws, t, zf, q)
        if self.fast:
            ev = self._rhs_compiled(ws, t, zfd, qd, qdd, extra)
            if ev is not None:
                return ev
        return self._rhs_numpy(ws, t, z.copy(), zfd, qd, qdd, extra)

    def _rhs_compiled(self, ws, t, zfd, qd, qdd, extra):
        """The same equations as _rhs_numpy through nsd_core.engine.compiled (None: singular, use numpy)."""
        if VELOCITIES not in DONE or DYNAMICS not in DONE:
            # their units first (compiled, or loaded from the cache): numba files a call's own
            # compilation apart from a unit's explicit signature, so a first call from Python before
            # any unit of the process compiled them again (7 s of a described mechanism's first run)
            compile_once(VELOCITIES, DYNAMICS)
        ws.qd[:] = qd
        ws.qdd[:] = qdd
        if velocities_and_predictor(self.model, ws, np.ascontiguousarray(zfd, dtype=float)) != OK:
            return None
        kin = Kinematics(ws.A.copy(), ws.r.copy(), ws.B.copy(), ws.Z.copy(), ws.vp.copy())
        z, zd = ws.z.copy(), ws.zd.copy()
        wrench, gen, extra_rate = self.forces(t, kin, z, zd, extra)
        ws.wrench[:] = wrench
        ws.gen[:] = 0.0 if gen is None else gen
        if reduced_dynamics(self.model, ws, True) != OK:   # every argument: the unit's specialisation (1.6 s)
            return None
        return Evaluation(t, z, zd, ws.zdd.copy(), kin, np.asarray(extra_rate, dtype=float), ws.lam.copy(),
                          ws.tau.copy(), ws.Phi.copy())

    def _rhs_numpy(self, ws, t, z, zfd, qd, qdd, extra):
        P, m, pr = self.partition, self.m, self.prescribed
        kin = positions(m, z)
        Phi, J, _ = closure(m, kin)
        Jr = J[P.rows]
        Jd_inv = _inverse(Jr[:, P.dependent]) if len(P.dependent) else np.zeros((0, 0))
        zd = np.zeros(m.n)
        zd[pr] = qd
        zd[P.free] = zfd
        zd[P.dependent] = -Jd_inv @ (Jr @ zd)
        S = -Jd_inv @ Jr
        S[:, P.dependent] = 0.0
        if len(P.dependent):
            ws.z_lin[:], ws.S[:], ws.has_lin[0] = z, S, 1
        velocities(m, kin, zd)
        _, _, c = closure(m, kin, with_rates=True)
        wrench, gen, extra_rate = self.forces(t, kin, z, zd, extra)
        M, Q = tree_equations(m, kin, wrench, gen)
        # Eq. 10: R_z, and the particular acceleration z''_0
        nf = len(P.free)
        Rz = np.zeros((m.n, nf))
        Rz[P.free, np.arange(nf)] = 1.0
        Rz[P.dependent] = -Jd_inv @ Jr[:, P.free]
        zdd0 = np.zeros(m.n)
        zdd0[pr] = qdd
        zdd0[P.dependent] = Jd_inv @ (-c[P.rows] - Jr[:, pr] @ qdd)
        MRz = M @ Rz
        zfdd = np.linalg.solve(Rz.T @ MRz, Rz.T @ (Q - M @ zdd0)) if nf else np.zeros(0)
        zdd = Rz @ zfdd + zdd0
        # reactions: M z'' - Q = Phi_z^T lambda + E^T tau
        res = MRz @ zfdd + M @ zdd0 - Q
        lam = Jd_inv.T @ res[P.dependent]
        tau = res[pr] - Jr[:, pr].T @ lam
        return Evaluation(t, z, zd, zdd, kin, np.asarray(extra_rate, dtype=float), lam, tau, Phi)

    # ---- the ODE in y = [z_f, z'_f, extra] (nsd_core.engine.compiled_model.split_state) ----
    def rhs(self, ws: Workspace, t: float, y: np.ndarray) -> np.ndarray:
        zf, zfd, extra = split_state(y, len(self.partition.free))
        ev = self.rhs_parts(ws, t, zf, zfd, extra)
        return np.concatenate([zfd, ev.zdd[self.partition.free], ev.extra_rate])

    def state(self, z: np.ndarray, zd: np.ndarray, extra=()) -> np.ndarray:
        f = self.partition.free
        return np.concatenate([z[f], zd[f], np.asarray(extra, dtype=float)])

    def evaluate(self, ws: Workspace, t: float, y: np.ndarray) -> Evaluation:
        return self.rhs_parts(ws, t, *split_state(y, len(self.partition.free)))

    def repartition(self, ws: Workspace, t: float, y: np.ndarray) -> np.ndarray:
        """Choose a new partition at the current configuration and map the state onto it.

        The number of dependent coordinates is kept (the state layout and the workspace stay the
        same), and the old partition is kept when the new one is not clearly better conditioned:
        near a singular position of the mechanism itself (the N-four-bar's flat position) every
        partition degrades, and switching back and forth would only restart the integrator for nothing.
        """
        ev = self.evaluate(ws, t, y)
        old, old_z = self.partition, self.z_ref
        J = closure(self.m, ev.kin)[1]
        before = _block_ratio(J, old)
        new = self.choose_partition(ev.z, n_dependent=len(old.dependent))
        if _block_ratio(J, new) < 2.0 * before:
            self._set_partition(old, old_z)
            return y
        ws.z[:] = ev.z
        ws.has_lin[0] = 0  # the predictor belonged to the old partition
        return self.state(ev.z, ev.zd, split_state(y, len(old.free)).extra)

    def pivot_ratio(self, ws: Workspace, t: float, y: np.ndarray) -> float:
        """Conditioning of the current dependent block (1 = ideal, 0 = singular)."""
        P = self.partition
        if len(P.dependent) == 0:
            return 1.0
        z = self.assemble(ws, t, split_state(y, len(P.free)).free_positions)
        return _block_ratio(closure(self.m, positions(self.m, z))[1], P)


def _block_ratio(J: np.ndarray, P: Partition) -> float:
    """sigma_min / sigma_max of the dependent block J[rows, dependent]."""
    if len(P.dependent) == 0:
        return 1.0
    s = np.linalg.svd(J[np.ix_(P.rows, P.dependent)], compute_uv=False)
    return float(s[-1] / s[0]) if s[0] > 0 else 0.0
