"""A peer's run of the isolated structure on a baseline isolator (a lead-rubber bearing or a friction
pendulum), without the device, built from its description: ``nsd seismic --isolator KIND --engines
semirecursive,mujoco,exudyn``'s cross-check of the in-house ``simulate_seismic(..., device=False)``.

The model is written by ``nsd_core.structure.describe_isolator.isolator_description`` (the plate on a
planar joint, the isolator's linear part as joint springs, its hysteresis as the registry's plane law
``bidirectional_hysteresis``) and built by the engine's builder (comparisons.builders.mujoco or
.exudyn) with the case's settings written in the description (each peer's step) over ``settings``.
The columns are the in-house run's names: x, y, theta, vx, vy, ax_abs, ay_abs, support_Fx, support_Fy
(the isolator's force on the plate, negated: k_d u + c u' + Q z), isolator_zx, isolator_zy, u and the
base shear (the isolator's force: no device, no restrainer, no building).
"""
from __future__ import annotations

import importlib
import tomllib

import numpy as np

from comparisons.engines.base import EngineError
from comparisons.engines.described_seismic import ground_table
from nsd_core.device.columns import units_of
from nsd_core.structure.describe_isolator import isolator_description
from nsd_core.device.params import ParameterError
from nsd_core.device.results import RunResult
from nsd_core.structure.seismic import output_times
from nsd_core.model.errors import ModelError
from nsd_core.model.load import parse_model

PEERS = ("mujoco", "exudyn")


def run_isolator(engine: str, structure, ground, duration: float | None = None, dt_out: float = 1e-3,
                 settings: dict | None = None) -> RunResult:
    """The run without the device on ``structure.isolator`` in ``engine`` (mujoco or exudyn), on the
    in-house run's output times."""
    if engine not in PEERS:
        raise ParameterError(f"isolator peer {engine!r}: allowed {', '.join(PEERS)}")
    duration = ground.duration if duration is None else float(duration)
    t_out = output_times(duration, dt_out)   # the in-house run's output times (ceil): the builders round
    try:
        raw = tomllib.loads(isolator_description(structure, ground_table(ground), duration, dt_out))
        model = parse_model(raw)
        if not np.array_equal(model.excitation.block, np.ascontiguousarray(ground.block(), dtype=float)):
            raise EngineError(f"{engine} (isolator): the [excitation] written for {ground.describe()!r} is not the "
                              "case's ground motion")
        s = {**raw["case"][0].get(engine, {}), **(settings or {})}
        run = importlib.import_module(f"comparisons.builders.{engine}").simulate(model, duration,
                                                                                 duration / (len(t_out) - 1), s)
    except (ModelError, ParameterError) as e:
        raise EngineError(f"{engine} (isolator): {e}") from None
    o, iso = run.outputs, structure.isolator
    x, y, vx, vy = o["u_x"], o["u_y"], o["v_x"], o["v_y"]
    fx = iso.stiffness * x + iso.damping * vx - o["hysteresis_x"]
    fy = iso.stiffness * y + iso.damping * vy - o["hysteresis_y"]
    cols = {"t": np.asarray(t_out, dtype=float), "x": x, "y": y, "theta": o["theta"], "vx": vx, "vy": vy,
            "ax_abs": o["a_x"], "ay_abs": o["a_y"], "support_Fx": fx, "support_Fy": fy,
            "isolator_zx": o["z_x"], "isolator_zy": o["z_y"], "u": np.hypot(x, y), "base_shear_x": fx,
            "base_shear_y": fy}
    stats = {**run.stats, "engine": engine, "mode": "seismic", "device": False, "isolator": iso.kind,
             "model": "described", "settings": s}
    return RunResult(engine, cols, units_of(cols), stats)


def isolator_metrics(ref, other) -> dict:
    """Differences of the peer's run against the in-house one on the same output times: du, dF (the
    isolator's force vector), da (absolute acceleration) as max|o - r| / max|r| over plan vectors,
    and the relative differences of the peak displacement and acceleration."""
    if len(ref["t"]) != len(other["t"]) or np.max(np.abs(ref["t"] - other["t"])) > 1e-9:
        raise ValueError("isolator_metrics: the runs are not on the same output times")

    def vec(r, a, b):
        return np.column_stack([r[a], r[b]])

    def rel(name_x, name_y):
        a, b = vec(other, name_x, name_y), vec(ref, name_x, name_y)
        return float(np.max(np.linalg.norm(a - b, axis=1)) / max(np.max(np.linalg.norm(b, axis=1)), 1e-300))

    def peak(name_x, name_y):
        a, b = vec(other, name_x, name_y), vec(ref, name_x, name_y)
        pr = np.max(np.linalg.norm(b, axis=1))
        return float((np.max(np.linalg.norm(a, axis=1)) - pr) / max(pr, 1e-300))

    return {"du": rel("x", "y"), "dF": rel("support_Fx", "support_Fy"), "da": rel("ax_abs", "ay_abs"),
            "peak_displacement": peak("x", "y"), "peak_absolute_acceleration": peak("ax_abs", "ay_abs")}
