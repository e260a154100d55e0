"""The device's parameter set: one typed, immutable object.

Every field carries its SI unit and its provenance (a table of Dai et al. 2024, or "assumed" with
the place in ``docs/model.md`` that argues for it). Angles are stored in degrees, and their field
names end in ``_deg`` so that no reader mistakes them for radians.
"""
from __future__ import annotations

import dataclasses
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

from nsd_core.common.errors import InputError, ParameterError  # noqa: F401 (ParameterError: imported from here by the device's modules)


def _p(default, unit: str, source: str, doc: str, kind=float):
    return field(default=default, metadata={"unit": unit, "source": source, "doc": doc, "kind": kind})


T2 = "Table 2"
MODEL = "assumed: docs/model.md"
WIRE = "assumed: docs/model.md (Table 3 missing)"
SPRING = "assumed: docs/model.md (Table 4 missing)"


@dataclass(frozen=True)
class Params:
    """Device parameters (SI units; angles in degrees). Defaults: Table 2, Section 4.1, docs/model.md."""

    # Geometry and masses (Table 2)
    cap_diameter: float = _p(0.128, "m", T2, "R_c, diameter of the cap")
    cap_mass: float = _p(0.737, "kg", T2, "m_c, mass of the cap")
    rod_length: float = _p(0.030, "m", T2, "l_d, rod length between joint centres")
    rod_mass: float = _p(0.017, "kg", T2, "m_d, mass of the rod")
    wall_diameter: float = _p(0.074, "m", T2, "R_l, diameter of the vertical movable wall")
    wall_mass: float = _p(0.210, "kg", T2, "m_l, mass of the wall")
    base_diameter: float = _p(0.128, "m", T2, "R_b, diameter of the base")
    base_mass: float = _p(1.082, "kg", T2, "m_b, mass of the base")
    spring_length: float = _p(0.062, "m", T2, "l_s, spring length after precompression")
    # Ropes (Table 2, Section 4.1, docs/model.md)
    n_ropes: int = _p(4, "-", T2, "n_r, number of ropes", int)
    rope_upper_radius: float = _p(0.055, "m", T2, "R_r,u, radius of the ropes' upper ends")
    rope_lower_radius: float = _p(0.055, "m", T2, "R_r,l, radius of the ropes' lower ends")
    rope_stiffness: float = _p(5.0e5, "N/m", "Section 4.1", "k_r, axial stiffness of each rope")
    rope_upper_height: float = _p(0.0189, "m", MODEL, "h_ru, rope upper end above the cap reference")
    precompression_force: float = _p(3800.0, "N", "Table 6 (= Table 5 column 0.03 m)", "F_press, spring push at rest")
    # Wires (Table 2 and docs/model.md)
    n_wires: int = _p(4, "-", T2, "n_w, number of SMA wires", int)
    wire_diameter: float = _p(0.002, "m", T2, "D_w, wire diameter")
    wire_upper_radius: float = _p(0.0165, "m", T2, "R_w,u, radius of the wires' upper ends")
    wire_first_azimuth_deg: float = _p(0.0, "deg", T2, "delta_0, azimuth of the first wire (and rope)")
    wire_inclination_deg: float = _p(12.8, "deg", T2, "theta, wire inclination from the vertical")
    wire_upper_height: float = _p(0.01 / math.tan(math.radians(12.8)) - 0.030, "m", MODEL,
                                  "h_wu, wire upper end above the cap reference (R_w,l = 0.0265 m at 12.8 deg)")
    # SMA law, Eq. 17 (Table 3 missing)
    wire_E: float = _p(50e9, "Pa", WIRE, "E, austenite Young modulus")
    wire_Y: float = _p(400e6, "Pa", WIRE, "Y, yield stress (the gamma under the power)")
    wire_alpha: float = _p(0.03, "-", WIRE, "alpha_w, post-elastic slope ratio")
    wire_n: float = _p(3.0, "-", WIRE, "eta_w, smoothness of the elastic-postelastic transition")
    wire_fT: float = _p(0.36, "-", WIRE, "f_T, twinning hysteresis / superelasticity")
    wire_a: float = _p(500.0, "-", WIRE, "a, pinching around the origin")
    wire_Em: float = _p(25e9, "Pa", WIRE, "E_m, martensite modulus")
    wire_eps_t: float = _p(0.07, "-", WIRE, "epsilon_t, strain of the martensitic transition")
    wire_c: float = _p(300.0, "-", WIRE, "c, smoothness of the martensitic transition")
    # Bouc-Wen spring, Eq. 18 (Table 4 missing)
    spring_kse: float = _p(3.44e5, "N/m", SPRING, "k_s,e, elastic stiffness")
    spring_ksd: float = _p(2.0e5, "N/m", SPRING, "k_s,d, hysteretic stiffness")
    spring_beta: float = _p(390.0, "1/m", SPRING, "beta_s (units for n_s = 1)")
    spring_gamma: float = _p(255.0, "1/m", SPRING, "gamma_s (units for n_s = 1)")
    spring_n: float = _p(1.0, "-", SPRING, "n_s, Bouc-Wen exponent")
    # Environment and materials
    gravity: float = _p(9.81, "m/s^2", MODEL, "g, along -Z")
    density: float = _p(7850.0, "kg/m^3", MODEL, "steel density for the disc thicknesses")

    def __post_init__(self):
        validate(self)

    # ---- derived quantities (never stored, so they cannot disagree) ----
    @property
    def wire_span(self) -> float:
        """h_w = l_d + h_wu: vertical span of a wire at rest (docs/model.md)."""
        return self.rod_length + self.wire_upper_height

    @property
    def wire_lower_radius(self) -> float:
        """R_w,l = R_w,u + h_w tan(theta) (docs/model.md; 0.0265 m in Table 2 at the nominal theta)."""
        return self.wire_upper_radius + self.wire_span * math.tan(math.radians(self.wire_inclination_deg))

    @property
    def wire_area(self) -> float:
        return math.pi * self.wire_diameter ** 2 / 4.0

    @property
    def rope_span(self) -> float:
        """H_r = l_s + l_d + h_ru: vertical span of a rope at rest (docs/model.md)."""
        return self.spring_length + self.rod_length + self.rope_upper_height

    @property
    def carried_weight(self) -> float:
        """W = (m_c + m_d + m_l) g, the weight the spring carries."""
        return (self.cap_mass + self.rod_mass + self.wall_mass) * self.gravity

    # ---- construction ----
    def replace(self, **changes) -> "Params":
        return with_overrides(self, changes)

    def to_dict(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    def describe(self) -> list[dict[str, Any]]:
        """One row per field: name, value, unit, source, description."""
        defaults = Params.__dataclass_fields__
        return [{"name": f.name, "value": getattr(self, f.name), "unit": f.metadata["unit"],
                 "source": f.metadata["source"] if getattr(self, f.name) == defaults[f.name].default
                 else "override", "doc": f.metadata["doc"]} for f in dataclasses.fields(self)]


FIELDS = {f.name: f for f in dataclasses.fields(Params)}
DERIVED = {"wire_lower_radius": "wire_upper_radius, wire_inclination_deg and wire_upper_height"}


def _coerce(name: str, value: Any):
    if name in DERIVED:
        raise ParameterError(f"{name}: is derived from {DERIVED[name]}; set those instead")
    if name not in FIELDS:
        raise ParameterError(f"{name}: unknown parameter; allowed: {', '.join(sorted(FIELDS))}")
    kind = FIELDS[name].metadata["kind"]
    if isinstance(value, str):
        try:
            value = int(value) if kind is int else float(value)
        except ValueError:
            what = "a whole number" if kind is int else "a number"
            raise ParameterError(f"{name} = {value!r}: not {what}") from None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{name} = {value!r}: must be a number ({FIELDS[name].metadata['unit']})")
    if kind is int:
        if not isinstance(value, int):  # 4.0 in a file is a typo for a count, not a count
            raise ParameterError(f"{name} = {value!r}: must be a whole number (an integer, no decimal point)")
        return value
    return float(value)


def with_overrides(base: Params, overrides: Mapping[str, Any]) -> Params:
    """A new Params with ``overrides`` applied (values may be strings from the command line)."""
    values = base.to_dict()
    for name, value in overrides.items():
        values[name] = _coerce(name, value)
    return Params(**values)


def parse_set(items: list[str], flag: str = "--set") -> dict[str, str]:
    """Parse ``name=value`` strings of ``--set`` (or of another NAME=VALUE flag, named in errors)."""
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ParameterError(f"{flag} {item!r}: expected name=value")
        out[name.strip()] = value.strip()
    return out


def read_toml(path: str | Path, what: str) -> dict:
    """A TOML input file as a dict; every way it can be unreadable is one ParameterError line. Only a
    regular file is read (a FIFO, a device or a folder is bad input, found before opening)."""
    from nsd_core.common.files import printable, read_input_text
    try:
        return tomllib.loads(read_input_text(path, what, 1_000_000, "UTF-8 TOML"))
    except InputError as e:
        raise ParameterError(str(e)) from None
    except tomllib.TOMLDecodeError as e:
        raise ParameterError(f"{what} {printable(path)}: not valid TOML ({e})") from None


def params_from_toml(data: dict, what: str) -> dict[str, Any]:
    """The overrides of a parameter file: flat ``name = value`` or under ``[params]``; a free-form
    ``[provenance]`` table may sit beside them (nsd calibrate writes one), and a ``[building]`` table
    (read by nsd seismic, nsd_cli.seismic_building). Anything else is an error
    rather than silently ignored (a key beside [params] would otherwise not apply)."""
    data = {k: v for k, v in data.items() if k not in ("provenance", "building")}  # [building]: nsd seismic's
    if "params" in data:
        extra = sorted(set(data) - {"params"})
        if extra:
            raise ParameterError(f"{what}: {extra[0]!r} beside [params]; put every parameter under [params] "
                                 "(allowed tables: params, provenance, building)")
        data = data["params"]
        if not isinstance(data, dict):
            raise ParameterError(f"{what}: params = {data!r}: must be a table of name = value")
    for k, v in data.items():
        if isinstance(v, (dict, list)):
            raise ParameterError(f"{what}: {k} = {type(v).__name__}: must be a number (tables allowed: params, "
                                 "provenance)")
    return data


def load_params(path: str | Path | None = None, overrides: Mapping[str, Any] | None = None) -> Params:
    """Defaults, then a TOML file (flat ``name = value`` or under ``[params]``), then overrides."""
    p = Params()
    if path is not None:
        if not str(path).strip():
            raise ParameterError("--params '': name a TOML file")
        p = with_overrides(p, params_from_toml(read_toml(path, "--params"), f"--params {path}"))
    if overrides:
        p = with_overrides(p, overrides)
    return p


_POSITIVE = [n for n, f in FIELDS.items() if f.metadata["kind"] is float
             and n not in ("wire_first_azimuth_deg", "wire_inclination_deg", "wire_upper_height",
                           "spring_gamma")]


# Magnitude bounds per unit: generous (orders of magnitude beyond the device's values) but finite, so
# that an input like rope_stiffness = 1e15 or rod_length = 1e308 is bad input, not a run that
# overflows or never ends (docs/limits.md).
MAGNITUDE_MAX = {"m": 10.0, "kg": 1e4, "N/m": 1e10, "Pa": 1e13, "N": 1e8, "1/m": 1e8, "deg": 360.0,
                 "kg/m^3": 1e5, "m/s^2": 100.0, "-": 1e6}
# and the smallest value of a parameter that must be > 0: orders of magnitude below the device's values,
# but no denormal (rope_stiffness = 1e-320 made the rope's natural length -inf and the run never ended)
MAGNITUDE_MIN = {"m": 1e-6, "kg": 1e-6, "N/m": 1e-3, "Pa": 1e-3, "N": 1e-3, "1/m": 1e-6, "kg/m^3": 1e-3,
                 "m/s^2": 1e-3, "-": 1e-6}


def validate(p: Params) -> None:
    """Reject anything physically impossible or outside the model's validity (one-line errors)."""
    for name in FIELDS:
        v = getattr(p, name)
        if isinstance(v, float) and not math.isfinite(v):
            raise ParameterError(f"{name} = {v}: must be a finite number")
    for name, f in FIELDS.items():
        top = MAGNITUDE_MAX.get(f.metadata["unit"])
        v = getattr(p, name)
        if top is not None and abs(v) > top:
            raise ParameterError(f"{name} = {v}: must be within +-{top:g} {f.metadata['unit']} "
                                 "(far outside any device this model describes)")
    for name in _POSITIVE:
        v = getattr(p, name)
        if not v > 0:
            raise ParameterError(f"{name} = {v}: must be > 0 ({FIELDS[name].metadata['unit']})")
        low = MAGNITUDE_MIN.get(FIELDS[name].metadata["unit"], 0.0)
        if v < low:
            raise ParameterError(f"{name} = {v}: must be >= {low:g} {FIELDS[name].metadata['unit']} (far below any "
                                 "device this model describes)")
    if p.n_ropes < 3:
        raise ParameterError(f"n_ropes = {p.n_ropes}: must be >= 3 (fewer ropes cannot hold the cap centred)")
    if p.n_ropes > 64:
        raise ParameterError(f"n_ropes = {p.n_ropes}: must be <= 64")
    if not 0 <= p.n_wires <= 64:
        raise ParameterError(f"n_wires = {p.n_wires}: must be in [0, 64]")
    if not 0.0 <= p.wire_inclination_deg < 45.0:
        raise ParameterError(f"wire_inclination_deg = {p.wire_inclination_deg}: must be in [0, 45)")
    if p.wire_span <= 0:
        raise ParameterError(f"wire_upper_height = {p.wire_upper_height}: makes the wire span "
                             f"l_d + h_wu = {p.wire_span:.4g} m, must be > 0")
    if p.rope_upper_height <= -p.rod_length:
        raise ParameterError(f"rope_upper_height = {p.rope_upper_height}: must be > -rod_length")
    if p.precompression_force <= p.carried_weight:
        raise ParameterError(f"precompression_force = {p.precompression_force}: must exceed the carried "
                             f"weight {p.carried_weight:.4g} N or the ropes are slack at rest")
    if p.spring_beta + p.spring_gamma <= 0:
        raise ParameterError("spring_beta + spring_gamma: must be > 0 (bounded hysteretic force)")
    if p.wire_eps_t >= 1:
        raise ParameterError(f"wire_eps_t = {p.wire_eps_t}: must be < 1 (a strain)")


def param_table_markdown(p: Params) -> str:
    rows = ["| name | value | unit | source |", "|---|---|---|---|"]
    rows += [f"| {r['name']} | {r['value']:.6g} | {r['unit']} | {r['source']} |" for r in p.describe()]
    return "\n".join(rows)
