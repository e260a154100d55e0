"""One small interface for every engine: build the device from Params, run a Drive, return a RunResult.

Like scipy's ``solve_ivp`` methods, each engine is one module exposing a class with this shape::

    class Engine:
        name: str                       # "semirecursive", "mujoco", "exudyn"
        default_settings: dict          # solver settings, overridable per case
        def run(self, params, drive, settings=None) -> RunResult

``run`` returns the columns of ``nsd_core.results.column_units`` (built with
``nsd_core.outputs.device_columns``) sampled at ``drive.output_times()``, and ``stats`` with at
least ``wall_time`` [s], ``steps`` and ``tracking_error`` [m] (max |u_engine - u_prescribed|).
An engine that fails raises ``EngineError`` with a one-line message.
"""
from __future__ import annotations

from typing import Any, Protocol

from nsd_core.device.drive import Drive
from nsd_core.device.params import Params
from nsd_core.device.results import RunResult


class EngineError(RuntimeError):
    """An engine failed on one case (exit code 3); the harness reports it and goes on."""


class Engine(Protocol):
    name: str
    default_settings: dict[str, Any]

    def run(self, params: Params, drive: Drive, settings: dict[str, Any] | None = None) -> RunResult: ...


def merged_settings(defaults: dict[str, Any], settings: dict[str, Any] | None, engine: str) -> dict[str, Any]:
    """Defaults updated by ``settings``; an unknown key is bad input (a one-line ParameterError)."""
    from nsd_core.device.params import ParameterError
    out = dict(defaults)
    for k, v in (settings or {}).items():
        if k not in defaults:
            raise ParameterError(f"{engine}.{k}: unknown solver setting; allowed: {', '.join(sorted(defaults))}")
        out[k] = v
    return out
