"""The building codes' restoring-force check of the isolation level (nsd_core.device.restoring_force,
docs/seismic.md "The restoring-force check"), against hand computations: the linear supports alone
exactly (F(D) - F(D/2) = k_b D / 2, W = M g), and with the device against the independent
quasi-static reference of tests/independent_reference.py (Newton body by body, written from the
model document alone)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from independent_reference import quasi_static_force
from nsd_core.device.isolation import default_structure
from nsd_core.device.params import ParameterError, Params
from nsd_core.device.restoring_force import RATIO, restoring_force_check

P = Params()
S = default_structure(P)


def test_supports_alone_is_k_b_D_over_2_exactly():
    D = 0.0183
    c = restoring_force_check(P, S, D, device=False)
    W = S.mass * 9.81                       # the hand computation: M g
    a = c["supports_alone"]
    assert c["W"] == pytest.approx(W, rel=1e-15)
    assert a["difference"] == pytest.approx(S.stiffness * D / 2, rel=1e-15)
    assert a["margin"] == pytest.approx(S.stiffness * D / 2 - 0.025 * W, rel=1e-13)
    assert a["pass"] is bool(S.stiffness * D / 2 >= 0.025 * W) and c["with_device"] is None
    assert a["least_passing_D"] == pytest.approx(2 * 0.025 * W / S.stiffness, rel=1e-15)   # 12.42 mm
    below = restoring_force_check(P, S, 0.99 * a["least_passing_D"], device=False)
    assert below["pass"] is False and below["supports_alone"]["margin"] < 0


def test_with_the_device_matches_the_independent_quasi_static_reference():
    """Along the first wire (psi = 0, the reference's only direction): F = k_b u + the device's drive
    force on first loading from rest, at D and D/2."""
    for D in (0.018, 0.024):
        c = restoring_force_check(P, S, D)
        u = np.linspace(0.0, D, 201)
        f = S.stiffness * u + quasi_static_force(u)["F"]
        e = c["with_device"]["0"]
        assert e["F_D"] == pytest.approx(f[-1], abs=0.05)          # N (of ~1.5-2.8 kN): two SMA integrators
        assert e["F_half_D"] == pytest.approx(f[100], abs=0.05)
        assert e["pass"] is bool(f[-1] - f[100] >= RATIO * S.mass * 9.81)
        assert c["pass"] is min(v["pass"] for v in c["with_device"].values())


def test_the_default_design_displacement_is_the_working_range():
    """Measured on the nominal device and default structure (docs/seismic.md): at X_max = 25.46 mm the
    check passes with the device (2630 N against 0.025 W = 918 N; the ropes going slack near X_max give
    the force back) and on the supports alone (1882 N); with the device it fails for D below about 20 mm
    (the negative stiffness takes the margin), the supports alone below 12.4 mm."""
    c = restoring_force_check(P, S)
    assert c["D"] == pytest.approx(0.025461, abs=1e-6) and c["D_source"].startswith("default")
    assert c["pass"] and c["required"] == pytest.approx(918.17, abs=0.01)
    assert c["with_device"]["0"]["difference"] == pytest.approx(2630.4, abs=0.5)
    least = max(v["over_working_range"]["least_passing_D"] for v in c["with_device"].values())
    assert 0.019 < least < 0.0205
    assert not restoring_force_check(P, S, 0.018)["pass"]


def test_with_a_building_W_counts_the_floors():
    from nsd_core.device.building import building_from
    sb = S.with_building(building_from(S.mass, {"stories": 3}))
    c = restoring_force_check(P, sb, 0.02, device=False)
    assert c["W"] == pytest.approx(2 * S.mass * 9.81, rel=1e-12)   # the default floors weigh M together


@pytest.mark.parametrize("value", ["abc", "0", "-0.01", "0.03", "nan", "inf", "1e300"])
def test_bad_design_displacement_is_one_line(value):
    with pytest.raises(ParameterError, match="design-displacement"):
        restoring_force_check(P, S, value)


def test_nsd_seismic_reports_it_and_refuses_bad_input(tmp_path, capsys):
    from nsd_cli.main import main
    out = tmp_path / "rf"
    code = main(["seismic", "--ground", "harmonic:amplitude=0.3,frequency=1,duration=0.05",
                 "--design-displacement", "0.018", "--out", str(out)])
    printed = capsys.readouterr().out
    s = json.loads((out / "summary.json").read_text())
    c = s["restoring_force"]
    assert code == 0 and c["D"] == 0.018 and c["pass"] is False and c["code"].startswith("ASCE/SEI 7-16")
    line = [ln for ln in printed.splitlines() if ln.startswith("restoring force")]
    assert len(line) == 1 and "D = 18 mm" in line[0] and "FAIL" in line[0] and "supports alone" in line[0]
    assert "restoring_force_fails" in s["warning_kinds"]   # and on stderr and the report's warnings page
    assert "restoring force: the isolation level with the device fails ASCE/SEI 7-16" in s["warnings"][-1]
    bad = tmp_path / "bad"
    assert main(["seismic", "--ground", "harmonic:amplitude=0.3,frequency=1,duration=0.05",
                 "--design-displacement", "0.04", "--out", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--design-displacement = 0.04" in err[0] and "allowed" in err[0]
    assert not bad.exists()
    code = main(["seismic", "--ground", "harmonic:amplitude=0.3,frequency=1,duration=0.05", "--no-device",
                 "--out", str(tmp_path / "nd")])
    c = json.loads((tmp_path / "nd" / "summary.json").read_text())["restoring_force"]
    assert code == 0 and c["with_device"] is None and math.isclose(c["D"], 0.025461, abs_tol=1e-6)


def test_help_gives_the_default_it_uses(capsys):
    """--design-displacement's help quotes the nominal X_max; checked against the computation."""
    from nsd_core.device.restoring_force import default_design_displacement
    with pytest.raises(SystemExit):
        main_help = __import__("nsd_cli.main", fromlist=["main"]).main
        main_help(["seismic", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert f"X_max ({default_design_displacement(P) * 1e3:.2f} mm for the nominal device)" in text


def test_a_device_without_a_working_range_still_runs_and_says_why_it_is_not_checked(tmp_path, capsys):
    """rope_stiffness = 1000 N/m: no slack point, so no X_max to default to (the structure given by hand);
    the run goes on, the check says why it is missing; with a D given it is computed."""
    from nsd_cli.main import main
    argv = ["seismic", "--set", "rope_stiffness=1000", "--structure", "mass=3000", "--structure", "stiffness=1e5",
            "--ground", "harmonic:amplitude=0.3,frequency=1,duration=0.05"]
    assert main(argv + ["--out", str(tmp_path / "a")]) == 0
    c = json.loads((tmp_path / "a" / "summary.json").read_text())["restoring_force"]
    assert c["pass"] is None and "no default for this device" in c["skipped"]
    assert "restoring force: not checked (--design-displacement: no default" in capsys.readouterr().out
    assert main(argv + ["--design-displacement", "0.02", "--out", str(tmp_path / "b")]) == 0
    c = json.loads((tmp_path / "b" / "summary.json").read_text())["restoring_force"]
    assert c["x_max"] is None and c["supports_alone"]["difference"] == pytest.approx(1e5 * 0.01, rel=1e-12)
    assert "over_working_range" not in c["with_device"]["0"]
