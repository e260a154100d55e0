"""``nsd seismic --record-set``: record-set runs with and without the device."""
from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from nsd_core.device.params import ParameterError
from nsd_core.study.seismic_set import parse_records

FIGURES = {**os.environ, "NSD_FIGURES": "1"}   # the set's PNGs drawn (tests/conftest.py)
SHORT = ["--record-set", "nearfield-pulse", "--records", "2,3", "--window", "2,2.6", "--dt-out", "0.002"]


def nsd(*args, **kw):
    return subprocess.run([sys.executable, "-m", "nsd_cli.main", *args], capture_output=True, text=True,
                          timeout=900, **kw)


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def test_record_lists():
    assert parse_records("1,3,5-7", "nearfield-pulse") == [1, 3, 5, 6, 7]
    assert parse_records(None, "nearfield-no-pulse") == list(range(15, 29))
    assert parse_records("7, 2-3, 3", "farfield") == [7, 2, 3]
    for bad in ("0", "15", "3-1", "a", "1,,2", "1-2-3", ""):
        with pytest.raises(ParameterError):
            parse_records(bad, "nearfield-pulse")


@pytest.mark.parametrize("args, words", [
    (["--record-set", "midfield"], "record set = 'midfield': unknown"),
    (["--record-set", "nearfield-pulse", "--records", "1,20"], "--records '1,20': 20 lies outside the set"),
    (["--record-set", "farfield", "--records", "x"], "--records 'x': 'x' is not an ID"),
    (["--record-set", "farfield", "--records", "1", "--scale", "0"], "scale = 0: must be > 0"),
    (["--record-set", "farfield", "--records", "1", "--window", "10,90"], "window = 10,90: must satisfy"),
    (["--record-set", "farfield", "--records", "1", "--window", "ten,20"], "--window 'ten,20': expected T0,T1"),
    (["--record-set", "farfield", "--records", "1", "--no-device"], "--no-device: --record-set runs every record both"),
    (["--set", "farfield"], "--set 'farfield': expected NAME=VALUE (a parameter override); a record set is --record-set farfield"),
    (["--scale", "2"], "give exactly one of --record SET:ID, --ground KIND:K=V,... or --record-set SET"),
    (["--record-set", "farfield", "--workers", "0"], "--workers = 0"),
    (["--record", "farfield:1", "--records", "1"], "--records: applies to --record-set only"),
])
def test_set_bad_input_exit_2_one_line_nothing_written(tmp_path, capsys, args, words):
    from nsd_cli.main import main
    out = tmp_path / "x"
    code = main(["seismic", *args, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert words in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists()


def test_record_set_excludes_record(tmp_path, capsys):
    from nsd_cli.main import main
    out = tmp_path / "x"
    with pytest.raises(SystemExit) as e:
        main(["seismic", "--record-set", "farfield", "--record", "farfield:1", "--out", str(out)])
    err = capsys.readouterr().err
    assert e.value.code == 2 and "not allowed with argument --record" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_a_window_outside_one_record_of_the_set_is_bad_input(tmp_path, capsys):
    """Far-field 1 lasts 29.98 s, far-field 2 19.99 s: 25,29 fits the first, not the second."""
    from nsd_cli.main import main
    out = tmp_path / "x"
    code = main(["seismic", "--record-set", "farfield", "--records", "1,2", "--window", "25,29", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "window = 25,29" in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists()


@pytest.fixture(scope="module")
def set_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("set") / "run"
    p = nsd("seismic", *SHORT, "--workers", "2", "--out", str(out), env=FIGURES)
    assert p.returncode == 0, p.stderr
    return out, p


def test_set_rows_are_complete_and_match_the_per_record_runs(set_run):
    from nsd_core.device.results import read_csv
    out, _ = set_run
    table = rows(out / "set.csv")
    assert [r["id"] for r in table] == ["2", "3"]
    for r in table:
        assert r["status"] == "ok" and r["reason"] == "" and r["pulse"] == "yes" and r["earthquake"]
        for col in ("pga [m/s^2]", "peak_u [m]", "peak_u_nodevice [m]", "peak_u_ratio [-]", "peak_a_abs [m/s^2]",
                    "peak_a_abs_nodevice [m/s^2]", "peak_a_abs_ratio [-]", "residual_u [m]", "energy_residual [-]"):
            assert r[col] != "" and np.isfinite(float(r[col])), col
        dev = read_csv(out / "records" / f"nearfield-pulse_{r['id']}" / "seismic.csv")
        nod = read_csv(out / "records" / f"nearfield-pulse_{r['id']}_nodevice" / "seismic.csv")
        # the row is measured from the time series written beside it
        assert float(r["peak_u [m]"]) == pytest.approx(np.max(np.hypot(dev["x"], dev["y"])), rel=1e-8)
        assert float(r["peak_u_nodevice [m]"]) == pytest.approx(np.max(np.hypot(nod["x"], nod["y"])), rel=1e-8)
        assert float(r["peak_u_ratio [-]"]) == pytest.approx(
            float(r["peak_u [m]"]) / float(r["peak_u_nodevice [m]"]), rel=1e-8)
        assert np.all(nod["device_Fx"] == 0) and np.max(np.abs(dev["device_Fx"])) > 0
        assert float(r["energy_residual [-]"]) < 1e-3
        s = json.loads((out / "records" / f"nearfield-pulse_{r['id']}" / "summary.json").read_text())
        assert s["device"] is True and s["ground"]["record"] == int(r["id"]) and s["ground"]["window"] == [2.0, 2.6]
    index = json.loads((out / "set.json").read_text())
    assert index["counts"]["ok"] == 2 and index["records"] == [2, 3]


def test_a_finished_set_run_again_runs_nothing_and_writes_the_same_bytes(set_run):
    out, _ = set_run
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    p = nsd("seismic", *SHORT, "--workers", "2", "--out", str(out), env=FIGURES)
    assert p.returncode == 0 and "4 already stored, 0 to run" in p.stderr, p.stderr
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before


# enough runs that a SIGTERM sent once the first is stored lands mid-set (one run takes ~0.2 s)
KILLED = ["--record-set", "nearfield-pulse", "--records", "1-10", "--window", "2,2.6", "--dt-out", "0.002"]


@pytest.mark.slow
def test_a_killed_set_run_resumes_to_the_same_bytes(tmp_path):
    ref = tmp_path / "ref"
    whole = nsd("seismic", *KILLED, "--workers", "1", "--out", str(ref))
    assert whole.returncode in (0, 4), whole.stderr  # 4: a record reached the rod, kept in its row
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-m", "nsd_cli.main", "seismic", *KILLED, "--workers", "1",
                             "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 600
    while time.time() < deadline and not list(out.glob("designs/*/result.json")):
        time.sleep(0.01)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143 and "interrupted" in err and "Traceback" not in err, err
    kept = {p: p.read_bytes() for p in out.glob("designs/*/*")}
    assert 1 <= len(list(out.glob("designs/*/result.json"))) < 20 and not (out / "set.csv").exists()
    p = nsd("seismic", *KILLED, "--workers", "1", "--out", str(out))
    assert p.returncode == whole.returncode, p.stderr
    assert all(path.read_bytes() == data for path, data in kept.items())  # kept runs were not run again
    assert (out / "set.csv").read_bytes() == (ref / "set.csv").read_bytes()
    for f in ref.glob("records/*/seismic.csv"):
        assert (out / f.relative_to(ref)).read_bytes() == f.read_bytes()


@pytest.mark.slow
def test_a_record_that_reaches_the_rod_is_kept_in_its_row_and_the_others_run(tmp_path):
    out = tmp_path / "run"
    p = nsd("seismic", "--record-set", "nearfield-pulse", "--records", "1,2", "--window", "2,3", "--scale", "16",
            "--dt-out", "0.002", "--workers", "2", "--out", str(out))
    table = {r["id"]: r for r in rows(out / "set.csv")}
    assert p.returncode == 4, p.stderr
    assert table["1"]["status"] == "rod_reach" and float(table["1"]["rod_reach_t [s]"]) > 0
    assert "the rod cannot reach" in table["1"]["reason"]
    assert float(table["1"]["peak_u_nodevice [m]"]) > 0  # the supports alone still ran
    s = json.loads((out / "records" / "nearfield-pulse_1" / "summary.json").read_text())
    assert s["status"] == "failed" and s["reason"] == "rod_reach"
    assert table["2"]["status"] == "ok"


def _not_blank(png):
    import matplotlib.image as mpimg
    img = mpimg.imread(png)
    return png.stat().st_size > 20_000 and float(np.std(img)) > 0.02


def test_report_pages_of_a_set_run_exist_and_are_not_blank(set_run, tmp_path):
    out, _ = set_run
    rep = tmp_path / "report"
    p = nsd("report", "--from", str(out), "--out", str(rep))
    assert p.returncode == 0, p.stderr
    pngs = sorted(rep.glob("*.png"))
    names = [png.name for png in pngs]
    assert names[0] == "01_set_table.png" and (rep / "validation.pdf").stat().st_size > 10_000
    for rid in (2, 3):
        for kind in ("response", "loops", "energy"):
            assert any(n.endswith(f"{kind}_nearfield-pulse_{rid}.png") for n in names), (kind, rid, names)
    assert all(_not_blank(png) for png in pngs)
    # nsd seismic --set drew the same pages into its own folder, every text on its page and apart
    assert sorted(png.name for png in out.glob("[0-9][0-9]_*.png")) == names
    from page_checks import figure_problems
    assert not figure_problems(out, ("set_table", "response_nearfield-pulse_2", "loops_nearfield-pulse_2",
                                     "energy_nearfield-pulse_2"))


def test_report_of_a_single_run_with_a_peer_and_of_a_compare_folder_with_seismic_cases(set_run, tmp_path):
    """A single run: its pages; a compare folder's seismic/<case>__<engine>.csv: the same pages added."""
    from reports.seismic_report import compare_seismic_pages
    out, _ = set_run
    single = out / "records" / "nearfield-pulse_2"
    rep = tmp_path / "single"
    p = nsd("report", "--from", str(single), "--out", str(rep))
    assert p.returncode == 0, p.stderr
    assert json.loads((single / "summary.json").read_text())["warning_kinds"] == ["peaks_at_last_sample"]
    assert sorted(x.name for x in rep.glob("*.png")) == [   # the run's warnings page first (docs/seismic.md)
        "01_warnings_nearfield-pulse_2.png", "02_response_nearfield-pulse_2.png", "03_loops_nearfield-pulse_2.png",
        "04_energy_nearfield-pulse_2.png"]
    cmp_dir = tmp_path / "compare"
    (cmp_dir / "seismic").mkdir(parents=True)
    for eng in ("semirecursive", "mujoco"):  # the format seisgate writes: nsd seismic's columns
        (cmp_dir / "seismic" / f"pulse2__{eng}.csv").write_bytes((single / "seismic.csv").read_bytes())
    stems = [s for s, _ in compare_seismic_pages(cmp_dir)]
    assert stems == ["response_seismic_case_pulse2", "loops_seismic_case_pulse2", "energy_seismic_case_pulse2"]


def test_report_bad_seismic_folder_exit_2_nothing_written(tmp_path, capsys):
    from nsd_cli.main import main
    src = tmp_path / "src"
    src.mkdir()
    (src / "seismic.csv").write_text("t [s],u [m]\n0,0\n1,1\n")
    out = tmp_path / "rep"
    code = main(["report", "--from", str(src), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "malformed (no column 'x')" in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists()


@pytest.mark.slow   # ~27 s; the peers' seismic runs are compared in the default run by test_harness_seismic.py
def test_a_set_run_with_peer_engines_stores_their_differences(tmp_path):
    """--engines with --record-set: every peer's run is summarised like the in-house one (it once failed
    with KeyError 'ax_g': the peers did not write the ground's columns), its differences reach set.csv
    and the record's summary.json, and its CSV carries the same ground input as the in-house run's."""
    from nsd_core.device.results import read_csv
    out = tmp_path / "run"
    p = nsd("seismic", "--record-set", "nearfield-pulse", "--records", "2", "--window", "2,2.3", "--dt-out", "0.002",
            "--engines", "semirecursive,mujoco,exudyn", "--workers", "1", "--out", str(out))
    assert p.returncode == 0, p.stdout + p.stderr
    (row,) = rows(out / "set.csv")
    assert row["status"] == "ok" and row["reason"] == "", row
    summary = json.loads((out / "records" / "nearfield-pulse_2" / "summary.json").read_text())
    ref = read_csv(out / "records" / "nearfield-pulse_2" / "seismic.csv")
    for peer in ("mujoco", "exudyn"):
        diffs = summary["engines"][peer]
        for c in ("du", "dF", "da"):
            assert float(row[f"{peer}_{c} [-]"]) == pytest.approx(diffs[c], rel=1e-9)
            assert 0 < diffs[c] < 0.05, (peer, c, diffs[c])  # the engines agree; a broken peer would not
        other = read_csv(out / "records" / "nearfield-pulse_2" / f"seismic_{peer}.csv")
        for c in ("x_g", "y_g", "ax_g", "ay_g"):
            np.testing.assert_allclose(other[c], ref[c], rtol=0, atol=1e-12 * np.max(np.abs(ref[c])))
