"""``nsd compare --model FILE --refine``: a peer that is 'not converged at these
settings' runs again at the step its own estimate asks for (comparisons.refine's rule and cap), only its
runs are new, the case is judged again, and results.json records the change under "refined"."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from comparisons.estimate import step_used
from nsd_cli.main import main

MODELS = Path(__file__).resolve().parents[1] / "models"
FOURBAR = (MODELS / "fourbar_spring.toml").read_text()


def case(text: str, duration: float, **engines: str) -> str:
    """The four-bar with its case shortened and the given engine tables (e.g. exudyn='step_size = 2e-3')."""
    body = text[: text.index("[[case]]")]
    tables = "".join(f"{e} = {{ {s} }}\n" for e, s in engines.items())
    return body + f'[[case]]\nname = "short"\nduration = {duration!r}\ndt_out = 0.01\n' + tables


def nsd(capsys, *args) -> tuple[int, str, str]:
    code = main(["compare", *args])
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def verdict_lines(stdout: str, engine: str) -> list[str]:
    """The table's lines of ``engine`` (the first verdicts, then the refined ones)."""
    return [ln for ln in stdout.splitlines() if ln.split()[:2] == ["short", engine]]


def test_refine_reruns_a_coarse_peer_finer_and_the_verdict_becomes_pass(tmp_path, capsys):
    """Exudyn at 2e-3 s is not converged on the four-bar (crank angle ~2.4e-3 of its scale > 1e-3):
    --refine re-runs it at the step its estimate asks (~1.2e-3 s) and the printed verdict is PASS."""
    model = tmp_path / "m.toml"
    model.write_text(case(FOURBAR, 0.5, exudyn="step_size = 2e-3"))
    out = tmp_path / "out"
    code, stdout, stderr = nsd(capsys, "--model", str(model), "--engines", "semirecursive,exudyn", "--out", str(out),
                               "--refine")
    assert code == 0, stdout + stderr
    first, last = verdict_lines(stdout, "exudyn")
    assert "FAIL  not converged at these settings" in first and "needs step_size <=" in first
    assert "PASS" in last
    assert "refined short: exudyn step_size 0.002 -> 0.00" in stdout
    s = json.loads((out / "results.json").read_text())
    (r,) = s["refined"]
    assert (r["case"], r["engine"], r["setting"], r["from"]) == ("short", "exudyn", "step_size", 0.002)
    assert 0.002 / 8 <= r["to"] < 0.002 and not r["capped"]
    runs = s["cases"]["short"]["runs"]
    used = step_used(r["to"], 0.01)   # the step the run takes: the largest <= the setting dividing dt_out
    assert runs["exudyn"]["step_size"] == pytest.approx(used) and runs["exudyn_h2"]["step_size"] == pytest.approx(used / 2)
    assert s["passed"] and s["cases"]["short"]["verdicts"]["exudyn"]["pass"]
    assert {row["case"] for row in s["rows"]} == {"short"}
    assert len([row for row in s["rows"] if row["engine"] == "exudyn"]) == len({row["metric"] for row in s["rows"]
                                                                                 if row["engine"] == "exudyn"})
    assert (out / "short" / "exudyn.csv").exists()


def test_refine_with_nothing_to_refine_says_so_and_records_an_empty_list(tmp_path, capsys):
    model = tmp_path / "m.toml"
    model.write_text(case(FOURBAR, 0.05))
    out = tmp_path / "out"
    code, stdout, stderr = nsd(capsys, "--model", str(model), "--engines", "semirecursive", "--out", str(out), "--refine")
    assert code == 0, stdout + stderr
    assert "--refine: no peer is 'not converged at these settings'" in stdout
    assert json.loads((out / "results.json").read_text())["refined"] == []


def test_a_refined_step_past_the_step_count_bound_is_capped_there():
    """The bound checked before any run (MAX_FIXED_STEPS for the h/2 run) holds for a refined step too:
    a step past it is capped at the bound and said; one already at the bound is not refined."""
    from comparisons.engines.base import MAX_FIXED_STEPS
    from comparisons.model_cases import ModelCase
    from comparisons.refine import refinements
    from nsd_cli.compare_model import _bounded
    duration = 100.0
    lowest = 2 * duration / MAX_FIXED_STEPS   # 1e-5 s
    cases = [ModelCase("a", duration, 0.1, {"exudyn": {"step_size": 4e-5}}),
             ModelCase("b", duration, 0.1, {"exudyn": {"step_size": lowest}})]
    summary = {"verdicts": {n: {"exudyn": {"needs": {"step_size": 1e-6}, "step": s, "setting": "step_size",
                                           "consistent": True, "accurate": False}}
                            for n, s in (("a", 4e-5), ("b", lowest))}}
    refined, changes = refinements(cases, summary)
    assert [r["to"] for r in changes] == [5e-6, lowest / 8]   # the 8x cap alone: past the step-count bound
    refined, changes, lines = _bounded(refined, cases, changes)
    (r,) = changes
    assert r["case"] == "a" and r["to"] == pytest.approx(lowest) and r["capped"]
    assert refined[0].settings["exudyn"]["step_size"] == pytest.approx(lowest)
    assert refined[1].settings["exudyn"]["step_size"] == lowest          # b: as it was
    assert f"capped: at most {MAX_FIXED_STEPS} steps with its h/2 run" in lines[0]
    assert "b: exudyn not refined" in lines[1]


def test_refine_a_coarse_mujoco_step(tmp_path, capsys):
    """MuJoCo at 1e-2 s on the four-bar over 2 s (crank angle ~1.9e-3 of its scale, and its closure over
    1e-6 m): refined to the step its estimate asks (~6.6e-3 s), where both pass."""
    model = tmp_path / "m.toml"
    model.write_text(case(FOURBAR, 2.0, mujoco="timestep = 1e-2"))
    out = tmp_path / "out"
    code, stdout, stderr = nsd(capsys, "--model", str(model), "--engines", "semirecursive,mujoco", "--out", str(out),
                               "--refine")
    first, last = verdict_lines(stdout, "mujoco")
    assert "not converged at these settings" in first and "PASS" in last, stdout
    assert code == 0, stdout + stderr
    assert json.loads((out / "results.json").read_text())["refined"][0]["engine"] == "mujoco"
