"""When a seismic result says less than its numbers suggest: the one home of the warning rules of a
seismic run (docs/seismic.md, "Warnings"). ``nsd seismic`` (single runs, --compare-supports,
--compare-building), the record sets and the report pages all read them from here.

A run's warnings, each {"kind", "text"}:

* ``stroke_exhausted``: the run stopped because the plate reached the rod's length (the device is
  spent; everything after is missing) or an element left its law's validity;
* ``stroke_nearly_exhausted``: a complete run with the device whose peak |u| is at least
  ``STROKE_FRACTION`` of the rod's length;
* ``beyond_stroke``: a run without the device (the supports alone, which have no stroke limit in the
  model) whose peak |u| is at least the device's rod length: a comparison with the device is not one
  at equal displacement capacity;
* ``beyond_design_stroke``: a run without the device (a baseline isolator or the linear supports)
  whose peak |u| passes the design basis's stroke (the displacement capacity the design allows,
  ``nsd_core.structure.design``: 25.46 mm at model scale) but not the rod's length;
* ``restrainer_impacts``: the restrainer was touched (any contact): how many, the largest impact
  energy and velocity, the peak contact force;
* ``peaks_at_last_sample``: a response peak falls on the run's last sample (a complete run only: a
  stopped run's end is its event), so the true peak may lie beyond the window;
* ``restoring_force_fails``: the isolation level of this run (with the device, or the supports alone)
  fails the building codes' restoring-force check at its design displacement
  (``nsd_core.structure.restoring_force``).
"""
from __future__ import annotations

STROKE_FRACTION = 0.95   # of the rod's length l_d: |u| this close to it leaves no stroke to speak of (assumed)
KINDS = ("stroke_exhausted", "stroke_nearly_exhausted", "beyond_stroke", "beyond_design_stroke", "restrainer_impacts",
         "peaks_at_last_sample", "restoring_force_fails")


def rod_length_of(summary: dict) -> float | None:
    """The rod's length [m] from a summary's ``params`` (nsd_core.device.params.Params.describe's rows)."""
    rows = summary.get("params")
    if isinstance(rows, list):
        for r in rows:
            if isinstance(r, dict) and r.get("name") == "rod_length" and isinstance(r.get("value"), (int, float)):
                return float(r["value"])
    return None


def _peak(summary: dict, key: str) -> dict | None:
    p = summary.get(key)
    return p if isinstance(p, dict) and isinstance(p.get("value"), (int, float)) else None


def _stroke(summary: dict, rod: float | None) -> list[dict]:
    stopped = summary.get("stopped")
    if isinstance(stopped, dict):
        what = ("the plate reached the rod's length" if stopped.get("kind") == "rod_reach"
                else "an element left its force law's validity")
        return [{"kind": "stroke_exhausted",
                 "text": f"stroke exhausted: the run stopped at t = {stopped.get('t', float('nan')):.6g} s ({what}); "
                         "the device is spent and the response after that time is missing, so peaks and ratios "
                         "cover only the time before it"}]
    u = _peak(summary, "peak_displacement")
    if u is None or rod is None or summary.get("fixed_base"):
        return []
    if summary.get("device", True) and u["value"] >= STROKE_FRACTION * rod:
        return [{"kind": "stroke_nearly_exhausted",
                 "text": f"stroke nearly exhausted: peak |u| = {u['value'] * 1e3:.4g} mm at t = {u['t']:.4g} s is "
                         f"{u['value'] / rod:.1%} of the rod's length {rod * 1e3:.4g} mm (warned from "
                         f"{STROKE_FRACTION:.0%}): the device worked at the end of its reach"}]
    if not summary.get("device", True) and u["value"] >= rod:
        return [{"kind": "beyond_stroke",
                 "text": f"beyond the device's stroke: the supports alone reached peak |u| = {u['value'] * 1e3:.4g} mm "
                         f"at t = {u['t']:.4g} s, more than the rod's length {rod * 1e3:.4g} mm (the model's supports "
                         "have no stroke limit): a comparison with the device is not one at equal displacement "
                         "capacity"}]
    if not summary.get("device", True):
        from nsd_core.structure.design import design, scale
        stroke = float(design()["stroke_m"]) * scale()
        if u["value"] > stroke:
            iso = (summary.get("structure") or {}).get("isolator") or {}
            what = iso.get("kind", "linear supports") if isinstance(iso, dict) else "linear supports"
            return [{"kind": "beyond_design_stroke",
                     "text": f"beyond the design stroke: the {what} run reached peak |u| = {u['value'] * 1e3:.4g} mm "
                             f"at t = {u['t']:.4g} s, past the design basis's stroke {stroke * 1e3:.4g} mm (the "
                             "displacement capacity the design allows, docs/design.md)"}]
    return []


def _restrainer(summary: dict) -> list[dict]:
    r = summary.get("restrainer")
    if not isinstance(r, dict) or not r.get("engagements"):
        return []
    hits = [e for e in summary.get("events") or [] if isinstance(e, dict) and e.get("kind") == "restrainer_engaged"]
    v = max((e.get("impact_velocity", 0.0) for e in hits), default=float("nan"))
    f = _peak(summary, "peak_restrainer_force") or {"value": float("nan"), "t": float("nan")}
    return [{"kind": "restrainer_impacts",
             "text": f"restrainer impacts: {r['engagements']} contact(s), {r.get('engaged_time', 0.0) * 1e3:.4g} ms "
                     f"engaged, largest impact energy {r.get('impact_energy_max', float('nan')):.4g} J (impact velocity "
                     f"up to {v:.3g} m/s), peak contact force {f['value']:.4g} N at t = {f['t']:.4g} s: the peak "
                     "accelerations and base shear include the impacts"}]


def _last_sample(summary: dict) -> list[dict]:
    at_end = summary.get("peaks_at_last_sample") or []
    if not at_end or isinstance(summary.get("stopped"), dict) or summary.get("complete") is False:
        return []
    t = (summary.get("residual_displacement") or {}).get("t", float("nan"))
    return [{"kind": "peaks_at_last_sample",
             "text": f"{', '.join(at_end)} at the last sample (t = {t:.6g} s): the true peak may lie beyond the "
                     "window (lengthen --duration or the window)"}]


def _restoring_force(summary: dict) -> list[dict]:
    rf = summary.get("restoring_force")
    if not isinstance(rf, dict) or summary.get("fixed_base"):
        return []
    if not summary.get("device", True) and isinstance(rf.get("baseline"), dict):
        rf = rf["baseline"]   # the run without the device stands on the baseline
    if "skipped" in rf or rf.get("pass") is not False:
        return []
    psi = rf.get("governing_direction_deg")
    e = (rf.get("directions") or {}).get(f"{psi:g}") if psi is not None else None
    if e is None:   # a summary written before the check had directions for every configuration
        e = (rf.get("with_device") or {}).get(f"{psi:g}") if psi is not None else None
        e = e or rf.get("supports_alone") or {}
    what = rf.get("configuration") or ("device" if summary.get("device", True) else "supports")
    along = "" if psi is None else f" along {psi:g} deg"
    return [{"kind": "restoring_force_fails",
             "text": f"restoring force: the {what} isolation level FAILS {rf.get('code')} at D = "
                     f"{rf['D'] * 1e3:.4g} mm{along}: F(D) - F(D/2) = {e['difference']:.4g} N < 0.025 W = "
                     f"{rf['required']:.4g} N (margin {e['difference'] - rf['required']:+.4g} N)"}]


def run_warnings(summary: dict, rod_length: float | None = None) -> list[dict]:
    """The warnings of one run's summary (see the module docstring); rod_length [m] defaults to the
    summary's own parameters."""
    rod = rod_length if rod_length is not None else rod_length_of(summary)
    return _stroke(summary, rod) + _restrainer(summary) + _last_sample(summary) + _restoring_force(summary)


def apply_warnings(summary: dict, rod_length: float | None = None) -> list[str]:
    """Set summary["warnings"] (the texts) and summary["warning_kinds"] from the rules; returns the texts."""
    found = run_warnings(summary, rod_length)
    summary["warnings"] = [w["text"] for w in found]
    summary["warning_kinds"] = [w["kind"] for w in found]
    return summary["warnings"]
