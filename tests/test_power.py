"""The gate's detection power (nsd compare --power), its limits file and the energy-balance metric.

Kept cheap: one 10 Hz case, MuJoCo only (about 2 s a run), three injections of the issue's list
that the old 1e-3 gate let through or only just caught (a 1 % cap mass, gravity off, a 1 % wire area).
"""
from __future__ import annotations

import numpy as np
import pytest

from comparisons.config import load_cases
from comparisons.tolerance_file import load_tolerances
from comparisons.energy import energy_balance_rel
from comparisons.engines.perturb import check, describe, perturbed
from comparisons.power import power_study
from nsd_core.device.model import simulate
from nsd_core.device.drive import Drive
from nsd_core.device.geometry import device_geometry
from nsd_core.device.params import ParameterError, Params

P = Params()


def test_injected_errors_in_mujocos_own_model_fail_the_default_gate(tmp_path):
    case = next(c for c in load_cases() if c.name == "A15mm_f10Hz")
    inj = [{"what": "cap_mass", "by": 0.01}, {"what": "gravity", "by": -1.0}, {"what": "wire_area", "by": 0.01}]
    out = power_study([case], ["mujoco"], load_tolerances(), tmp_path, injections=inj, workers=2, ladder=False,
                      log=lambda s: None)
    assert (tmp_path / "power.json").is_file()
    for row in out["rows"]:
        assert row["failed"], row
        assert row["ratio"] > 3.0, row   # not by a hair: measured 20x (cap mass) and more
    assert out["all_seen"]


def test_perturbations_change_only_what_they_name():
    g = device_geometry(P)
    h = perturbed(g, {"what": "wire_wall_point", "index": 1, "axis": "z", "by": 2e-4})
    d = h.wire_wall_points - g.wire_wall_points
    assert d[1, 2] == pytest.approx(2e-4) and np.count_nonzero(d) == 1
    assert np.array_equal(h.rope_natural_length, g.rope_natural_length)
    assert perturbed(g, {"what": "cap_mass", "by": 0.01}).cap.mass == pytest.approx(1.01 * P.cap_mass)
    assert perturbed(g, {"what": "gravity", "by": -1.0}).params.gravity == 0.0
    assert perturbed(g, None) is g
    assert describe({"what": "rod_length", "by": -2e-4}) == "rod_length -0.2 mm"
    for bad, field in [({"what": "nose_mass"}, "perturb.what"), ({"what": "cap_mass", "by": "x"}, "perturb.by"),
                       ({"what": "cap_mass", "size": 1}, "perturb.size")]:
        with pytest.raises(ParameterError, match=field):
            check(bad)


def test_limits_per_engine_and_case(tmp_path):
    f = tmp_path / "tol.toml"
    f.write_text("[limits]\nmax_dF_rel = 1e-3\n[limits.mujoco]\nmax_dF_rel = 2e-4\n"
                 "[limits.mujoco.case.\"A\"]\nmax_dF_rel = 1e-5\n")
    t = load_tolerances(f)
    assert t["max_dF_rel"] == 1e-3 and t.limit("exudyn", "A", "max_dF_rel") == 1e-3
    assert t.limit("mujoco", "B", "max_dF_rel") == 2e-4 and t.limit("mujoco", "A", "max_dF_rel") == 1e-5
    f.write_text("[limits]\nmax_dF_rel = 1e-3\n[limits.adams]\nmax_dF_rel = 2e-4\n")
    with pytest.raises(ParameterError, match="adams"):
        load_tolerances(f)
    f.write_text("max_dF_rel = 1e-3\n")   # the old flat form still reads
    assert load_tolerances(f)["max_dF_rel"] == 1e-3


def test_regression_limits_sit_near_1e_4():
    t = load_tolerances("comparisons/limits_regression.toml")
    assert t.rule is None   # fixed limits: the regression profile, not the default verdict
    for e in ("mujoco", "exudyn"):
        assert t.limit(e, "any other case", "max_dF_rel") <= 1.5e-4
        assert t.limit(e, "A15mm_f1Hz", "max_dF_rel") <= 1e-4


def test_energy_balance_closes_and_sees_a_wrong_force():
    d = Drive(0.015, 10.0, cycles=2, samples_per_cycle=1000)
    r = simulate(P, d)
    g = device_geometry(P)
    assert energy_balance_rel(r, g, 10.0, d.unit_vector) < 1e-4       # measured 1.9e-6 at 2000 samples
    for k in ("F", "F_x", "F_y"):                                       # the drive force 0.1 % off
        r.columns[k] = r[k] * 1.001
    assert energy_balance_rel(r, g, 10.0, d.unit_vector) > 5e-4


@pytest.mark.parametrize("text, words", [
    ("[engineering]\nmax_dF_rel = 0\n", "engineering.max_dF_rel = 0: allowed: a number in (0, 1]"),
    ("[engineering]\nmax_dF_rel = 2.0\n", "engineering.max_dF_rel = 2.0"),
    ("[engineering]\nmax_dF_rel = \"x\"\n", "engineering.max_dF_rel = 'x'"),
    ("[engineering]\nwobble = 1e-3\n", "engineering.wobble: unknown metric"),
    ("[verdict]\nk = 0.5\n", "verdict.k = 0.5: allowed: 1 to 100"),
    ("[verdict]\nbeta = 2\n", "verdict.beta = 2.0: allowed: 0 to 1"),
    ("[verdict]\nrule = \"limits\"\n", "verdict.rule = 'limits'"),
    ("[verdict]\nsafety = 3\n", "verdict.safety: unknown"),
    ("[engineering]\nmax_dF_rel = 1e-3\n[limits]\nmax_dF_rel = 1e-3\n", "'limits' beside [engineering]"),
])
def test_bad_engineering_tolerances_exit_2_naming_the_field(tmp_path, text, words):
    import subprocess
    import sys
    f = tmp_path / "tol.toml"
    f.write_text(text)
    out = tmp_path / "out"
    p = subprocess.run([sys.executable, "-m", "nsd_cli.main", "compare", "--tolerances", str(f), "--out", str(out)],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and words in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert not out.exists()


def test_engineering_file_reads_with_defaults_and_refine_needs_it(tmp_path):
    import subprocess
    import sys
    f = tmp_path / "tol.toml"
    f.write_text("[verdict]\nk = 5\n[engineering]\nmax_dF_rel = 5e-4\n")
    t = load_tolerances(f)
    assert t.rule.k == 5.0 and t.rule.engineering["max_dF_rel"] == 5e-4
    assert t.rule.engineering["max_du_rel"] == 1e-3 and "max_du_rel" in t.defaulted   # the rule's default, named
    out = tmp_path / "out"
    p = subprocess.run([sys.executable, "-m", "nsd_cli.main", "compare", "--profile", "regression", "--refine",
                        "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and "--refine" in p.stderr and "fixed limits" in p.stderr, p.stderr
    assert not out.exists()
    p = subprocess.run([sys.executable, "-m", "nsd_cli.main", "compare", "--power", "--refine", "--out", str(out)],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and "--refine: applies to the gate, not to --power" in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and not out.exists()


POWER_CASE = """
[[case]]
name = "A25.5mm_f10Hz"
amplitude = 0.0255
frequency = 10.0
settings.mujoco = { timestep = 5e-6 }
"""
SEISMIC_CASE = """
[[case]]
name = "seismic_nf1_pulse"
mode = "seismic"
record = "nearfield-pulse:1"
window = [4.8, 6.0]
scale = 0.4
rotate_deg = 20.0
dt_out = 1e-3
settings.exudyn = { step_size = 1e-4 }
"""


def _power_cli(tmp_path, case_text: str, engine: str) -> tuple[int, dict]:
    import json
    import subprocess
    import sys
    cases = tmp_path / "cases.toml"
    cases.write_text(case_text)
    out = tmp_path / "power"
    p = subprocess.run([sys.executable, "-m", "nsd_cli.main", "compare", "--power", "--power-size", "0.001",
                        "--power-engines", engine, "--cases", str(cases), "--tolerances", "comparisons/tolerances.toml",
                        "--out", str(out), "--workers", "2"], capture_output=True, text=True, timeout=1500)
    assert p.returncode in (0, 1), p.stdout[-2000:] + p.stderr[-2000:]
    return p.returncode, json.loads((out / "power.json").read_text())


@pytest.mark.slow   # ~44 s; the default run keeps the docs' --power command (test_readme.py) and the test above
def test_power_cli_end_to_end_under_the_per_run_verdict(tmp_path):
    """nsd compare --power at 0.1 % on one drive case, MuJoCo: every listed error runs at h and h/2 in
    MuJoCo's own model and is judged by the rule; measured 28 of 31 seen (the rod mass +-0.1 % and the
    spring's zeta0 are below 3x MuJoCo's numerical error there), every one as a disagreement."""
    code, d = _power_cli(tmp_path, POWER_CASE, "mujoco")
    assert d["rule"]["name"] == "estimated" and len(d["table"]) == 31
    seen = sum(t["seen_at_nominal"] for t in d["table"])
    assert seen >= 26, [t["injection"] for t in d["table"] if not t["seen_at_nominal"]]
    assert code == (0 if seen == 31 else 1)
    nominal = [r for r in d["rows"] if r["scale"] == 1.0]
    assert all(r["kind"] == "disagrees" for r in nominal if r["failed"])   # never a spurious 'not converged'
    assert not [r for r in nominal if r.get("error")]


@pytest.mark.slow
def test_power_cli_on_a_seismic_case(tmp_path):
    """The same on the gate's near-fault seismic window in Exudyn: measured 25 of 31 seen at 0.1 % with
    its estimate's companion at 2h (27 with the h/2 companion: cap_mass +-0.1 % fell from 1.74 / 1.56 to
    0.46 / 0.41 of its bound on this case; both are still seen by both engines on the drive cases,
    docs/validation.md)."""
    _, d = _power_cli(tmp_path, SEISMIC_CASE, "exudyn")
    assert sum(t["seen_at_nominal"] for t in d["table"]) >= 24
