"""The symbolic engine's consistent state at t = 0, from the description's initial values and its own
derived closure equations (comparisons.builders.symbolic_derive): the contract of docs/models.md
("Which assembly branch the start picks"), computed here with this engine's own Newton.

- the free coordinates (``[initial].free`` and every prescribed one) are kept as given; the others
  are chosen by Gaussian elimination with full pivoting on Phi_q at the guess (the dependent
  coordinates are the pivots' columns; coordinates the user names free are offered only when the
  others do not reach the rank); a guessed dependent coordinate is corrected by Gauss-Newton on
  Phi(q) = 0 (least squares: a redundant row, as in Bricard's mechanism, costs nothing);
- the dependent rates solve Phi_q u = 0 for the free coordinates' given rates.
"""
from __future__ import annotations

import numpy as np

from nsd_core.model.errors import ModelError

NEWTON_TOL = 1e-13      # m (or rad): the closure's largest residual at the start
NEWTON_ITER = 50


def pivot_columns(A: np.ndarray, candidates: list[int], rel_tol: float = 1e-9) -> list[int]:
    """The columns where the pivots of a full-pivoting Gaussian elimination on A[:, candidates] fall."""
    B = A[:, candidates].astype(float, copy=True)
    rows, cols, picked, first = list(range(B.shape[0])), list(range(B.shape[1])), [], None
    while rows and cols:
        sub = np.abs(B[np.ix_(rows, cols)])
        ri, ci = np.unravel_index(int(np.argmax(sub)), sub.shape)
        pv = sub[ri, ci]
        first = pv if first is None else first
        if pv <= rel_tol * max(first, 1e-300):
            break
        r, c = rows[ri], cols[ci]
        for rr in rows:
            if rr != r:
                B[rr] -= B[rr, c] / B[r, c] * B[r]
        rows.remove(r)
        cols.remove(c)
        picked.append(candidates[c])
    return picked


def dependent(J: np.ndarray, candidates: list[int], preferred: list[int]) -> list[int]:
    """The dependent coordinates: among the non-preferred candidates when they reach the full rank."""
    everyone = pivot_columns(J, candidates)
    rest = [i for i in candidates if i not in preferred]
    if preferred and rest:
        mine = pivot_columns(J, rest)
        if len(mine) == len(everyone):
            return sorted(mine)
    return sorted(everyone)


def initial_state(model, coordinates: list, constraints, prescribed: dict) -> tuple[np.ndarray, np.ndarray]:
    """(q, u) at t = 0. ``constraints(q) -> (Phi, Phi_q)``; ``prescribed``: coordinate -> (q, q')."""
    n = len(coordinates)
    q = np.array([float(model.initial_coordinates.get(c, 0.0)) for c in coordinates])
    u = np.array([float(model.initial_velocities.get(c, 0.0)) for c in coordinates])
    for i, (qi, ui) in prescribed.items():
        q[i], u[i] = qi, ui
    Phi, Phi_q = constraints(q)
    if Phi.size == 0:
        return q, u
    index = {c: i for i, c in enumerate(coordinates)}
    candidates = [i for i in range(n) if i not in prescribed]
    preferred = [index[c] for c in model.free if c in index]
    dep = dependent(Phi_q, candidates, preferred)
    polish = 2   # Newton steps past the tolerance, down to round-off (a drive's force at t = 0 feels 1e-13 m)
    for _ in range(NEWTON_ITER):
        if np.max(np.abs(Phi)) <= NEWTON_TOL:
            if polish == 0:
                break
            polish -= 1
        step = np.linalg.lstsq(Phi_q[:, dep], -Phi, rcond=None)[0]
        q[dep] += step
        Phi, Phi_q = constraints(q)
    if not np.max(np.abs(Phi)) <= 1e-10:
        raise ModelError(f"[initial].coordinates: the loops do not close from this guess (largest residual "
                         f"{np.max(np.abs(Phi)):.3g} m after {NEWTON_ITER} Newton steps); give guesses nearer a closed position")
    indep = [i for i in range(n) if i not in dep]
    u[dep] = np.linalg.lstsq(Phi_q[:, dep], -Phi_q[:, indep] @ u[indep], rcond=None)[0]
    residual = float(np.max(np.abs(Phi_q @ u))) if Phi.size else 0.0
    if residual > 1e-9 * max(1.0, float(np.max(np.abs(u)))):
        raise ModelError(f"[initial].velocities: the loops forbid these rates (Phi_q u = {residual:.3g}); "
                         "give the rates of the free coordinates only")
    return q, u
