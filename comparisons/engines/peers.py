"""MuJoCo and Exudyn behind the gate's engine interface (comparisons.engines.base.Engine): each peer's
model is built from the device's description by that engine's builder (comparisons/builders), in
the drive mode (comparisons/engines/described.py) and the seismic mode, restrainer and building
included (described_seismic.py). No peer model is written by hand: a change to the device is a change
to its description (nsd_core.device.describe, describe_seismic), which every engine then builds.

Each class holds the settings a gate case may give that peer (``default_settings``, the drive mode;
``seismic_default_settings``) and their checks; the numbers of the defaults are those the gate's
limits and case settings were measured with (docs/cases.md lists every key):
- MuJoCo: ``timestep`` [s], the largest step (the step used divides the output interval);
  ``integrator`` Euler (semi-implicit, first order) or RK4; ``solref_factor``, the loop constraints'
  time constant in steps (2: MuJoCo's floor, the stiffest); ``passive``, the passive forces' code
  ("compiled": generated from the description; "python": the readable reference, the same numbers).
- Exudyn: ``step_size`` [s]; in the drive mode also ``min_steps_per_cycle`` (the step is at most
  1 / (f x that)); ``builder_forces``, its force path ("predicted": the forces once a step at the
  step's predicted end, explicit in the forces; "compiled": every Newton iteration, implicit;
  "connectors": Exudyn's own connectors where the laws have one).
- Both: ``perturb``, a modelling error injected into this peer's description only (engines/perturb.py,
  ``nsd compare --power``); ``model``, kept for files written when the peers had hand-written models:
  "described" is the only value.
"""
from __future__ import annotations

import time

from comparisons.engines.base import SeismicSettings, check_settings
from comparisons.engines.described import DescribedEngine
from comparisons.engines.described_seismic import DescribedSeismic
from nsd_core.device.drive import Drive
from nsd_core.device.params import ParameterError, Params
from nsd_core.device.results import RunResult

MODEL = "described"


class _Peer:
    name: str
    default_settings: dict
    seismic_default_settings: dict

    def run(self, params: Params, drive: Drive, settings: dict | None = None) -> RunResult:
        s = check_settings(self, settings, self.name)   # an unknown or bad setting: one line, before any work
        drive.check_followable(params)   # a drive the mechanism cannot follow: exit 4, as the in-house run
        c0 = time.process_time()
        return _cpu(DescribedEngine(self.name).run(params, drive, _without_model(settings)), c0, s)

    def run_seismic(self, params: Params, structure, ground, duration=None, dt_out=1e-3,
                    settings: dict | None = None) -> RunResult:
        s = check_settings(SeismicSettings(self), settings, self.name)
        c0 = time.process_time()
        return _cpu(DescribedSeismic(self.name).run_seismic(params, structure, ground, duration=duration,
                                                            dt_out=dt_out, settings=_without_model(settings)), c0, s)


def _cpu(result: RunResult, c0: float, settings: dict) -> RunResult:
    """The run's CPU seconds, the model's build from the description included (and, in a process's first
    run of a model's shape, its code's compilation: comparisons.engines.run_engine warms up first), and
    the gate's settings it ran with (the builder's own are in the stats beside them)."""
    result.stats["cpu_time"] = time.process_time() - c0
    result.stats.setdefault("settings", settings)
    return result


def _without_model(settings: dict | None) -> dict | None:
    return {k: v for k, v in (settings or {}).items() if k != "model"} or None


def _choice(name: str, s: dict, key: str, allowed: tuple) -> None:
    if key in s and s[key] not in allowed:
        raise ParameterError(f"{name}.{key} = {s[key]!r}: allowed: {', '.join(allowed)}")


class MujocoEngine(_Peer):
    name = "mujoco"
    default_settings = {"timestep": 1e-5, "integrator": "Euler", "solref_factor": 2.0, "passive": "compiled",
                        "perturb": None, "model": MODEL}
    seismic_default_settings = default_settings

    @staticmethod
    def validate_settings(s: dict) -> None:
        _choice("mujoco", s, "integrator", ("Euler", "RK4"))
        _choice("mujoco", s, "passive", ("compiled", "python"))
        if s["solref_factor"] < 2.0:
            raise ParameterError(f"mujoco.solref_factor = {s['solref_factor']!r}: must be >= 2 (MuJoCo's minimum)")

    validate_seismic_settings = validate_settings


class ExudynEngine(_Peer):
    name = "exudyn"
    default_settings = {"step_size": 1e-5, "min_steps_per_cycle": 20000, "builder_forces": "predicted",
                        "perturb": None, "model": MODEL}
    seismic_default_settings = {"step_size": 1e-5, "builder_forces": "compiled", "perturb": None, "model": MODEL}
    # a warm-up's tiny run (comparisons.engines._warm_peer) compiles what a run does without the
    # 20000 steps a cycle of the default (2.5 s in each pool worker, for nothing)
    warm_settings = {"min_steps_per_cycle": 100}
