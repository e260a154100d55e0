"""``--limit-states``: the thresholds of the limit states an IDA reports apart
(nsd_core.study.limit_states), checked before anything runs (one line, exit 2)."""
from __future__ import annotations

import math

from nsd_core.device.params import ParameterError

# name: (lowest, highest, unit, what): generous bounds that keep every threshold a finite positive
# number a run can reach (impact 0 means any engagement of the restrainer)
BOUNDS = {
    "capacity": (1e-6, 10.0, "m", "isolator displacement capacity"),
    "drift": (1e-6, 1.0, "-", "story drift ratio"),
    "floor_acceleration": (1e-3, 1e3, "m/s^2", "peak floor acceleration"),
    "impact": (0.0, 1e9, "N", "restrainer force"),
}


def default_capacity(params, structure) -> tuple[float, str]:
    """(capacity [m], where it comes from): a structure's own displacement capacity when it states
    one (a designed isolation level), else the device's working range X_max (the largest
    displacement at which it works as designed), else the rod's length."""
    own = getattr(structure, "displacement_capacity", None)
    if own:
        return float(own), "the structure's displacement capacity"
    from nsd_core.structure.restoring_force import NoDefaultError, working_range
    try:
        return working_range(params), "the device's working range X_max"
    except NoDefaultError:
        return params.rod_length, "the rod's length (the device has no working range)"


def parse_limit_states(text: str | None, params, structure, option: str = "--limit-states", limit=None):
    """'capacity=0.02,drift=0.01' -> LimitStates (the defaults for what is not given; a drift or impact
    ``limit`` that ends the traces gives its state's threshold unless the text does)."""
    from nsd_core.study.limit_states import limit_states_for
    given: dict[str, float] = {}
    allowed = ", ".join(f"{n}=VALUE ({lo:g}..{hi:g} {u}, {what})" for n, (lo, hi, u, what) in BOUNDS.items())
    for item in (text or "").split(","):
        if not item.strip():
            continue
        name, sep, value = item.partition("=")
        name = name.strip()
        if name not in BOUNDS or not sep:
            raise ParameterError(f"{option} {text!r}: {item.strip()!r} is not NAME=VALUE of a limit state; "
                                 f"allowed: {allowed}")
        lo, hi, unit, what = BOUNDS[name]
        try:
            v = float(value)
        except ValueError:
            v = math.nan
        if not (math.isfinite(v) and lo <= v <= hi):
            raise ParameterError(f"{option} {name} = {value.strip()!r}: allowed: a number in [{lo:g}, {hi:g}] {unit} "
                                 f"({what})")
        given[name] = v
    if "drift" in given and structure.building is None:
        raise ParameterError(f"{option} drift = {given['drift']:g}: drift needs a building on the slab "
                             "(--building stories=N)")
    if "impact" in given and structure.restrainer is None:
        raise ParameterError(f"{option} impact = {given['impact']:g}: an impact needs the restrainer (--restrainer)")
    if limit is not None and limit.kind in ("drift", "impact"):
        given.setdefault(limit.kind, limit.value)
    capacity = given.get("capacity")
    if capacity is None:
        capacity, _ = default_capacity(params, structure)
    return limit_states_for(structure, params, capacity, floor_acceleration=given.get("floor_acceleration"),
                            drift=given.get("drift"), impact_force=given.get("impact"))
