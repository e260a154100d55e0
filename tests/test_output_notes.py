"""What the study outputs say beside their numbers: the fragility's notes (docs/ida.md, Fragility),
ida.csv's row statuses (docs/ida.md, Outputs), and a record-set row that ran but left the device's
working range or has a peak on its last sample."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from nsd_core.study.fragility import fit_lognormal
from nsd_core.study.ida_outputs import row_status


def test_fragility_same_level_with_records_that_never_reached_is_fitted():
    """Two records reached the limit at 0.8, two others survived 1.6: the censored records bound the
    dispersion, so the maximum exists (before: null, 'every record reached the limit at the same
    level', which the never-reached records contradict)."""
    fit = fit_lognormal([0.8, 0.8], [1.6, 1.6])
    assert fit["median"] is not None and fit["dispersion"] is not None and "note" not in fit
    assert 0.8 < fit["median"] < 1.6 and 0 < fit["dispersion"] < 2
    # it is the maximum: every nearby (theta, beta) has a lower likelihood
    from nsd_core.study.fragility import _neg_log_likelihood
    ln_im, ln_c = np.log([0.8, 0.8]), np.log([1.6, 1.6])
    best = _neg_log_likelihood([math.log(fit["median"]), math.log(fit["dispersion"])], ln_im, ln_c)
    for dm in (-0.02, 0.02):
        for db in (-0.02, 0.02):
            assert _neg_log_likelihood([math.log(fit["median"]) + dm, math.log(fit["dispersion"]) + db],
                                       ln_im, ln_c) > best


@pytest.mark.parametrize("reached, censored, words", [
    ([0.8, 0.8], [], "all reached it at the same level"),
    ([0.8, 0.8, 0.8], [0.5], "no record is known to survive above it"),
    ([0.5], [2.0, 2.0], "one record reached the limit (fewer than two)"),
    ([], [2.0], "no record reached the limit (fewer than two)"),
])
def test_fragility_undetermined_says_why_in_the_documented_words(reached, censored, words):
    fit = fit_lognormal(reached, censored)
    assert fit["median"] is None and fit["dispersion"] is None
    assert words in fit["note"]
    assert "every record" not in fit["note"]


@pytest.mark.parametrize("rec, status", [
    ({"status": "ok", "metrics": {}}, "ok"),
    ({"status": "failed", "metrics": {"reason": "rod_reach", "t": 3.2}}, "stopped"),
    ({"status": "failed", "metrics": {"reason": "outside_validity", "t": 3.2}}, "stopped"),
    ({"status": "failed", "metrics": {"reason": "solver_failure", "t": 3.2}}, "failed"),
])
def test_ida_row_status_agrees_with_limit_reached(rec, status):
    """A run the rod's reach stopped reached the limit (limit_reached = yes): its row says 'stopped',
    not 'failed' (which is kept for a solver failure, limit_reached = unknown)."""
    from nsd_core.study.ida import parse_limit
    assert row_status(rec) == status
    if status != "ok":
        reached, _ = parse_limit("stroke=0.02").evaluate(rec)
        assert reached is (True if status == "stopped" else None)


def _summary(outside: bool, at_end=()):
    peak = {"value": 0.0287, "t": 4.0}
    return {"peak_ground_acceleration": {"value": 3.0}, "peak_displacement": peak,
            "peak_absolute_acceleration": {"value": 2.0}, "residual_displacement": {"u": 0.001},
            "outside_working_range": outside, "energy": {"relative_residual": 1e-6},
            "peaks_at_last_sample": list(at_end), "params": [{"name": "rod_length", "value": 0.03}]}


def test_record_set_row_says_it_left_the_working_range():
    """A record whose device run completed but left the working range (peak 28.7 mm of the 30 mm rod):
    status ok, and the reason (and nsd seismic's line) says so instead of a bare 'ok'."""
    from nsd_core.study.seismic_set import _row
    group = {n: SimpleNamespace(key=n, folder=n, engine="semirecursive") for n in ("semirecursive", "nodevice")}
    recs = {"semirecursive": {"status": "ok", "summary": _summary(True)},
            "nodevice": {"status": "ok", "summary": _summary(False, ["building.peak_drift_ratio[story 1]"])}}
    row, entry = _row("nearfield-pulse", 1, group, recs, [])
    assert row["status"] == "ok" and row["outside_working_range"] == "yes"
    assert "outside the working range" in row["reason"] and "28.7 mm of the 30 mm rod" in row["reason"]
    # nsd_core.structure.seismic_warnings: the supports' run at 28.7 mm is also past the design stroke (25.46 mm)
    assert [w.split(":")[0] for w in entry["warnings"]] == ["device", "nodevice", "nodevice"]
    assert "stroke nearly exhausted: peak |u| = 28.7 mm" in entry["warnings"][0]
    assert entry["warnings"][1].startswith("nodevice: beyond the design stroke") and "25.46 mm" in entry["warnings"][1]
    assert entry["warnings"][2].startswith("nodevice: building.peak_drift_ratio[story 1] at the last sample")
    recs["semirecursive"]["summary"] = _summary(False)
    recs["nodevice"]["summary"] = _summary(False)
    row, _ = _row("nearfield-pulse", 1, group, recs, [])
    assert row["reason"] == ""
