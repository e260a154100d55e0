"""The seismic mode (Table 1, second row) on the in-house engine, and the default isolated structure."""
from __future__ import annotations

import math

import numpy as np
import pytest

from nsd_core.ground.motions import Harmonic, Pulse
from nsd_core.structure.isolation import Structure
from nsd_core.device.model import BODY
from nsd_core.device.params import Params
from nsd_core.structure.seismic import RodReachError, seismic_system, simulate_seismic

# the default structure's numbers (nsd_core.structure.isolation.default_structure, recorded in the README)
STRUCTURE = Structure(mass=3743.80, radius_of_gyration=0.40825, stiffness=147799.2, damping=2352.30,
                      support_radius=0.5)


def sdof_harmonic_from_rest(t, A, f, T_n, zeta):
    """u'' + 2 zeta w_n u' + w_n^2 u = -A sin(w t), u(0) = u'(0) = 0 (Chopra, Sections 3.1-3.2)."""
    w, wn = 2 * math.pi * f, 2 * math.pi / T_n
    wd, r = wn * math.sqrt(1 - zeta ** 2), w / wn
    den = (1 - r * r) ** 2 + (2 * zeta * r) ** 2
    C = -A / wn ** 2 * (1 - r * r) / den
    D = -A / wn ** 2 * (-2 * zeta * r) / den
    E = -D
    F = (zeta * wn * E - C * w) / wd
    return C * np.sin(w * t) + D * np.cos(w * t) + np.exp(-zeta * wn * t) * (E * np.cos(wd * t) + F * np.sin(wd * t))


def test_supports_alone_match_the_closed_form_single_degree_of_freedom():
    A, f, psi = 1.0, 1.5, 30.0
    r = simulate_seismic(Params(), STRUCTURE, Harmonic(A, f, psi, duration=1.2), device=False)
    u = sdof_harmonic_from_rest(r["t"], A, f, STRUCTURE.period, STRUCTURE.damping_ratio)
    e = (math.cos(math.radians(psi)), math.sin(math.radians(psi)))
    err = max(np.max(np.abs(r["x"] - u * e[0])), np.max(np.abs(r["y"] - u * e[1])))
    assert err / np.max(np.abs(u)) < 1e-6, err
    assert np.max(np.abs(r["theta"])) < 1e-15  # nothing turns the plate
    # Newton on the plate: base shear = -M a_abs; energy balance closes
    assert np.max(np.abs(r["base_shear_x"] + STRUCTURE.mass * r["ax_abs"])) < 1e-9 * np.max(np.abs(r["base_shear_x"]))
    assert np.max(np.abs(r["E_residual"])) < 1e-8 * np.max(r["E_input"])


@pytest.fixture(scope="module")
def with_device():
    return simulate_seismic(Params(), STRUCTURE, Harmonic(0.8, 2.0, 0.0, duration=0.3))


def test_partition_is_table_1_second_row():
    system, _, _ = seismic_system(Params(), STRUCTURE, Harmonic(1.0, 1.0))
    names = system.m.names
    assert [names[i] for i in system.partition.free] == ["plate_x", "plate_y", "plate", "cap"]
    assert sorted(names[i] for i in system.partition.dependent) == ["rod", "rod_x", "wall"]
    assert [names[i] for i in system.prescribed] == ["base_x", "base_y", "base"]


def test_device_run_closes_the_loop_and_the_energy_balance(with_device):
    r = with_device
    assert np.max(r["closure"]) < 1e-13
    assert np.max(r["u"]) > 5e-3  # the device is really worked (a tenth of its range or more)
    assert np.max(np.abs(r["E_residual"])) < 1e-6 * np.max(r["E_input"])
    # the device's work is a real part of the balance (negative while its precompression pushes out)
    assert np.max(np.abs(r["E_device"])) > 0.1 * np.max(r["E_input"])


def test_base_shear_is_the_superstructure_s_inertia(with_device):
    """Plate + mass + cap move together horizontally: V = support + device = -(M + m_c) a_abs. The
    device force comes from the cut's multiplier and the element forces, the acceleration from the
    equations of motion: they meet only if both are right."""
    r = with_device
    m = STRUCTURE.mass + Params().cap_mass
    for c in "xy":
        V = r[f"base_shear_{c}"]
        assert np.max(np.abs(V + m * r[f"a{c}_abs"])) < 1e-9 * max(np.max(np.abs(r["base_shear_x"])), 1.0)


def test_a_drive_along_a_wire_does_not_turn_the_plate_and_stays_in_its_plane(with_device):
    r = with_device  # psi = 0 is a mirror plane of the device: no torque, no Y motion
    assert np.max(np.abs(r["theta"])) < 1e-12 and np.max(np.abs(r["y"])) < 1e-12


def test_device_force_opposes_small_motions_with_the_device_s_initial_stiffness(with_device):
    """Near rest device_F (the plate's force on the device) is the device's initial tangent stiffness
    (positive, ~7e4 N/m) times u: from the quasi-static solution, independent of the multibody engine."""
    from nsd_core.device.quasistatic import quasi_static_path
    r = with_device
    small = (np.abs(r["x"]) < 4e-4) & (r["t"] < 0.12)
    qs = quasi_static_path(Params(), np.linspace(0.0, 4e-4, 41))
    k0 = np.polyfit(qs["u"], qs["F_device"], 1)[0]
    k_run = np.polyfit(r["x"][small], r["device_Fx"][small], 1)[0]
    assert k0 > 0 and abs(k_run / k0 - 1) < 0.05, (k_run, k0)


@pytest.mark.slow
def test_a_motion_beyond_the_rod_s_reach_stops_with_the_time():
    soft = Structure(mass=STRUCTURE.mass, radius_of_gyration=0.40825, stiffness=2.0e5, damping=0.0,
                     support_radius=0.5)
    with pytest.raises(RodReachError, match=r"t = [0-9.]+ s: \|u\| = 0.03\d* m.*rod_length = 0.03 m.*the rod cannot reach"):
        simulate_seismic(Params(), soft, Pulse(1.2, 2.0, 2.0), duration=0.6)


def test_the_device_force_in_the_seismic_run_is_the_quasi_static_force_along_its_path():
    """device_F (the plate's force on the device, drive-mode sign), from the multibody run, against the independent quasi-static
    solution (virtual work, no tree) driven along the run's own displacement history: they differ
    only by the device's own inertia and its fast vertical mode."""
    from nsd_core.device.quasistatic import quasi_static_path
    r = simulate_seismic(Params(), STRUCTURE, Harmonic(0.8, 2.0, 0.0, duration=0.6), dt_out=2e-3)
    qs = quasi_static_path(Params(), r["x"], 0.0, substeps=4)
    F = r["device_Fx"]
    assert np.max(np.abs(r["x"])) > 0.01 and np.max(np.abs(F)) > 1000.0
    assert np.max(np.abs(F - qs["F_device"])) < 1e-3 * np.max(np.abs(F))
    assert np.max(np.abs(r["cap_z"] - qs["z_c"])) < 1e-6


def test_default_structure_follows_the_model_document_rules():
    from nsd_core.structure.isolation import MARGIN, default_structure
    s = default_structure()
    K = s.provenance["K_dev"]["value"]
    assert s.stiffness + K == pytest.approx(MARGIN * s.stiffness, rel=1e-12)
    assert s.period == pytest.approx(1.0, rel=1e-12) and s.damping_ratio == pytest.approx(0.05, rel=1e-12)
    assert (s.mass, s.stiffness, s.damping) == pytest.approx((STRUCTURE.mass, STRUCTURE.stiffness, STRUCTURE.damping),
                                                             rel=1e-5)


@pytest.mark.slow
def test_the_recorded_device_stiffness_is_what_the_quasi_static_cycles_give():
    from nsd_core.structure.isolation import NOMINAL_K_DEV, device_min_stiffness
    k = device_min_stiffness(Params())
    assert k["K_dev"] == pytest.approx(NOMINAL_K_DEV["K_dev"], rel=1e-9) and k["direction_deg"] == 45.0
    # the model document expected about -70 to -90 kN/m; this model gives -99 (psi = 0) and -111 (45 deg)
    assert -1.2e5 < k["K_dev"] < -0.8e5
    assert k["per_direction"]["0.0"]["K_dev"] == pytest.approx(NOMINAL_K_DEV["per_direction"]["0.0"]["K_dev"], rel=1e-9)


def nsd(*args):
    import subprocess
    import sys
    return subprocess.run([sys.executable, "-m", "nsd_cli.main", *args], capture_output=True, text=True, timeout=600)


def test_nsd_seismic_writes_the_time_series_and_the_summary(tmp_path):
    import json
    from nsd_core.device.results import read_csv
    out = tmp_path / "run"
    p = nsd("seismic", "--ground", "harmonic:amplitude=0.8,frequency=2,azimuth=0,duration=0.2", "--dt-out", "0.002",
            "--out", str(out))
    assert p.returncode == 0, p.stderr
    r = read_csv(out / "seismic.csv")
    for col in ("x", "y", "ax_abs", "ay_abs", "device_Fx", "device_Fy", "support_Fx", "base_shear_x", "cap_z",
                "rope0_tension", "wire3_stress", "E_input", "E_residual"):
        assert col in r.columns
    s = json.loads((out / "summary.json").read_text())
    for key in ("peak_displacement", "peak_absolute_acceleration", "residual_displacement", "energy", "events",
                "structure", "ground", "versions", "params"):
        assert key in s
    assert s["structure"]["stiffness"] == pytest.approx(STRUCTURE.stiffness, rel=1e-5)
    assert s["peak_displacement"]["value"] == pytest.approx(np.max(r["u"]), rel=1e-6)


@pytest.mark.parametrize("args, words", [
    (["--record", "midfield:1"], "record set = 'midfield': unknown"),
    (["--record", "farfield:40"], "record = '40': unknown in set farfield; allowed 1..22"),
    (["--record", "farfield:1", "--scale", "0"], "scale = 0: must be > 0"),
    (["--record", "farfield:1", "--scale", "-1"], "scale = -1: must be > 0"),
    (["--record", "farfield:1", "--window", "10,90"], "window = 10,90: must satisfy 0 <= t0 < t1 <= 29.98 s"),
    (["--record", "farfield:1", "--rotate", "east"], "rotate_deg = 'east': not a number"),
    (["--record", "farfield"], "--record 'farfield': expected SET:ID"),
    (["--ground", "sine:amplitude=1"], "--ground 'sine': unknown kind"),
    (["--ground", "pulse:velocity=0.3,frequency=1,gamma=0.5"], "gamma = 0.5: must be > 1"),
    (["--ground", "harmonic:amplitude=0.8"], "--ground harmonic: frequency required"),
    (["--ground", "harmonic:amplitude=1,frequency=1", "--engines", "mujoco"], "semirecursive (the reference) must"),
    (["--ground", "harmonic:amplitude=1,frequency=1", "--engines", "semirecursive,bullet"], "--engines 'bullet'"),
    (["--ground", "harmonic:amplitude=1,frequency=1", "--structure", "mass=-3"], "structure mass = -3.0: must be"),
])
def test_nsd_seismic_bad_input_exit_2_one_line_nothing_written(tmp_path, capsys, args, words):
    from nsd_cli.main import main
    out = tmp_path / "x"
    code = main(["seismic", *args, "--out", str(out)])  # in-process: the same entry point as the command
    err = capsys.readouterr().err
    assert code == 2, err
    assert words in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists()


@pytest.mark.slow
def test_nsd_seismic_exit_4_with_the_time_when_the_rod_cannot_reach(tmp_path):
    out = tmp_path / "x"
    p = nsd("seismic", "--ground", "pulse:velocity=1.2,frequency=2,gamma=2", "--structure", "stiffness=2e5",
            "--structure", "damping=0", "--duration", "0.6", "--out", str(out))
    assert p.returncode == 4 and "the rod cannot reach" in p.stderr and "t = 0." in p.stderr, p.stderr
    # a run that ends is still a result: the series up to the event, the event in the summary
    import json
    from nsd_core.device.results import read_csv
    s = json.loads((out / "summary.json").read_text())
    r = read_csv(out / "seismic.csv")
    assert s["stopped"]["kind"] == "rod_reach" and 0.2 < s["stopped"]["t"] < 0.6 and s["complete"] is False
    assert r["t"][-1] <= s["stopped"]["t"] < r["t"][-1] + 1e-3 and len(r["t"]) > 100
    assert 0.95 * 0.03 < np.max(r["u"]) < 0.03  # it ran up to the rod's length
    from reports.build import build_report  # the report draws the kept series, the stop marked
    assert len(build_report(out, tmp_path / "rep")["pngs"]) >= 2


def test_mujoco_seismic_agrees_with_the_in_house_engine():
    """Real MuJoCo, ground-frame loads, off a symmetry axis (so X, Y and the rotation all move).
    Measured: 3.7e-6 in displacement, 3.2e-5 in device force; the issue's aim is 1e-3."""
    from comparisons.engines.peers import MujocoEngine
    gm = Harmonic(0.8, 2.0, 30.0, duration=0.3)
    ref = simulate_seismic(Params(), STRUCTURE, gm, dt_out=2e-3)
    mj = MujocoEngine().run_seismic(Params(), STRUCTURE, gm, dt_out=2e-3)
    du = np.max(np.hypot(mj["x"] - ref["x"], mj["y"] - ref["y"])) / np.max(ref["u"])
    F = np.hypot(ref["device_Fx"], ref["device_Fy"])
    dF = np.max(np.hypot(mj["device_Fx"] - ref["device_Fx"], mj["device_Fy"] - ref["device_Fy"])) / np.max(F)
    da = np.max(np.abs(mj["ax_abs"] - ref["ax_abs"])) / np.max(np.abs(ref["ax_abs"]))
    assert np.max(ref["u"]) > 0.01 and np.max(np.abs(ref["theta"])) > 1e-6
    assert du < 1e-4 and dF < 1e-4 and da < 1e-4, (du, dF, da)
    assert np.max(np.abs(mj["theta"] - ref["theta"])) < 1e-3 * np.max(np.abs(ref["theta"]))
    assert np.max(mj["closure"]) < 1e-7


def test_exudyn_seismic_agrees_with_the_in_house_engine():
    """Real Exudyn (generalized-alpha, h = 1e-5 s). Measured over 0.3 s: 4.7e-6 in displacement,
    4.1e-5 in device force, 2.4e-5 in absolute acceleration; this test runs the first 0.2 s."""
    from comparisons.engines.peers import ExudynEngine
    gm = Harmonic(0.8, 2.0, 30.0, duration=0.3)
    ref = simulate_seismic(Params(), STRUCTURE, gm, dt_out=2e-3, duration=0.2)
    ex = ExudynEngine().run_seismic(Params(), STRUCTURE, gm, dt_out=2e-3, duration=0.2)
    du = np.max(np.hypot(ex["x"] - ref["x"], ex["y"] - ref["y"])) / np.max(ref["u"])
    F = np.hypot(ref["device_Fx"], ref["device_Fy"])
    dF = np.max(np.hypot(ex["device_Fx"] - ref["device_Fx"], ex["device_Fy"] - ref["device_Fy"])) / np.max(F)
    da = np.max(np.abs(ex["ax_abs"] - ref["ax_abs"])) / np.max(np.abs(ref["ax_abs"]))
    assert np.max(ref["u"]) > 3e-3
    assert du < 1e-4 and dF < 1e-4 and da < 1e-4, (du, dF, da)
    assert np.max(ex["closure"]) < 1e-12


def test_leaving_the_working_range_is_an_event_and_the_run_goes_on():
    """A ground motion that takes the plate past X_max (25.46 mm): the ropes go slack, the events
    come with their times and the run finishes, its energy balance still closed."""
    from nsd_core.structure.seismic import seismic_summary
    from nsd_core.device.working_range import x_max_at_slack
    r = simulate_seismic(Params(), STRUCTURE, Harmonic(1.2, 2.0, 0.0, duration=0.4), dt_out=1e-3)
    s = seismic_summary(r)
    assert r["t"][-1] == pytest.approx(0.4) and s["outside_working_range"]
    slack = [e for e in s["events"] if e["kind"] == "ropes_slack"]
    x_max = x_max_at_slack(Params())
    first = slack[0]
    assert 0.0 < first["start"] < 0.4 and first["duration"] > 0
    assert x_max <= first["u_start"] < x_max + 0.5e-3  # within the sampling of the edge
    assert np.all(r["u"][r["t"] < first["start"]] < x_max + 1e-6)
    assert s["energy"]["relative_residual"] < 1e-6


def test_exudyn_seismic_on_a_record_window_that_starts_in_motion():
    """A window cut mid-record starts with a_g(0) != 0: every engine starts from relative rest with
    the ground already accelerating (Exudyn's initial accelerations need its loads set at t = 0)."""
    from comparisons.engines.peers import ExudynEngine
    from comparisons.seismic import seismic_metrics
    from nsd_core.ground.records import fema_record
    gm = fema_record("nearfield-pulse", 1, window=(2.0, 2.15), rotate_deg=20, scale=0.4)
    assert np.linalg.norm(gm(0.0)[2]) > 0.03
    ref = simulate_seismic(Params(), STRUCTURE, gm, dt_out=2e-3)
    m = seismic_metrics(ref, ExudynEngine().run_seismic(Params(), STRUCTURE, gm, dt_out=2e-3))
    assert m["du"] < 1e-4 and m["dF"] < 1e-4 and m["da"] < 1e-4, m
