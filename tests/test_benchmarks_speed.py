"""The issue-26 benchmarks' own logic (fast: no engine runs): the work-precision walk to the aim,
the measurement commands' short mode, and the generated tables read the JSON the benchmarks write."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from benchmarks import docs, docs_common, docs_performance, measure  # noqa: E402

wp = pytest.importorskip("work_precision")


def _rows(engine, settings_list):
    return [{"engine": engine, "settings": s, "case_default": False, "cpu": [], "wall": []} for s in settings_list]


def test_walk_stops_each_sub_ladder_at_the_aim_and_leaves_out_peers_far_costlier(monkeypatch):
    # (dF, CPU s per cycle) each rung gives, by engine and settings
    table = {
        ("semirecursive", 1e-3): (5e-4, 0.02), ("semirecursive", 1e-4): (4e-5, 0.021),
        ("semirecursive", 1e-5): (2e-6, 0.03),
        ("mujoco", 1e-4): (2e-4, 0.01), ("mujoco", 2.5e-5): (5e-5, 0.03), ("mujoco", 1e-5): (1e-5, 0.08),
        ("exudyn", 1e-3): (3e-4, 0.7), ("exudyn", 1e-4): (5e-5, 2.0),
    }
    ran = []

    def fake_run(case, ref, row, first):
        key = row["settings"].get("rtol", row["settings"].get("timestep", row["settings"].get("step_size")))
        ran.append((row["engine"], key))
        dF, cpu = table[(row["engine"], key)]
        row["cpu"].append(cpu)
        row["wall"].append(cpu)
        row["dF"] = dF

    monkeypatch.setattr(wp, "_run", fake_run)
    rungs = {"semirecursive": _rows("semirecursive", [{"rtol": r} for r in (1e-3, 1e-4, 1e-5)]),
             "mujoco": _rows("mujoco", [{"timestep": h} for h in (1e-4, 2.5e-5, 1e-5)]),
             "exudyn": _rows("exudyn", [{"step_size": h} for h in (1e-3, 1e-4)])}
    wp._walk_to_aim(None, None, rungs)
    # each ladder up to its first rung within 1e-4, no further; Exudyn's second rung is not run: its
    # first already cost more than PRUNE x the best peer within the aim (MuJoCo 0.03 s)
    assert ran == [("semirecursive", 1e-3), ("mujoco", 1e-4), ("exudyn", 1e-3),
                   ("semirecursive", 1e-4), ("mujoco", 2.5e-5)]
    assert "reached the aim" in rungs["semirecursive"][2]["skipped"]
    assert "best peer" in rungs["exudyn"][1]["skipped"]
    assert wp._best_peer_cpu(rungs) == 0.03


def test_sub_ladders_are_the_named_choices():
    assert wp.group_of({"integrator": "RK4", "timestep": 1e-4}) == (("integrator", "RK4"),)
    assert wp.group_of({"rtol": 1e-4, "max_step": 1.0}) == ()


def test_short_mode_commands():
    for name in measure.SHORT:
        cmd = measure.command(name, short=True)
        assert "--short" in cmd and "--repeats" not in cmd and cmd[-2:] == ["--out", "OUT"], cmd
    assert measure.command("work_precision")[-4:] == ["--repeats", "3", "--out", "OUT"]
    assert measure.main(["--short", "bench_cycle"]) == 2   # no short mode there


@pytest.mark.parametrize("name,render", [("bench_start", docs.bench_start), ("bench_record_set", docs.bench_record_set),
                                         ("work_precision", docs.work_precision), ("bench_dask", docs.bench_dask)])
def test_generated_tables_come_from_the_committed_json(name, render):
    rec = json.loads((docs_common.RESULTS / f"{name}.json").read_text())
    text = render()
    assert rec["command"] in text and text.count("\n|") >= 3


@pytest.mark.slow
def test_bench_dask_measures_the_efficiency_and_the_overhead_per_task(tmp_path):
    """One record on a LocalCluster of one worker process and on the local pool: the rows the docs read."""
    import subprocess
    import sys
    out = tmp_path / "bench_dask.json"
    p = subprocess.run([sys.executable, "benchmarks/bench_dask.py", "--records", "1", "--workers", "1", "--tasks", "20",
                        "--out", str(out)], cwd=docs_common.ROOT, capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stderr[-2000:]
    rows = json.loads(out.read_text())["data"]["rows"]
    dask, pool = rows
    assert dask["where"] == "dask" and dask["efficiency_from_1"] == 1.0 and 0 < dask["overhead_per_task_s"] < 1
    assert pool["where"] == "local pool" and pool["runs"] == dask["runs"] > 0


def test_the_ida_table_says_a_refined_peer_its_first_verdict_and_its_steps():
    """bench-ida-farfield: a peer the cross-check refined (nsd_cli.ida_refine) is shown with the step it
    ran at first, its first verdict and its largest estimate there, and the step it passed at."""
    v = {"du": 1.2e-6, "dF": 4.4e-4, "verdict": "PASS",
         "estimates": {"du": {"estimate": 6.8e-6}, "dF": {"estimate": 4.4e-4}},
         "first": {"verdict": "FAIL", "estimates": {"du": {"estimate": 2.1e-4}, "dF": {"estimate": 1.6e-2}}},
         "refined": {"from": {"step_size": 1e-4}, "to": {"step_size": 1.25e-5}, "asked": 1.1e-5, "capped": True}}
    text = docs_performance._refined(v)
    assert "step_size 0.0001 -> 1.25e-05 s (its runs asked 1.1e-05 s; at most 8 x the steps)" in text
    assert "first pair said FAIL" in text and "dF 1.6e-02" in text
    assert docs_performance._refined({"du": 1e-5, "verdict": "PASS"}) == ""
    rec = json.loads((docs_common.RESULTS / "bench_ida_farfield.json").read_text())
    assert rec["command"] in docs.bench_ida_farfield()
