"""A peer's drive-mode run built from the device's description (docs/models.md): the gate's engine interface
(``run(params, drive, settings) -> RunResult``) over a builder (comparisons/builders), which
comparisons/engines/peers.py puts behind each peer's name.

The device is written as a description by ``nsd_core.device.describe.device_description`` (the case's
parameters and plate path), with every output the gate's columns need: the drive force, the cap's
position, the wall's height, every wire's stress and the spring's zeta (the laws' states). The columns
then come from the device's one column builder (``nsd_core.device.outputs.device_columns``), as the
in-house engine's do.

The gate's settings (peers.py) map onto the builders' own: MuJoCo's ``timestep``, ``integrator`` and
``solref_factor``, ``passive``; Exudyn's ``step_size`` capped by ``min_steps_per_cycle`` per drive
cycle and its force path from ``builder_forces``. Before the hand-written adapters were removed the two
were run side by side on every gate case (docs/validation.md): the same verdicts, within 1.25x their
time.
"""
from __future__ import annotations

import importlib
import tomllib

import numpy as np

from comparisons.engines.base import EngineError
from comparisons.engines.perturb import perturbed
from nsd_core.device.describe import device_description
from nsd_core.device.drive import Drive
from nsd_core.device.geometry import device_geometry
from nsd_core.device.outputs import device_columns
from nsd_core.device.params import Params
from nsd_core.model.errors import ModelError
from nsd_core.model.load import parse_model

# the gate's settings a builder has under the same name
SHARED = {"mujoco": ("timestep", "integrator", "solref_factor", "passive"), "exudyn": ("step_size",)}


def builder_settings(engine: str, settings: dict | None, frequency: float, mode: str = "drive") -> dict:
    """The builder's settings for a case's ``settings`` (see the module's docstring), over the peer's
    defaults of ``mode`` (Exudyn's force path: "predicted" in drive mode, the forces once a step;
    "compiled", implicit, in the seismic mode)."""
    from comparisons.engines import get_engine
    e = get_engine(engine)
    defaults = e.default_settings
    if mode != "drive":   # the seismic defaults over the drive's (MuJoCo's Euler), no cycle to cap a step
        defaults = {**defaults, **e.seismic_default_settings, "min_steps_per_cycle": None}
    s = {**defaults, **(settings or {})}
    out = {k: s[k] for k in SHARED[engine] if k in s and s[k] is not None}
    if engine == "exudyn":   # its force path
        out["forces"] = s.get("builder_forces", "predicted")
    if engine == "exudyn" and s.get("min_steps_per_cycle"):   # the cap on its step, per drive cycle
        out["step_size"] = min(float(s["step_size"]), 1.0 / (float(s["min_steps_per_cycle"]) * frequency))
    return out


def _outputs(n_wires: int) -> str:
    """The outputs the columns need beyond the description's own (cap_x, cap_y, every wire's stress)."""
    blocks = [f'\n[[outputs]]\nname = "cap_{c}"\nkind = "coordinate"\njoint = "cap"\ndof = {k}\n'
              for k, c in enumerate("xy")]
    blocks += [f'\n[[outputs]]\nname = "wire{j}_stress"\nkind = "state"\nelement = "wire{j}"\n'
               for j in range(1, n_wires)]
    return "".join(blocks)


def described_model(params: Params, drive: Drive, perturb: dict | None = None):
    """The device under ``drive`` as a parsed description with the columns' outputs; ``perturb``: a
    modelling error injected into this engine's description only (comparisons.engines.perturb)."""
    g = perturbed(device_geometry(params), perturb)
    text = device_description(params, drive.amplitude, drive.frequency, drive.direction_deg, drive.cycles,
                              drive.samples_per_cycle, drive=drive, case="", geometry=g) + _outputs(g.n_wires)
    return parse_model(tomllib.loads(text)), g


class DescribedEngine:
    """The gate's engine interface over ``comparisons.builders.<engine>`` (drive mode)."""

    def __init__(self, engine: str):
        self.name = engine
        self.builder = importlib.import_module(f"comparisons.builders.{engine}")

    def run(self, params: Params, drive: Drive, settings: dict | None = None):
        try:
            model, g = described_model(params, drive, (settings or {}).get("perturb"))
            t_out = drive.output_times()
            run = self.builder.simulate(model, drive.duration, float(t_out[1] - t_out[0]),
                                        builder_settings(self.name, settings, drive.frequency))
        except ModelError as e:
            raise EngineError(f"{self.name} (described): {e}") from None
        o = run.outputs
        cap = np.column_stack([o["cap_x"], o["cap_y"], o["cap_z"]])
        stress = np.column_stack([o[f"wire{j}_stress"] for j in range(g.n_wires)]) if g.n_wires else \
            np.zeros((len(run.t), 0))
        closure = np.full(len(run.t), float(run.stats.get("closure_max", 0.0)))
        stats = {**run.stats, "model": "described", "tracking_error": float(run.stats.get("tracking_error", 0.0))}
        return device_columns(self.name, g, drive, run.t, cap, o["wall_z"], stress, o["spring_zeta"], closure,
                              drive_force=np.column_stack([o["F_x"], o["F_y"]]), stats=stats)
