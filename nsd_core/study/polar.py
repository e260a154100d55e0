"""The direction study: how the device responds versus the drive's azimuth psi, for
n_w = n_r = n wires and ropes, to test the paper's guideline on the number of wires ("multiples of
4 wires ensure axial symmetry relative to both X- and Y-axes").

Per design n and azimuth psi over a full turn, on the quasi-static solution
(nsd_core.device.quasistatic: inertia-free, the right limit for these stiffness and range measures;
at 1 Hz, A = 15 mm it is within 0.1 % of the dynamic model's force, tests/test_paths.py):
- X_max(psi): the working range, where the ropes go slack (nsd_core.device.working_range.x_max_at_slack);
- K0(psi): the initial stiffness dF/du at u = 0 (secant over the first 1 micrometre of loading);
- K_min(psi): the most negative tangent stiffness on the loading branch u = 0 .. A;
- the loop area (energy dissipated per cycle) and the peak force of a cycle at amplitude A, from the
  closed loop +A -> -A -> +A after the first loading quarter (u = A sin(2 pi s), s = 0 .. 1.25).
"""
from __future__ import annotations

import math
from functools import partial

import numpy as np

from nsd_core.device.cycle import loop_area
from nsd_core.device.params import ParameterError, Params
from nsd_core.device.quasistatic import quasi_static_path
from nsd_core.device.working_range import x_max_at_slack

FIELDS = ("x_max", "k0", "k_min", "loop_area", "peak_force")
UNITS = {"psi_deg": "deg", "x_max": "m", "k0": "N/m", "k_min": "N/m", "loop_area": "J", "peak_force": "N"}


def direction_point(params: Params, psi_deg: float, amplitude: float, points_per_cycle: int = 100,
                    substeps: int = 2) -> dict[str, float]:
    """X_max, K0, K_min, loop area and peak force of one design along one azimuth (quasi-static)."""
    delta = 1e-6
    k0_path = quasi_static_path(params, np.array([0.0, delta]), psi_deg, substeps=substeps)
    s = np.linspace(0.0, 1.25, int(round(1.25 * points_per_cycle)) + 1)
    q = quasi_static_path(params, amplitude * np.sin(2.0 * math.pi * s), psi_deg, substeps=substeps)
    u, F = q["u"], q["F_device"]
    load = s <= 0.25 + 1e-12
    k = np.gradient(F[load], u[load])
    loop = s >= 0.25 - 1e-12
    return {"psi_deg": float(psi_deg), "x_max": x_max_at_slack(params, psi_deg),
            "k0": float(k0_path["F_device"][1] / delta), "k_min": float(np.min(k)),
            "loop_area": loop_area(u[loop], F[loop]), "peak_force": float(np.max(np.abs(F[loop])))}


def _job(args):
    params, psi, amplitude, ppc = args
    return direction_point(params, psi, amplitude, ppc)


def polar_study(wires=(3, 4, 6, 8), step_deg: float = 15.0, amplitude: float = 0.015,
                base: Params | None = None, points_per_cycle: int = 100, workers: int = 1) -> dict:
    """Every design n in ``wires`` (n_w = n_r = n) at psi = 0, step, ... < 360 deg."""
    if not wires or any(not isinstance(n, int) or n < 3 for n in wires):
        raise ParameterError(f"wires = {list(wires)}: each must be a whole number >= 3")
    if not (0.0 < step_deg <= 90.0) or abs(360.0 / step_deg - round(360.0 / step_deg)) > 1e-9:
        raise ParameterError(f"step = {step_deg} deg: must divide 360 and be in (0, 90]")
    base = base or Params()
    if not 0.0 < amplitude < base.rod_length:
        raise ParameterError(f"amplitude = {amplitude}: must be in (0, rod_length = {base.rod_length}) m")
    psis = [i * step_deg for i in range(int(round(360.0 / step_deg)))]
    designs = {n: base.replace(n_wires=n, n_ropes=n) for n in wires}
    jobs = [(designs[n], psi, amplitude, points_per_cycle) for n in wires for psi in psis]
    if workers > 1:
        from nsd_core.engine.workers import worker_pool  # workers that end with their parent
        warm = partial(_job, jobs[0])  # its kernels loaded before the first job (~0.1 s warm)
        with worker_pool(min(workers, len(jobs)), warm=warm) as pool:
            points = list(pool.map(_job, jobs))
    else:
        points = [_job(j) for j in jobs]
    out = {"amplitude": amplitude, "step_deg": step_deg, "units": UNITS, "designs": {}}
    for i, n in enumerate(wires):
        rows = points[i * len(psis):(i + 1) * len(psis)]
        d = {"psi_deg": psis, **{f: [r[f] for r in rows] for f in FIELDS}}
        d["spread"] = {f: _spread(d[f]) for f in FIELDS}  # (max - min) / |mean| over the turn
        out["designs"][str(n)] = d
    return out


def _spread(values) -> float:
    v = np.asarray(values, dtype=float)
    return float((v.max() - v.min()) / abs(v.mean())) if v.mean() else float("inf")


def polar_csv(result: dict) -> str:
    lines = ["n," + ",".join(f"{k} [{UNITS[k]}]" for k in ("psi_deg",) + FIELDS)]
    for n, d in result["designs"].items():
        for i, psi in enumerate(d["psi_deg"]):
            lines.append(f"{n},{psi:g}," + ",".join(f"{d[f][i]:.10g}" for f in FIELDS))
    return "\n".join(lines) + "\n"
