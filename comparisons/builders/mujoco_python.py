"""The MuJoCo builder's readable reference loop (``passive = "python"`` of comparisons.builders.mujoco):
the description's forces as MuJoCo's passive callback (mujoco_passive.Passive), one Python iteration a
step, the drives' coordinates put on their paths after each step and their forces measured. The
compiled path (mujoco_compiled) gives the same numbers; this one is the reference it is held to."""
from __future__ import annotations

import time

import mujoco
import numpy as np

from comparisons.builders.mujoco_passive import DRIVE, Passive
from comparisons.builders.mujoco_start import rigid_start
from comparisons.builders.subnormals import flushed
from comparisons.engines.base import EngineError


def run(model, s, m, d, drives, pairs, t_out, n_sub, h, n_steps, weights, uses, sampler, plan):
    """The readable reference loop (``passive = "python"``): Passive as mjcb_passive, one Python
    iteration per step. Returns as mujoco_compiled.run. Work outputs (``plan``: mujoco_passive.work_plan):
    the trapezoid of each one's power at the steps' first evaluations (second order; RK4's stages are
    not weighed in), the drives' as each step's measured average force times the change of q(t)."""
    forces = Passive(model, m, drives, advance=s["integrator"] == "Euler")
    sample = sampler(forces)
    advance = {"RK4": lambda: mujoco.mj_RungeKutta(m, d, 4), "Euler": lambda: mujoco.mj_Euler(m, d)}[s["integrator"]]
    drive_at = np.zeros((len(t_out), len(drives)))   # the drive forces at the output times
    armature, drive_dof = np.array([A for *_, A in drives]), [da for _, _, da, _ in drives]
    measure = _drive_measure(forces, d, armature, drive_dof, weights, uses, drive_at, h, s["integrator"] == "RK4")
    previous = mujoco.get_mjcb_passive(), mujoco.get_mjcb_act_dyn()
    try:
        mujoco.set_mjcb_passive(forces)
        mujoco.set_mjcb_act_dyn(forces.act_dyn)
        start = _python_start(m, d, forces, drives, pairs, armature, drive_dof)
        with flushed():   # as the compiled loop (comparisons.builders.subnormals)
            begin = time.perf_counter()
            rows, closure, tracking, rec_work = _python_steps(m, d, s, forces, sample, advance, measure, drives,
                                                              pairs, t_out, n_sub, h, n_steps, plan, start)
            wall = time.perf_counter() - begin
    finally:
        mujoco.set_mjcb_passive(previous[0])
        mujoco.set_mjcb_act_dyn(previous[1])
    if start is not None:
        drive_at[0] = start[1]
    return np.array(rows, dtype=float), drive_at, wall, closure, tracking, rec_work


def _drive_measure(forces: Passive, d, armature, drive_dof, weights, uses: dict, drive_at, h: float, rk4: bool):
    """``measure(n, t)``: step n's average drive force into ``drive_at``'s rows and Passive's feed-forward."""

    def measure(n, t):
        # the step's average drive force (its impulse / h; RK4: at the step's middle): the weighted
        # feed-forward of the stages less the armature times the step's average acceleration (MuJoCo's
        # qacc after the step). Unlike one evaluation's force, it carries no share of the soft loop
        # constraints' velocity offset, which RK4 leaves at the step's ends. Euler: its one
        # evaluation's, the force at the step's start
        bar = weights @ np.array(forces.feeds) - armature * d.qacc[drive_dof]
        for k, w in uses.get(n, ()):
            drive_at[k] += w * bar
        forces.tau_slope[:] = (bar - forces.tau) / h if n else 0.0
        forces.tau[:], forces.t_tau = bar, t + (0.5 * h if rk4 else 0.0)
    return measure


def _python_start(m, d, forces: Passive, drives, pairs, armature, drive_dof):
    """t = 0: the drive forces refined; with loops, the rigid start's (accelerations, drive forces), else None."""
    for _ in range(3 if drives else 0):   # the drive force at t = 0, refined by its own measurement
        forces.feeds.clear()
        mujoco.mj_forward(m, d)
        forces.tau[:] = forces.feeds[-1] - armature * d.qacc[drive_dof]
    if not pairs:
        return None
    # the loops' soft constraints start with a transient: t = 0 taken as rigid (mujoco_start)
    if not drives:   # (with drives, the refinement above left d evaluated at t = 0)
        mujoco.mj_forward(m, d)
    feeds = np.array(forces.feeds[-1]) if drives else np.zeros(0)
    return rigid_start(m, d, drives, feeds, pairs, np.array([p(0.0)[2] for p, *_ in drives]))


def _python_steps(m, d, s, forces: Passive, sample, advance, measure, drives, pairs, t_out, n_sub, h, n_steps,
                  plan, start) -> tuple:
    """The steps: (the rows sampled at the output times, the largest loop gap, the tracking error, the work)."""
    rows, closure, tracking = [], 0.0, 0.0
    rk4 = s["integrator"] == "RK4"
    work_of, sign, mass = plan
    work, power, rec_work = np.zeros(len(work_of)), None, np.zeros((len(t_out), len(work_of)))
    drive_work = work_of == DRIVE
    for n in range(n_steps + 1):
        t = min(n * h, float(t_out[-1]))   # n h may pass the run's end by an ulp (past an excitation's block)
        d.time = t
        forces.feeds.clear()
        mujoco.mj_forward(m, d)
        if len(work_of):
            now = forces.powers(m, d, work_of, sign, mass)
            work += 0.0 if power is None else 0.5 * h * (power + now)
            power = now
        if n % n_sub == 0:
            rec_work[n // n_sub] = work
            gap = max((float(np.linalg.norm(d.site_xpos[a] - d.site_xpos[b])) for a, b in pairs), default=0.0)
            closure = max(closure, gap)
            if not (np.all(np.isfinite(d.qpos)) and gap < s["closure_limit"]):
                raise EngineError(f"mujoco: unstable at t = {t:.6g} s (loop gap {gap:.3g} m); "
                                  "try a smaller timestep")
            if n == 0 and start is not None:   # the rigid start's accelerations for this sample alone:
                soft = d.qacc.copy()                # the step below begins from MuJoCo's own
                d.qacc[:] = start[0]
                rows.append(sample())
                d.qacc[:] = soft
            else:
                rows.append(sample())
        if n == n_steps:
            if drives and not rk4:   # Euler's last output: this evaluation's (qacc is mj_forward's)
                measure(n, t)
            break
        advance()
        if drives:
            measure(n, t)
            if drive_work.any():   # the step's drive work: its average force times q's change
                work[drive_work] += float(forces.tau @ np.array([p(t + h)[0] - p(t)[0] for p, *_ in drives]))
        for p, qa, da, _ in drives:   # the drive's coordinate, exactly on its path
            q, qd, _ = p(t + h)
            tracking = max(tracking, abs(d.qpos[qa] - q))
            d.qpos[qa], d.qvel[da] = q, qd
    return rows, closure, tracking, rec_work
