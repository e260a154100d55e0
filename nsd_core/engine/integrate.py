"""Adaptive embedded Runge-Kutta integration of a SemiRecursiveSystem (the paper used RKF45).

scipy's step-by-step solvers are driven directly so that every accepted step can be counted,
outputs are taken from each step's dense output at the requested times, and the dependent/free
partition is re-chosen (and the integration restarted) when the dependent block of Phi_z
degrades, as when a mechanism passes near a singular position.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from nsd_core.common.errors import InputError, SolverError
from nsd_core.engine.compiled_model import Workspace
from nsd_core.engine.semirecursive import SemiRecursiveSystem

STEP_FLOOR = 1e-8  # s: the smallest max_step accepted (bounded work; docs/limits.md)
# scipy's solvers by name; scipy.integrate is imported where one is made (~1 s: every command would pay
# it at start-up, the in-house runs use the compiled step loop)
METHODS = ("RK45", "DOP853", "RK23", "Radau", "LSODA")


def solver_class(method: str):
    """scipy's step-by-step solver named ``method`` (one of METHODS)."""
    import scipy.integrate
    return getattr(scipy.integrate, method)


@dataclass
class Trajectory:
    t: np.ndarray
    y: np.ndarray            # (len(t), len(y0)); the state layout may change at repartitions
    partitions: list         # (t, Partition) in force from t on
    steps: int
    nfev: int
    wall_time: float


def check_tolerances(rtol, atol, max_step) -> None:
    """The bounds every integrator here accepts (scipy's and the compiled one, nsd_core.engine.rk)."""
    for name, v, low, high in (("rtol", rtol, 1e-13, 0.1), ("atol", atol, 1e-300, 1.0),
                               ("max_step", max_step, STEP_FLOOR, np.inf)):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not low <= v <= high or np.isnan(v):
            raise InputError(f"{name} = {v!r}: must be a number in [{low:g}, {high:g}]")


def integrate(system: SemiRecursiveSystem, ws: Workspace, y0: np.ndarray, t_eval: np.ndarray, method: str = "RK45",
              rtol: float = 1e-8, atol: float = 1e-10, max_step: float = np.inf,
              min_pivot_ratio: float = 1e-3, progress: Callable[[float], None] | None = None,
              outputs: Callable[[float, np.ndarray], None] | None = None,
              max_steps: int | None = None, first_step: float | None = None) -> Trajectory:
    """Integrate from t_eval[0] to t_eval[-1] with the per-run workspace ws (system.workspace());
    ``outputs(t, y)`` is called at every t_eval.

    ``max_steps`` bounds the work: a run that needs more accepted steps stops with a SolverError
    ("exceeded N steps") instead of running for hours on a stiff or runaway input.
    ``first_step``: the first step (default: the solver's own guess, whose trial evaluation may lie
    anywhere up to t_eval[-1] when the state starts at rest; a prescribed motion that has moved far
    by then can put that trial where the loops cannot close)."""
    if method not in METHODS:
        raise InputError(f"method = {method!r}: allowed {', '.join(METHODS)}")
    check_tolerances(rtol, atol, max_step)
    t0, t1 = float(t_eval[0]), float(t_eval[-1])
    start = time.perf_counter()
    nfev, solver_of = [0], solver_class(method)

    def fun(t, y):
        nfev[0] += 1
        return system.rhs(ws, t, y)

    ys = np.zeros((len(t_eval), len(y0)))
    partitions = [(t0, system.partition)]
    y = np.asarray(y0, dtype=float)
    k = 0  # next output index
    steps = 0
    t = t0
    while True:
        solver = solver_of(fun, t, y, t1, rtol=rtol, atol=atol, max_step=max_step, first_step=first_step)
        while k < len(t_eval) and t_eval[k] <= t:
            ys[k] = y
            if outputs:
                outputs(t_eval[k], y)
            k += 1
        restart = False
        while solver.status == "running":
            t_old = solver.t
            msg = solver.step()
            if solver.status == "failed":
                raise SolverError(f"{method} failed at t = {solver.t:.6g} s: {msg}")
            steps += 1
            if max_steps is not None and steps > max_steps:
                raise SolverError(f"exceeded {max_steps} steps at t = {solver.t:.6g} s of {t1:.6g} s "
                                  f"(step {solver.step_size:.3g} s): a stiff or runaway input")
            if k < len(t_eval) and t_eval[k] <= solver.t:
                dense = solver.dense_output()
                while k < len(t_eval) and t_eval[k] <= solver.t:
                    yk = solver.y if t_eval[k] == solver.t else dense(t_eval[k])
                    ys[k] = yk
                    if outputs:
                        outputs(t_eval[k], yk)
                    k += 1
            if not np.all(np.isfinite(solver.y)):
                raise SolverError(f"non-finite state at t = {solver.t:.6g} s")
            if progress:
                progress((solver.t - t0) / (t1 - t0))
            if min_pivot_ratio > 0 and solver.status == "running" and \
                    len(system.partition.dependent) and system.pivot_ratio(ws, solver.t, solver.y) < min_pivot_ratio:
                before = system.partition
                y_new = system.repartition(ws, solver.t, solver.y)
                if system.partition is before:
                    continue  # no better partition here (a singular position of the mechanism)
                t, y = solver.t, y_new
                partitions.append((t, system.partition))
                restart = t_old < t
                break
        if not restart:
            break
    return Trajectory(t_eval, ys, partitions, steps, nfev[0], time.perf_counter() - start)
