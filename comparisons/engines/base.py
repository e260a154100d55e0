"""One small interface for every engine: build the device from Params, run a Drive, return a RunResult.

Like scipy's ``solve_ivp`` methods, each engine is one module exposing a class with this shape::

    class Engine:
        name: str                       # "semirecursive", "mujoco", "exudyn"
        default_settings: dict          # solver settings, overridable per case
        def run(self, params, drive, settings=None) -> RunResult
        # the seismic mode (Table 1, second row; docs/seismic.md): the same engine, base driven by the ground
        seismic_default_settings: dict
        def run_seismic(self, params, structure, ground, duration=None, dt_out=1e-3, settings=None) -> RunResult

``run`` returns the columns of ``nsd_core.results.column_units`` (built with
``nsd_core.outputs.device_columns``) sampled at ``drive.output_times()``, and ``stats`` with at
least ``wall_time`` [s], ``steps`` and ``tracking_error`` [m] (max |u_engine - u_prescribed|).
An engine that fails raises ``EngineError`` with a one-line message.

``run_seismic`` returns the seismic columns of ``nsd_core.structure.seismic`` (at least t, x, y, theta,
ax_abs, ay_abs, device_Fx, device_Fy, cap_z, closure and the energy balance E_input ... E_residual,
computed from the engine's own state with the nominal masses) every ``dt_out`` up to ``duration``.
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

    seismic_default_settings: dict[str, Any]

    def run_seismic(self, params: Params, structure, ground, duration: float | None = None, dt_out: float = 1e-3,
                    settings: dict[str, Any] | None = None) -> RunResult: ...


class SeismicSettings:
    """An engine's seismic settings seen through the drive settings' checks (``check_settings``)."""

    def __init__(self, engine):
        self.name = engine.name
        self.default_settings = engine.seismic_default_settings
        hook = getattr(engine, "validate_seismic_settings", None)
        if hook is not None:
            self.validate_settings = hook


def merged_settings(defaults: dict[str, Any], settings: dict[str, Any] | None, engine: str) -> dict[str, Any]:
    """Defaults updated by ``settings``; an unknown key is bad input (a one-line ParameterError)."""
    from nsd_core.device.params import ParameterError
    if settings is not None and not isinstance(settings, dict):
        raise ParameterError(f"{engine} = {settings!r}: must be a table of setting = value")
    out = dict(defaults)
    for k, v in (settings or {}).items():
        if k not in defaults:
            raise ParameterError(f"{engine}.{k}: unknown solver setting; allowed: {', '.join(sorted(defaults))}")
        out[k] = v
    return out


# Floors that keep one run's work bounded (docs/limits.md): no step below STEP_FLOOR seconds, tolerances
# a double can honour, and at most MAX_FIXED_STEPS steps for an engine with a fixed step.
STEP_FLOOR = 1e-8
STEP_SETTINGS = ("step_size", "timestep", "max_step")
MAX_FIXED_STEPS = 20_000_000


def check_settings(engine, settings: dict[str, Any] | None, where: str) -> dict[str, Any]:
    """Every setting typed like its default and in range, then the engine's own ``validate_settings``
    hook: a bad setting is bad input (exit 2) found before any work starts."""
    from nsd_core.device.params import ParameterError
    s = merged_settings(engine.default_settings, settings, where)
    for k, v in (settings or {}).items():
        d = engine.default_settings[k]
        name = f"{where}.{k} = {v!r}"
        choices = {"model": ("described",), "builder_forces": ("compiled", "predicted", "connectors")}.get(k)
        if choices and v not in choices:
            gone = " (the peers' models are built from the device's description; the hand-written adapters " \
                "were removed)" if k == "model" else ""
            raise ParameterError(f"{name}: allowed: {', '.join(choices)}{gone}")
        if k == "perturb":   # an injected modelling error (nsd compare --power): its own checks
            from comparisons.engines.perturb import check as check_perturbation
            try:
                check_perturbation(v)
            except ParameterError as err:
                raise ParameterError(f"{where}.{err}") from None
            continue
        if isinstance(d, bool):
            if not isinstance(v, bool):
                raise ParameterError(f"{name}: must be true or false")
        elif isinstance(d, str):
            if not isinstance(v, str):
                raise ParameterError(f"{name}: must be a string")
        elif isinstance(d, list):
            if not isinstance(v, list) or len(v) != len(d) or not all(_finite(x) for x in v):
                raise ParameterError(f"{name}: must be a list of {len(d)} finite numbers")
        elif d is None or isinstance(d, int):  # counts: a whole number >= 1 (None: the engine chooses)
            if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= 10_000_000:
                raise ParameterError(f"{name}: must be a whole number in [1, 10000000]")
        elif isinstance(d, float):
            if not _finite(v) or not v > 0:
                raise ParameterError(f"{name}: must be a finite number > 0")
            if k in STEP_SETTINGS and v < STEP_FLOOR:
                raise ParameterError(f"{name}: must be >= {STEP_FLOOR:g} s (the step-size floor)")
            if k == "rtol" and not 1e-13 <= v <= 0.1:
                raise ParameterError(f"{name}: must be in [1e-13, 0.1]")
            if k == "atol" and not v <= 1.0:
                raise ParameterError(f"{name}: must be in (0, 1]")
    hook = getattr(engine, "validate_settings", None)
    if hook is not None:
        hook(s)
    return s


def _finite(v) -> bool:
    import math
    return not isinstance(v, bool) and isinstance(v, (int, float)) and math.isfinite(v)


def check_step_count(engine: str, n_steps: int) -> None:
    """A fixed-step run longer than MAX_FIXED_STEPS fails for its case (exit 3), before it starts."""
    if n_steps > MAX_FIXED_STEPS:
        raise EngineError(f"{engine}: exceeded {MAX_FIXED_STEPS} steps ({n_steps} needed at this step size)")
