"""Every input a user can set, listed with value, unit, bounds and provenance (``nsd params``).

The device's parameters come from ``Params`` (unit, provenance and description in each field's
metadata); their bounds are the rules ``params.validate`` enforces, stated per field here
(``tests/test_params_listing.py`` probes every stated bound against ``validate``: inside passes,
outside fails). The isolated structure's fields come from ``isolation.Structure``.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Any

from nsd_core.device.params import _POSITIVE, FIELDS, MAGNITUDE_MAX, MAGNITUDE_MIN, Params

# the rules of params.validate that are not "> 0" or the magnitude bound of the unit
_SPECIAL = {
    "n_ropes": (3, False, 64, False, "fewer than 3 ropes cannot hold the cap centred"),
    "n_wires": (0, False, 64, False, ""),
    "wire_inclination_deg": (0.0, False, 45.0, True, ""),
    "wire_eps_t": (0.0, True, 1.0, True, "a strain"),
}


def bounds(name: str, p: Params | None = None) -> dict[str, Any]:
    """Allowed range of one parameter as ``{"min", "min_open", "max", "max_open", "note"}`` (None: no
    bound on that side). Bounds that depend on other parameters are evaluated for ``p``."""
    p = p or Params()
    unit = FIELDS[name].metadata["unit"]
    top = MAGNITUDE_MAX.get(unit)
    lo, lo_open, hi, hi_open, note = (-top, False, top, False, "")
    if name in _POSITIVE:
        lo, lo_open = (MAGNITUDE_MIN[unit], False) if unit in MAGNITUDE_MIN else (0.0, True)
    if name in _SPECIAL:
        lo, lo_open, hi, hi_open, note = _SPECIAL[name]
        if name in _POSITIVE and lo == 0.0 and lo_open and unit in MAGNITUDE_MIN:   # the validated smallest value
            lo, lo_open = MAGNITUDE_MIN[unit], False
    if name == "wire_upper_height":
        lo, lo_open, note = -p.rod_length, True, "rod_length + wire_upper_height > 0 (the wire span)"
    elif name == "precompression_force":
        w = p.carried_weight
        lo, lo_open, note = w, True, f"more than the carried weight (m_c + m_d + m_l) g = {w:.6g} N: ropes taut at rest"
    elif name == "spring_gamma":
        lo, lo_open, note = -p.spring_beta, True, "spring_beta + spring_gamma > 0 (a bounded hysteretic force)"
    return {"min": lo, "min_open": lo_open, "max": hi, "max_open": hi_open, "note": note}


def bounds_text(b: dict[str, Any]) -> str:
    """An interval in the usual notation, e.g. ``(0, 10]``, plus the note."""
    def num(v):  # short where that is exact, else every digit
        return str(v) if not isinstance(v, float) else f"{v:g}" if float(f"{v:g}") == v else repr(v)
    text = f"{'(' if b['min_open'] else '['}{num(b['min'])}, {num(b['max'])}{')' if b['max_open'] else ']'}"
    return f"{text}; {b['note']}" if b["note"] else text


def param_rows(p: Params | None = None) -> list[dict[str, Any]]:
    """One row per parameter: name, value, unit, bounds (text), provenance, description."""
    p = p or Params()
    return [{"name": r["name"], "value": r["value"], "unit": r["unit"], "bounds": bounds_text(bounds(r["name"], p)),
             "provenance": r["source"], "doc": r["doc"]} for r in p.describe()]


STRUCTURE_UNITS = {"mass": "kg", "radius_of_gyration": "m", "stiffness": "N/m", "damping": "N s/m",
                   "support_radius": "m", "restrainer": "-", "restrainer_gap": "m",
                   "restrainer_stiffness": "N/m^n", "restrainer_exponent": "-", "restrainer_damping": "s/m"}
STRUCTURE_DOCS = {"mass": "M, the isolated mass on the plate", "radius_of_gyration": "r_g, polar inertia M r_g^2",
                  "stiffness": "k_b, the supports' horizontal stiffness (each direction)",
                  "damping": "c_b, the supports' viscous damping", "support_radius": "r_b, torsional pair k_b r_b^2, c_b r_b^2",
                  "restrainer": "the displacement restrainer on (nsd seismic --restrainer; off by default)",
                  "restrainer_gap": "u_gap, |u| at which the restrainer engages (Hunt-Crossley contact)",
                  "restrainer_stiffness": "k, contact stiffness of F = k delta^n (1 + alpha delta')",
                  "restrainer_exponent": "n, contact exponent", "restrainer_damping": "alpha, Hunt-Crossley damping"}
# the ranges nsd_core.structure.restrainer.Restrainer enforces (the gap also below the rod's length)
_RESTRAINER_BOUNDS = {"restrainer_gap": "(0, rod_length)", "restrainer_stiffness": "(0, inf)",
                      "restrainer_exponent": "[1, inf)", "restrainer_damping": "[0, inf)"}


def structure_fields() -> list[str]:
    """The isolated structure's own fields (``--structure NAME=VALUE``, a case's ``structure``); the building
    has its own table (``--building``, docs/building.md), the baseline isolator is chosen by ``--isolator``
    and sized by the design basis (docs/design.md), neither a number ``--structure`` sets."""
    from nsd_core.structure.isolation import Structure
    return [f.name for f in dataclasses.fields(Structure)
            if f.name not in ("provenance", "restrainer", "building", "isolator")]


def restrainer_fields() -> list[str]:
    """The restrainer's switch and its constants (``--restrainer``, ``--structure restrainer_*=VALUE``)."""
    from nsd_core.structure.restrainer import KEYS
    return ["restrainer", *KEYS]


def _structure_bounds(name: str) -> str:
    """The range ``isolation.Structure`` enforces for one field (its bounds where it has them; docs/limits.md)."""
    from nsd_core.structure.isolation import STRUCTURE_BOUNDS, SUPPORT_FREQUENCY_MAX
    if name == "restrainer":
        return "true or false"
    if name in _RESTRAINER_BOUNDS:
        return _RESTRAINER_BOUNDS[name]
    if name not in STRUCTURE_BOUNDS:
        return "[0, inf)" if name == "damping" else "(0, inf)"
    lo, hi, _ = STRUCTURE_BOUNDS[name]
    extra = f"; sqrt(stiffness/mass)/2pi <= {SUPPORT_FREQUENCY_MAX:g} Hz" if name in ("mass", "stiffness") else ""
    return f"[{lo:g}, {hi:g}]{extra}"


def structure_rows(structure=None, params: Params | None = None) -> list[dict[str, Any]]:
    """One row per field of the isolated structure (default: the nominal device's), then the
    restrainer's switch and constants (their values: the default restrainer's, used when it is on)."""
    from nsd_core.structure.isolation import default_structure
    from nsd_core.structure.restrainer import default_restrainer
    params = params or Params()
    st = structure or default_structure(params)
    rest = st.restrainer or default_restrainer(params, st)
    rows = []
    for name in [*structure_fields(), *restrainer_fields()]:
        if name == "restrainer":
            value, prov = st.restrainer is not None, "assumed: off by default (the paper's device has none)"
        elif name.startswith("restrainer_"):
            key = name[len("restrainer_"):]
            value, prov = getattr(rest, key), rest.provenance.get(key, "")
        else:
            value, prov = getattr(st, name), st.provenance.get(name, "")
        rows.append({"name": name, "value": value, "unit": STRUCTURE_UNITS.get(name, "?"),
                     "bounds": _structure_bounds(name),
                     "provenance": prov if isinstance(prov, str) else str(prov), "doc": STRUCTURE_DOCS.get(name, "")})
    return rows


def toml_value(v) -> str:
    """A TOML literal that reads back exactly (floats by repr)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float) and math.isfinite(v):
        return repr(v)
    raise ValueError(f"{v!r}: not a finite number")
