"""The IDA cross-check's check of the supports alone (nsd_cli.ida_check): the in-house run of the
isolated mass on its linear supports against the exact solution of the linear oscillator
M u'' + c_b u' + k_b u = -M a_g per component, by ``eqsig`` (Nigam and Jennings 1968, exact for a
piecewise-linear input), on the record's own samples. MuJoCo and Exudyn do not model the supports
alone; the exact solution is the independent check there."""
from __future__ import annotations

import math

import numpy as np

from nsd_core.structure.isolation import Structure
from nsd_core.device.results import RunResult
from nsd_core.study.ida import Trace


def _not_applicable(why: str) -> dict:
    return {"engine": "exact (eqsig, Nigam-Jennings)", "status": "not applicable", "error": why}


def exact_supports_alone(run: RunResult, trace: Trace, level: float) -> tuple[dict, dict | None]:
    """The supports-alone run against the exact linear oscillator on the run's output times: eqsig's
    Nigam-Jennings recursion on each component's own samples (exact for the record, linear between
    them; zeros after its end), u and u' there, cubic Hermite between them (the solution is smooth
    inside a sample interval), the pair rotated as the run's input. eqsig's u is -(the displacement
    relative to the ground) for an input ground acceleration: the sign is turned."""
    from eqsig import sdof
    from scipy.interpolate import CubicHermiteSpline
    from nsd_core.ground.records import fema_record
    p = trace.point(level)
    s = Structure(**p.structure)
    if s.building is not None:   # several masses: no single oscillator to compare with, no series
        return _not_applicable("a building on the slab: the exact solution here is the single oscillator's (the "
                               "building's is checked in tests/test_building.py)"), None
    motion = fema_record(p.set, p.record, **p.ground)
    t_out = run["t"]
    period = 2.0 * math.pi * math.sqrt(s.mass / s.stiffness)
    comps = []
    for c in motion.comp:
        dt = float(c.t[1] - c.t[0])
        n = max(len(c.t), int(math.ceil(t_out[-1] / dt)) + 2)
        a = np.zeros(n)
        a[:len(c.a)] = c.a
        resp_u, resp_v, _ = sdof.response_series(a, dt, np.array([period]), s.damping_ratio)
        grid = c.t[0] + dt * np.arange(n)
        comps.append(CubicHermiteSpline(grid, -resp_u[0], -resp_v[0])(t_out))
    ux, uy = motion.rotation @ np.vstack(comps)
    ref = np.hypot(ux, uy)
    diff = np.hypot(run["x"] - ux, run["y"] - uy)
    if "restrainer_F" in run.columns and np.max(run["restrainer_F"]) > 0:
        return _not_applicable("the restrainer engaged: the exact linear solution holds without contact"), \
            {"t": t_out, "x": ux, "y": uy, "u": ref}
    metrics = {"engine": "exact (eqsig, Nigam-Jennings)", "du": float(np.max(diff) / max(np.max(ref), 1e-300)),
               "peak_displacement": float((np.max(run["u"]) - np.max(ref)) / max(np.max(ref), 1e-300)),
               "period_s": period, "damping_ratio": s.damping_ratio}
    return metrics, {"t": t_out, "x": ux, "y": uy, "u": ref}
