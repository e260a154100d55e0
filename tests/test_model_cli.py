"""``nsd compare --model``: the table, verdict, results and exit codes for a described mechanism; bad
input is one line, exit 2, nothing written."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

MODELS = Path(__file__).resolve().parents[1] / "models"


def nsd(*args):
    return subprocess.run([sys.executable, "-m", "nsd_cli.main", *args], capture_output=True, text=True, timeout=600)


def test_compare_model_in_house_pass_with_reference_solution(tmp_path):
    out = tmp_path / "run"
    p = nsd("compare", "--model", str(MODELS / "slider_crank.toml"), "--engines", "semirecursive", "--out", str(out),
            "--junit", str(tmp_path / "j.xml"))
    assert p.returncode == 0, p.stdout + p.stderr
    s = json.loads((out / "results.json").read_text())
    v = s["cases"]["slider_crank_2turns"]["verdicts"]
    assert v["semirecursive"]["pass"] and v["converged"]["pass"]   # the converged run meets the closed form
    metrics = {r["metric"] for r in s["rows"]}
    assert {"slider_x", "slider_x vs solution", "tracking_error", "closure_max"} <= metrics
    header = (out / "slider_crank_2turns" / "semirecursive.csv").read_text().splitlines()[0]
    assert header == "t [s],slider_x [m],slider_v [m/s],rod_angle [rad],drive_torque [N m]"
    assert 'failures="0"' in (tmp_path / "j.xml").read_text()


def test_the_model_report_puts_at_most_six_outputs_on_an_a4_page(tmp_path):
    """A description with more outputs than fit one page (a copy of the slider-crank with its 4 outputs
    named twice more) gets its case drawn over A4 pages of at most 6 outputs, each page non-blank."""
    import tomllib
    import tomli_w
    from PIL import Image
    raw = tomllib.loads((MODELS / "slider_crank.toml").read_text())
    raw["outputs"] += [{**o, "name": f"{o['name']}_{k}"} for k in (2, 3) for o in raw["outputs"]]
    for c in raw["case"]:
        c.pop("reference", None)
    model = tmp_path / "many.toml"
    model.write_text(tomli_w.dumps(raw))
    out = tmp_path / "run"
    p = nsd("compare", "--model", str(model), "--engines", "semirecursive", "--out", str(out), "--report")
    assert p.returncode == 0, p.stdout + p.stderr
    pngs = sorted((out / "report").glob("model_page*.png"))
    assert [q.name for q in pngs] == [f"model_page{k}.png" for k in range(1, 4)]   # summary + 12 outputs / 6
    for q in pngs[1:]:
        w, h = Image.open(q).size
        assert abs(h / w - 11.69 / 8.27) < 0.01   # A4
        assert len(set(Image.open(q).convert("L").getdata())) > 50   # drawn, not blank


def test_compare_model_fails_when_the_reference_solution_disagrees(tmp_path):
    """A reference solution shifted by 1 mm: every engine, and the converged reference, disagree with it
    beyond numerical error (exit 1), while the engines still agree with each other."""
    text = (MODELS / "slider_crank_reference.csv").read_text().splitlines()
    rows = [text[0]] + [",".join([r.split(",")[0], repr(float(r.split(",")[1]) + 1e-3)] + r.split(",")[2:]) for r in text[1:]]
    (tmp_path / "ref.csv").write_text("\n".join(rows) + "\n")
    cases = tmp_path / "cases.toml"
    cases.write_text('[[case]]\nname = "shifted"\nduration = 0.1\ndt_out = 0.002\n'
                     'reference = { file = "ref.csv", source = "the closed form shifted by 1 mm" }\n')
    out = tmp_path / "run"
    p = nsd("compare", "--model", str(MODELS / "slider_crank.toml"), "--cases", str(cases), "--engines", "semirecursive",
            "--out", str(out))
    assert p.returncode == 1, p.stdout + p.stderr
    v = json.loads((out / "results.json").read_text())["cases"]["shifted"]["verdicts"]
    assert not v["converged"]["pass"] and "disagrees beyond numerical error: slider_x vs solution" in v["converged"]["text"]


BAD = [
    (["--model", "nope.toml"], "--model nope.toml: file not found"),
    (["--model", str(MODELS / "andrews.toml"), "--engines", "semirecursive,bullet"], "--engines 'bullet'"),
    (["--model", str(MODELS / "andrews.toml"), "--set", "n_wires=8"], "--profile/--set/--params"),
    (["--model", str(MODELS / "andrews.toml"), "--cases", str(MODELS / "slider_crank.toml")], "unknown table"),
]


@pytest.mark.parametrize("args,expected", BAD, ids=range(len(BAD)))
def test_bad_model_input_exit_2_nothing_written(tmp_path, args, expected):
    out = tmp_path / "never"
    p = nsd("compare", *args, "--out", str(out))
    assert p.returncode == 2, p.stdout + p.stderr
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and expected in lines[0], p.stderr
    assert not out.exists()


def test_bad_case_setting_exit_2(tmp_path):
    cases = tmp_path / "cases.toml"
    cases.write_text('[[case]]\nname = "c"\nduration = 0.01\ndt_out = 0.001\nsemirecursive = { rtol = -1.0 }\n')
    p = nsd("compare", "--model", str(MODELS / "andrews.toml"), "--cases", str(cases), "--engines", "semirecursive",
            "--out", str(tmp_path / "o"))
    assert p.returncode == 2 and "case.c.semirecursive.rtol = -1.0" in p.stderr, p.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("case,expected", [
    ('duration = 0.1\ndt_out = 0.002\nreference = { file = "ref.csv" }\n', "holds a value that is not a finite number"),
    ('duration = 1e4\ndt_out = 0.01\nmujoco = { timestep = 1e-8 }\n', "case.c.mujoco.timestep = 1e-08: 2e+12 steps"),
], ids=["nan-reference", "unbounded-steps"])
def test_hostile_cases_exit_2_nothing_written(tmp_path, case, expected):
    (tmp_path / "ref.csv").write_text("t,slider_x\n0,nan\n")
    (tmp_path / "cases.toml").write_text('[[case]]\nname = "c"\n' + case)
    p = nsd("compare", "--model", str(MODELS / "slider_crank.toml"), "--cases", str(tmp_path / "cases.toml"),
            "--engines", "semirecursive,mujoco", "--out", str(tmp_path / "o"))
    assert p.returncode == 2 and expected in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert not (tmp_path / "o").exists()
