"""Ŝ_CT at a stated resolution, the capacity that passes, ida.csv's configuration column and the
limit states' median first time (docs/p695.md): synthetic IDA data, the expected numbers worked out
here by hand, not through the code under test."""
from __future__ import annotations

import csv
import io
import math

import pytest

from nsd_core.study.hunt import Hunt, bracket_state, next_hunt_level


def _trace(h: Hunt, capacity: float) -> list:
    hist = []
    while (lv := next_hunt_level(h, hist)) is not None:
        hist.append((lv, lv >= capacity))
    return hist


@pytest.mark.parametrize("capacity", [0.3, 0.9, 1.1, 1.6, 2.3])
def test_hunt_without_fill_stops_once_the_bracket_is_within_the_resolution(capacity):
    h = Hunt(resolution=0.05, max_runs=10, fill=False)
    hist = _trace(h, capacity)
    state = bracket_state(h, hist)
    assert state["resolved"] and state["why"] == "resolved"
    lo, hi = state["lo"], state["hi"]
    assert lo < capacity <= hi and (hi - lo) / hi <= 0.05
    # no fill: the last run is the one that closed the bracket (every earlier bracket was wider)
    before = bracket_state(h, hist[:-1])
    assert before["width"] is None or before["width"] > 0.05
    assert len(hist) <= 10


def test_a_record_out_of_budget_says_so():
    h = Hunt(resolution=0.05, max_runs=5, fill=False)
    hist = _trace(h, 2.3)   # hunt 0.25, 0.5, 0.875, 1.375, 2.0: 5 runs spent before 2.3 is reached
    assert bracket_state(h, hist) == {"lo": 2.0, "hi": None, "width": None, "resolved": False,
                                      "why": "never reached"}
    h = Hunt(resolution=0.05, max_runs=6, fill=False)
    hist = _trace(h, 1.3)   # 0.25 0.5 0.875 1.375 | 1.125 then 1.25: bracket (1.25, 1.375], 9.1 %
    st = bracket_state(h, hist)
    assert (st["lo"], st["hi"], st["why"], st["resolved"]) == (1.25, 1.375, "budget", False)
    assert st["width"] == pytest.approx(0.125 / 1.375, rel=1e-12)


def test_s_ct_is_the_median_geometric_midpoint_and_its_bracket_the_median_ends():
    from nsd_core.study.p695_resolution import s_ct_bracketed
    recs = [{"collapse_im": 1.0, "below_im": 0.95},     # estimate sqrt(0.95)
            {"collapse_im": 2.0, "below_im": 1.9},
            {"collapse_im": None, "censored_at": 3.0},  # never collapsed: above every level
            {"collapse_im": 1.2, "below_im": None},     # nothing below: 0.6, its bracket from 0
            {"collapse_im": 1.5, "below_im": 1.45}]
    out = s_ct_bracketed(recs)
    est = sorted([math.sqrt(0.95), math.sqrt(2.0 * 1.9), math.inf, 0.6, math.sqrt(1.5 * 1.45)])
    assert out["S_CT"] == pytest.approx(est[2], rel=1e-15)   # the 3rd smallest of 5
    assert out["S_CT"] == pytest.approx(math.sqrt(1.5 * 1.45), rel=1e-15)
    # the 3rd smallest lo of (0.95, 1.9, 3.0, 0, 1.45) and hi of (1.0, 2.0, inf, 1.2, 1.5)
    assert out["S_CT_bracket"] == [1.45, 1.5]
    assert out["S_CT_bracket_width"] == pytest.approx(0.05 / 1.5, rel=1e-12)


def test_fewer_than_half_collapsed_leaves_s_ct_undetermined():
    from nsd_core.study.p695_resolution import s_ct_bracketed
    out = s_ct_bracketed([{"collapse_im": 1.0, "below_im": 0.9}, {"collapse_im": None, "censored_at": 2.0},
                          {"collapse_im": None, "censored_at": 2.0}])
    assert out["S_CT"] is None and out["S_CT_bracket"] == [2.0, None]


def test_verdict_over_the_bracket():
    from nsd_core.study.p695_resolution import verdict_over_bracket
    v = verdict_over_bracket([1.4, 1.6], s_mt=1.0, ssf=1.0, acmr10=1.9, acmr20=1.5)
    assert v["low"]["ACMR"] == pytest.approx(1.4) and v["high"]["ACMR"] == pytest.approx(1.6)
    assert (v["low"]["pass_ACMR20"], v["high"]["pass_ACMR20"], v["resolved"]) == (False, True, False)
    v = verdict_over_bracket([1.6, 1.7], s_mt=1.0, ssf=1.1, acmr10=1.9, acmr20=1.5)
    assert v["resolved"] and v["low"]["pass_ACMR20"] and not v["high"]["pass_ACMR10"]


def test_ranking_says_which_pairs_are_resolved():
    from nsd_core.study.p695_resolution import ranking
    configs = {"a": {"S_CT": 1.0, "S_CT_bracket": [0.98, 1.02], "S_CT_interval": {"low": 0.8, "high": 1.2}},
               "b": {"S_CT": 2.0, "S_CT_bracket": [1.95, 2.05], "S_CT_interval": {"low": 1.5, "high": 2.5}},
               "c": {"S_CT": 1.05, "S_CT_bracket": [1.01, 1.09], "S_CT_interval": {"low": 0.9, "high": 1.3}},
               "d": {"S_CT": None}}
    r = ranking(configs)
    assert r["order"] == ["b", "c", "a"] and r["undetermined"] == ["d"]
    (bc, ca) = r["pairs"]
    assert (bc["brackets_overlap"], bc["intervals_overlap"], bc["resolved"]) == (False, False, True)
    assert (ca["brackets_overlap"], ca["intervals_overlap"], ca["resolved"]) == (True, True, False)
    assert r["resolved"] is False


def test_collapse_level_at_a_capacity_from_the_ida_curve():
    from nsd_core.study.p695_capacity import collapse_level
    pts = [(0.5, 0.010), (1.0, 0.025), (1.6, 0.040)]
    # between (1.0, 25 mm) and (1.6, 40 mm) in ln-ln: ln L = ln 1 + ln(30/25) ln(1.6) / ln(40/25)
    want = math.exp(math.log(30 / 25) * math.log(1.6) / math.log(40 / 25))
    assert collapse_level(pts, 0.030) == (pytest.approx(want, rel=1e-14), "interpolated")
    # beyond the highest run: the secant, ln-ln, from the highest point to the highest at most 2/3 of its
    # level (1.0 of 1.6)
    want = math.exp(math.log(60 / 25) * math.log(1.6) / math.log(40 / 25))
    assert collapse_level(pts, 0.060) == (pytest.approx(want, rel=1e-14), "extrapolated")
    # a bracket's two close points are not the secant: from (1.6, 40 mm) back to (1.0, 25 mm), not (1.55, 39 mm)
    assert collapse_level(sorted(pts + [(1.55, 0.039)]), 0.060)[0] == pytest.approx(want, rel=1e-14)
    # a run the rod's reach stopped (inf): the geometric midpoint of its bracket
    assert collapse_level([(0.5, 0.01), (1.0, math.inf)], 0.02) == (pytest.approx(math.sqrt(0.5)), "interpolated")


def test_linear_system_capacity_is_exact():
    """peak |u| proportional to the level: S_CT(c) = c x level / peak of the median record, exactly,
    inside and beyond the runs; the capacity that passes: S_CT(c) SSF / S_MT = ACMR20 (mu_T = 1)."""
    from nsd_core.study.p695_capacity import least_passing, s_ct_at
    ratio = {1: 0.020, 2: 0.025, 3: 0.030}   # peak per unit level, m per m/s^2
    curves = {r: [(lv, k * lv) for lv in (0.25, 0.5, 0.875)] for r, k in ratio.items()}
    for c in (0.01, 0.02, 0.05):
        assert s_ct_at(curves, c)["S_CT"] == pytest.approx(c / 0.025, rel=1e-12)   # the 2nd of 3: record 2
    level = {"S_MT": 1.2, "T": 3.16, "sdc": "dmin"}
    ratings = {"DR": "B", "TD": "C", "MDL": "B"}
    out = least_passing("ACMR20", curves, lambda c: 1.0, level, ratings, 0.01, 0.1)
    # mu_T = 1: SSF 1, beta_TOT = round(sqrt(0.2^2 + 0.2^2 + 0.35^2 + 0.2^2) / 0.025) 0.025 = 0.5
    beta = round(math.sqrt(0.2 ** 2 + 0.2 ** 2 + 0.35 ** 2 + 0.2 ** 2) / 0.025) * 0.025
    from scipy.stats import norm
    acmr20 = math.exp(-beta * norm.ppf(0.2))
    want = acmr20 * 1.2 * 0.025   # S_CT = c / 0.025 = ACMR20 S_MT
    assert out["found"] and out["capacity"] == pytest.approx(want, rel=2e-4)
    assert out["capacity"] >= want * (1 - 1e-12)   # the least passing capacity, from above


def test_first_time_median_counts_the_records_without_a_time():
    from nsd_core.study.limit_state_outputs import first_time_median
    known = first_time_median([(3.0, None), (1.0, None), (2.0, None)])
    assert known == {"first_t_median": 2.0, "first_t_median_range": [2.0, 2.0], "n_first_t_unknown": 0}
    # two unknown: one before 1.5 s (stopped there), one unbounded: median of 4 between
    # [0, 0, 1, 3] -> 0.5 and [1, 1.5, 3, inf] -> 2.25
    out = first_time_median([(1.0, None), (3.0, None), (None, 1.5), (None, None)])
    assert out == {"first_t_median": None, "first_t_median_range": [0.5, 2.25], "n_first_t_unknown": 2}
    # one unknown (before 1 s) that cannot move the median of 5: [2, 2, 2, 9, 0] and [2, 2, 2, 9, 1]
    out = first_time_median([(2.0, None), (2.0, None), (2.0, None), (9.0, None), (None, 1.0)])
    assert out["first_t_median"] == 2.0 and out["n_first_t_unknown"] == 1


class _Store:
    def __init__(self, recs):
        self.recs = recs

    def load(self, key):
        return self.recs[key]


def _ok(peak):
    return {"status": "ok", "design": {"ground": {"scale": 1.0}},
            "metrics": {"peak_displacement": {"value": peak}, "peak_absolute_acceleration": {"value": 1.0},
                        "peak_base_shear": {"value": 1.0}, "residual_displacement": {"u": 0.0}}}


def test_ida_csv_names_each_row_s_configuration():
    """nsd p695's traces (device and three baselines, all but the device without it) and nsd ida's
    (device / nodevice, or the baseline isolator the runs stand on)."""
    from nsd_core.study.ida import Limit, Trace
    from nsd_core.study.ida_outputs import IDA_COLUMNS, ida_rows
    limit = Limit("stroke", 0.02)
    recs = {f"k{i}": _ok(0.01 * i) for i in range(1, 3)}
    traces = [Trace(1, name == "device", 1.0, {"set": "farfield"}, limit, config=name)
              for name in ("device", "linear", "bilinear", "friction-pendulum")]
    traces += [Trace(2, True, 1.0, {"set": "farfield"}, limit), Trace(2, False, 1.0, {"set": "farfield"}, limit),
               Trace(3, False, 1.0, {"set": "farfield", "structure": {"isolator": {"kind": "bilinear"}}}, limit)]
    for tr in traces:
        tr.history = [(0.5, False, "", "k1"), (1.0, True, "stroke", "k2")]
    rows = ida_rows(traces, _Store(recs))
    assert "configuration" in dict(IDA_COLUMNS)
    got = [(r["record"], r["device"], r["configuration"]) for r in rows]
    assert got == [(1, "yes", "device")] * 2 + [(1, "no", "linear")] * 2 + [(1, "no", "bilinear")] * 2 \
        + [(1, "no", "friction-pendulum")] * 2 + [(2, "yes", "device")] * 2 + [(2, "no", "nodevice")] * 2 \
        + [(3, "no", "bilinear")] * 2


def test_evaluation_reads_each_capacity_collapse_from_the_peaks():
    """Synthetic traces of three records (capacity 25 mm): each record's collapse level interpolated
    in ln-ln between its bracket's two peaks, Ŝ_CT the 2nd of 3, its bracket the 2nd lo and hi."""
    from nsd_core.structure.isolation import default_structure
    from nsd_core.device.params import Params
    from nsd_core.study import p695
    from nsd_core.study.ida import Limit, Trace
    from nsd_core.study.limit_states import LimitStates
    from nsd_core.study.p695_outputs import evaluation
    params = Params()
    s = default_structure(params)
    limit = Limit("stroke", 0.025)
    pts = {1: [(1.0, 0.020), (1.05, 0.026)], 2: [(0.9, 0.024), (0.95, 0.030)], 3: [(1.2, 0.0249), (1.25, 0.0251)]}
    traces = []
    for rid, (a, b) in pts.items():
        tr = Trace(rid, False, 1.0, {"set": "farfield"}, limit, config="linear")
        tr.history = [(a[0], False, "", "k"), (b[0], True, "stroke", "k")]
        traces.append(tr)
    level = p695.design_level("basis", s.first_period, math.sqrt(0.1), 9.80665)
    res = evaluation(traces, params, {"linear": (False, s)}, LimitStates(capacity=0.025, rod_length=0.03), limit,
                     level, 0.7, {"DR": "B", "TD": "C", "MDL": "B"}, 200, 1, [1, 2, 3], 1.0, (0.0, 0.0, 0.0),
                     curves={"linear": pts})
    c = res["configurations"]["linear"]

    def interp(a, b):
        return math.exp(math.log(a[0]) + math.log(0.025 / a[1]) * math.log(b[0] / a[0]) / math.log(b[1] / a[1]))
    est = sorted(interp(*pts[r]) for r in (1, 2, 3))
    assert sorted(r["estimate_im"] for r in c["records"]) == pytest.approx(est, rel=1e-14)
    assert c["S_CT"] == pytest.approx(est[1], rel=1e-14)
    assert c["S_CT_bracket"] == [1.0, 1.05]    # 2nd smallest lo of (1.0, 0.9, 1.2), hi of (1.05, 0.95, 1.25)
    assert c["S_CT_top"] == 1.05
    assert c["CMR"] == pytest.approx(est[1] / level["S_MT"], rel=1e-12)
