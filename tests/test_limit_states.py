"""Limit states kept apart: each run's states from its stored record, each trace's
outcome per state (a trace the rod's reach ends is stroke exhausted, never drift), the first
crossing times from a series, the thresholds' bad input, and one small real IDA reporting them."""
from __future__ import annotations

import csv
import math
import json

import numpy as np
import pytest

from nsd_core.device.params import ParameterError
from nsd_core.study.limit_states import LimitStates, classify, first_crossings, trace_states

LS = LimitStates(capacity=0.025, floor_acceleration=5.0, drift=0.01, impact_force=0.0, rod_length=0.03,
                 restrainer_gap=0.024)


def ok_run(u=0.01, acc=1.0, drift=0.002, restrainer=0.0, crossings=None):
    m = {"peak_displacement": {"value": u, "t": 3.0}, "peak_absolute_acceleration": {"value": 0.5, "t": 3.0},
         "building": {"peak_drift_ratio": [{"value": drift, "t": 4.0}, {"value": drift / 2, "t": 4.0}],
                      "peak_floor_acceleration": [{"value": acc / 3, "t": 4.0}, {"value": acc, "t": 4.5}]},
         "peak_restrainer_force": {"value": restrainer, "t": 5.0}}
    if crossings:
        m["crossings"] = crossings
    return {"status": "ok", "metrics": m}


def stopped(reason="rod_reach", t=1.7):
    return {"status": "failed", "metrics": {"reason": reason, "t": t}}


def reached(c):
    return {s: v["reached"] for s, v in c.items()}


def test_a_completed_run_states_each_against_its_threshold():
    c = classify(ok_run(u=0.026, acc=4.9, drift=0.0101, restrainer=12.0,
                        crossings={"capacity": 2.5, "drift": 3.25, "restrainer": 2.4}), LS, device=True)
    assert reached(c) == {"stroke": False, "restrainer": True, "capacity": True, "drift": True,
                          "floor_acceleration": False}
    assert (c["capacity"]["t"], c["drift"]["t"], c["floor_acceleration"]["t"]) == (2.5, 3.25, None)
    assert c["floor_acceleration"]["peak"] == 4.9   # the worst floor, not the first


def test_supports_alone_have_no_stroke_and_states_apply_only_with_their_part():
    c = classify(ok_run(), LS, device=False)
    assert "stroke" not in c
    bare = LimitStates(capacity=0.025, rod_length=0.03)   # no building, no restrainer
    c = classify(ok_run(acc=9.0), bare, device=True)
    assert set(c) == {"stroke", "capacity", "floor_acceleration"}
    # the default floor threshold, 1 g = 9.80665 m/s^2, lies above the worst floor's 9.0
    assert c["floor_acceleration"] == {"reached": False, "t": None, "peak": 9.0, "note": ""}


def test_the_rod_s_reach_is_stroke_and_the_capacity_passed_never_drift():
    c = classify(stopped("rod_reach", 1.7), LS, device=True)
    assert reached(c) == {"stroke": True, "restrainer": True, "capacity": True, "drift": None,
                          "floor_acceleration": None}
    assert c["stroke"]["t"] == 1.7 and c["capacity"]["before_t"] == 1.7 and c["capacity"]["t"] is None
    assert c["drift"]["note"] == "stroke exhausted"
    # a capacity beyond the rod's length was not passed; an impact force above zero was not observed
    far = LimitStates(capacity=0.05, floor_acceleration=5.0, drift=0.01, impact_force=100.0, rod_length=0.03,
                      restrainer_gap=0.024)
    c = classify(stopped("rod_reach"), far, device=True)
    assert (c["capacity"]["reached"], c["restrainer"]["reached"]) == (None, None)
    c = classify(stopped("outside_validity"), LS, device=True)
    assert c["stroke"]["reached"] is True and c["capacity"]["reached"] is None
    c = classify(stopped("solver_failure"), LS, device=True)
    assert set(reached(c).values()) == {None}


def test_a_trace_ended_at_the_rod_s_reach_is_censored_for_drift():
    history = [(0.5, classify(ok_run(u=0.01, drift=0.004), LS, True)),
               (1.0, classify(ok_run(u=0.027, drift=0.008, crossings={"capacity": 6.0}), LS, True)),
               (1.5, classify(stopped("rod_reach", 2.2), LS, True))]
    out = trace_states(history, ["stroke", "capacity", "drift", "floor_acceleration"])
    assert (out["stroke"]["limit_im"], out["stroke"]["below_im"], out["stroke"]["t"]) == (1.5, 1.0, 2.2)
    assert (out["capacity"]["limit_im"], out["capacity"]["below_im"], out["capacity"]["t"]) == (1.0, 0.5, 6.0)
    assert out["drift"]["limit_im"] is None and out["drift"]["censored_at"] == 1.0
    assert "stroke exhausted" in out["drift"]["note"]
    only = trace_states([(0.5, classify(stopped(), LS, True))], ["drift"])
    assert only["drift"]["masked"] and only["drift"]["censored_at"] is None


def test_the_ida_s_own_limit_does_not_count_the_rod_s_reach_as_drift():
    from nsd_core.study.ida import Trace, parse_limit, trace_result
    tr = Trace(record=1, device=True, im1=1.0, common={"set": "farfield"}, limit=parse_limit("drift=0.01"))
    tr.history = [(0.5, False, "", "a"), (1.0, False, "", "b"), (1.5, True, "rod_reach", "c")]
    r = trace_result(tr)
    assert (r["limit_im"], r["censored_at"], r["stroke_exhausted_at"]) == (None, 1.0, 1.5)
    tr = Trace(record=1, device=True, im1=1.0, common={"set": "farfield"}, limit=parse_limit("stroke=0.02"))
    tr.history = [(0.5, False, "", "a"), (1.5, True, "rod_reach", "c")]
    assert trace_result(tr)["limit_im"] == 1.5   # a displacement limit below l_d was passed on the way


class _Series:
    def __init__(self, columns, stats=None):
        self.columns, self.stats = columns, stats or {}

    def __getitem__(self, k):
        return self.columns[k]


def test_first_crossings_are_interpolated_between_the_samples_around_the_threshold():
    t = np.linspace(0.0, 1.0, 11)
    u = np.array([0, 0.01, 0.02, 0.026, 0.02, 0.03, 0, 0, 0, 0, 0], dtype=float)
    cols = {"t": t, "u": u, "ax_abs": 6.0 * np.sin(np.pi * t), "ay_abs": np.zeros(11),
            "restrainer_F": np.where(u > 0.024, 50.0, 0.0)}
    got = first_crossings(_Series(cols), LS.to_dict())
    assert got["capacity"] == pytest.approx(0.2 + 0.1 * (0.025 - 0.02) / (0.026 - 0.02), rel=1e-12)   # 0.28333 s
    assert got["restrainer"] == pytest.approx(0.3)    # the first positive force (impact 0: any engagement, an onset)
    # 6 sin(pi t) >= 5 first at t = asin(5/6)/pi = 0.3128...: linear between the samples at 0.3 and 0.4
    a3, a4 = 6 * math.sin(0.3 * math.pi), 6 * math.sin(0.4 * math.pi)
    assert got["floor_acceleration"] == pytest.approx(0.3 + 0.1 * (5 - a3) / (a4 - a3), rel=1e-12)
    assert first_crossings(_Series({**cols, "u": u / 10}), LS.to_dict())["capacity"] is None


@pytest.mark.parametrize("text", ["capacity=0", "capacity=x", "drift=0.01", "impact=5", "speed=3", "capacity",
                                  "floor_acceleration=-1"])
def test_bad_thresholds_are_one_line_naming_the_field(text):
    from nsd_cli.ida_states import parse_limit_states
    from nsd_core.structure.isolation import default_structure
    from nsd_core.device.params import Params
    with pytest.raises(ParameterError) as e:
        parse_limit_states(text, Params(), default_structure(Params()))
    msg = str(e.value)
    assert "\n" not in msg and "--limit-states" in msg and ("allowed" in msg or "needs" in msg)


@pytest.mark.slow
def test_ida_reports_every_state_apart(tmp_path):
    """Two levels on far-field record 2 (6.3 model s): limit_states.json/.csv/.png, every run's states
    against its own peaks in ida.csv, the device's trace stopped at the rod's reach (stroke) and not
    counted as floor acceleration."""
    from nsd_cli.main import main
    out = tmp_path / "ida"
    assert main(["ida", "--record-set", "farfield", "--records", "2", "--levels", "0.3,2", "--limit", "stroke=0.02",
                 "--limit-states", "capacity=0.015,floor_acceleration=1.0", "--engines", "semirecursive",
                 "--cross-check", "none", "--workers", "1", "--out", str(out)]) == 0
    rep = json.loads((out / "limit_states.json").read_text())
    assert rep["thresholds"]["capacity"] == 0.015
    with open(out / "ida.csv") as f:
        rows = {(r["device"], float(r["im [m/s^2]"])): r for r in csv.DictReader(f)}
    for run in rep["runs"]:
        row = rows[("yes" if run["configuration"] == "device" else "no", run["im"])]
        if row["status"] == "ok":
            assert run["reached"]["capacity"] == (float(row["peak_u [m]"]) >= 0.015)
            assert run["reached"]["floor_acceleration"] == (float(row["peak_a_abs [m/s^2]"]) >= 1.0)
        else:
            assert row["why"] == "rod_reach" and run["reached"]["stroke"] is True
            assert run["reached"]["floor_acceleration"] is None
    dev = rep["configurations"]["device"]
    assert dev["stroke"]["records"][0]["limit_im"] == 2.0
    assert dev["floor_acceleration"]["records"][0]["limit_im"] is None
    assert set(rep["configurations"]["nodevice"]) == {"capacity", "floor_acceleration"}
    with open(out / "limit_states.csv") as f:
        table = list(csv.DictReader(f))
    assert {(r["configuration"], r["state"]) for r in table} == {
        ("device", "stroke"), ("device", "capacity"), ("device", "floor_acceleration"),
        ("nodevice", "capacity"), ("nodevice", "floor_acceleration")}
    assert (out / "limit_states.png").stat().st_size > 10000
