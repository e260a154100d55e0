"""The building fixed-base, isolated on the supports alone and isolated with the device, under the
same ground motion (docs/building.md): the comparison isolation engineers judge a system by.

``run_three`` runs the three configurations on the in-house engine (a run the device's failure ends
is kept over what it computed, as ``with_without.run_one``); ``building_ratios`` the numbers per
story and floor: peak drift ratio (|drift| / h_i), peak floor acceleration, and the base shear.

Base shear: the horizontal force the structure passes to the ground. Fixed base: story 1's shear
(the slab is the ground). Isolated: the isolation level's (supports + device + restrainer). Story 1's
shear (the superstructure's base shear) is reported for every configuration as well.
"""
from __future__ import annotations

import math

from nsd_core.study.with_without import run_one

CONFIGURATIONS = ("fixed_base", "supports", "device")


def run_three(params, structure, ground, duration=None, dt_out=1e-3, solver=None, progress=None) -> dict:
    """{"fixed_base", "supports", "device"}: with_without.run_one's dicts (result, summary, complete,
    stopped), and "ratios" (building_ratios, None if a run has no samples)."""
    if structure.building is None:
        raise ValueError("run_three needs a structure with a building")
    out = {"fixed_base": run_one(params, structure, ground, False, duration, dt_out, {**(solver or {}),
                                                                                      "fixed_base": True}, progress),
           "supports": run_one(params, structure, ground, False, duration, dt_out, solver, progress),
           "device": run_one(params, structure, ground, True, duration, dt_out, solver, progress)}
    have = all(out[c]["summary"] is not None for c in CONFIGURATIONS)
    out["ratios"] = building_ratios({c: out[c]["summary"] for c in CONFIGURATIONS}) if have else None
    out["complete"] = all(out[c]["complete"] for c in CONFIGURATIONS)
    return out


def base_shear(summary: dict, fixed_base: bool) -> float:
    """The run's peak base shear (on a fixed base the run's base shear columns are story 1's shear)."""
    return summary["peak_base_shear"]["value"]


def _ratio(a, b):
    return (a / b) if b != 0 and math.isfinite(b) else None


def building_ratios(summaries: dict) -> list[dict]:
    """Rows: quantity, index (story or floor; 0 for the whole building), the three configurations'
    values, and the ratios supports / fixed_base, device / fixed_base, device / supports."""
    rows = []

    def add(quantity, index, get, what):
        v = {c: float(get(summaries[c], c == "fixed_base")) for c in CONFIGURATIONS}
        rows.append({"quantity": quantity, "index": index, **v,
                     "supports_over_fixed": _ratio(v["supports"], v["fixed_base"]),
                     "device_over_fixed": _ratio(v["device"], v["fixed_base"]),
                     "device_over_supports": _ratio(v["device"], v["supports"]), "what": what})

    n = len(summaries["fixed_base"]["building"]["peak_drift_ratio"])
    for i in range(n):
        add("peak_drift_ratio", i + 1, lambda s, f, i=i: s["building"]["peak_drift_ratio"][i]["value"],
            f"story {i + 1}: peak |drift| / story height [-]")
    for i in range(n):
        add("peak_floor_acceleration", i + 1, lambda s, f, i=i: s["building"]["peak_floor_acceleration"][i]["value"],
            f"floor {i + 1}: peak |a_abs| [m/s^2]")
    add("base_shear", 0, base_shear, "peak |force into the ground| [N] (fixed base: story 1; isolated: "
        "supports + device + restrainer)")
    add("story1_shear", 0, lambda s, f: s["building"]["peak_story_shear"][0]["value"],
        "peak |story 1 shear| (the superstructure's base shear) [N]")
    return rows
