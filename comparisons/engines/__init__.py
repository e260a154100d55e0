"""The engines behind comparisons.engines.base.Engine, one class each: the in-house model
(semirecursive_engine) and the peers, MuJoCo and Exudyn, on models their builders make from the
device's description (peers.py); the one registry of the drive mode and the seismic mode
(``run_job`` / ``run_seismic_job``)."""
from __future__ import annotations

import importlib
import time
from typing import Any

from nsd_core.device.params import ParameterError, Params

ENGINES = {
    "semirecursive": ("comparisons.engines.semirecursive_engine", "SemirecursiveEngine"),
    "mujoco": ("comparisons.engines.peers", "MujocoEngine"),
    "exudyn": ("comparisons.engines.peers", "ExudynEngine"),
}
REFERENCE = "semirecursive"
# peers of the seismic mode's baseline isolators only (not of the device, not in the gate's cases):
# OpenSees builds the structure on a lead-rubber bearing or a friction pendulum (comparisons/engines/opensees_peer.py)
BASELINE_PEERS = ("opensees",)


def get_engine(name: str):
    """An engine instance by name (imported lazily: MuJoCo and Exudyn load only when used)."""
    if name not in ENGINES:
        raise ParameterError(f"engine {name!r}: unknown; allowed: {', '.join(ENGINES)}")
    module, cls = ENGINES[name]
    return getattr(importlib.import_module(module), cls)()

_WARM: set = set()   # (mode, engine, path kind, the settings' choices) compiled in this process


def tiny_settings(name: str, mode: str, settings: dict | None) -> dict | None:
    """A peer's settings for a warm-up's tiny run: the named choices of ``settings`` (what compiles),
    over the engine's ``warm_settings`` in the drive mode (Exudyn: fewer steps a cycle)."""
    choices = {k: v for k, v in (settings or {}).items() if isinstance(v, str)}
    warm = getattr(get_engine(name), "warm_settings", {}) if mode == "drive" else {}
    return {**warm, **choices} or None


def _warm_peer(mode: str, name: str, line: bool, settings: dict | None, tiny, shape: tuple = ()) -> float:
    """A peer engine's numba code (MuJoCo's callback and step loop, Exudyn's step) compiles on its first
    call: run ``tiny`` once per process and kind of run first, and return its seconds, so that the real
    run's wall_time is its integration (the in-house engine does this in nsd_core.compilation.warmup).
    ``tiny`` is given the settings' named choices alone (they decide what compiles; a case's own step,
    e.g. Exudyn's 6.25e-6 s, would make the tiny run cost seconds), over the engine's ``warm_settings``.
    ``shape``: what else decides the compiled code (a described model's code is generated per number of
    ropes, wires, stories and restrainer: a variant's first run warms up again instead of compiling
    inside its timed run)."""
    choices = tuple(sorted((k, v) for k, v in (settings or {}).items() if isinstance(v, str)))
    key = (mode, name, line, choices, shape)
    if name == REFERENCE or key in _WARM:
        return 0.0
    _WARM.add(key)
    start = time.perf_counter()
    try:
        tiny(tiny_settings(name, mode, settings))
    except Exception:  # noqa: BLE001 (the real run reports its own error)
        pass
    return time.perf_counter() - start


def _chosen(name: str, settings: dict) -> tuple:
    """(model, engine) for a run: ``settings``' own ``model`` (popped; "described", the only model a peer
    has: files written when the peers also had hand-written adapters name it) and the engine."""
    model = settings.pop("model", None if name == REFERENCE else "described")
    if name == REFERENCE and model is not None:
        raise ParameterError(f"{name}.model = {model!r}: a peer's setting (mujoco, exudyn)")
    if name != REFERENCE and model != "described":
        raise ParameterError(f"{name}.model = {model!r}: allowed: described (the peers' models are built from the "
                             "device's description; the hand-written adapters were removed)")
    return model, get_engine(name)


def run_engine(name: str, params: Params, drive, settings: dict | None = None):
    """Run one engine by name: the runner the study layer is given to sweep any engine. Whatever the
    engine prints (Exudyn's memory-allocation warnings) goes to stderr, never into stdout's table.
    The run's stats carry ``compile_time`` (a first, tiny run of the same kind) apart from its cost."""
    from nsd_core.compilation.warmup import tiny_drive
    from nsd_core.engine.workers import stdout_to_stderr
    settings = dict(settings or {})
    _, engine = _chosen(name, settings)
    with stdout_to_stderr():
        warm = _warm_peer("drive", name, drive.is_line, settings, lambda choices: engine.run(
            params, tiny_drive("line" if drive.is_line else "circle"), choices), (params.n_ropes, params.n_wires))
        c0 = time.process_time()
        result = engine.run(params, drive, settings or None)
    return _with_times(name, result, warm, time.process_time() - c0)


def _with_times(name: str, result, warm: float, cpu: float):
    """A peer's compile_time, and its cpu_time where it did not measure one (the run, warm)."""
    if name != REFERENCE:
        result.stats["compile_time"] = warm
        result.stats.setdefault("cpu_time", cpu)
    return result


def parse_engine_list(text: str, option: str = "--engines", extra: tuple = ()) -> list[str]:
    """Comma-separated engine names of the registry (and of ``extra``, e.g. BASELINE_PEERS), each once
    (ParameterError otherwise)."""
    names = [e.strip() for e in text.split(",") if e.strip()]
    for e in names:
        if e not in ENGINES and e not in extra:
            raise ParameterError(f"{option} {e!r}: unknown engine; allowed: {', '.join([*ENGINES, *extra])}")
    if not names or len(set(names)) != len(names):
        raise ParameterError(f"{option} {text!r}: give each engine once")
    return names


def run_seismic_engine(name: str, params: Params, structure, ground, duration=None, dt_out=1e-3,
                       settings: dict | None = None):
    """One engine's seismic run by name (Exudyn's prints go to stderr, as in ``run_engine``)."""
    from nsd_core.compilation.warmup import TINY_DT_OUT, TINY_DURATION, tiny_ground
    from nsd_core.engine.workers import stdout_to_stderr
    if name in BASELINE_PEERS:   # the structure on its baseline isolator (the run without the device)
        from comparisons.engines.opensees_peer import run_opensees
        with stdout_to_stderr():
            return _with_ground(run_opensees(structure, ground, duration, dt_out, settings), ground)
    settings = dict(settings or {})
    _, engine = _chosen(name, settings)
    with stdout_to_stderr():   # the warm-up's key names the model's shape: each shape compiles its own code
        warm = _warm_peer("seismic", name, True, settings, lambda choices: engine.run_seismic(
            params, structure, tiny_ground(), duration=TINY_DURATION, dt_out=TINY_DT_OUT, settings=choices),
            (params.n_ropes, params.n_wires, structure.building.stories if structure.building is not None else 0,
             structure.restrainer is not None))
        c0 = time.process_time()
        result = engine.run_seismic(params, structure, ground, duration=duration, dt_out=dt_out,
                                    settings=settings or None)
    return _with_ground(_with_times(name, result, warm, time.process_time() - c0), ground)


GROUND_COLUMNS = ("x_g", "y_g", "ax_g", "ay_g")  # nsd_core.structure.seismic's columns of the input itself


def _with_ground(result, ground):
    """The ground motion the engine was given, at its output times, as the in-house run's columns
    (x_g, y_g, ax_g, ay_g) where the engine did not write them: a peer's seismic_<engine>.csv then has
    the in-house columns, and its summary (nsd_core.structure.seismic_summary: the peak ground
    acceleration) can be made from it, as a record set does for every run."""
    from nsd_core.device.columns import units_of
    missing = [c for c in GROUND_COLUMNS if c not in result.columns]
    if missing:
        d, _, a = ground(result["t"])
        values = {"x_g": d[:, 0], "y_g": d[:, 1], "ax_g": a[:, 0], "ay_g": a[:, 1]}
        cols = {"t": result.columns["t"], **{c: values[c] for c in missing},
                **{k: v for k, v in result.columns.items() if k != "t"}}
        result.columns.clear()
        result.columns.update(cols)
        result.units.update(units_of(dict.fromkeys(missing)))
    return result


def _finite(result):
    """``result``, or SolverError naming the first NaN or inf in its outputs: a non-finite output is that
    engine's failure on that case (reported for it, exit 3), never a result to measure."""
    from nsd_core.device.results import first_nonfinite
    from nsd_core.common.errors import SolverError
    bad = first_nonfinite(result)
    if bad:
        raise SolverError(f"a non-finite output: {bad}")
    return result


def run_seismic_job(engine: str, params: Params, structure, ground, duration, dt_out, settings: dict) -> dict[str, Any]:
    """One engine on one seismic case, in a worker process. Never raises: failures come back as data."""
    start, started = time.perf_counter(), time.time()  # started: the pool's start-up ends here
    try:
        result = _finite(run_seismic_engine(engine, params, structure, ground, duration, dt_out, settings))
        return {"status": "ok", "result": result, "wall_time": time.perf_counter() - start, "started": started}
    except Exception as e:  # an engine's failure is reported for its case; the others go on
        msg = " ".join(f"{type(e).__name__}: {e}".split())
        return {"status": "error", "message": msg[:500], "wall_time": time.perf_counter() - start}


def run_job(engine: str, params: Params, drive, settings: dict) -> dict[str, Any]:
    """One engine on one case, in a worker process. Never raises: failures come back as data."""
    start, started = time.perf_counter(), time.time()  # started: the pool's start-up ends here
    try:
        result = _finite(run_engine(engine, params, drive, settings))
        return {"status": "ok", "result": result, "wall_time": time.perf_counter() - start, "started": started}
    except Exception as e:  # an engine's failure is reported for its case; the others go on
        msg = " ".join(f"{type(e).__name__}: {e}".split())
        return {"status": "error", "message": msg[:500], "wall_time": time.perf_counter() - start}
