"""Shared pieces of the benchmark problems: running a system to fixed output times, timing it,
counting correct digits, and the mechanical-energy bookkeeping the IFToMM library asks for.

Digits follow the Test Set for IVP Solvers (Mazzia & Magherini): the number of significant correct
digits of a component is scd = -log10(|y - y_ref| / |y_ref|).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from nsd_core.engine.dynamics import kinetic_energy, potential_energy_gravity
from nsd_core.engine.integrate import integrate
from nsd_core.engine.kinematics import positions, velocities
from nsd_core.engine.semirecursive import SemiRecursiveSystem

REFERENCES = Path(__file__).resolve().parents[3] / "references"


@dataclass
class Run:
    """One integration: outputs at t_eval (whatever ``sample`` returned) and what it cost."""
    t: np.ndarray
    samples: list
    wall_time: float
    steps: int
    nfev: int
    repartitions: int
    info: dict = field(default_factory=dict)


def run_system(system: SemiRecursiveSystem, y0: np.ndarray, t_eval: np.ndarray, sample, method="DOP853",
               rtol=1e-10, atol=1e-12, max_step=np.inf, min_pivot_ratio=1e-3) -> Run:
    """Integrate and call ``sample(Evaluation)`` at every output time. Wall time covers the
    integration and the output evaluations (what a user waits for), not model construction."""
    samples = []
    ws = system.workspace()

    def record(t, y):
        samples.append(sample(system.evaluate(ws, t, y)))

    start = time.perf_counter()
    traj = integrate(system, ws, y0, np.asarray(t_eval, dtype=float), method=method, rtol=rtol, atol=atol,
                     max_step=max_step, min_pivot_ratio=min_pivot_ratio, outputs=record)
    wall = time.perf_counter() - start
    return Run(np.asarray(t_eval, float), samples, wall, traj.steps, traj.nfev, len(traj.partitions) - 1)


def digits(value, reference) -> np.ndarray:
    """Significant correct digits per component (Test Set convention), capped at 16."""
    value, reference = np.asarray(value, float), np.asarray(reference, float)
    err = np.abs(value - reference) / np.abs(reference)
    with np.errstate(divide="ignore"):
        return np.minimum(-np.log10(np.maximum(err, 1e-16)), 16.0)


def mechanical_energy(system: SemiRecursiveSystem, z: np.ndarray, zd: np.ndarray) -> float:
    """Kinetic + gravitational potential energy at (z, z') (the IFToMM A-group accuracy measure)."""
    m = system.m
    k = velocities(m, positions(m, z), zd)
    return kinetic_energy(m, k) + potential_energy_gravity(m, k)


def library_error(value: np.ndarray, reference: np.ndarray, threshold: float = 1e-3) -> float:
    """Error of a reference-solution time history, as we read the IFToMM/MBS benchmark rule.

    For every reference variable (a column), the RMS of the difference over the output steps is
    divided by the RMS of the reference, unless that RMS is below ``threshold``, in which case the
    absolute RMS is used; the problem's error is the largest over the variables.
    """
    value, reference = np.atleast_2d(value), np.atleast_2d(reference)
    out = 0.0
    for j in range(reference.shape[1]):
        rms_d = math.sqrt(float(np.mean((value[:, j] - reference[:, j]) ** 2)))
        rms_r = math.sqrt(float(np.mean(reference[:, j] ** 2)))
        out = max(out, rms_d / rms_r if rms_r > threshold else rms_d)
    return out


def median_time(fn, repeats: int) -> tuple[object, float, list[float]]:
    """Run ``fn() -> Run`` repeats times; return the last result, the median wall time and all times."""
    times, res = [], None
    for _ in range(max(1, repeats)):
        res = fn()
        times.append(res.wall_time)
    return res, float(np.median(times)), times
