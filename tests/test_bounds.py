"""Bounded work and honest output: step caps give "exceeded N steps" (exit 3), a gate that
measured nothing is not a PASS, a partial tolerance file takes the default limits and says so,
files respect the umask, engine chatter stays off stdout, and `nsd --help` agrees with the README."""
import os
import re
from pathlib import Path

import pytest

from comparisons.config import DEFAULT_TOLERANCES, METRICS
from comparisons.tolerance_file import load_tolerances
from comparisons.engines.base import EngineError
from nsd_cli.compare import format_table
from nsd_cli.main import build_parser, main
from nsd_core.device.drive import Drive
from nsd_core.device.params import Params
from nsd_core.common.files import atomic_write_text

ROOT = Path(__file__).resolve().parents[1]


def test_cycle_that_needs_too_many_steps_exits_3(tmp_path, capsys, monkeypatch):
    import nsd_core.device.model as model
    monkeypatch.setattr(model, "MAX_STEPS_PER_CYCLE", 10)
    code = main(["cycle", "--amplitude", "0.015", "--frequency", "10", "--cycles", "1", "--samples-per-cycle", "100",
                 "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 3 and "exceeded 10 steps" in err, err
    assert not (tmp_path / "out" / "cycle.csv").exists()


@pytest.mark.parametrize("engine,setting", [("exudyn", "step_size"), ("mujoco", "timestep")])
def test_fixed_step_engines_refuse_runaway_step_counts(engine, setting):
    from comparisons.engines import get_engine
    drive = Drive(0.01, 0.05, cycles=1, samples_per_cycle=100)  # 20 s at the 1e-8 s floor: 2e9 steps
    with pytest.raises(EngineError, match="exceeded 20000000 steps"):
        get_engine(engine).run(Params(), drive, {setting: 1e-8})


def test_partial_tolerance_file_takes_the_default_limits_and_says_so(tmp_path):
    f = tmp_path / "t.toml"
    f.write_text("[limits]\nmax_dF_rel = 2e-3\n")
    limits = load_tolerances(f)
    # a fixed-limit file's defaults are the regression profile's (the default file states the rule instead)
    defaults = load_tolerances(DEFAULT_TOLERANCES.with_name("limits_regression.toml"))
    assert limits["max_dF_rel"] == 2e-3 and limits.rule is None
    assert set(limits) == set(METRICS) and set(limits.defaulted) == set(METRICS) - {"max_dF_rel"}
    assert all(limits[k] == defaults[k] for k in limits.defaulted)
    row = {"case": "q", "engine": "mujoco", "reference": None, "metric": "closure_max", "value": 1e-9,
           "limit": 1e-6, "pass": True, "gated": True}
    table = format_table({"metrics": [row], "runs": {}, "tolerances_defaulted": list(limits.defaulted)})
    assert "closure_max" in table and "(default limit)" in table


def test_a_gate_that_measured_nothing_is_not_a_pass(tmp_path):
    from comparisons.config import load_cases
    from comparisons.harness import compare
    cases = tmp_path / "c.toml"
    cases.write_text('[[case]]\nname = "q"\namplitude = 0.015\nfrequency = 10.0\ncycles = 1\nsamples_per_cycle = 100\n')
    # a seismic metric only, on a drive case: nothing is gated (the in-house run is gated against the
    # converged reference on the drive metrics, so a drive metric would be measured)
    summary = compare(load_cases(cases), ["semirecursive"], {"max_du_rel": 1e-3}, tmp_path / "out", workers=1,
                      log=lambda s: None)
    assert summary["exit_code"] == 3 and summary["verdict"] == "ERROR"
    assert any("nothing was gated" in f for f in summary["failures"])


@pytest.mark.parametrize("umask,mode", [(0o022, 0o644), (0o002, 0o664), (0o077, 0o600)])
def test_written_files_respect_the_umask(tmp_path, umask, mode):
    old = os.umask(umask)
    try:
        atomic_write_text(tmp_path / "x.json", "{}")
    finally:
        os.umask(old)
    assert (tmp_path / "x.json").stat().st_mode & 0o777 == mode


def test_engine_output_goes_to_stderr(capfd):
    from nsd_core.engine.workers import stdout_to_stderr
    with stdout_to_stderr():
        os.write(1, b"engine chatter\n")  # as C++ code writes it, below Python's sys.stdout
    out, err = capfd.readouterr()
    assert out == "" and "engine chatter" in err


def test_help_is_whole_and_agrees_with_the_readme():
    parser = build_parser()
    text = parser.format_help()
    assert text.rstrip().endswith("for each command's options.")
    subs = next(a for a in parser._actions if a.dest == "command").choices
    readme = (ROOT / "README.md").read_text()
    rows = re.findall(r"^\| `nsd (\w+)(?: ([^`]*))?`", readme, flags=re.M)   # a command without options too
    assert {name for name, _ in rows} == set(subs)
    for name, usage in rows:
        flags = set(re.findall(r"--[a-z][a-z-]*", usage))
        known = {s for a in subs[name]._actions for s in a.option_strings}
        assert flags <= known, f"README lists {sorted(flags - known)} for nsd {name}"
        optional = set(re.findall(r"\[(--[a-z-]+)", usage))
        required = {s for a in subs[name]._actions if a.required for s in a.option_strings}
        assert not optional & required, f"README shows {sorted(optional & required)} of nsd {name} as optional"
