"""Discrepancy metrics between two engines' steady cycles, on a common phase grid."""
from __future__ import annotations

import numpy as np

from nsd_core.device.cycle import loop_area, phase_resample, steady_cycle
from nsd_core.device.results import RunResult


def region_boundaries(summary: dict) -> list[float]:
    return [r["to"] for r in summary["stiffness_regions"][:-1]]


def pair_metrics(run: RunResult, ref: RunResult, run_summary: dict, ref_summary: dict,
                 amplitude: float, frequency: float) -> dict[str, float]:
    """max/RMS force difference, loop area and peak-force differences, region-boundary shift."""
    F = phase_resample(run, frequency, "F")
    Fr = phase_resample(ref, frequency, "F")
    scale = float(np.max(np.abs(Fr)))
    dF = F - Fr
    cyc, cyc_r = steady_cycle(run, frequency), steady_cycle(ref, frequency)
    area = loop_area(run["u"][cyc], run["F"][cyc])
    area_r = loop_area(ref["u"][cyc_r], ref["F"][cyc_r])
    b, br = region_boundaries(run_summary), region_boundaries(ref_summary)
    shift = float(np.max(np.abs(np.subtract(b, br)))) / amplitude if len(b) == len(br) and b else (
        0.0 if len(b) == len(br) else float("inf"))
    return {
        "max_dF_rel": float(np.max(np.abs(dF))) / scale,
        "rms_dF_rel": float(np.sqrt(np.mean(dF ** 2))) / scale,
        "loop_area_rel": abs(area - area_r) / abs(area_r) if area_r else float("inf"),
        "peak_force_rel": abs(float(np.max(np.abs(F))) - scale) / scale,
        "region_shift_rel": shift,
    }


def own_metrics(run: RunResult) -> dict[str, float]:
    """Metrics of one engine on its own: loop closure and drive tracking."""
    return {"closure_max": float(np.max(np.abs(run["closure"]))),
            "tracking_error": float(run.stats.get("tracking_error", 0.0))}
