"""The building codes' restoring-force check (ASCE/SEI 7-16 Section 17.2.4.4; nsd_core.structure.restoring_force,
docs/seismic.md "The restoring-force check") of each configuration, against arithmetic of its own here:
the linear supports exactly (F(D) - F(D/2) = k_b D / 2, W = M g with g = 9.80665), the lead-rubber
bearing's law integrated apart (scipy's solve_ivp on z' = (1 - z^n) / D_y), the friction pendulum's in
closed form (n = 2: z = tanh(u / D_y)), and the device along 0 deg against the independent quasi-static
reference of tests/independent_reference.py (Newton body by body, written from the model document alone),
its least passing D solved on that reference with scipy's brentq. Along 45 deg (no independent model here)
against the number an independent check outside the project measured: 878.1 N at D_M."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from independent_reference import quasi_static_force
from nsd_core.structure.isolation import default_structure, designed_structure
from nsd_core.structure.isolators import sized
from nsd_core.device.params import ParameterError, Params
from nsd_core.structure.restoring_force import XTOL, restoring_force_check

P = Params()
S = designed_structure(design_level=True)
G = 9.80665
D_M = 0.019638166939008318     # m: g 1.5 S_D1 T_D / (4 pi^2 B_D) x 0.1 = 9.80665 x 0.375 x sqrt(10) / (4 pi^2 x 1.5) x 0.1


@pytest.fixture(scope="module")
def at_d_m():
    return restoring_force_check(P, S)


def _independent_device_margin(D: float) -> tuple[float, float]:
    u = np.linspace(0.0, D, 201)
    f = S.stiffness * u + quasi_static_force(u)["F"]
    return f[-1], f[100]


def test_the_default_is_D_M_and_the_device_fails_along_45_deg(at_d_m):
    c = at_d_m
    assert c["D"] == pytest.approx(9.80665 * 0.375 * math.sqrt(10.0) / (4 * math.pi ** 2 * 1.5) * 0.1, rel=1e-12)
    assert c["D_source"].startswith("default: the design basis's maximum displacement D_M")
    assert c["code"] == "ASCE/SEI 7-16 Section 17.2.4.4" and c["configuration"] == "device"
    W = S.mass * G
    assert c["W"] == pytest.approx(W, rel=1e-15) and c["required"] == pytest.approx(0.025 * W, rel=1e-15)
    f_d, f_half = _independent_device_margin(D_M)
    e0, e45 = c["directions"]["0"], c["directions"]["45"]
    assert e0["F_D"] == pytest.approx(f_d, abs=0.05) and e0["F_half_D"] == pytest.approx(f_half, abs=0.05)
    assert e0["difference"] == pytest.approx(935.9, abs=0.05) and e0["pass"] is True
    assert e45["difference"] == pytest.approx(878.1, abs=0.05) and e45["pass"] is False
    assert c["pass"] is False and c["governing_direction_deg"] == 45.0
    assert c["margin"] == pytest.approx(878.12 - 0.025 * W, abs=0.05)        # -39.7 N


def test_the_least_passing_D_is_solved_not_read_off_a_grid(at_d_m):
    """0 deg: the root of the independent reference's margin (brentq here); 45 deg: between 19.89 and
    19.90 mm (the independent check: 19.90 mm at g = 9.81); the grid's last failing point is earlier."""
    W = S.mass * G

    def m(D):
        f_d, f_half = _independent_device_margin(D)
        return f_d - f_half - 0.025 * W
    root = brentq(m, 0.019, 0.0196, xtol=1e-10)
    e0, e45 = at_d_m["directions"]["0"], at_d_m["directions"]["45"]
    assert at_d_m["least_passing_D_tolerance"] == XTOL == 1e-8
    assert e0["least_passing_D"] == pytest.approx(root, abs=2e-8)            # 19.4938 mm
    assert 0.01989 < e45["least_passing_D"] < 0.01990
    assert at_d_m["least_passing_D"] == e45["least_passing_D"]
    for e in (e0, e45):
        assert e["scan"]["failing_D_on_grid"][-1][1] < e["least_passing_D"]


@pytest.mark.parametrize("D", [0.0183, D_M])
def test_the_linear_supports_are_k_b_D_over_2_exactly(D):
    c = restoring_force_check(P, S, D, device=False)
    W = S.mass * G
    assert c["configuration"] == "linear" and c["with_device"] is None
    for e in c["directions"].values():
        assert e["difference"] == pytest.approx(S.stiffness * D / 2, rel=1e-13)
        assert e["margin"] == pytest.approx(S.stiffness * D / 2 - 0.025 * W, rel=1e-12)
        assert e["least_passing_D"] == pytest.approx(2 * 0.025 * W / S.stiffness, abs=XTOL)   # 12.42 mm
    below = restoring_force_check(P, S, 0.99 * 2 * 0.025 * W / S.stiffness, device=False)
    assert below["pass"] is False and below["margin"] < 0


def test_the_lead_rubber_bearing_is_checked_with_its_own_law():
    """k_d u + Q_d z(u), z on first loading by solve_ivp (rtol 1e-10); at X_max 1224.8 N (the independent
    check's figure), not the supports' k_b D / 2 = 1881.6 N."""
    st = S.with_isolator(sized("bilinear", S.mass))
    iso = st.isolator
    W = S.mass * G

    def F(D):
        sol = solve_ivp(lambda u, z: [(1.0 - abs(z[0]) ** iso.exponent) / iso.yield_displacement], (0.0, D), [0.0],
                        t_eval=[D / 2, D], rtol=1e-10, atol=1e-12)
        return iso.stiffness * np.array([D / 2, D]) + iso.q_slow * sol.y[0]
    for D in (D_M, 0.025461093389):
        c = restoring_force_check(P, st, D, device=False)
        half, full = F(D)
        assert c["configuration"] == "bilinear"
        for e in c["directions"].values():
            assert e["F_D"] == pytest.approx(full, abs=1e-3) and e["F_half_D"] == pytest.approx(half, abs=1e-3)
            assert e["pass"] is bool(full - half >= 0.025 * W)
    assert c["directions"]["0"]["difference"] == pytest.approx(1224.8, abs=0.1)


def test_the_friction_pendulum_is_checked_with_its_own_law():
    """(W/R) u + mu W tanh(u / D_y) (n = 2), at D_M; its least passing D where (W/R) D/2 + mu W (tanh(D/D_y)
    - tanh(D/2D_y)) = 0.025 W."""
    st = S.with_isolator(sized("friction-pendulum", S.mass))
    iso = st.isolator
    W = S.mass * G

    def F(u):
        return iso.stiffness * u + iso.q_slow * math.tanh(u / iso.yield_displacement)
    c = restoring_force_check(P, st, device=False)
    assert c["configuration"] == "friction-pendulum"
    e = c["directions"]["45"]
    assert e["F_D"] == pytest.approx(F(D_M), abs=1e-3) and e["F_half_D"] == pytest.approx(F(D_M / 2), abs=1e-3)
    root = brentq(lambda D: F(D) - F(D / 2) - 0.025 * W, 1e-4, 0.03, xtol=1e-12)
    assert c["least_passing_D"] == pytest.approx(root, abs=2 * XTOL)


def test_with_a_building_W_counts_the_floors():
    from nsd_core.structure.building import building_from
    sb = S.with_building(building_from(S.mass, {"stories": 3}))
    c = restoring_force_check(P, sb, 0.02, device=False)
    assert c["W"] == pytest.approx(2 * S.mass * G, rel=1e-12)   # the default floors weigh M together


@pytest.mark.parametrize("value", ["abc", "0", "-0.01", "0.03", "nan", "inf", "1e300"])
def test_bad_design_displacement_is_one_line(value):
    with pytest.raises(ParameterError, match="design-displacement"):
        restoring_force_check(P, S, value)


def test_nsd_seismic_reports_it_on_page_one_and_refuses_bad_input(tmp_path, capsys):
    """The judged run, shortened (the check is made before the run, from the design basis): near-field
    pulse 1 at the design level on the device: both directions printed, the FAIL along 45 deg with its
    margin in summary.json, its warnings and the report's first page."""
    from nsd_cli.main import main
    out = tmp_path / "rf"
    code = main(["seismic", "--record", "nearfield-pulse:1", "--design-level", "--isolator", "device",
                 "--duration", "0.05", "--out", str(out)])
    printed = capsys.readouterr().out
    s = json.loads((out / "summary.json").read_text())
    c = s["restoring_force"]
    assert code == 0 and c["pass"] is False and c["governing_direction_deg"] == 45.0
    line = [ln for ln in printed.splitlines() if ln.startswith("restoring force")]
    assert len(line) == 1 and "D = 19.64 mm (D_M)" in line[0] and "0 deg F(D) - F(D/2) = " in line[0]
    assert "935.91 N, margin +18.05 N: pass" in line[0] and "878.12 N, margin -39.74 N: FAIL" in line[0]
    assert "restoring_force_fails" in s["warning_kinds"]
    text = next(w for w in s["warnings"] if w.startswith("restoring force"))
    assert "FAILS ASCE/SEI 7-16 Section 17.2.4.4" in text and "along 45 deg" in text and "margin -39.74 N" in text
    bad = tmp_path / "bad"
    assert main(["seismic", "--ground", "harmonic:amplitude=0.3,frequency=1,duration=0.05",
                 "--design-displacement", "0.04", "--out", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--design-displacement = 0.04" in err[0] and "allowed" in err[0]
    assert not bad.exists()


def test_a_baseline_run_checks_its_own_law(tmp_path, capsys):
    from nsd_cli.main import main
    out = tmp_path / "lrb"
    assert main(["seismic", "--ground", "harmonic:amplitude=0.3,frequency=1,duration=0.05", "--isolator", "bilinear",
                 "--design-displacement", "0.025461093389", "--out", str(out)]) == 0
    c = json.loads((out / "summary.json").read_text())["restoring_force"]
    assert c["configuration"] == "bilinear" and c["directions"]["0"]["difference"] == pytest.approx(1224.8, abs=0.1)
    assert "of the bilinear isolation level" in capsys.readouterr().out


def test_compare_supports_checks_each_run_with_its_own_configuration(tmp_path, capsys):
    from nsd_cli.main import main
    out = tmp_path / "cmp"
    assert main(["seismic", "--ground", "harmonic:amplitude=0.3,frequency=1,duration=0.05", "--isolator",
                 "friction-pendulum", "--compare-supports", "--out", str(out)]) == 0
    dev = json.loads((out / "device" / "summary.json").read_text())["restoring_force"]
    alone = json.loads((out / "supports" / "summary.json").read_text())["restoring_force"]
    assert dev["configuration"] == "device" and alone["configuration"] == "friction-pendulum"
    assert "restoring_force_fails" in json.loads((out / "device" / "summary.json").read_text())["warning_kinds"]
    printed = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("restoring force")]
    assert len(printed) == 2


def test_the_device_structure_of_the_model_document_is_checked_too():
    """--resize's structure (derived from the device): the same law, W of its own mass."""
    s = default_structure(P)
    c = restoring_force_check(P, s, 0.024)
    assert c["W"] == pytest.approx(s.mass * G, rel=1e-15) and set(c["directions"]) == {"0", "45"}


def test_p695_json_and_its_first_page_carry_each_configuration_s_check(tmp_path, monkeypatch):
    """Synthetic traces through nsd p695's evaluation: p695.json's restoring_force per configuration, each
    with its own law (the device FAILS at D_M along 45 deg; the lead-rubber bearing passes, 944.7 N), and
    the printed lines and p695.png's notes say each verdict with its margin."""
    from nsd_core.study import p695
    from nsd_core.study.ida import Trace, parse_limit
    from nsd_core.study.limit_states import LimitStates
    from nsd_core.study.p695_outputs import evaluation, print_lines, restoring_lines, write_p695
    lrb = S.with_isolator(sized("bilinear", S.mass))
    limit = parse_limit("drift=0.01")
    traces = []
    for dev in (True, False):
        for rid in (1, 2, 3):
            tr = Trace(rid, dev, 1.0, {"set": "farfield"}, limit)
            tr.history = [(0.5, False, "", "k"), (1.0 + rid, True, "drift", "k")]
            traces.append(tr)
    level = p695.design_level("basis", S.first_period, math.sqrt(0.1), 9.80665)
    res = evaluation(traces, P, {"device": (True, S), "nodevice": (False, lrb)},
                     LimitStates(capacity=0.02, rod_length=0.03), limit, level, 0.7,
                     {"DR": "B", "TD": "C", "MDL": "B"}, 50, 1, [1, 2, 3], 1.0, (0.0, 0.0, 0.0))
    rf = res["restoring_force"]
    assert rf["device"]["pass"] is False and rf["device"]["margin"] == pytest.approx(878.12 - 0.025 * S.mass * G, abs=0.05)
    assert rf["nodevice"]["configuration"] == "bilinear" and rf["nodevice"]["pass"] is True
    assert rf["nodevice"]["directions"]["0"]["difference"] == pytest.approx(944.67, abs=0.05)
    lines = print_lines(res)
    assert "FAIL along 45 deg" in lines[1] and "margin -39.74 N" in lines[1] and "PASS" in lines[2]
    import matplotlib.figure
    seen = []
    save = matplotlib.figure.Figure.savefig

    def spy(fig, *a, **k):   # p695.png: each verdict with its margin on the page
        seen.append(" ".join(t.get_text() for t in fig.texts))
        return save(fig, *a, **k)
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", spy)
    write_p695(res, tmp_path)
    assert seen and "device: restoring force (ASCE/SEI 7-16 Section 17.2.4.4), device at D = 19.64 mm: FAIL along " \
        "45 deg" in seen[0] and "margin -39.74 N" in seen[0] and "nodevice: restoring force" in seen[0]
    assert json.loads((tmp_path / "p695.json").read_text())["restoring_force"]["device"]["pass"] is False
    assert restoring_lines({"restoring_force": rf["device"]})[0].startswith("device: restoring force")


def test_help_gives_the_default_it_uses(capsys):
    """--design-displacement's help quotes D_M; checked against the design basis."""
    from nsd_cli.main import main
    from nsd_core.structure.restoring_force import default_design_displacement
    with pytest.raises(SystemExit):
        main(["seismic", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert f"D_M ({default_design_displacement() * 1e3:.2f} mm at model scale)" in text


def test_a_record_set_s_first_page_states_each_verdict(at_d_m):
    """The set table (a record set's first page) carries each configuration's verdict, the FAIL in red,
    inside the page."""
    from page_checks import text_problems
    from reports.seismic_pages import set_table_figure
    from reports.style import RED
    linear = restoring_force_check(P, S, device=False)
    index = {"set": "nearfield-pulse", "ground": {}, "rows": [], "restoring_force": {**at_d_m, "baseline": linear}}
    fig = set_table_figure(index)
    lines = [t for t in fig.texts if t.get_text().startswith("restoring force")]
    assert len(lines) == 2 and "device at D = 19.64 mm: FAIL along 45 deg" in lines[0].get_text()
    assert "margin -39.74 N" in lines[0].get_text() and lines[0].get_color() == RED
    assert "linear at D = 19.64 mm: PASS" in lines[1].get_text()
    assert text_problems(fig) == []
