"""Discrepancy metrics between two engines' steady cycles, on a common phase grid, on the force vector."""
from __future__ import annotations

import numpy as np

from nsd_core.device.cycle import loop_area, phase_resample, steady_cycle
from nsd_core.device.results import RunResult


def region_boundaries(summary: dict) -> list[float]:
    return [r["to"] for r in summary["stiffness_regions"][:-1]]


def pair_metrics(run: RunResult, ref: RunResult, run_summary: dict, ref_summary: dict,
                 amplitude: float, frequency: float) -> dict[str, float]:
    """Force differences as vectors, loop work and peak-force differences, region-boundary shift.

    The force is the vector (F_x, F_y) the drive applies to the cap, on any path:
    max_dF_rel = max |F - F_ref| / max |F_ref| and rms_dF_rel = RMS |F - F_ref| / max |F_ref| over
    both components; loop_area_rel compares the work per cycle, the closed integral of F . dp (for a
    line, the loop area of F along psi); peak_force_rel compares max |F|. region_shift_rel (the
    stiffness regions along the line) only for lines.
    """
    F = np.column_stack([phase_resample(run, frequency, c) for c in ("F_x", "F_y")])
    Fr = np.column_stack([phase_resample(ref, frequency, c) for c in ("F_x", "F_y")])
    mag_r = np.linalg.norm(Fr, axis=1)
    scale = float(np.max(mag_r))
    dF = np.linalg.norm(F - Fr, axis=1)
    area, area_r = _work(run, frequency), _work(ref, frequency)
    out = {
        "max_dF_rel": float(np.max(dF)) / scale,
        "rms_dF_rel": float(np.sqrt(np.mean(dF ** 2))) / scale,
        "loop_area_rel": abs(area - area_r) / abs(area_r) if area_r else float("inf"),
        "peak_force_rel": abs(float(np.max(np.linalg.norm(F, axis=1))) - scale) / scale,
    }
    if "stiffness_regions" in run_summary and "stiffness_regions" in ref_summary:
        b, br = region_boundaries(run_summary), region_boundaries(ref_summary)
        out["region_shift_rel"] = float(np.max(np.abs(np.subtract(b, br)))) / amplitude if len(b) == len(br) and b \
            else (0.0 if len(b) == len(br) else float("inf"))
    return out


def _work(result: RunResult, frequency: float) -> float:
    """Work per steady cycle, the closed integral of F_x dx + F_y dy [J]."""
    cyc = steady_cycle(result, frequency)
    return loop_area(result["x"][cyc], result["F_x"][cyc]) + loop_area(result["y"][cyc], result["F_y"][cyc])


def path_length(result: RunResult, frequency: float) -> float:
    """The length of the drive's path over the steady cycle, sum |dp| [m]: |loop work difference| is at
    most max |F - F_ref| x this (the runs on the same path)."""
    cyc = steady_cycle(result, frequency)
    return float(np.sum(np.hypot(np.diff(result["x"][cyc]), np.diff(result["y"][cyc]))))


def own_metrics(run: RunResult) -> dict[str, float]:
    """Metrics of one engine on its own: loop closure and drive tracking."""
    return {"closure_max": float(np.max(np.abs(run["closure"]))),
            "tracking_error": float(run.stats.get("tracking_error", 0.0))}
