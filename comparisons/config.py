"""Case and tolerance files (TOML), validated into plain data with one-line errors."""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from nsd_core.device.drive import SAMPLES_PER_CYCLE, Drive
from nsd_core.device.params import ParameterError, Params, load_params, read_toml

HERE = Path(__file__).resolve().parent
DEFAULT_CASES = HERE / "cases.toml"
DEFAULT_TOLERANCES = HERE / "tolerances.toml"
# nsd compare --profile: (case file, tolerance file)
# default and strict: the estimated rule (comparisons/verdict.py) on the default and on finer peer steps;
# regression: the fixed limits derived on the nominal device (comparisons/limits_regression*.toml)
PROFILES = {"default": (DEFAULT_CASES, DEFAULT_TOLERANCES),
            "strict": (HERE / "cases_strict.toml", DEFAULT_TOLERANCES),
            "regression": (DEFAULT_CASES, HERE / "limits_regression.toml"),
            "regression-strict": (HERE / "cases_strict.toml", HERE / "limits_regression_strict.toml")}

METRICS = {  # name -> (unit, description)
    "max_dF_rel": ("-", "max |F - F_ref| / max |F_ref|, F the force vector (F_x, F_y)"),
    "rms_dF_rel": ("-", "RMS |F - F_ref| / max |F_ref|, F the force vector"),
    "loop_area_rel": ("-", "|loop work - reference| / |reference|, work = closed integral of F . dp"),
    "peak_force_rel": ("-", "|peak |F| - reference| / reference"),
    "region_shift_rel": ("-", "largest stiffness-region boundary shift / amplitude (lines only)"),
    "closure_max": ("m", "largest loop-closure violation"),
    "tracking_error": ("m", "largest drive tracking error"),
    "energy_balance_rel": ("-", "|drive work - (wires + spring hysteresis + stored change)| / drive work, steady cycle"),
    # seismic cases (mode = "seismic"): on the time histories, every output time
    "max_du_rel": ("-", "seismic: max |u - u_ref| / max |u_ref|, u the plate's plan displacement relative to the base"),
    "max_dF_device_rel": ("-", "seismic: max |F - F_ref| / max |F_ref|, F = device_F, the plate's force on the "
                               "device (minus the device's force on the plate)"),
    "peak_u_rel": ("-", "seismic: |peak |u| - reference| / reference"),
    "peak_a_rel": ("-", "seismic: |peak |a_abs| - reference| / reference, a_abs the plate's absolute acceleration"),
    "energy_residual_rel": ("-", "seismic: the engine's own max |E_residual| / max |E_input| (frame of the ground)"),
    # seismic cases with a building (docs/building.md): the worst floor or story of each
    "max_dfloor_rel": ("-", "building: max over floors of max |d_i - d_i,ref| / max |d_i,ref| (plan vectors, relative to the ground)"),
    "max_ddrift_rel": ("-", "building: max over stories of max |drift_i - ref| / max |drift_i,ref| (plan vectors)"),
    "max_dfloor_a_rel": ("-", "building: max over floors of max |a_abs,i - ref| / max |a_abs,i,ref| (plan vectors)"),
    "order_deviation": ("-", "largest |observed order - expected| over the step halved twice ([order] of the case file)"),
}
CASE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._+-]{0,63}")
MAX_CASES = 200
DEFAULT_KEYS = {"amplitude", "frequency", "direction_deg", "cycles", "samples_per_cycle", "params", "settings",
                "path", "minor"}
CASE_KEYS = {"name", "amplitude", "frequency", "direction_deg", "cycles", "samples_per_cycle", "params",
             "settings", "engine_params", "path", "minor"}


SEISMIC_KEYS = {"name", "mode", "record", "ground", "scale", "window", "rotate_deg", "duration", "dt_out",
                "device", "params", "settings", "engine_params", "structure", "building"}
SEISMIC_DURATION_MAX = 60.0   # model seconds: bounds one case's work
SEISMIC_OUTPUTS_MAX = 1_000_000


@dataclass(frozen=True)
class SeismicCase:
    """A seismic case (Table 1, second row): the ground drives the base, the plate with the isolated
    mass is free. ``ground`` is the GroundMotion; ``spec`` what the case file said (for job_key)."""
    name: str
    ground: Any
    spec: dict
    params: Params
    duration: float | None = None
    dt_out: float = 1e-3
    device: bool = True
    structure: dict = field(default_factory=dict)                 # overrides of the default structure
    settings: dict[str, dict] = field(default_factory=dict)
    engine_params: dict[str, Params] = field(default_factory=dict)
    building: dict | None = None                                  # [building] table (docs/building.md)
    refined: tuple = ()                                           # engines at a step --refine chose
    mode = "seismic"

    def params_for(self, engine: str) -> Params:
        return self.engine_params.get(engine, self.params)

    @property
    def model_duration(self) -> float:
        return self.ground.duration if self.duration is None else self.duration

    def isolated_structure(self):
        """The default structure of the case's (nominal) parameters with the case's overrides: the
        same structure for every engine (engine_params change the device, not the structure)."""
        from nsd_core.structure.isolation import structure_with
        from nsd_core.structure.restrainer import split_overrides, with_restrainer
        own, restrainer = split_overrides({k: v for k, v in self.structure.items() if k != "restrainer"})
        st = structure_with(self.params, own)   # (a device without a default: the case's mass and stiffness)
        st = with_restrainer(st, self.params, self.structure.get("restrainer") is True, restrainer)
        if self.building is not None:
            from nsd_core.structure.building import building_from
            st = st.with_building(building_from(st.mass, self.building))
        return st

    def describe(self) -> dict[str, Any]:
        return {"name": self.name, "mode": "seismic", **self.spec, "duration": self.model_duration,
                "dt_out": self.dt_out, "device": self.device, "structure": self.structure, "building": self.building,
                "params_overridden": {k: v for k, v in self.params.to_dict().items() if v != getattr(Params(), k)},
                "settings": self.settings,
                "engine_params": {e: {k: v for k, v in p.to_dict().items() if v != getattr(self.params, k)}
                                  for e, p in self.engine_params.items()}}


@dataclass(frozen=True)
class Case:
    name: str
    drive: Drive
    params: Params
    settings: dict[str, dict] = field(default_factory=dict)       # engine -> solver settings
    engine_params: dict[str, Params] = field(default_factory=dict)  # engine -> its own parameter set
    refined: tuple = ()                                             # engines at a step --refine chose

    def params_for(self, engine: str) -> Params:
        return self.engine_params.get(engine, self.params)

    def describe(self) -> dict[str, Any]:
        d = self.drive
        return {"name": self.name, "amplitude": d.amplitude, "frequency": d.frequency,
                "direction_deg": d.direction_deg, "cycles": d.cycles, "samples_per_cycle": d.samples_per_cycle,
                "path": d.path, **({"minor": d.minor_axis} if d.path in ("ellipse", "figure8") else {}),
                "params_overridden": {k: v for k, v in self.params.to_dict().items() if v != getattr(Params(), k)},
                "settings": self.settings,
                "engine_params": {e: {k: v for k, v in p.to_dict().items() if v != getattr(self.params, k)}
                                  for e, p in self.engine_params.items()}}


def _read(path: Path, what: str) -> dict:
    if not str(path).strip():
        raise ParameterError(f"{what} '': name a TOML file")
    return read_toml(path, what)


def _number(where: str, v, positive=True) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or (positive and v <= 0):
        raise ParameterError(f"{where} = {v!r}: must be a {'positive ' if positive else ''}finite number")
    return float(v)


def _whole(where: str, v, low: int, high: int) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or not low <= v <= high:
        raise ParameterError(f"{where} = {v!r}: must be a whole number in [{low}, {high}] (no decimal point)")
    return v


def _table(where: str, v) -> dict:
    if not isinstance(v, dict):
        raise ParameterError(f"{where} = {v!r}: must be a table")
    return v


def _engine_tables(where: str, v) -> dict[str, dict]:
    """settings / engine_params: a table per engine of the registry (an unknown engine is an error)."""
    from comparisons.engines import ENGINES
    for e, t in _table(where, v).items():
        if e not in ENGINES:
            raise ParameterError(f"{where}.{e}: unknown engine; allowed: {', '.join(ENGINES)}")
        _table(f"{where}.{e}", t)
    return v


def _case_name(where: str, v) -> str:
    """A case name becomes a file name (cycles/NAME__ENGINE.csv): a plain name, never a path."""
    if not isinstance(v, str) or not CASE_NAME.fullmatch(v) or v in (".", ".."):
        raise ParameterError(f"{where} = {v!r}: must be a plain file name of 1-64 letters, digits, '.', '_', "
                             "'+' or '-' (starting with a letter or digit)")
    return v


def load_convergence(path: str | Path | None, cases: list[Case]) -> dict | None:
    """The [convergence] table of a case file, validated; None when the file has none."""
    raw = _read(Path(path or DEFAULT_CASES), "--cases").get("convergence")
    return parse_convergence(raw, cases) if raw is not None else None


ORDER_KEYS = ("case", "setting", "expected")


def load_order(path: str | Path | None, cases: list) -> dict | None:
    """The [order] table of a case file (per peer: the drive case whose step is halved twice in the
    gate, the step setting and the expected order; the band is the limit order_deviation of the
    tolerance file), validated; None when there is none."""
    from comparisons.engines import ENGINES, REFERENCE
    raw = _read(Path(path or DEFAULT_CASES), "--cases").get("order")
    if raw is None:
        return None
    drive = {c.name: c for c in cases if isinstance(c, Case)}
    out = {}
    for engine, spec in _table("order", raw).items():
        where = f"order.{engine}"
        if engine not in ENGINES or engine == REFERENCE:
            raise ParameterError(f"{where}: must be a peer engine; allowed: "
                                 f"{', '.join(e for e in ENGINES if e != REFERENCE)}")
        for k in _table(where, spec):
            if k not in ORDER_KEYS:
                raise ParameterError(f"{where}.{k}: unknown key; allowed: {', '.join(ORDER_KEYS)}")
        if spec.get("case") not in drive:
            raise ParameterError(f"{where}.case = {spec.get('case')!r}: must name a drive case of the file "
                                 f"({', '.join(drive)})")
        setting = spec.get("setting")
        from comparisons.engines import get_engine
        if not isinstance(setting, str) or setting not in get_engine(engine).default_settings:
            raise ParameterError(f"{where}.setting = {setting!r}: must name {engine}'s step setting")
        out[engine] = {"case": spec["case"], "setting": setting,
                       "expected": _number(f"{where}.expected", spec.get("expected"))}
    return out


CONVERGENCE_KEYS = ("case", "cycles", "reference", "sweep")
SWEEP_KEYS = ("setting", "values", "settings")


def parse_convergence(raw, cases: list[Case]) -> dict:
    """Types and names here; each engine checks its settings (nsd_cli.compare, before any run)."""
    from comparisons.engines import ENGINES
    raw = _table("convergence", raw)
    for k in raw:
        if k not in CONVERGENCE_KEYS:
            raise ParameterError(f"convergence.{k}: unknown key; allowed: {', '.join(CONVERGENCE_KEYS)}")
    by_name = {c.name: c for c in cases}
    if raw.get("case") not in by_name:
        raise ParameterError(f"convergence.case = {raw.get('case')!r}: must name a case of the file "
                             f"({', '.join(by_name)})")
    cycles = _whole("convergence.cycles", raw.get("cycles", 1), 1, 100)
    reference = _table("convergence.reference", raw.get("reference", {"rtol": 1e-10}))
    sweep = _table("convergence.sweep", raw.get("sweep", {}))
    if not sweep:
        raise ParameterError("convergence.sweep: empty; give at least one engine = { setting, values }")
    for engine, spec in sweep.items():
        where = f"convergence.sweep.{engine}"
        if engine not in ENGINES:
            raise ParameterError(f"{where}: unknown engine; allowed: {', '.join(ENGINES)}")
        for k in _table(where, spec):
            if k not in SWEEP_KEYS:
                raise ParameterError(f"{where}.{k}: unknown key; allowed: {', '.join(SWEEP_KEYS)}")
        if not isinstance(spec.get("setting"), str):
            raise ParameterError(f"{where}.setting = {spec.get('setting')!r}: must name a solver setting")
        values = spec.get("values")
        if not isinstance(values, list) or not 1 <= len(values) <= 20:
            raise ParameterError(f"{where}.values = {values!r}: must be a list of 1 to 20 numbers")
        for j, v in enumerate(values):
            _number(f"{where}.values[{j}]", v)
        _table(f"{where}.settings", spec.get("settings", {}))
    return {"case": by_name[raw["case"]], "cycles": cycles, "reference": dict(reference), "sweep": sweep}


def _path(name: str, value, case_file) -> str:
    """A case's path: a named path, or a CSV file relative to the case file's folder."""
    from nsd_core.device.drive import PATHS
    if not isinstance(value, str) or not value:
        raise ParameterError(f"case {name}.path = {value!r}: allowed: {', '.join(PATHS)} or a CSV file of t,x,y")
    if value in PATHS:
        return value
    return str((Path(case_file or DEFAULT_CASES).resolve().parent / value))


def load_cases(path: str | Path | None = None, base_params: Params | None = None) -> list[Case]:
    data = _read(Path(path or DEFAULT_CASES), "--cases")
    unknown = set(data) - {"defaults", "case", "convergence", "order"}
    if unknown:
        raise ParameterError(f"--cases: unknown table {sorted(unknown)[0]!r}; allowed: defaults, case, convergence, order")
    defaults = _table("defaults", data.get("defaults", {}))
    for k in defaults:
        if k not in DEFAULT_KEYS:
            raise ParameterError(f"defaults.{k}: unknown key; allowed: {', '.join(sorted(DEFAULT_KEYS))}")
    raw_cases = data.get("case", [])
    if not isinstance(raw_cases, list):
        raise ParameterError("case: must be an array of tables ([[case]] entries), not a single [case] table")
    if not raw_cases:
        raise ParameterError("--cases: no [[case]] entries")
    if len(raw_cases) > MAX_CASES:
        raise ParameterError(f"--cases: {len(raw_cases)} cases; at most {MAX_CASES}")
    d_params = _table("defaults.params", defaults.get("params", {}))
    d_settings = _engine_tables("defaults.settings", defaults.get("settings", {}))
    out, names = [], set()
    for i, raw in enumerate(raw_cases):
        raw = _table(f"case[{i}]", raw)
        if raw.get("mode", "drive") != "drive":
            if raw.get("mode") != "seismic":
                raise ParameterError(f"case[{i}].mode = {raw.get('mode')!r}: allowed: drive, seismic")
            case = _seismic_case(i, raw, d_params, base_params)
            if case.name in names:
                raise ParameterError(f"case[{i}].name = {case.name!r}: duplicate case name")
            names.add(case.name)
            out.append(case)
            continue
        raw = {k: v for k, v in raw.items() if k != "mode"}
        merged = {**{k: v for k, v in defaults.items() if k not in ("params", "settings")}, **raw}
        bad = set(merged) - CASE_KEYS
        if bad:
            raise ParameterError(f"case[{i}].{sorted(bad)[0]}: unknown key; allowed: {', '.join(sorted(CASE_KEYS))}")
        name = _case_name(f"case[{i}].name", merged.get("name", f"case{i}"))
        if name in names:
            raise ParameterError(f"case[{i}].name = {name!r}: duplicate case name")
        names.add(name)
        for key in ("amplitude", "frequency"):
            if key not in merged:
                raise ParameterError(f"case {name}: missing {key}")
        overrides = {**d_params, **_table(f"case {name}.params", raw.get("params", {}))}
        base = base_params.to_dict() if base_params else {}
        params = load_params(None, {**base, **overrides})
        drive = Drive(_number(f"case {name}.amplitude", merged["amplitude"], positive=False),
                      _number(f"case {name}.frequency", merged["frequency"]),
                      _number(f"case {name}.direction_deg", merged.get("direction_deg", 0.0), positive=False),
                      _whole(f"case {name}.cycles", merged.get("cycles", 2), 1, Drive.CYCLES_MAX),
                      _whole(f"case {name}.samples_per_cycle", merged.get("samples_per_cycle", SAMPLES_PER_CYCLE), 16,
                             Drive.SAMPLES_MAX),
                      path=_path(name, merged.get("path", "line"), path),
                      minor=None if merged.get("minor") is None else _number(f"case {name}.minor", merged["minor"]))
        settings = {e: dict(s) for e, s in d_settings.items()}
        for e, s in _engine_tables(f"case {name}.settings", raw.get("settings", {})).items():
            settings[e] = {**settings.get(e, {}), **s}
        engine_params = {e: params.replace(**p) for e, p in
                         _engine_tables(f"case {name}.engine_params", raw.get("engine_params", {})).items()}
        out.append(Case(name, drive, params, settings, engine_params))
    return out


def _seismic_case(i: int, raw: dict, d_params: dict, base_params: Params | None) -> SeismicCase:
    """A [[case]] with mode = "seismic": every key typed and in range here (one line, exit 2). Of
    [defaults] only params apply ([defaults] drive keys and drive settings do not)."""
    bad = set(raw) - SEISMIC_KEYS
    if bad:
        raise ParameterError(f"case[{i}].{sorted(bad)[0]}: unknown key for a seismic case; allowed: "
                             f"{', '.join(sorted(SEISMIC_KEYS))}")
    name = _case_name(f"case[{i}].name", raw.get("name", f"case{i}"))
    w = f"case {name}"
    motion, spec = _seismic_ground(w, raw)
    duration = None if "duration" not in raw else _number(f"{w}.duration", raw["duration"])
    total = motion.duration if duration is None else duration
    if not total <= SEISMIC_DURATION_MAX:
        raise ParameterError(f"{w}.duration = {total:g} s: at most {SEISMIC_DURATION_MAX:g} model seconds "
                             "(a window of the record: window = [t0, t1])")
    dt_out = _number(f"{w}.dt_out", raw.get("dt_out", 1e-3))
    if not dt_out <= total or total / dt_out > SEISMIC_OUTPUTS_MAX:
        raise ParameterError(f"{w}.dt_out = {dt_out!r}: must be in [duration / {SEISMIC_OUTPUTS_MAX}, duration]")
    device = raw.get("device", True)
    if not isinstance(device, bool):
        raise ParameterError(f"{w}.device = {device!r}: must be true or false")
    structure = _table(f"{w}.structure", raw.get("structure", {}))
    for k, v in structure.items():
        if k == "restrainer":  # the displacement restrainer on (its constants: restrainer_* keys)
            if not isinstance(v, bool):
                raise ParameterError(f"{w}.structure.restrainer = {v!r}: must be true or false")
            continue
        _number(f"{w}.structure.{k}", v, positive=k not in ("damping", "restrainer_damping"))
    overrides = {**d_params, **_table(f"{w}.params", raw.get("params", {}))}
    base = base_params.to_dict() if base_params else {}
    params = load_params(None, {**base, **overrides})
    settings = {e: dict(t) for e, t in _engine_tables(f"{w}.settings", raw.get("settings", {})).items()}
    engine_params = {e: params.replace(**p) for e, p in
                     _engine_tables(f"{w}.engine_params", raw.get("engine_params", {})).items()}
    building = None if "building" not in raw else dict(_table(f"{w}.building", raw["building"]))
    for k, v in (building or {}).items():   # TOML numbers: a string here is a type mistake (the command line's are parsed)
        if any(isinstance(x, str) for x in (v if isinstance(v, list) else [v])):
            raise ParameterError(f"{w}.building.{k} = {v!r}: must be a number or an array of numbers, not a string")
    case = SeismicCase(name, motion, spec, params, duration, dt_out, device, dict(structure), settings, engine_params,
                       building)
    _check_structure(w, case, structure, building)
    return case


def _seismic_ground(w: str, raw: dict) -> tuple[Any, dict]:
    """A seismic case's ground motion and its spec as given: a record of a set (record = "SET:ID", with
    its scale, window and rotation, each in range) or a synthetic motion (ground = "pulse:..."/"harmonic:...")."""
    from comparisons.seismic import parse_ground
    from nsd_core.ground import motions as gm
    from nsd_core.ground.records import fema_record
    if ("record" in raw) == ("ground" in raw):
        raise ParameterError(f"{w}: give exactly one of record = \"SET:ID\" or ground = \"pulse:...\"/\"harmonic:...\"")
    if "ground" in raw:
        for k in ("scale", "window", "rotate_deg"):
            if k in raw:
                raise ParameterError(f"{w}.{k}: applies to record = \"SET:ID\" only")
        return parse_ground(raw["ground"], f"{w}.ground"), {"ground": raw["ground"]}
    rec = raw["record"]
    set_, sep, rid = rec.partition(":") if isinstance(rec, str) else ("", "", "")
    if not sep or not rid.strip():
        raise ParameterError(f"{w}.record = {rec!r}: expected \"SET:ID\", e.g. \"nearfield-pulse:1\"")
    scale = _number(f"{w}.scale", raw.get("scale", 1.0))
    rotate = _number(f"{w}.rotate_deg", raw.get("rotate_deg", 0.0), positive=False)
    for key, value, (lo, hi), unit in (("scale", scale, gm.SCALE_RANGE, ""), ("rotate_deg", rotate, gm.ROTATE_RANGE,
                                                                             " deg")):
        if not lo <= value <= hi:   # nsd seismic --scale / --rotate's bounds (docs/limits.md)
            raise ParameterError(f"{w}.{key} = {value!r}: must be in [{lo:g}, {hi:g}]{unit}")
    window = raw.get("window")
    if window is not None:
        if not isinstance(window, list) or len(window) != 2:
            raise ParameterError(f"{w}.window = {window!r}: must be [t0, t1] in the record's seconds")
        window = [_number(f"{w}.window[{j}]", v, positive=False) for j, v in enumerate(window)]
    try:
        motion = fema_record(set_, rid.strip(), scale=scale, window=window, rotate_deg=rotate)
    except ParameterError as e:
        raise ParameterError(f"{w}: {e}") from None
    return motion, {"record": rec, "scale": scale, "window": window, "rotate_deg": rotate}


def _check_structure(w: str, case: SeismicCase, structure: dict, building: dict | None) -> None:
    """The case's building and structure overrides known and in range: its structure derived here, once."""
    if building is not None:
        try:
            case.isolated_structure()
        except ParameterError as e:
            raise ParameterError(f"{w}: {e}") from None
    if structure:
        from nsd_core.structure.isolation import Structure
        from nsd_core.structure.restrainer import KEYS
        names_ = (Structure.__dataclass_fields__.keys() - {"provenance"}) | set(KEYS)
        for k in structure:
            if k not in names_:
                raise ParameterError(f"{w}.structure.{k}: unknown; allowed: {', '.join(sorted(names_))}")
        try:
            case.isolated_structure()  # every value in range (restrainer_gap < rod_length ...)
        except ParameterError as e:
            raise ParameterError(f"{w}: {e}") from None
