"""nsd ida --cross-check none|median|all (docs/ida.md, "Cross-check"): each re-run printed with its
time, the IDA's time and the cross-check's apart and together in the last line and in ida.json, the
work of 'all' bounded before anything runs; real runs on near-field pulse records 9 and 6 (6.3 and
6.6 model s)."""
from __future__ import annotations

import json
import re

import pytest

from nsd_cli.main import main

BASE = ["ida", "--record-set", "nearfield-pulse", "--levels", "0.5,0.9", "--limit", "stroke=0.02", "--workers", "1"]


@pytest.mark.parametrize("extra,words", [
    (["--cross-check", "bogus"], "--cross-check 'bogus': unknown; allowed: none, median, all"),
    (["--cross-check", "ALL"], "--cross-check 'ALL': unknown; allowed: none, median, all"),
    (["--cross-check", ""], "--cross-check '': unknown"),
    (["--records", "1-14", "--cross-check", "all"], "--cross-check all: 14 records x 2 engines (mujoco, exudyn)"),
])
def test_bad_cross_check_is_one_line_exit_2_nothing_written(extra, words, tmp_path, capsys):
    out = tmp_path / "ida"
    argv = [a for a in BASE if a != "--workers" and a != "1"] + (["--records", "9"] if "--records" not in extra else [])
    assert main(argv + extra + ["--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0] and "allowed" in err[0], err
    assert not out.exists()


def _last_line(text: str) -> re.Match:
    line = [ln for ln in text.splitlines() if "IDA runs in" in ln][-1]
    m = re.match(r"(\d+) IDA runs in ([\d.]+) s \+ cross-check \((\w+)\) (\d+) runs in ([\d.]+) s.* = ([\d.]+) s in all",
                 line)
    assert m, line
    return m


def test_all_checks_every_record_and_the_last_line_adds_both_times(tmp_path, capsys):
    """--engines semirecursive: the supports alone of both records against the exact solution, each
    re-run printed with its time; a second call finds them stored (0 runs, said 'stored'); --cross-check
    none then runs nothing (13 s measured)."""
    out = tmp_path / "ida"
    argv = BASE + ["--records", "6,9", "--engines", "semirecursive", "--out", str(out)]
    assert main(argv + ["--cross-check", "all"]) == 0
    printed = capsys.readouterr().out
    m = _last_line(printed)
    ida_s, check_s, total = float(m[2]), float(m[5]), float(m[6])
    assert m[1] == "8" and m[3] == "all" and m[4] == "2" and total == pytest.approx(ida_s + check_s, abs=0.11)
    index = json.loads((out / "ida.json").read_text())
    assert index["cross_check_mode"] == "all" and index["elapsed_total_s"] == pytest.approx(
        index["elapsed_this_run_s"] + index["elapsed_cross_check_s"])
    assert index["cross_check_cost"]["semirecursive"]["runs"] == 2
    median, others = index["cross_check"]["nodevice"], index["cross_check"]["records"]["nodevice"]
    assert len(others) == 1 and {median["record"], others[0]["record"]} == {6, 9}
    for c in (median, others[0]):
        assert c["engines"]["exact"]["du"] < 1e-6 and c["run_now"]["semirecursive"]
    assert (out / "cross_check" / "nodevice" / f"record_{others[0]['record']}" / "exact.csv").is_file()
    lines = [ln for ln in printed.splitlines() if ln.startswith("cross-check nodevice: record")]
    assert len(lines) == 2 and all(re.search(r"in-house re-run \([\d.]+ s\)", ln) for ln in lines)
    assert main(argv + ["--cross-check", "all"]) == 0
    printed = capsys.readouterr().out
    assert _last_line(printed)[4] == "0" and printed.count(" s, stored)") == 2
    assert main(argv + ["--cross-check", "none"]) == 0
    printed = capsys.readouterr().out
    m = _last_line(printed)
    assert m[3] == "none" and m[4] == "0" and float(m[5]) == 0.0
    assert "cross-check nodevice: not asked for (--cross-check none)" in printed
    check = json.loads((out / "ida.json").read_text())["cross_check"]
    assert check["device"]["skipped"] == check["nodevice"]["skipped"] == "not asked for (--cross-check none)"


@pytest.mark.slow
def test_a_peer_re_run_is_printed_with_its_time_and_judged_by_its_own_estimate(tmp_path, capsys):
    """MuJoCo re-runs the device's median record (record 9, 6.3 model s) at its cross-check step and at
    half of it; its line carries the difference, its own Richardson estimate and the gate's verdict,
    and the last line both runs' time."""
    out = tmp_path / "ida"
    assert main(BASE + ["--records", "9", "--engines", "semirecursive,mujoco", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    line = [ln for ln in printed.splitlines() if ln.startswith("cross-check device: record 9")][0]
    assert re.search(r"mujoco du [\d.e+-]+ \(estimate [\d.e+-]+, (PASS|FAIL)\) \(([\d.]+) s\)", line), line
    index = json.loads((out / "ida.json").read_text())
    m = index["cross_check"]["device"]["engines"]["mujoco"]
    assert m["settings"] == {"timestep": 2e-5} and m["check_wall_time"] > 0
    for metric in ("du", "dF", "da"):   # the rule, recomputed from the entry
        e = m["estimates"][metric]
        assert e["estimate"] > 0 and e["consistent"] == (m[metric] <= 3.0 * e["estimate"])
        assert e["accurate"] == (max(e["estimate"], m[metric]) <= e["tolerance"])
    cost = index["cross_check_cost"]
    assert cost["mujoco"]["runs"] == 2 and f"mujoco 2 in {cost['mujoco']['wall_s']:.1f} s" in printed


def test_a_peer_its_own_estimate_calls_unconverged_gets_the_step_it_needs():
    """The rule on a cross-checked peer, from two synthetic runs: consistent but not accurate (the far-field
    record 15's Exudyn numbers at 1e-4 s), so FAIL with the step its estimate asks for (order 2, to 0.8 x
    the tolerance), and PASS when both are small; the printed line says which."""
    from nsd_cli.ida_check import judged
    from nsd_cli.ida_check_text import describe_entry
    rec = {"metrics": {"solver": {"settings": {"step_size": 1e-4}, "steps": 1000}}}
    rec2 = {"metrics": {"solver": {"settings": {"step_size": 5e-5}, "steps": 2000}}}
    diff = {"du": 2.7e-2, "dF": 4.6e-2, "da": 5.7e-2}
    v = judged("exudyn", diff, {"du": 2.4e-2, "dF": 4.2e-2, "da": 3.1e-2}, rec, rec2)
    assert v["verdict"] == "FAIL" and all(e["consistent"] and not e["accurate"] for e in v["estimates"].values())
    worst = max(max(diff[k], v["estimates"][k]["estimate"]) for k in diff)
    assert v["step_needed"]["step_size"] == pytest.approx(1e-4 * (0.8e-3 / worst) ** 0.5)
    ok = judged("exudyn", {"du": 2e-5, "dF": 3e-5, "da": 4e-5}, {"du": 1e-5, "dF": 2e-5, "da": 2e-5}, rec, rec2)
    assert ok["verdict"] == "PASS" and "step_needed" not in ok
    entry = {"record": 15, "level": 0.78, "engines": {"exudyn": {**diff, **v, "wall_time": 26.4, "run_now": True}}}
    assert "exudyn du 2.70e-02 (estimate 3.2e-02, FAIL; not converged: needs step_size <= 1.2e-05 s)" in \
        describe_entry("device", entry)


def _verdict(est: dict, tol: float = 1e-3, consistent: bool = True) -> dict:
    estimates = {m: {"estimate": e, "tolerance": tol, "consistent": consistent, "accurate": e <= tol}
                 for m, e in est.items()}
    ok = consistent and all(v["accurate"] for v in estimates.values())
    return {"estimates": estimates, "verdict": "PASS" if ok else "FAIL"}


def test_a_peer_not_converged_is_refined_from_its_half_step_run_at_the_order_its_record_shows():
    """ida_refine.refined_step: from the h/2 run's measured error down to 0.8 x the tolerance at the
    order log2(d(h) / d(h/2)), clamped to [1, the method's]; none for a PASS or a disagreement; at most
    8 x the steps. The far-field median record's dF (1.4e-2 at 1e-4 s), were it to fall at ~1.5 to h/2,
    asks for about 1.5e-5 s, where order 2 from the first estimate asked 2.2e-5 s (1.1e-3 measured at 2e-5 s)."""
    import math
    from nsd_cli.ida_refine import refined_step
    d = {"du": 1.7e-4, "dF": 1.37e-2, "da": 6.4e-3}
    d2 = {"du": 4.3e-5, "dF": 4.84e-3, "da": 2.0e-3}   # dF falls at order 1.5 from h to h/2
    v = _verdict({"du": 2.1e-4, "dF": 1.64e-2, "da": 7.7e-3})
    step = refined_step(1e-4, v, d, d2, 2.0)
    by_dF = 0.5e-4 * (0.8e-3 / 4.84e-3) ** (1 / math.log2(1.37e-2 / 4.84e-3))   # order 1.50
    by_da = 0.5e-4 * (0.8e-3 / max(2.0e-3, 7.7e-3 / 4)) ** (1 / min(2.0, math.log2(6.4e-3 / 2.0e-3)))
    assert step == pytest.approx(min(by_dF, by_da)) and 1.4e-5 < step < 1.6e-5
    assert refined_step(1e-4, _verdict({"du": 1e-5, "dF": 2e-4, "da": 3e-4}), d, d2, 2.0) is None   # PASS
    assert refined_step(1e-4, _verdict({"du": 1e-2, "dF": 1e-2, "da": 1e-2}, consistent=False), d, d2, 2.0) is None
    far = refined_step(1e-4, _verdict({"du": 1e-4, "dF": 0.5, "da": 1e-4}), {**d, "dF": 0.4}, {**d2, "dF": 0.1}, 2.0)
    assert far == pytest.approx(1e-4 / 8)   # capped: at most 8 x the first run's steps
    slow = refined_step(1e-4, _verdict({"du": 1e-4, "dF": 3e-3, "da": 1e-4}), {**d, "dF": 2e-3}, {**d2, "dF": 1.9e-3},
                        2.0)   # an error that hardly falls: order 1, not less
    assert slow == pytest.approx(max(0.5e-4 * 0.8e-3 / 1.9e-3, 1e-4 / 8))


def test_a_peer_refined_below_the_in_house_runs_own_error_is_not_called_a_disagreement():
    """Near-field no-pulse record 16 (measured): MuJoCo refined to 2.5e-6 s differs from the IDA's
    in-house re-run by dF 1.2e-4 against its own estimate 1.7e-5; the in-house run at the IDA's rtol
    carries its own error, measured against the converged in-house run. Within 3 x (estimate + that
    error) it is consistent; counted as exact (no ``own``) it was called a disagreement."""
    from nsd_cli.ida_check import judged
    rec = {"metrics": {"solver": {"settings": {"timestep": 2.5e-6}, "steps": 8000}}}
    rec2 = {"metrics": {"solver": {"settings": {"timestep": 1.25e-6}, "steps": 16000}}}
    diff = {"du": 1.43e-5, "dF": 1.18e-4, "da": 5.8e-5}
    h_vs_h2 = {"du": 1.3e-6, "dF": 8.3e-6, "da": 6.3e-6}   # MuJoCo Euler, order 1: estimate = 2 x this
    alone = judged("mujoco", diff, h_vs_h2, rec, rec2)
    assert alone["verdict"] == "FAIL" and not alone["estimates"]["dF"]["consistent"]
    own = {"du": 1.2e-5, "dF": 1.1e-4, "da": 5e-5}
    both = judged("mujoco", diff, h_vs_h2, rec, rec2, own)
    assert both["verdict"] == "PASS" and all(v["consistent"] and v["accurate"] for v in both["estimates"].values())
    far = judged("mujoco", {**diff, "dF": 5e-4}, h_vs_h2, rec, rec2, own)   # beyond both: still a disagreement
    assert far["verdict"] == "FAIL" and not far["estimates"]["dF"]["consistent"]


def test_each_peer_pairs_its_run_with_the_gates_companion_for_its_method():
    """Exudyn's companion at 2h (its observed order on the device is its nominal 2: the pair costs 1.5 x
    its run), MuJoCo Euler's at h/2 (its nominal 1 understates what it shows), as the gate's
    (comparisons.estimate.companion_times); the work estimate counts each pair's cost."""
    from nsd_cli.ida_check import check_work, pair_cost, peer_settings
    assert peer_settings("exudyn", False) == {"step_size": 1.25e-5}
    assert peer_settings("exudyn", False, True) == {"step_size": 2.5e-5}
    assert peer_settings("mujoco", False, True) == {"timestep": 1e-5}
    assert peer_settings("mujoco", True, True) == {"timestep": 5e-6}
    assert peer_settings("exudyn", False, True, step=1e-5) == {"step_size": 2e-5}
    assert (pair_cost("exudyn"), pair_cost("mujoco")) == (1.5, 3.0)
    work = check_work("median", {1: 10.0, 2: 16.9}, ["mujoco", "exudyn"])
    assert work["peer_steps"] == pytest.approx(3.0 * 16.9 / 2e-5 + 1.5 * 16.9 / 1.25e-5)


def test_a_coarser_companion_gives_the_judged_runs_estimate_and_refines_from_the_judged_run():
    """With the companion at 2h the estimate is d(h, 2h) / (2^p - 1) (the step counts say which run is
    the coarser), and the refinement extrapolates from the judged run (the finer) at the order the
    record shows between 2h and h."""
    import math
    from nsd_cli.ida_check import judged
    from nsd_cli.ida_refine import refined_step
    rec = {"metrics": {"solver": {"settings": {"step_size": 1.25e-5}, "steps": 4000}}}
    rec2 = {"metrics": {"solver": {"settings": {"step_size": 2.5e-5}, "steps": 2000}}}
    diff = {"du": 1e-5, "dF": 2.4e-3, "da": 4e-4}
    v = judged("exudyn", diff, {"du": 3e-5, "dF": 6.6e-3, "da": 1.2e-3}, rec, rec2)
    assert v["estimates"]["dF"]["estimate"] == pytest.approx(6.6e-3 / 3)
    assert v["estimates"]["du"]["estimate"] == pytest.approx(1e-5)
    assert v["verdict"] == "FAIL" and v["estimates"]["dF"]["consistent"] and not v["estimates"]["dF"]["accurate"]
    assert v["estimates"]["da"]["accurate"]
    coarse = {"du": 4e-5, "dF": 9e-3, "da": 1.6e-3}   # the 2h run's differences from the in-house run
    step = refined_step(1.25e-5, v, diff, coarse, 2.0, times=2.0)
    p = math.log2(9e-3 / 2.4e-3)   # 1.91, below the method's 2
    assert step == pytest.approx(1.25e-5 * (0.8e-3 / 2.4e-3) ** (1 / p))
    # read the other way round (as h/2) the same numbers would ask for another step: the direction counts
    assert refined_step(1.25e-5, v, diff, coarse, 2.0, times=0.5) != pytest.approx(step)
