"""Limit states kept apart (docs/ida.md): every run of an IDA says which of five limit states it
reached and when, and each state gets its own fragility per configuration.

States (``STATES``), each with its threshold (``LimitStates``):

* ``stroke``      the device is spent: the rod's reach (|u| = l_d) or a wire outside the SMA law's
                  validity stopped the run (with the device only; the supports alone have no rod);
* ``restrainer``  restrainer impact: the restrainer's force reaches ``impact_force`` N (0: any
                  engagement, |u| > u_gap); only when the runs carry the restrainer;
* ``capacity``    the isolator displacement capacity: peak |u| >= ``capacity`` m;
* ``drift``       peak story drift ratio (worst story) >= ``drift``; only with a building;
* ``floor_acceleration``  peak absolute acceleration of the worst floor (the slab without a
                  building) >= ``floor_acceleration`` m/s^2.

A run the rod's reach stopped passed, on its way to |u| = l_d, every displacement threshold below
l_d: it counts as reaching ``capacity`` (and a zero-force restrainer engagement) when these lie
below the rod's length, at the time its series crossed them (``t``; None when the series was not
kept) before the stop (``before_t``). Drift and
floor acceleration were never observed in it: for them the run is "stroke exhausted", neither
reached nor below (a competing failure), so a trace that ends at the rod's reach is censored for
drift at its last level that ran to the end, never counted as drift.

The time a run first reached each state (``first_crossings``: linear between the output times around
the crossing) is found in the worker from the run's series, which the IDA does not keep; for a run the
rod's reach stopped, from its series up to the stop (so its capacity time is the series' crossing,
not the stop).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

STATES = ("stroke", "restrainer", "capacity", "drift", "floor_acceleration")
SPENT = ("rod_reach", "outside_validity")   # as nsd_core.study.ida.SPENT (imported there from here)
DESCRIBE = {
    "stroke": "device stroke: the run stopped at the rod's reach (or a wire outside the SMA law's validity)",
    "restrainer": "restrainer impact: restrainer force >= {impact_force:g} N",
    "capacity": "isolator displacement capacity: peak |u| >= {capacity:g} m",
    "drift": "story drift: peak drift ratio of the worst story >= {drift:g}",
    "floor_acceleration": "floor acceleration: peak absolute acceleration of the worst floor (the slab "
                          "without a building) >= {floor_acceleration:g} m/s^2",
}
# A threshold of floor acceleration is the user's choice: 1 g is an order of magnitude at which
# acceleration-sensitive contents are damaged, stated as the default, not a code value.
FLOOR_ACCELERATION_DEFAULT = 9.80665
# ASCE/SEI 7-16 Section 17.5.6 bounds the drift of the structure above the isolation system at
# 0.015 h_sx (at the maximum displacement); the default for the drift state.
DRIFT_DEFAULT = 0.015


@dataclass(frozen=True)
class LimitStates:
    """Thresholds of the five states [SI]; None where a state does not apply to the runs."""
    capacity: float                      # m
    floor_acceleration: float = FLOOR_ACCELERATION_DEFAULT   # m/s^2
    drift: float | None = None           # -, with a building only
    impact_force: float | None = None    # N, with the restrainer only (0: any engagement)
    rod_length: float = math.inf         # m, l_d: what the rod's reach means in displacement
    restrainer_gap: float | None = None  # m

    def to_dict(self) -> dict:
        return asdict(self)

    def applies(self, state: str, device: bool) -> bool:
        if state == "stroke":
            return device
        if state == "restrainer":
            return self.impact_force is not None
        if state == "drift":
            return self.drift is not None
        return True

    def describe(self, state: str) -> str:
        return DESCRIBE[state].format(**{k: (v if v is not None else math.nan) for k, v in self.to_dict().items()})


def limit_states_for(structure, params, capacity: float, floor_acceleration: float | None = None,
                     drift: float | None = None, impact_force: float | None = None) -> LimitStates:
    """The states of a structure's runs: drift only with a building (default DRIFT_DEFAULT),
    restrainer only with the restrainer (default 0 N: any engagement)."""
    has_building, has_restrainer = structure.building is not None, structure.restrainer is not None
    return LimitStates(capacity=float(capacity),
                       floor_acceleration=FLOOR_ACCELERATION_DEFAULT if floor_acceleration is None else floor_acceleration,
                       drift=(DRIFT_DEFAULT if drift is None else drift) if has_building else None,
                       impact_force=(0.0 if impact_force is None else impact_force) if has_restrainer else None,
                       rod_length=params.rod_length,
                       restrainer_gap=structure.restrainer.gap if has_restrainer else None)


def _first(t: np.ndarray, values: np.ndarray, threshold: float, strict: bool = False) -> float | None:
    """The first time the series reaches the threshold: linear between the last output below it and
    the first at or over it (the first output time when the series starts there, and for ``strict``,
    any value above a zero threshold: an onset, not a level crossed; None: never)."""
    hit = values > threshold if strict else values >= threshold
    k = np.flatnonzero(hit)
    if not k.size:
        return None
    k = int(k[0])
    if k == 0 or strict or values[k] == values[k - 1]:
        return float(t[k])
    return float(t[k - 1] + (threshold - values[k - 1]) * (t[k] - t[k - 1]) / (values[k] - values[k - 1]))


def first_crossings(result, states: dict) -> dict:
    """{state: the time a run first reached it (None: never)} from its series, interpolated between
    output times (``_first``); a stopped run's series up to its stop (``states``: LimitStates.to_dict())."""
    c, t = result.columns, result["t"]
    out = {"capacity": _first(t, c["u"], states["capacity"])}
    if states.get("impact_force") is not None and "restrainer_F" in c:
        out["restrainer"] = _first(t, c["restrainer_F"], states["impact_force"], strict=states["impact_force"] == 0)
    floors = [k[5:-7] for k in c if k.startswith("floor") and k.endswith("_ax_abs")]
    if floors:
        acc = np.max([np.hypot(c[f"floor{j}_ax_abs"], c[f"floor{j}_ay_abs"]) for j in floors], axis=0)
    else:
        acc = np.hypot(c["ax_abs"], c["ay_abs"])
    out["floor_acceleration"] = _first(t, acc, states["floor_acceleration"])
    if states.get("drift") is not None and floors:
        heights = (result.stats.get("structure") or {}).get("building", {}).get("heights")
        if heights:
            ratio = np.max([np.hypot(c[f"drift{j}_x"], c[f"drift{j}_y"]) / heights[int(j) - 1] for j in floors],
                           axis=0)
            out["drift"] = _first(t, ratio, states["drift"])
    return out


def _peaks(m: dict) -> dict:
    from nsd_core.study.seismic_set import peak_drift_ratio, worst_building_peak
    floor = worst_building_peak(m, "peak_floor_acceleration")
    return {"capacity": m["peak_displacement"]["value"],
            "restrainer": (m.get("peak_restrainer_force") or {}).get("value"),
            "drift": peak_drift_ratio(m),
            "floor_acceleration": floor if floor is not None else m["peak_absolute_acceleration"]["value"]}


def classify(rec: dict, ls: LimitStates, device: bool) -> dict:
    """{state: {"reached": True | False | None, "t", "peak", "note"}} of one stored run; reached None:
    not observed (a solver failure, or the device spent before the state could show), and the
    states that do not apply are left out."""
    out = {}
    m = rec.get("metrics") or {}
    if rec["status"] != "ok":
        reason, t_stop = m.get("reason"), m.get("t")
        for s in STATES:
            if not ls.applies(s, device):
                continue
            if reason not in SPENT:
                out[s] = {"reached": None, "t": None, "peak": None, "note": f"run failed ({reason})"}
            elif s == "stroke":
                out[s] = {"reached": True, "t": t_stop, "peak": None, "note": reason}
            elif reason == "rod_reach" and _passed_on_the_way(s, ls):   # t: its series' crossing, if kept
                out[s] = {"reached": True, "t": (m.get("crossings") or {}).get(s), "before_t": t_stop, "peak": None,
                          "note": "passed on the way to the rod's reach"}
            else:
                out[s] = {"reached": None, "t": None, "peak": None, "note": "stroke exhausted"}
        return out
    peaks, times = _peaks(m), m.get("crossings") or {}
    threshold = {"capacity": ls.capacity, "restrainer": ls.impact_force, "drift": ls.drift,
                 "floor_acceleration": ls.floor_acceleration}
    for s in STATES:
        if not ls.applies(s, device):
            continue
        if s == "stroke":
            out[s] = {"reached": False, "t": None, "peak": None, "note": ""}
            continue
        peak = peaks[s]
        if peak is None:
            out[s] = {"reached": None, "t": None, "peak": None, "note": "not in the run's outputs"}
            continue
        hit = peak > 0.0 if (s == "restrainer" and threshold[s] == 0) else peak >= threshold[s]
        out[s] = {"reached": bool(hit), "t": times.get(s) if hit else None, "peak": peak, "note": ""}
    return out


def _passed_on_the_way(state: str, ls: LimitStates) -> bool:
    """Whether |u| rising continuously to l_d must have passed this state's threshold."""
    if state == "capacity":
        return ls.capacity <= ls.rod_length
    if state == "restrainer":
        return ls.impact_force == 0 and ls.restrainer_gap is not None and ls.restrainer_gap < ls.rod_length
    return False


def trace_states(history: list[tuple[float, dict]], states: list[str]) -> dict:
    """Per state, one trace's outcome from [(level, classify(...))] in the order run: limit_im (the
    lowest level that reached it) and below_im, or censored_at (the highest level observed below
    it), or masked (never observed: every run failed or stopped first), and how the trace ended."""
    out = {}
    for s in states:
        reached = [lv for lv, c in history if c.get(s, {}).get("reached") is True]
        below = [lv for lv, c in history if c.get(s, {}).get("reached") is False]
        masked = [lv for lv, c in history if c.get(s, {}).get("reached") is None]
        r = {"limit_im": None, "below_im": None, "censored_at": None, "t": None, "masked": False}
        if reached:
            hi = min(reached)
            r["limit_im"] = hi
            first = next(c[s] for lv, c in history if lv == hi and c.get(s, {}).get("reached"))
            r["t"], r["before_t"] = first.get("t"), first.get("before_t")
            lower = [lv for lv in below if lv < hi]
            r["below_im"] = max(lower) if lower else None
        elif below:
            r["censored_at"] = max(below)
            if masked:
                r["note"] = f"{history_note(history, s)} at {min(masked):.5g} m/s^2: censored below it"
        else:
            r["masked"] = True
            r["note"] = history_note(history, s) if history else "no run"
        out[s] = r
    return out


def history_note(history, state: str) -> str:
    notes = {c.get(state, {}).get("note") for _, c in history if c.get(state, {}).get("reached") is None}
    return ", ".join(sorted(n for n in notes if n)) or "not observed"
