"""Warm pool workers for the comparisons' jobs (docs/performance.md, start-up): what each worker runs once before its
first job (``nsd_core.engine.workers.worker_pool``'s ``warm``), so that no job pays for imports,
numba's cache loading or compilation. The in-house kernels warm through ``nsd_core.compilation.warmup``;
each peer engine and setting through a tiny job of the same kind (its import, its compiled force
callbacks and step loop: ``comparisons.engines._warm_peer``)."""
from __future__ import annotations

from functools import partial

from nsd_core.structure.describe_seismic import structure_for
from nsd_core.structure.isolation import default_structure
from nsd_core.device.params import Params
from nsd_core.compilation.warmup import TINY_DT_OUT, TINY_DURATION, tiny_drive, tiny_ground
from nsd_core.compilation.worker_warmup import kind, warm_worker

from comparisons.engines import REFERENCE, run_job, run_seismic_job, tiny_settings


def spec(engine: str, seismic: bool, drive=None, settings: dict | None = None) -> tuple:
    """One job's warm-up kind: (engine, mode, path kind, the settings' choices, settings), the path
    kind and choices as each engine tells its runs apart (the in-house engine by path, method and
    backend; a peer by line or not and its named choices, e.g. MuJoCo's integrator)."""
    mode = "seismic" if seismic else "drive"
    if seismic:
        path = "line"
    elif engine == REFERENCE:
        path = kind("drive", None, drive.path)[3]
    else:
        path = "line" if drive.is_line else "circle"
    choices = tuple(sorted((k, v) for k, v in (settings or {}).items() if isinstance(v, str)))  # as _warm_peer
    return (engine, mode, path, choices, settings or {})


def job_warmup(specs) -> partial:
    """``warm`` for ``worker_pool``: every distinct kind of ``specs`` (from ``spec``), the in-house
    ones as kernels, each peer's as a tiny job of the same engine, mode and settings."""
    specs = list(specs)
    kinds = {kind(mode, settings, path) for engine, mode, path, _, settings in specs if engine == REFERENCE}
    return partial(warm_worker, tuple(sorted(kinds)), (), tuple(peer_calls(specs)))


def peer_calls(specs) -> list:
    """A tiny job of each distinct peer kind of ``specs`` (engine, mode, path kind, named choices)."""
    calls, seen = [], set()
    for engine, mode, path, key, settings in specs:
        if engine != REFERENCE and (engine, mode, path, key) not in seen:
            seen.add((engine, mode, path, key))
            # the named choices alone: they decide what compiles; a case's step (A25.5mm_f1Hz: Exudyn
            # at 6.25e-6 s) would make the tiny run cost 2.5 s in each worker
            settings = tiny_settings(engine, mode, settings)
            if mode == "seismic":
                calls.append(partial(run_seismic_job, engine, Params(), default_structure(Params()), tiny_ground(),
                                     TINY_DURATION, TINY_DT_OUT, settings))
            else:
                calls.append(partial(run_job, engine, Params(), tiny_drive(path), settings))
    return calls


def every_mode_calls() -> list:
    """The peers' tiny jobs of every kind the default cases run (each peer's drive along a line and a
    circle, MuJoCo's RK4, the seismic mode): what nsd_core.compilation.warm_all (``nsd warm``) compiles once per version."""
    from comparisons.engines import ENGINES
    peers = [e for e in ENGINES if e != REFERENCE]
    specs = [spec(e, False, tiny_drive(p), {}) for e in peers for p in ("line", "circle")]
    specs += [spec(e, True, None, {}) for e in peers]
    if "mujoco" in peers:
        specs.append(spec("mujoco", False, tiny_drive("line"), {"integrator": "RK4"}))
    # a described model's code is generated per shape: the default cases' restrainer and 3-story building too
    shaped = [partial(run_seismic_job, e, Params(), structure_for(Params(), stories, restrainer), tiny_ground(),
                      TINY_DURATION, TINY_DT_OUT, None)
              for e in peers for stories, restrainer in ((0, True), (3, False))]
    # Exudyn's generated forces and MuJoCo's passive callback are one module per set of laws: a mechanism
    # of the model layer's laws (nsd compare --model) shares the ones this tiny pendulum compiles
    described = [partial(tiny_described_run, e) for e in ("exudyn", "mujoco") if e in peers]
    return peer_calls(specs) + shaped + described


# a pendulum with a spring to the ground: a described mechanism of the model layer's laws (SI units)
TINY_MECHANISM = """
[model]
name = "warm_pendulum"
gravity = [0.0, -9.81, 0.0]

[[bodies]]
name = "bar"
joint = { type = "revolute", position = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0] }
mass = 1.0
com = [0.1, 0.0, 0.0]
inertia = [1e-4, 3e-3, 3e-3]

[[forces]]
name = "spring"
law = "linear_spring_damper"
body_a = "bar"
point_a = [0.2, 0.0, 0.0]
body_b = "ground"
point_b = [0.2, 0.2, 0.0]
parameters = { stiffness = 100.0, damping = 0.1, free_length = 0.15 }

[initial]
coordinates = { bar = 0.1 }

[[outputs]]
name = "spring_force"
kind = "force"
element = "spring"
"""


def tiny_described_run(engine: str) -> None:
    """A few steps of TINY_MECHANISM on a peer's described builder, at its default settings."""
    import importlib
    import tomllib
    from nsd_core.model.load import parse_model
    builder = importlib.import_module(f"comparisons.builders.{engine}")
    step = {"exudyn": {"step_size": 1e-3}, "mujoco": {"timestep": 1e-3}}[engine]
    builder.simulate(parse_model(tomllib.loads(TINY_MECHANISM)), 0.004, 0.002, step)
