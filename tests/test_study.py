"""Sweeps (Section 4.3), Tables 5 and 6, calibration and their command lines.

Tiny sweeps only: 1 cycle, 32 samples, loose tolerances (a few seconds per design).
"""
from __future__ import annotations

import csv
import dataclasses
import json
import math
import os
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import pytest

from nsd_cli import main as cli
from nsd_core.device.params import Params, load_params
from nsd_core.device.working_range import x_max_at_slack
from nsd_core.study.designs import PAPER_STUDIES, make_designs, paper_designs
from nsd_core.study.store import Store
from nsd_core.study.sweep import run_sweep
from nsd_core.study.tables import TABLE5, TABLE6, table_rows

ROOT = Path(__file__).resolve().parents[1]
PAPER_DATA = Path(__file__).resolve().parents[1] / "references" / "paper-data.toml"
FAST = dict(rtol=1e-5, atol=1e-8)
TINY = ["--cycles", "1", "--samples-per-cycle", "32", "--rtol", "1e-5", "--atol", "1e-8"]


def tiny(param="rod_length", values=(0.03, 0.04), **kw):
    return make_designs(param, list(values), cycles=1, samples_per_cycle=32, settings=FAST, **kw)


def stored(out: Path) -> dict[str, dict]:
    return {p.parent.name: json.loads(p.read_text()) for p in (out / "designs").glob("*/result.json")}


# ---------------------------------------------------------------- designs and keys
def test_keys_deduplicate_the_nominal_design_and_follow_the_settings():
    designs = paper_designs(cycles=1, samples_per_cycle=32)
    assert len(designs) == sum(len(v) for v, _ in PAPER_STUDIES.values()) == 47
    nominal = [d for d in designs if d.params == Params().to_dict()]
    assert len(nominal) == 7 and len({d.key for d in nominal}) == 1  # one run for seven studies
    assert len({d.key for d in designs}) == 41
    a, b = tiny(values=(0.03,))[0], tiny(values=(0.03,))[0]
    assert a.key == b.key
    assert dataclasses.replace(a, settings=dict(a.settings, rtol=1e-6)).key != a.key
    assert dataclasses.replace(a, amplitude=0.02).key != a.key


def test_amplitude_stays_inside_the_working_range():
    (low,) = make_designs("precompression_force", [2400.0])
    xm = x_max_at_slack(Params(precompression_force=2400.0))
    assert low.amplitude == pytest.approx(0.95 * xm) and low.amplitude < 0.024
    assert "X_max" in low.amplitude_rule
    (nom,) = make_designs("rod_length", [0.03])
    assert nom.amplitude == 0.024 and nom.amplitude_rule == "0.024 m"


@pytest.mark.skipif(not PAPER_DATA.exists(), reason="paper-data.toml not available")
def test_paper_numbers_match_the_transcription():
    ref = tomllib.loads(PAPER_DATA.read_text())
    for name, (values, _) in PAPER_STUDIES.items():
        assert values == ref["parametric"][name], name
    assert TABLE5["x_max"] == ref["table5"]["x_max"] and TABLE5["values"] == ref["table5"]["rod_length"]
    assert TABLE5["theta_max_deg"] == ref["table5"]["theta_max_deg"]
    assert TABLE6["x_max"] == ref["table6"]["x_max"]
    assert TABLE6["values"] == ref["table6"]["precompression_force"]


# ---------------------------------------------------------------- resumable sweeps
def test_killed_sweep_resumes_and_stores_every_design_once(tmp_path):
    out = tmp_path / "sweep"
    args = [sys.executable, "-m", "nsd_cli.main", "sweep", "--param", "rod_length", "--values",
            "0.03,0.032,0.034,0.036,0.038,0.04,0.042,0.044,0.046,0.048,0.05", *TINY, "--workers", "1", "--out", str(out)]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen(args, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.time() + 90
        while not stored(out) and time.time() < deadline and proc.poll() is None:
            time.sleep(0.002)  # a design takes ~0.05 s warm: look often
        proc.send_signal(signal.SIGKILL)  # a hard kill: no clean-up code runs
    finally:
        proc.wait(timeout=30)
    first = stored(out)
    assert 1 <= len(first) < 11, "the kill should land after the first design and before the last"
    assert not (out / "sweep.json").exists()
    # restart (in a pool of two this time): only the missing designs run
    rc = cli.main(["sweep", "--param", "rod_length", "--values", "0.03,0.032,0.034,0.036,0.038,0.04,0.042,0.044,0.046,0.048,0.05", *TINY, "--workers", "2",
                   "--out", str(out)])
    assert rc == 0
    final = stored(out)
    assert len(final) == 11 and all(r["status"] == "ok" for r in final.values())
    for key, rec in first.items():  # finished work was kept, not redone
        assert final[key]["stored_at"] == rec["stored_at"]
    summary = json.loads((out / "rod_length" / "summary.json").read_text())
    assert [d["value"] for d in summary["designs"]] == [0.03, 0.032, 0.034, 0.036, 0.038, 0.04, 0.042, 0.044, 0.046, 0.048, 0.05]
    assert len({d["key"] for d in summary["designs"]}) == 11
    for d in summary["designs"]:
        assert (out / d["steady_csv"]).exists() and (out / d["cycle_csv"]).exists()
        assert d["theta_max_deg"] == pytest.approx(math.degrees(math.asin(d["x_max_quasi_static"] / d["value"])))
        assert d["dissipated_energy"] > 0
    assert not list(out.rglob("*.tmp"))  # atomic writes leave no partial files behind


def test_failing_design_is_recorded_and_the_others_finish(tmp_path):
    good, other = tiny(values=(0.03, 0.04))
    bad = dataclasses.replace(other, amplitude=0.045)  # |u| >= l_d: the mechanism cannot follow
    logs = []
    index = run_sweep([good, bad], tmp_path, workers=1, log=logs.append)
    recs = stored(tmp_path)
    assert recs[good.key]["status"] == "ok"
    assert recs[bad.key]["status"] == "failed" and "rod_length" in recs[bad.key]["error"]
    assert index["failed"] == [bad.key] and index["ok"] == 1
    assert any("FAILED" in line for line in logs)
    # a rerun does not repeat either design; --retry-failed runs the failed one again
    logs.clear()
    run_sweep([good, bad], tmp_path, workers=1, log=logs.append)
    assert "2 already stored, 0 to run" in logs[0]
    logs.clear()
    run_sweep([good, bad], tmp_path, workers=1, retry_failed=True, log=logs.append)
    assert "1 already stored, 1 to run" in logs[0]


def test_dask_local_cluster(tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        index = run_sweep(tiny(), tmp_path, scheduler=cluster.scheduler_address, log=lambda s: None)
    assert index["ok"] == 2 and not index["failed"]
    assert all(r["status"] == "ok" for r in stored(tmp_path).values())


def test_store_ignores_unfinished_designs(tmp_path):
    (d,) = tiny(values=(0.03,))
    folder = Store(tmp_path).folder(d.key)
    folder.mkdir(parents=True)
    (folder / "cycle.csv").write_text("partial")  # a run killed before its result.json
    assert Store(tmp_path).load(d.key) is None


# ---------------------------------------------------------------- Tables 5 and 6
def test_tables_cli_prints_and_writes_every_entry_within_the_goal(tmp_path, capsys):
    assert cli.main(["tables", "--out", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    assert "Table 5" in text and "Table 6" in text and "goal 0.3 mm: met" in text
    with open(tmp_path / "tables.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 16
    assert "difference [mm]" in rows[0] and "model_x_max [m]" in rows[0]
    for r in rows:
        diff = (float(r["model_x_max [m]"]) - float(r["paper_x_max [m]"])) * 1e3
        assert float(r["difference [mm]"]) == pytest.approx(diff, abs=2e-3)
        assert abs(diff) <= 0.3
        if r["table"] == "Table 5":
            assert abs(float(r["theta_difference [deg]"])) < 0.5


def test_slack_point_matches_the_stepped_quasi_static_path():
    from nsd_core.device.quasistatic import x_max
    for p in (Params(), Params(precompression_force=2400.0)):
        assert x_max_at_slack(p) == pytest.approx(x_max(p, step=1e-4), abs=6e-5)


def test_tables_detect_a_wrong_model():
    rows = table_rows(Params(rope_upper_height=0.025))  # a different device misses the paper
    assert max(abs(r["difference_mm"]) for r in rows) > 0.3


# ---------------------------------------------------------------- calibration
def test_calibrate_cli_writes_a_loadable_parameter_file(tmp_path, capsys):
    assert cli.main(["calibrate", "--fit", "rope_upper_height,spring_kse", "--out", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    assert "rank" in text and "condition number" in text
    rep = json.loads((tmp_path / "calibration.json").read_text())
    assert rep["rms_mm"] <= rep["rms_start_mm"] + 1e-9 and rep["rank"] == 2
    assert all(v == 0.0 or v < 1e-12 for v in rep["wire_sensitivity_mm_per_10pct"].values())
    p = load_params(tmp_path / "calibrated_params.toml")
    assert p.rope_upper_height == pytest.approx(rep["values"]["rope_upper_height"])
    assert "provenance" in tomllib.loads((tmp_path / "calibrated_params.toml").read_text())


# ---------------------------------------------------------------- bad input
@pytest.mark.parametrize("argv, needle", [
    (["sweep", "--param", "nope", "--values", "1", "--out", "x"], "nope"),
    (["sweep", "--param", "rod_length", "--values", "0.03,abc", "--out", "x"], "abc"),
    (["sweep", "--param", "rod_length", "--out", "x"], "--values"),
    (["sweep", "--paper", "--param", "rod_length", "--values", "0.03", "--out", "x"], "--paper"),
    (["sweep", "--param", "n_ropes", "--values", "2", "--out", "x"], "n_ropes"),
    (["sweep", "--param", "rod_length", "--values", "0.03", "--workers", "0", "--out", "x"], "--workers"),
    (["sweep", "--param", "rod_length", "--values", "0.03", "--engines", "adams", "--out", "x"], "adams"),
    (["sweep", "--param", "rod_length", "--values", "0.03", "--amplitude", "0.05", "--out", "x"], "amplitude"),
    (["tables", "--method", "guess"], "guess"),
    (["calibrate", "--fit", "n_ropes"], "n_ropes"),
])
def test_bad_input_exits_2_with_one_line(argv, needle, tmp_path, capsys):
    argv = [a if a != "x" else str(tmp_path / "x") for a in argv]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("nsd: error:") and needle in err and "\n" not in err
    assert not (tmp_path / "x").exists()
