"""Engine adapters, one module each, all behind comparisons.engines.base.Engine."""
from __future__ import annotations

import importlib

from nsd_core.device.params import ParameterError

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
