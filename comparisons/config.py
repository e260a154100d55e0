"""Case and tolerance files (TOML), validated into plain data with one-line errors."""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from nsd_core.device.drive import Drive
from nsd_core.device.params import ParameterError, Params, load_params

HERE = Path(__file__).resolve().parent
DEFAULT_CASES = HERE / "cases.toml"
DEFAULT_TOLERANCES = HERE / "tolerances.toml"

METRICS = {  # name -> (unit, description)
    "max_dF_rel": ("-", "max |F - F_ref| / max |F_ref|"),
    "rms_dF_rel": ("-", "RMS (F - F_ref) / max |F_ref|"),
    "loop_area_rel": ("-", "|loop area - reference| / |reference|"),
    "peak_force_rel": ("-", "|peak |F| - reference| / reference"),
    "region_shift_rel": ("-", "largest stiffness-region boundary shift / amplitude"),
    "closure_max": ("m", "largest loop-closure violation"),
    "tracking_error": ("m", "largest drive tracking error"),
    "energy_balance_rel": ("-", "|drive work - (wires + spring hysteresis + stored change)| / drive work, steady cycle"),
}
CASE_KEYS = {"name", "amplitude", "frequency", "direction_deg", "cycles", "samples_per_cycle", "params",
             "settings", "engine_params"}


@dataclass(frozen=True)
class Case:
    name: str
    drive: Drive
    params: Params
    settings: dict[str, dict] = field(default_factory=dict)       # engine -> solver settings
    engine_params: dict[str, Params] = field(default_factory=dict)  # engine -> its own parameter set

    def params_for(self, engine: str) -> Params:
        return self.engine_params.get(engine, self.params)

    def describe(self) -> dict[str, Any]:
        d = self.drive
        return {"name": self.name, "amplitude": d.amplitude, "frequency": d.frequency,
                "direction_deg": d.direction_deg, "cycles": d.cycles, "samples_per_cycle": d.samples_per_cycle,
                "params_overridden": {k: v for k, v in self.params.to_dict().items() if v != getattr(Params(), k)},
                "settings": self.settings,
                "engine_params": {e: {k: v for k, v in p.to_dict().items() if v != getattr(self.params, k)}
                                  for e, p in self.engine_params.items()}}


def _read(path: Path, what: str) -> dict:
    try:
        return tomllib.loads(Path(path).read_text())
    except FileNotFoundError:
        raise ParameterError(f"{what} {path}: file not found") from None
    except tomllib.TOMLDecodeError as e:
        raise ParameterError(f"{what} {path}: not valid TOML ({e})") from None


def _number(where: str, v, positive=True) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or (positive and v <= 0):
        raise ParameterError(f"{where} = {v!r}: must be a {'positive ' if positive else ''}finite number")
    return float(v)


def load_convergence(path: str | Path | None, cases: list[Case]) -> dict | None:
    """The [convergence] table of a case file, validated; None when the file has none."""
    raw = _read(Path(path or DEFAULT_CASES), "--cases").get("convergence")
    return parse_convergence(raw, cases) if raw else None

def parse_convergence(raw: dict, cases: list[Case]) -> dict:
    by_name = {c.name: c for c in cases}
    if raw.get("case") not in by_name:
        raise ParameterError(f"convergence.case = {raw.get('case')!r}: must name a case of the file")
    sweep = raw.get("sweep", {})
    for engine, spec in sweep.items():
        if not isinstance(spec, dict) or "setting" not in spec or not spec.get("values"):
            raise ParameterError(f"convergence.sweep.{engine}: needs setting = NAME and values = [..]")
    return {"case": by_name[raw["case"]], "cycles": int(raw.get("cycles", 1)),
            "reference": dict(raw.get("reference", {"rtol": 1e-10})), "sweep": sweep}


def load_cases(path: str | Path | None = None, base_params: Params | None = None) -> list[Case]:
    data = _read(Path(path or DEFAULT_CASES), "--cases")
    unknown = set(data) - {"defaults", "case", "convergence"}
    if unknown:
        raise ParameterError(f"--cases: unknown table {sorted(unknown)[0]!r}; allowed: defaults, case, convergence")
    defaults = data.get("defaults", {})
    raw_cases = data.get("case", [])
    if not raw_cases:
        raise ParameterError("--cases: no [[case]] entries")
    out, names = [], set()
    for i, raw in enumerate(raw_cases):
        merged = {**{k: v for k, v in defaults.items() if k not in ("params", "settings")}, **raw}
        bad = set(merged) - CASE_KEYS
        if bad:
            raise ParameterError(f"case[{i}].{sorted(bad)[0]}: unknown key; allowed: {', '.join(sorted(CASE_KEYS))}")
        name = str(merged.get("name", f"case{i}"))
        if name in names:
            raise ParameterError(f"case[{i}].name = {name!r}: duplicate case name")
        names.add(name)
        for key in ("amplitude", "frequency"):
            if key not in merged:
                raise ParameterError(f"case {name}: missing {key}")
        overrides = {**defaults.get("params", {}), **raw.get("params", {})}
        base = base_params.to_dict() if base_params else {}
        params = load_params(None, {**base, **overrides})
        drive = Drive(_number(f"case {name}.amplitude", merged["amplitude"], positive=False),
                      _number(f"case {name}.frequency", merged["frequency"]),
                      float(merged.get("direction_deg", 0.0)), int(merged.get("cycles", 2)),
                      int(merged.get("samples_per_cycle", 2000)))
        settings = {e: dict(s) for e, s in defaults.get("settings", {}).items()}
        for e, s in raw.get("settings", {}).items():
            settings[e] = {**settings.get(e, {}), **s}
        engine_params = {e: params.replace(**p) for e, p in raw.get("engine_params", {}).items()}
        out.append(Case(name, drive, params, settings, engine_params))
    return out


class Tolerances(dict):
    """Default limits (metric -> value; a plain dict, as before) plus overrides per engine and per
    engine and case: ``limit(engine, case, metric)`` takes the most specific one."""

    def __init__(self, defaults: dict[str, float], engines: dict[str, dict] | None = None):
        super().__init__(defaults)
        self.engines = engines or {}

    def limit(self, engine: str, case: str, metric: str) -> float | None:
        e = self.engines.get(engine, {})
        return e.get("case", {}).get(case, {}).get(metric, e.get(metric, self.get(metric)))


def _metric_limits(where: str, table: dict) -> dict[str, float]:
    for k, v in table.items():
        if k not in METRICS:
            raise ParameterError(f"{where}{k}: unknown metric; allowed: {', '.join(METRICS)}")
        _number(f"{where}{k}", v)
    return {k: float(v) for k, v in table.items()}


def load_tolerances(path: str | Path | None = None) -> Tolerances:
    """[limits] metric = value, optionally [limits.ENGINE] metric = value and
    [limits.ENGINE.case.CASE] metric = value (more specific wins); a flat file of metrics still works."""
    from comparisons.engines import ENGINES
    data = _read(Path(path or DEFAULT_TOLERANCES), "--tolerances")
    limits = data.get("limits", data)
    defaults = _metric_limits("tolerance ", {k: v for k, v in limits.items() if not isinstance(v, dict)})
    engines = {}
    for name, table in ((k, v) for k, v in limits.items() if isinstance(v, dict)):
        if name not in ENGINES:
            raise ParameterError(f"tolerance {name}: neither a metric nor an engine; allowed metrics: "
                                 f"{', '.join(METRICS)}; engines: {', '.join(ENGINES)}")
        own = _metric_limits(f"tolerance {name}.", {k: v for k, v in table.items() if k != "case"})
        cases = table.get("case", {})
        if not isinstance(cases, dict):
            raise ParameterError(f"tolerance {name}.case = {cases!r}: must be a table of cases")
        own["case"] = {c: _metric_limits(f"tolerance {name}.case.{c}.", t) for c, t in cases.items()}
        engines[name] = own
    return Tolerances(defaults, engines)
