"""The validation report (nsd report): built from a small real `nsd compare` run, no mocks.

One passing run (1 case, 1 cycle at 10 Hz, semirecursive and MuJoCo) is made once per session; a
failing run is made from it by tightening a limit in a copy of its results.json (what a failed
gate writes), and a malformed folder by damaging a copy.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NSD = [sys.executable, "-m", "nsd_cli.main"]
CASES = """[defaults]
cycles = 1
samples_per_cycle = 200
[[case]]
name = "A15mm_f10Hz"
amplitude = 0.015
frequency = 10.0
"""
EXPECTED = ["summary", "parameters", "cycles", "stiffness", "breakdown", "convergence", "cost", "closure"]


def nsd(*args, timeout=300):
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.run(NSD + list(args), capture_output=True, text=True, timeout=timeout, cwd=ROOT, env=env)


@pytest.fixture(scope="session")
def run_dir(tmp_path_factory):
    base = tmp_path_factory.mktemp("report")
    cases = base / "cases.toml"
    cases.write_text(CASES)
    out = base / "run"
    p = nsd("compare", "--cases", str(cases), "--engines", "semirecursive,mujoco", "--workers", "2",
            "--out", str(out))
    assert p.returncode in (0, 1), p.stderr[-2000:]
    return out, p.returncode


@pytest.fixture(scope="session")
def report(run_dir, tmp_path_factory):
    from reports.build import build_report
    out = tmp_path_factory.mktemp("rep") / "report"
    start = time.perf_counter()
    paths = build_report(run_dir[0], out)
    return paths, time.perf_counter() - start


@pytest.fixture(scope="session")
def failing_dir(run_dir, tmp_path_factory):
    """The same run judged against a limit it cannot meet: what nsd compare writes for a failed gate."""
    src = run_dir[0]
    dst = tmp_path_factory.mktemp("fail") / "run"
    shutil.copytree(src, dst)
    s = json.loads((dst / "results.json").read_text())
    s["tolerances"]["max_dF_rel"] = 1e-12
    for m in s["metrics"]:
        if m["metric"] == "max_dF_rel":
            m["limit"], m["pass"] = 1e-12, bool(m["value"] <= 1e-12)
    bad = [m for m in s["metrics"] if m["gated"] and not m["pass"]]
    assert bad, "the MuJoCo run should differ from the reference by more than 1e-12"
    s["failures"] = [f"{m['case']}: {m['engine']} {m['metric']} = {m['value']:.3g} > {m['limit']:.3g}" for m in bad]
    s["verdict"], s["exit_code"] = "FAIL", 1
    (dst / "results.json").write_text(json.dumps(s))
    return dst, s


def _page_text(pdf, i=0):
    from pypdf import PdfReader
    return " ".join(PdfReader(pdf).pages[i].extract_text().split())


def test_pdf_has_the_expected_pages(report):
    from pypdf import PdfReader
    paths, _ = report
    pdf = Path(paths["pdf"])
    assert pdf.is_file() and pdf.name == "validation.pdf"
    assert paths["pages"] == EXPECTED
    assert len(PdfReader(pdf).pages) == len(EXPECTED)
    assert "Parameter set and provenance" in _page_text(pdf, 1)
    assert "Convergence" in _page_text(pdf, 5)  # no study in this run: the page says how to make one
    assert "nsd compare --cases FILE --convergence" in _page_text(pdf, 5)
    assert not list(pdf.parent.glob(".*tmp*")), "temporary files left behind"


def test_every_png_exists_and_is_not_blank(report):
    import matplotlib.image as mpimg
    paths, _ = report
    assert len(paths["pngs"]) == len(EXPECTED)
    for png, stem in zip(paths["pngs"], EXPECTED):
        assert Path(png).name.endswith(f"_{stem}.png") and Path(png).is_file()
        img = mpimg.imread(png)[..., :3]
        assert img.std() > 0.01, png
        assert (img < 0.95).mean() > 0.002, f"{png} is (nearly) all white"


def test_summary_verdict_matches_the_run(run_dir, report):
    out, code = run_dir
    paths, _ = report
    verdict = {0: "PASS", 1: "FAIL", 3: "ERROR"}[code]
    assert json.loads((out / "results.json").read_text())["exit_code"] == code
    text = _page_text(paths["pdf"])
    assert f"VERDICT: {verdict}" in text
    assert f"exit code {code}" in text
    for name in ("semirecursive", "mujoco", "max_dF_rel", "A15mm_f10Hz"):
        assert name in text


def test_failing_run_names_the_failure_on_page_one(failing_dir, tmp_path):
    from reports.build import build_report
    src, s = failing_dir
    paths = build_report(src, tmp_path / "r")
    text = _page_text(paths["pdf"])
    assert "VERDICT: FAIL" in text and "WHAT FAILED" in text
    assert text.index("WHAT FAILED") < text.index("What was run")  # failures come first
    assert "A15mm_f10Hz: mujoco max_dF_rel" in text


def test_error_run_and_missing_engine_output_still_render(run_dir, tmp_path):
    """An engine that failed on a case (exit 3) has no CSV: the report says so instead of breaking."""
    from reports.build import build_report
    dst = tmp_path / "run"
    shutil.copytree(run_dir[0], dst)
    s = json.loads((dst / "results.json").read_text())
    case = s["cases"][0]["name"]
    s["runs"][case]["mujoco"] = {"status": "error", "message": "SolverError: diverged at t = 0.01 s",
                                 "wall_time": 0.1}
    s["metrics"] = [m for m in s["metrics"] if m["engine"] != "mujoco"]
    s["failures"] = [f"{case}: mujoco failed: SolverError: diverged at t = 0.01 s"]
    s["verdict"], s["exit_code"] = "ERROR", 3
    (dst / "results.json").write_text(json.dumps(s))
    paths = build_report(dst, tmp_path / "r")
    text = _page_text(paths["pdf"])
    assert "VERDICT: ERROR" in text and "diverged" in text


@pytest.mark.parametrize("damage", ["missing_folder", "no_results", "not_json", "not_compare", "missing_csv"])
def test_bad_input_exits_2_and_writes_nothing(run_dir, tmp_path, damage):
    src = tmp_path / "run"
    if damage != "missing_folder":
        shutil.copytree(run_dir[0], src)
    if damage == "no_results":
        (src / "results.json").unlink()
    elif damage == "not_json":
        (src / "results.json").write_text("{ not json")
    elif damage == "not_compare":
        (src / "results.json").write_text(json.dumps({"problems": {}}))
    elif damage == "missing_csv":
        # an engine's run (the folder also keeps the converged reference's, which the report does not read)
        next(f for f in sorted((src / "cycles").glob("*.csv")) if "__converged" not in f.name).unlink()
    out = tmp_path / "out"
    p = nsd("report", "--from", str(src), "--out", str(out), timeout=120)
    assert p.returncode == 2, p.stdout + p.stderr
    assert p.stderr.startswith("nsd: error: ") and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert not out.exists()


def test_cli_writes_the_report_quickly(run_dir, tmp_path):
    out = tmp_path / "cli"
    start = time.perf_counter()
    p = nsd("report", "--from", str(run_dir[0]), "--out", str(out), timeout=120)
    elapsed = time.perf_counter() - start
    assert p.returncode == 0, p.stderr
    assert (out / "validation.pdf").is_file() and len(list(out.glob("*.png"))) == len(EXPECTED)
    assert elapsed < 30.0


def test_generation_time_under_30_s(report):
    _, seconds = report
    assert seconds < 30.0


def test_extra_pages_when_the_folder_has_them(run_dir, tmp_path):
    """Benchmark and study folders (written by nsd benchmark / nsd sweep) each add a page."""
    from reports.build import build_report
    dst = tmp_path / "run"
    shutil.copytree(run_dir[0], dst)
    s = json.loads((dst / "results.json").read_text())
    s["convergence"] = {"mujoco": {"setting": "timestep", "case": s["cases"][0]["name"], "reference": "semirecursive",
                                   "points": [{"value": v, "max_dF_rel": 4 * v, "loop_area_rel": v, "wall_time": 1e-5 / v}
                                              for v in (4e-5, 2e-5, 1e-5)]}}
    (dst / "results.json").write_text(json.dumps(s))
    (dst / "benchmark").mkdir()
    (dst / "benchmark" / "results.json").write_text(json.dumps({"quick": True, "problems": {
        "andrews": {"error": 1e-10, "min_digits": 10.0, "cpu_time": 0.1, "passed": True,
                    "work_precision": [{"rtol": 1e-8, "min_digits": 6.6, "wall_time": 0.05, "method": "DOP853"},
                                       {"rtol": 1e-10, "min_digits": 9.4, "wall_time": 0.1, "method": "DOP853"}]},
        "slider_crank": {"error": 1e-15, "cpu_time": 0.01, "goal": 1e-10, "passed": True}}}))
    paths = build_report(dst, tmp_path / "r")
    assert paths["pages"] == EXPECTED + ["benchmark"]
    assert "max |dF| against cost" in _page_text(paths["pdf"], 5)
    assert "Andrews" in _page_text(paths["pdf"], len(EXPECTED))


def test_tables_page_from_nsd_tables(run_dir, tmp_path):
    """`nsd tables --out DIR/study` adds the Tables 5-6 page (paper against model)."""
    from reports.build import build_report
    dst = tmp_path / "run"
    shutil.copytree(run_dir[0], dst)
    p = nsd("tables", "--out", str(dst / "study"))
    assert p.returncode == 0, p.stderr
    paths = build_report(dst, tmp_path / "r")
    assert paths["pages"] == EXPECTED + ["tables"]
    text = _page_text(paths["pdf"], len(EXPECTED))
    assert "Tables 5 and 6" in text and "worst" in text


def test_work_precision_page_when_the_folder_has_it(run_dir, tmp_path):
    """benchmarks/work_precision.py's JSON under work_precision/ adds the work-precision page; a
    malformed one is skipped (an optional page never breaks the report)."""
    from reports.build import build_report
    dst = tmp_path / "run"
    shutil.copytree(run_dir[0], dst)
    (dst / "work_precision").mkdir()
    runs = [{"engine": "semirecursive", "settings": {"rtol": r, "max_step": 1.0}, "case_default": False,
             "cpu_per_cycle": c, "dF": e} for r, c, e in ((1e-3, 0.2, 4e-4), (1e-4, 0.3, 3e-5))]
    runs += [{"engine": "mujoco", "settings": {"integrator": "Euler", "timestep": h}, "case_default": h == 1e-5,
              "cpu_per_cycle": 1e-6 / h, "dF": 4 * h, "step_used": h} for h in (5e-5, 2.5e-5, 1e-5)]
    runs += [{"engine": "exudyn", "settings": {"step_size": 2.5e-4}, "case_default": False, "cpu_per_cycle": 0.3,
              "dF": 2.8e-5, "step_used": 2.5e-4}]
    at = {"semirecursive": runs[1], "mujoco": runs[3], "exudyn": runs[5]}
    wp = {"aim": 1e-4, "repeats": 3, "cpus": 2, "load_average_start": [3.0, 3.0, 3.0],
          "cases": [{"name": "A15mm_f1Hz", "runs": runs, "at_aim": at, "ratio_best_peer_over_in_house": 0.1 / 0.3}],
          "compile": {"mujoco": {"warm": {"startup_s": 1.5}, "cold": {"startup_s": 20.0}}}}
    (dst / "work_precision" / "work_precision.json").write_text(json.dumps(wp))
    paths = build_report(dst, tmp_path / "r")
    assert paths["pages"] == EXPECTED + ["work_precision"]
    text = _page_text(paths["pdf"], len(EXPECTED))
    assert "Work-precision" in text and "A15mm_f1Hz" in text and "0.333" in text and "Euler h 2.50e-05" in text
    (dst / "work_precision" / "work_precision.json").write_text('{"cases": "none"}')
    assert build_report(dst, tmp_path / "r2")["pages"] == EXPECTED
