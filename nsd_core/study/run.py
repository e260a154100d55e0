"""One design of a sweep, run and analysed (in a worker process)."""
from __future__ import annotations

import math
import time
import traceback
from typing import Callable

import numpy as np

from nsd_core.device.params import ParameterError, Params
from nsd_core.device.results import RunResult, first_nonfinite
from nsd_core.common.errors import SolverError
from nsd_core.study.designs import Design

EngineRunner = Callable[..., RunResult]


def steady_table(result: RunResult, d: Design, wire_length: float) -> dict[str, np.ndarray]:
    """The last cycle: u, F, tangent stiffness dF/du (Figures 8-17 B), wire elongations (15, 18)."""
    from nsd_core.device.cycle import steady_cycle
    m = steady_cycle(result, d.frequency)
    t = result["t"][m]
    w = 2 * math.pi * d.frequency
    udot = d.amplitude * w * np.cos(w * t)
    # dF/du = (dF/dt)/(du/dt): undefined at the turning points, where du/dt vanishes
    k = np.gradient(result["F"][m], t) / np.where(np.abs(udot) > 0.05 * d.amplitude * w, udot, np.nan)
    cols = {"t": t, **{n: result[n][m] for n in ("u", "F", "F_device")}, "stiffness": k,
            **{n: result[n][m] for n in ("F_rod", "F_ropes", "F_wires", "spring_push")}}
    for j in range(int(d.params["n_wires"])):
        cols[f"wire{j}_elongation"] = result[f"wire{j}_strain"][m] * wire_length
    return cols


def run_design(d: Design, run_engine: EngineRunner | None = None) -> dict:
    """Run one design and analyse it; never raises for the design's own failure (status failed).

    ``run_engine(name, params, drive, settings) -> RunResult`` runs the named engine; the study
    layer knows only the in-house model, so the caller (the command line) passes the engine
    registry's runner to sweep other engines. It must be picklable (a module-level function).
    """
    start = time.perf_counter()
    try:
        from nsd_core.device.cycle import analyse
        from nsd_core.device.drive import Drive
        from nsd_core.device.geometry import device_geometry
        from nsd_core.device.working_range import SlackPointError, x_max_at_slack
        p = Params(**d.params)
        drive = Drive(d.amplitude, d.frequency, d.direction_deg, d.cycles, d.samples_per_cycle)
        if run_engine is not None:
            result = run_engine(d.engine, p, drive, d.settings)
        elif d.engine == "semirecursive":
            from nsd_core.device.model import simulate
            result = simulate(p, drive, **d.settings)
        else:
            raise ParameterError(f"engine {d.engine!r}: this sweep was given no runner for other engines")
        bad = first_nonfinite(result.columns)
        if bad:
            raise SolverError(f"a non-finite output: {bad}")
        summary = analyse(result, d.amplitude, d.frequency)
        try:
            xq = x_max_at_slack(p, d.direction_deg)
            theta = math.degrees(math.asin(xq / p.rod_length))
        except SlackPointError:
            xq = theta = None
        steady = steady_table(result, d, device_geometry(p).wire.natural_length)
        elong = [steady[n][1] for n in steady if n.endswith("_elongation")]
        metrics = {**summary, "dissipated_energy": summary["loop_area"], "x_max_quasi_static": xq,
                   "theta_max_deg": theta,
                   "wire_elongation_max": [float(np.max(e)) for e in elong],
                   "wire_elongation_min": [float(np.min(e)) for e in elong],
                   "solver": {k: v for k, v in result.stats.items() if isinstance(v, (int, float, str))}}
        return {"status": "ok", "error": None, "metrics": metrics, "result": result, "steady": steady,
                "wall_time": time.perf_counter() - start}
    except Exception as e:  # noqa: BLE001 - the design failed; record it and let the sweep go on
        msg = f"{type(e).__name__}: {e}".splitlines()[0]
        return {"status": "failed", "error": msg, "traceback": traceback.format_exc(limit=6),
                "metrics": None, "wall_time": time.perf_counter() - start}
