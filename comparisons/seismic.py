"""The seismic mode across engines: one registry and the metrics on time histories (issue 14).

Every seismic engine has ``run(params, structure, ground, duration=None, dt_out=1e-3, settings=None)
-> RunResult`` with the columns of ``nsd_core.device.seismic`` it can measure (at least t, x, y,
theta, ax_abs, ay_abs, device_Fx, device_Fy, cap_z) on the same output times.
"""
from __future__ import annotations

import importlib

import numpy as np

from nsd_core.device.params import ParameterError

SEISMIC_ENGINES = {
    "semirecursive": None,  # the reference: nsd_core.device.seismic.simulate_seismic
    "mujoco": ("comparisons.engines.mujoco_seismic", "MujocoSeismic"),
    "exudyn": ("comparisons.engines.exudyn_seismic", "ExudynSeismic"),
}


def parse_seismic_engines(text: str) -> list[str]:
    names = [e.strip() for e in text.split(",") if e.strip()]
    for e in names:
        if e not in SEISMIC_ENGINES:
            raise ParameterError(f"--engines {e!r}: unknown engine; allowed: {', '.join(SEISMIC_ENGINES)}")
    if not names or len(set(names)) != len(names):
        raise ParameterError(f"--engines {text!r}: give each engine once")
    return names


def run_seismic(name: str, params, structure, ground, duration=None, dt_out=1e-3, settings=None, **solver):
    """One engine's seismic run (the in-house engine takes its solver options as keywords)."""
    if SEISMIC_ENGINES[name] is None:
        from nsd_core.device.seismic import simulate_seismic
        return simulate_seismic(params, structure, ground, duration=duration, dt_out=dt_out, **solver)
    module, cls = SEISMIC_ENGINES[name]
    return getattr(importlib.import_module(module), cls)().run(params, structure, ground, duration=duration,
                                                                dt_out=dt_out, settings=settings)


def seismic_metrics(ref, other) -> dict:
    """Differences of ``other`` against ``ref`` on the same output times:
    du = max|u_o - u_r| / max|u_r| (plan vectors), dF the same for the device force vector,
    da for the absolute acceleration vector, and the differences of the peaks (relative)."""
    if len(ref["t"]) != len(other["t"]) or np.max(np.abs(ref["t"] - other["t"])) > 1e-9:
        raise ValueError("seismic_metrics: the runs are not on the same output times")

    def vec(r, a, b):
        return np.column_stack([r[a], r[b]])

    def rel(a, b):
        return float(np.max(np.linalg.norm(a - b, axis=1)) / max(np.max(np.linalg.norm(b, axis=1)), 1e-300))

    u_r, u_o = vec(ref, "x", "y"), vec(other, "x", "y")
    F_r, F_o = vec(ref, "device_Fx", "device_Fy"), vec(other, "device_Fx", "device_Fy")
    a_r, a_o = vec(ref, "ax_abs", "ay_abs"), vec(other, "ax_abs", "ay_abs")

    def peak_diff(o, r):
        pr = np.max(np.linalg.norm(r, axis=1))
        return float((np.max(np.linalg.norm(o, axis=1)) - pr) / max(pr, 1e-300))

    return {"du": rel(u_o, u_r), "dF": rel(F_o, F_r), "da": rel(a_o, a_r),
            "peak_displacement": peak_diff(u_o, u_r), "peak_absolute_acceleration": peak_diff(a_o, a_r),
            "dtheta": float(np.max(np.abs(other["theta"] - ref["theta"])) / max(np.max(np.abs(ref["theta"])), 1e-300)),
            "dcap_z": float(np.max(np.abs(other["cap_z"] - ref["cap_z"])))}
