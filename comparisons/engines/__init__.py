"""Engine adapters, one module each, all behind comparisons.engines.base.Engine: the one registry of
the drive mode and the seismic mode (``run_job`` / ``run_seismic_job``)."""
from __future__ import annotations

import importlib
import time
from typing import Any

from nsd_core.device.params import ParameterError, Params

ENGINES = {
    "semirecursive": ("comparisons.engines.semirecursive_engine", "SemirecursiveEngine"),
    "mujoco": ("comparisons.engines.mujoco_engine", "MujocoEngine"),
    "exudyn": ("comparisons.engines.exudyn_engine", "ExudynEngine"),
}
REFERENCE = "semirecursive"


def get_engine(name: str):
    """An engine instance by name (imported lazily: MuJoCo and Exudyn load only when used)."""
    if name not in ENGINES:
        raise ParameterError(f"engine {name!r}: unknown; allowed: {', '.join(ENGINES)}")
    module, cls = ENGINES[name]
    return getattr(importlib.import_module(module), cls)()

def run_engine(name: str, params: Params, drive, settings: dict | None = None):
    """Run one engine by name: the runner the study layer is given to sweep any engine. Whatever the
    engine prints (Exudyn's memory-allocation warnings) goes to stderr, never into stdout's table."""
    from nsd_core.engine.workers import stdout_to_stderr
    with stdout_to_stderr():
        return get_engine(name).run(params, drive, settings or None)


def parse_engine_list(text: str, option: str = "--engines") -> list[str]:
    """Comma-separated engine names of the registry, each once (ParameterError otherwise)."""
    names = [e.strip() for e in text.split(",") if e.strip()]
    for e in names:
        if e not in ENGINES:
            raise ParameterError(f"{option} {e!r}: unknown engine; allowed: {', '.join(ENGINES)}")
    if not names or len(set(names)) != len(names):
        raise ParameterError(f"{option} {text!r}: give each engine once")
    return names


def run_seismic_engine(name: str, params: Params, structure, ground, duration=None, dt_out=1e-3,
                       settings: dict | None = None):
    """One engine's seismic run by name (Exudyn's prints go to stderr, as in ``run_engine``)."""
    from nsd_core.engine.workers import stdout_to_stderr
    with stdout_to_stderr():
        return get_engine(name).run_seismic(params, structure, ground, duration=duration, dt_out=dt_out,
                                            settings=settings or None)


def run_seismic_job(engine: str, params: Params, structure, ground, duration, dt_out, settings: dict) -> dict[str, Any]:
    """One engine on one seismic case, in a worker process. Never raises: failures come back as data."""
    start = time.perf_counter()
    try:
        result = run_seismic_engine(engine, params, structure, ground, duration, dt_out, settings)
        return {"status": "ok", "result": result, "wall_time": time.perf_counter() - start}
    except Exception as e:  # an engine's failure is reported for its case; the others go on
        msg = " ".join(f"{type(e).__name__}: {e}".split())
        return {"status": "error", "message": msg[:500], "wall_time": time.perf_counter() - start}


def run_job(engine: str, params: Params, drive, settings: dict) -> dict[str, Any]:
    """One engine on one case, in a worker process. Never raises: failures come back as data."""
    start = time.perf_counter()
    try:
        result = run_engine(engine, params, drive, settings)
        return {"status": "ok", "result": result, "wall_time": time.perf_counter() - start}
    except Exception as e:  # an engine's failure is reported for its case; the others go on
        msg = " ".join(f"{type(e).__name__}: {e}".split())
        return {"status": "error", "message": msg[:500], "wall_time": time.perf_counter() - start}
