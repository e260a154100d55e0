"""nsd compare: the gate passes on agreeing engines, fails on a perturbed one, reports failures."""
import json
import subprocess
import sys

import pytest

CASE = """
[defaults]
cycles = 1
samples_per_cycle = 1000   # the energy balance is a trapezoid quadrature: ~7e-4 at 100 samples, ~2e-6 at 2000
[[case]]
name = "quick"
amplitude = 0.015
frequency = 10.0
"""


def nsd(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "nsd_cli.main", *args], capture_output=True, text=True,
                          timeout=600, cwd=cwd)


@pytest.fixture(scope="module")
def perturbed(tmp_path_factory):
    d = tmp_path_factory.mktemp("gate")
    cases = d / "cases.toml"
    cases.write_text(CASE + """
[[case]]
name = "stiff_ropes"
amplitude = 0.015
frequency = 10.0
engine_params.mujoco = { rope_stiffness = 6.0e5 }   # +20 % for one engine only
""")
    out = d / "out"
    p = nsd("compare", "--cases", str(cases), "--engines", "semirecursive,mujoco", "--out", str(out),
            "--junit", str(d / "junit.xml"))
    return p, out, d


def test_gate_fails_and_names_case_and_metric(perturbed):
    p, out, d = perturbed
    assert p.returncode == 1, p.stderr
    assert "FAILED stiff_ropes: mujoco disagrees beyond numerical error" in p.stdout, p.stdout
    res = json.loads((out / "results.json").read_text())
    assert not res["verdicts"]["stiff_ropes"]["mujoco"]["consistent"]
    assert res["verdicts"]["quick"]["mujoco"]["pass"] and res["verdicts"]["stiff_ropes"]["semirecursive"]["pass"]
    assert res["verdict"] == "FAIL" and res["exit_code"] == 1
    # the unperturbed case passes inside the same run: the engines agree to well within 0.1 %
    quick = [m for m in res["metrics"] if m["case"] == "quick" and m["gated"]]
    assert quick and all(m["pass"] for m in quick)
    dF = next(m["value"] for m in quick if m["metric"] == "max_dF_rel")
    assert dF < 1e-3
    assert (out / "cycles" / "quick__mujoco.csv").exists() and (out / "cycles" / "stiff_ropes__semirecursive.csv").exists()
    junit = (d / "junit.xml").read_text()
    assert 'name="stiff_ropes.mujoco"' in junit and "<failure" in junit and 'failures="1"' in junit
    assert "disagrees beyond numerical error" in junit


def test_engine_failure_is_reported_for_its_case_and_others_kept(tmp_path):
    cases = tmp_path / "cases.toml"
    cases.write_text(CASE + """
[[case]]
name = "broken"
frequency = 10.0
amplitude = 0.0305   # beyond the rod: the engine refuses it at run time (a bad setting would be exit 2)
""")
    out = tmp_path / "out"
    p = nsd("compare", "--cases", str(cases), "--engines", "semirecursive", "--out", str(out))
    assert p.returncode == 3, p.stdout + p.stderr
    res = json.loads((out / "results.json").read_text())
    assert res["runs"]["broken"]["semirecursive"]["status"] == "error"
    assert "amplitude" in res["runs"]["broken"]["semirecursive"]["message"]
    assert res["runs"]["quick"]["semirecursive"]["status"] == "ok"
    assert (out / "cycles" / "quick__semirecursive.csv").exists()


@pytest.mark.parametrize("args,fragment", [
    (["--engines", "semirecursive,bullet"], "unknown engine"),
    (["--tolerances", "{tol}"], "unknown metric"),
    (["--cases", "{badcase}"], "unknown key"),
    (["--set", "n_ropes=2"], "n_ropes = 2"),
])
def test_bad_input_exits_2_and_writes_nothing(tmp_path, args, fragment):
    tol = tmp_path / "tol.toml"
    tol.write_text("[limits]\nmax_dF = 1e-3\n")
    bad = tmp_path / "bad.toml"
    bad.write_text(CASE.replace("frequency = 10.0", "frequency = 10.0\nfrequncy = 3"))
    args = [a.format(tol=tol, badcase=bad) for a in args]
    out = tmp_path / "out"
    p = nsd("compare", *args, "--out", str(out))
    assert p.returncode == 2
    assert fragment in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize("seismic", [False, True], ids=["drive", "seismic"])
def test_a_non_finite_output_is_that_engine_s_failure_not_a_result(monkeypatch, seismic):
    """A real MuJoCo run whose output gets one NaN (a fault injected after the engine ran): the job
    comes back as that engine's error naming the column and sample, never as a result to measure."""
    import comparisons.engines as E
    from nsd_core.device.drive import Drive
    from nsd_core.structure.isolation import default_structure
    from nsd_core.device.params import Params
    from nsd_core.compilation.warmup import tiny_ground
    real = E.run_seismic_engine if seismic else E.run_engine

    def poisoned(*args, **kwargs):
        result = real(*args, **kwargs)
        result.columns["t"] = result.columns["t"].copy()
        result.columns["t"][3] = float("nan")
        return result

    monkeypatch.setattr(E, "run_seismic_engine" if seismic else "run_engine", poisoned)
    if seismic:
        job = E.run_seismic_job("mujoco", Params(), default_structure(Params()), tiny_ground(), 0.004, 1e-3, {})
    else:
        job = E.run_job("mujoco", Params(), Drive(0.002, 10.0, cycles=1, samples_per_cycle=20), {})
    assert job["status"] == "error", job
    assert job["message"].startswith("SolverError: a non-finite output: t[3] = nan"), job["message"]
    monkeypatch.undo()   # the same run unpoisoned is a result
    job = (E.run_seismic_job("mujoco", Params(), default_structure(Params()), tiny_ground(), 0.004, 1e-3, {})
           if seismic else E.run_job("mujoco", Params(), Drive(0.002, 10.0, cycles=1, samples_per_cycle=20), {}))
    assert job["status"] == "ok", job
