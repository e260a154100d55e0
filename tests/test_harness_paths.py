"""The gate on a path off the axis: it passes on agreeing engines and catches an error
that only shows as a direction, the wire pattern turned by 5 deg in one engine."""
import json
import subprocess
import sys

CASES = """
[defaults]
cycles = 3
samples_per_cycle = 300
[[case]]
name = "circle"
path = "circle"
amplitude = 0.015
frequency = 10.0
[[case]]
name = "circle_turned"
path = "circle"
amplitude = 0.015
frequency = 10.0
engine_params.mujoco = { wire_first_azimuth_deg = 5.0 }   # the pattern turned, in one engine only
"""


def test_gate_on_a_circle_passes_and_catches_a_turned_pattern(tmp_path):
    (tmp_path / "cases.toml").write_text(CASES)
    p = subprocess.run([sys.executable, "-m", "nsd_cli.main", "compare", "--cases", str(tmp_path / "cases.toml"),
                        "--engines", "semirecursive,mujoco", "--out", str(tmp_path / "out")],
                       capture_output=True, text=True, timeout=900)
    assert p.returncode == 1, p.stderr
    res = json.loads((tmp_path / "out" / "results.json").read_text())
    gated = [m for m in res["metrics"] if m["gated"]]
    ok = {m["metric"]: m for m in gated if m["case"] == "circle"}
    assert ok and all(m["pass"] for m in ok.values()) and ok["max_dF_rel"]["value"] < 1e-4
    assert "region_shift_rel" not in ok  # stiffness regions belong to lines
    bad = {m["metric"]: m for m in gated if m["case"] == "circle_turned"}
    assert not bad["max_dF_rel"]["pass"]


def test_a_kept_run_is_reused_only_for_the_same_path(tmp_path):
    """The resume key holds the whole drive: the path's kind, its minor axis, and a table's content
    (not only its name), so an edited case never reuses a run of another motion."""
    from comparisons.config import Case
    from comparisons.harness import job_key
    from nsd_core.device.drive import Drive
    from nsd_core.device.params import Params

    def key(**drive):
        return job_key(Case(name="c", drive=Drive(amplitude=0.015, frequency=1.0, **drive), params=Params()),
                       "semirecursive")

    assert len({key(), key(path="circle"), key(path="figure8"), key(path="figure8", minor=0.005)}) == 4
    table = tmp_path / "path.csv"
    table.write_text("t,x,y\n0,0,0\n0.3,0.01,0\n0.6,0.005,0.004\n2,0,0\n")
    first = key(path=str(table))
    assert key(path=str(table)) == first
    table.write_text("t,x,y\n0,0,0\n0.3,0.012,0\n0.6,0.005,0.004\n2,0,0\n")
    assert key(path=str(table)) != first
