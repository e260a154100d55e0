"""nsd cycle with paths in the plane, and the direction study nsd polar."""
import json
import subprocess
import sys

import numpy as np
import pytest

from nsd_core.device.params import Params
from nsd_core.device.results import read_csv
from nsd_core.study.polar import polar_study


def nsd(*args):
    return subprocess.run([sys.executable, "-m", "nsd_cli.main", *args], capture_output=True, text=True, timeout=600)


def test_circle_from_the_cli_writes_the_force_vector(tmp_path):
    out = tmp_path / "run"
    p = nsd("cycle", "--path", "circle", "--amplitude", "0.015", "--frequency", "10", "--cycles", "3",
            "--samples-per-cycle", "100", "--out", str(out))
    assert p.returncode == 0, p.stderr
    r = read_csv(out / "cycle.csv")
    for col in ("x", "y", "F_x", "F_y", "F_tangent", "F_radial", "rope0_tension", "wire3_stress"):
        assert col in r.columns
    s = json.loads((out / "summary.json").read_text())
    assert s["drive"]["path"] == "circle" and s["work_per_cycle"] > 0 and s["peak_force_magnitude"] > 1000
    assert "peak |F|" in p.stdout


@pytest.mark.parametrize("args, words", [
    (["--path", "ellipse", "--amplitude", "0.015"], "minor: missing"),
    (["--path", "circle"], "--amplitude: missing"),
    (["--path", "nosuch.csv"], "no such file"),
    (["--path", "circle", "--amplitude", "0.015", "--minor", "0.01"], "only an ellipse or a figure8"),
])
def test_bad_path_input_exit_2_and_nothing_written(tmp_path, args, words):
    out = tmp_path / "x"
    p = nsd("cycle", *args, "--frequency", "10", "--out", str(out))
    assert p.returncode == 2 and words in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_polar_bad_input(tmp_path):
    p = nsd("polar", "--wires", "2,4", "--out", str(tmp_path / "p"))
    assert p.returncode == 2 and "wires" in p.stderr and not (tmp_path / "p").exists()
    p = nsd("polar", "--step", "7", "--out", str(tmp_path / "p"))
    assert p.returncode == 2 and "step" in p.stderr


def test_polar_study_shows_the_patterns_symmetry():
    res = polar_study((4, 8), step_deg=45.0, amplitude=0.015, base=Params(), points_per_cycle=40)
    d4, d8 = res["designs"]["4"], res["designs"]["8"]
    for key in ("k0", "k_min", "loop_area", "peak_force"):
        v4, v8 = np.array(d4[key]), np.array(d8[key])
        np.testing.assert_allclose(v4[::2], v4[0], rtol=1e-6)  # n = 4: 0, 90, 180, 270 deg alike
        np.testing.assert_allclose(v8, v8[0], rtol=1e-6)       # n = 8: every 45 deg alike
    assert abs(d4["peak_force"][1] / d4["peak_force"][0] - 1) > 0.05  # n = 4: 45 deg differs
