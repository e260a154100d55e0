"""With and without the device, side by side (docs/seismic.md): one ground motion run on the
isolated structure with the device and on the supports alone (the isolation effect's reference),
and the ratios an isolation engineer acts on.

``run_with_and_without`` is the one function the command line (``nsd seismic --compare-supports``)
and the incremental dynamic analysis call. A run the device's failure ends (RodReachError,
DriveError: exit 4) is still a result: its series up to the event is kept (``partial``), and the
ratios are taken over what it computed, flagged ``complete = False``.
"""
from __future__ import annotations

import math

from nsd_core.device.drive import DriveError
from nsd_core.structure.seismic import seismic_summary, simulate_seismic

# ratio name -> (what it divides, how it is read from a seismic_summary)
RATIOS = {
    "peak_displacement": ("peak |u| relative to the base [m]", lambda s: s["peak_displacement"]["value"]),
    "peak_absolute_acceleration": ("peak |a_abs| of the plate [m/s^2]",
                                   lambda s: s["peak_absolute_acceleration"]["value"]),
    "residual_displacement": ("|u| at the last sample [m]", lambda s: s["residual_displacement"]["u"]),
    "peak_base_shear": ("peak |base shear| (supports + device + restrainer) [N]",
                        lambda s: s["peak_base_shear"]["value"]),
    "supports_dissipated": ("energy dissipated in the supports' dampers at the end [J]",
                            lambda s: s["energy"]["supports_dissipated"]),
}


def run_one(params, structure, ground, device: bool, duration=None, dt_out=1e-3, solver=None, progress=None) -> dict:
    """One seismic run as a result either way: {"result": RunResult or None, "summary": dict or None,
    "complete": bool, "stopped": None or {"reason", "t", "kind"}}. SolverError and bad input propagate."""
    try:
        result = simulate_seismic(params, structure, ground, duration=duration, dt_out=dt_out, device=device,
                                  progress=progress, **(solver or {}))
        return {"result": result, "summary": seismic_summary(result), "complete": True, "stopped": None}
    except DriveError as err:
        from nsd_core.structure.seismic import RodReachError
        partial = getattr(err, "partial", None)
        stopped = {"kind": "rod_reach" if isinstance(err, RodReachError) else "outside_validity",
                   "reason": str(err), "t": getattr(err, "t_event", None)}
        summary = seismic_summary(partial) if partial is not None and len(partial["t"]) > 1 else None
        if summary is not None:
            summary["stopped"] = stopped
        return {"result": partial, "summary": summary, "complete": False, "stopped": stopped, "error": err}


def ratios(with_device: dict, supports: dict) -> dict:
    """name -> {"with_device", "supports_alone", "ratio" (with / without; None where the reference
    is 0), "what"} over the RATIOS, plus the energy the device absorbed (no ratio: the supports alone
    have no device) and its share of the input energy."""
    out = {}
    for name, (what, get) in RATIOS.items():
        a, b = float(get(with_device)), float(get(supports))
        out[name] = {"with_device": a, "supports_alone": b, "ratio": (a / b) if b != 0 else None, "what": what}
    e = with_device["energy"]
    out["device_absorbed"] = {"with_device": e["device"], "supports_alone": 0.0, "ratio": None,
                              "share_of_input": (e["device"] / e["input"]) if e["input"] else None,
                              "what": "energy the device absorbed by the end (dissipated + change of stored) [J]"}
    if "restrainer_dissipated" in e:
        out["restrainer_dissipated"] = {"with_device": e["restrainer_dissipated"],
                                        "supports_alone": supports["energy"].get("restrainer_dissipated", 0.0),
                                        "ratio": None, "what": "energy dissipated by the restrainer [J]"}
    return out


def run_with_and_without(params, structure, ground, duration=None, dt_out=1e-3, solver=None, progress=None) -> dict:
    """The ground motion on the structure with the device and on the supports alone (the same
    structure, restrainer included when it has one). Returns {"device": run_one(...), "supports":
    run_one(...), "ratios": ratios(...) or None (a run with no samples), "complete": both complete}."""
    dev = run_one(params, structure, ground, True, duration, dt_out, solver, progress)
    sup = run_one(params, structure, ground, False, duration, dt_out, solver, progress)
    both = dev["summary"] is not None and sup["summary"] is not None
    out = {"device": dev, "supports": sup, "ratios": ratios(dev["summary"], sup["summary"]) if both else None,
           "complete": dev["complete"] and sup["complete"]}
    if both and not dev["complete"]:  # compared over different spans: say so in the numbers' record
        out["note"] = (f"the device run stopped at t = {dev['stopped']['t']:.6g} s ({dev['stopped']['kind']}); "
                       "its peaks are over that span, the supports alone over the whole window")
    return out


def ratio_rows(r: dict) -> list[dict]:
    """The ratios as table rows (the ratios.csv file): quantity, with, without, ratio, what."""
    rows = []
    for name, v in (r or {}).items():
        ratio = v.get("ratio")
        rows.append({"quantity": name, "with_device": v["with_device"], "supports_alone": v["supports_alone"],
                     "ratio": "" if ratio is None or not math.isfinite(ratio) else repr(ratio), "what": v["what"]})
    return rows
