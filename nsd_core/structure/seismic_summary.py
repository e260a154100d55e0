"""The summary of a seismic run (what summary.json holds): peaks with their times, the displacement
left at the end, the energy balance, the working-range and restrainer events, and the response peaks
that fall on the last sample (a warning: the true peak may lie beyond the window)."""
from __future__ import annotations

import numpy as np

from nsd_core.device.results import RunResult


def seismic_summary(result: RunResult) -> dict:
    """Peaks (with their times), the displacement left at the end, the energy balance and the
    working-range events of a seismic run (what summary.json holds)."""
    from nsd_core.device.cycle import events
    c, t = result.columns, result["t"]

    def peak(values):
        k = int(np.argmax(values))
        return {"value": float(values[k]), "t": float(t[k])}

    E_in = c["E_input"]
    out = {
        "peak_displacement": peak(c["u"]),
        "peak_x": peak(np.abs(c["x"])), "peak_y": peak(np.abs(c["y"])),
        "peak_rotation": peak(np.abs(c["theta"])),
        "peak_absolute_acceleration": peak(np.hypot(c["ax_abs"], c["ay_abs"])),
        "peak_base_shear": peak(np.hypot(c["base_shear_x"], c["base_shear_y"])),
        "peak_device_force": peak(np.hypot(c["device_Fx"], c["device_Fy"])),
        "peak_support_force": peak(np.hypot(c["support_Fx"], c["support_Fy"])),
        "peak_ground_acceleration": peak(np.hypot(c["ax_g"], c["ay_g"])),
        "residual_displacement": {"x": float(c["x"][-1]), "y": float(c["y"][-1]), "u": float(c["u"][-1]),
                                  "t": float(t[-1])},
        "energy": {"input": float(E_in[-1]), "kinetic": float(c["E_kinetic"][-1]),
                   "gravity": float(c["E_gravity"][-1]), "supports_stored": float(c["E_supports_stored"][-1]),
                   "supports_dissipated": float(c["E_supports_dissipated"][-1]), "device": float(c["E_device"][-1]),
                   "max_residual": float(np.max(np.abs(c["E_residual"]))),
                   "relative_residual": float(np.max(np.abs(c["E_residual"])) / max(np.max(np.abs(E_in)), 1e-300))},
    }
    if "floor1_x" in c:  # a building on the slab (nsd_core.structure.building)
        from nsd_core.structure.building import building_dict_from, building_summary
        building = building_dict_from((result.stats.get("structure") or {}).get("building"))
        out["energy"]["building_stored"] = float(c["E_building_stored"][-1])
        out["energy"]["building_dissipated"] = float(c["E_building_dissipated"][-1])
        out["building"] = building_summary(building, c)
    if "restrainer_F" in c:
        out["energy"]["restrainer_stored"] = float(c["E_restrainer_stored"][-1])
        out["energy"]["restrainer_dissipated"] = float(c["E_restrainer_dissipated"][-1])
        out["peak_restrainer_force"] = peak(c["restrainer_F"])
        out["peak_restrainer_indentation"] = peak(c["restrainer_indentation"])
    if "spring_push" in c:
        ev = events(result)
        out.update({"events": ev, "outside_working_range": any(e["kind"] == "ropes_slack" for e in ev),
                    "cap_z": {"min": float(np.min(c["cap_z"])), "max": float(np.max(c["cap_z"]))},
                    "closure_max": float(np.max(c["closure"]))})
    else:
        out.update({"events": [], "outside_working_range": False})
    if "restrainer_F" in c:
        from nsd_core.structure.restrainer import engagement_events
        mass = (result.stats.get("structure") or {}).get("mass", float("nan"))
        rate = _radial_rate(c)
        engaged = engagement_events(t, c["u"], c["restrainer_F"], rate, mass,
                                    c["E_restrainer_stored"] + c["E_restrainer_dissipated"], c["E_restrainer_stored"])
        out["events"] = sorted(out["events"] + engaged, key=lambda e: e["start"])
        out["restrainer"] = {"engagements": len(engaged), "engaged_time": float(sum(e["duration"] for e in engaged)),
                             "impact_energy_max": max((e["impact_energy"] for e in engaged), default=0.0),
                             "dissipated": out["energy"]["restrainer_dissipated"]}
    out["peaks_at_last_sample"] = peaks_at_last_sample(out, float(t[-1]))
    return out


def _radial_rate(c) -> np.ndarray:
    """d|u|/dt from the sampled relative motion (0 where u = 0)."""
    u = c["u"]
    return np.where(u > 0, (c["x"] * c["vx"] + c["y"] * c["vy"]) / np.where(u > 0, u, 1.0), 0.0)


PEAK_KEYS = ("peak_displacement", "peak_x", "peak_y", "peak_rotation", "peak_absolute_acceleration",
             "peak_base_shear", "peak_device_force", "peak_support_force", "peak_restrainer_force")


BUILDING_PEAK_KEYS = (("peak_drift_ratio", "story"), ("peak_story_shear", "story"),
                      ("peak_floor_acceleration", "floor"), ("peak_floor_displacement", "floor"))


def peaks_at_last_sample(summary: dict, t_end: float) -> list[str]:
    """The response peaks (not the ground's) that fall on the run's last sample, the building's
    (``building.peak_drift_ratio[story 2]``) included: the true peak may lie beyond the window (a
    warning in summary.json and on stderr)."""
    def at_end(p):
        return p["value"] > 0 and p["t"] >= t_end
    out = [k for k in PEAK_KEYS if k in summary and at_end(summary[k])]
    building = summary.get("building")
    if isinstance(building, dict):
        for key, level in BUILDING_PEAK_KEYS:
            out += [f"building.{key}[{level} {i}]" for i, p in enumerate(building.get(key, []), 1) if at_end(p)]
    return out
