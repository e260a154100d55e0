"""The in-house two-step semirecursive model (nsd_core.device) behind the shared engine interface."""
from __future__ import annotations

from nsd_core.device.model import DEFAULT_SOLVER, simulate
from nsd_core.device.drive import Drive
from nsd_core.common.errors import SolverError
from nsd_core.device.params import Params
from nsd_core.device.results import RunResult

from comparisons.engines.base import EngineError, merged_settings


class SemirecursiveEngine:
    name = "semirecursive"
    default_settings = dict(DEFAULT_SOLVER)

    @staticmethod
    def validate_settings(s: dict) -> None:
        from nsd_core.device.params import ParameterError
        from nsd_core.engine.integrate import METHODS
        if s["method"] not in METHODS:
            raise ParameterError(f"semirecursive.method = {s['method']!r}: allowed: {', '.join(METHODS)}")

    def run(self, params: Params, drive: Drive, settings: dict | None = None) -> RunResult:
        s = merged_settings(self.default_settings, settings, self.name)
        try:
            result = simulate(params, drive, **s)
        except SolverError as e:
            raise EngineError(str(e)) from None
        result.stats["settings"] = s
        return result

    # the seismic mode: nsd_core.structure.seismic, with the same solver options (its own backends)
    seismic_default_settings = dict(DEFAULT_SOLVER)
    validate_seismic_settings = validate_settings

    def run_seismic(self, params: Params, structure, ground, duration=None, dt_out=1e-3,
                    settings: dict | None = None) -> RunResult:
        from nsd_core.structure.seismic import simulate_seismic
        s = merged_settings(self.seismic_default_settings, settings, self.name)
        try:
            result = simulate_seismic(params, structure, ground, duration=duration, dt_out=dt_out, **s)
        except SolverError as e:
            raise EngineError(str(e)) from None
        result.stats["settings"] = s
        return result
