"""The nsd command as a user runs it: outputs, units, exit codes."""
import json
import subprocess
import sys

import numpy as np
import pytest

from nsd_core.device.results import read_csv


def nsd(*args):
    return subprocess.run([sys.executable, "-m", "nsd_cli.main", *args], capture_output=True, text=True, timeout=600)


@pytest.mark.parametrize("A,f", [(0.015, 1.0), (0.015, 10.0), (0.0255, 1.0), (0.0255, 10.0)])
def test_figure6_cases_from_the_cli(tmp_path, A, f):
    out = tmp_path / "run"
    p = nsd("cycle", "--amplitude", str(A), "--frequency", str(f), "--samples-per-cycle", "500", "--out", str(out))
    assert p.returncode == 0, p.stderr
    header = (out / "cycle.csv").read_text().splitlines()[0]
    assert header.startswith("t [s],u [m],F [N],F_device [N]") and "wire0_stress [Pa]" in header
    s = json.loads((out / "summary.json").read_text())
    for key in ("peak_force", "loop_area", "x_max", "stiffness_regions", "solver", "wall_time", "versions",
                "params", "events"):
        assert key in s
    assert s["versions"]["numpy"] and len(s["params"]) > 30
    signs = [r["sign"] for r in s["stiffness_regions"]]
    assert signs[:2] == ["+", "-"]  # Figure 7: positive at the origin, then the negative plateau
    if A == 0.0255:
        assert signs[-1] == "+" and s["outside_working_range"]  # positive again at the edge, ropes slack
        assert 0.0245 < s["x_max"] <= 0.0255
    else:
        assert not s["outside_working_range"] and s["x_max"] is None
    r = read_csv(out / "cycle.csv")
    assert s["loop_area"] > 0 and np.isfinite(r["F"]).all()


def test_bad_input_exit_2_and_nothing_written(tmp_path):
    out = tmp_path / "x"
    for args in (["--set", "wire_inclination_deg=50"], ["--set", "rod_length=nan"], ["--set", "bogus=1"],
                 ["--params", str(tmp_path / "missing.toml")]):
        p = nsd("cycle", "--amplitude", "0.01", "--frequency", "1", *args, "--out", str(out))
        assert p.returncode == 2, args
        assert len(p.stderr.strip().splitlines()) == 1 and "error" in p.stderr
    assert not out.exists()


def test_drive_beyond_the_rod_exit_4(tmp_path):
    p = nsd("cycle", "--amplitude", "0.03", "--frequency", "1", "--out", str(tmp_path / "y"))
    assert p.returncode == 4 and "cannot follow" in p.stderr
    assert not (tmp_path / "y").exists()


def test_state_outside_the_laws_validity_exit_4(tmp_path):
    # a long rod and steep wires let the cap strain the wires beyond the law's range (20 %)
    p = nsd("cycle", "--amplitude", "0.09", "--frequency", "10", "--set", "rod_length=0.1", "--set",
            "wire_inclination_deg=40", "--cycles", "1",
            "--samples-per-cycle", "200", "--out", str(tmp_path / "z"))
    assert p.returncode == 4 and "validity" in p.stderr, p.stderr
    assert not (tmp_path / "z").exists()
