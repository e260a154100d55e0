"""The displacement restrainer: its law, an independent check against a
hand-written integrator of the equations of motion that shares no code with the harness, the
energy balance and events with the device, and its options on the command line."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from nsd_core.device.forces import restrainer_force_scalar, restrainer_stored_scalar
from nsd_core.ground.motions import Harmonic
from nsd_core.structure.isolation import Structure, default_structure
from nsd_core.device.params import ParameterError, Params
from nsd_core.structure.restrainer import Restrainer, default_restrainer, with_restrainer
from nsd_core.structure.seismic import output_times, seismic_summary, simulate_seismic

GAP, K, N, ALPHA = 0.024, 8.5e8, 1.5, 2.5


def test_the_law_is_zero_inside_the_gap_continuous_at_touch_and_never_pulls():
    assert restrainer_force_scalar(0.02, 0.0, 1.0, 0.0, GAP, K, N, ALPHA) == (0.0, 0.0, 0.0, 0.0, 0.0)
    # just past the gap the force is tiny (continuous at touch) and points along u
    fx, fy, F, d, rate = restrainer_force_scalar(0.6 * (GAP + 1e-9), 0.8 * (GAP + 1e-9), 0.3, 0.4, GAP, K, N, ALPHA)
    assert 0 < F < 1e-3 and d == pytest.approx(1e-9, rel=1e-6) and rate == pytest.approx(0.5)
    assert fx == pytest.approx(0.6 * F) and fy == pytest.approx(0.8 * F)
    # separating fast (alpha delta' < -1): a Hunt-Crossley dashpot would pull; the law clips at 0
    assert restrainer_force_scalar(GAP + 1e-3, 0.0, -1.0, 0.0, GAP, K, N, ALPHA)[2] == 0.0
    # the elastic part: F = k delta^n at rest in the contact; stored energy's slope is that force
    d = 2e-3
    F = restrainer_force_scalar(GAP + d, 0.0, 0.0, 0.0, GAP, K, N, ALPHA)[2]
    assert F == pytest.approx(K * d ** N, rel=1e-14)
    h = 1e-8
    slope = (restrainer_stored_scalar(d + h, K, N) - restrainer_stored_scalar(d - h, K, N)) / (2 * h)
    assert slope == pytest.approx(F, rel=1e-6)


def test_default_restrainer_follows_its_stated_rule():
    p, st = Params(), default_structure(Params())
    r = default_restrainer(p, st)
    assert r.gap == pytest.approx(0.8 * p.rod_length) and r.exponent == 1.5
    # an undamped impact of M at 0.3 m/s stops within half the room l_d - u_gap: M v^2/2 = k d^2.5/2.5
    d = (0.5 * st.mass * 0.3 ** 2 * 2.5 / r.stiffness) ** (1 / 2.5)
    assert d == pytest.approx(0.5 * (p.rod_length - r.gap), rel=1e-12)
    assert r.damping == pytest.approx(3 * (1 - 0.5) / (2 * 0.3))
    assert all(k in r.provenance for k in ("gap", "stiffness", "exponent", "damping"))


@pytest.mark.parametrize("over, words", [
    ({"restrainer_gap": "0.03"}, "restrainer_gap = 0.03: must be < rod_length"),
    ({"restrainer_gap": "x"}, "restrainer_gap = 'x': not a number"),
    ({"restrainer_exponent": "0.5"}, "restrainer_exponent = 0.5: must be a finite number >= 1"),
    ({"restrainer_damping": "-1"}, "restrainer_damping = -1.0: must be a finite number >= 0"),
    ({"restrainer_stiffness": "nan"}, "restrainer_stiffness = nan"),
    ({"restrainer_width": "1"}, "restrainer_width: unknown"),
])
def test_bad_restrainer_values_are_one_line_errors(over, words):
    with pytest.raises(ParameterError, match=words.replace("(", r"\(").replace(")", r"\)")):
        with_restrainer(default_structure(Params()), Params(), True, over)


def test_a_structure_with_its_restrainer_round_trips_through_its_dict():
    st = with_restrainer(default_structure(Params()), Params(), False, {"restrainer_gap": "0.02"})
    assert st.restrainer.gap == 0.02 and st.restrainer.provenance["gap"] == "override"
    again = Structure(**{k: v for k, v in st.to_dict().items()})
    assert again == st and isinstance(again.restrainer, Restrainer)
    assert st.replace(mass="100").restrainer == st.restrainer


def _hand_integrated(st: Structure, r: Restrainer, A: float, f: float, psi_deg: float, t_end: float, h: float):
    """The supports alone with the restrainer, written out here from the equations (no harness code):
        M x'' = -k_b x - c_b x' - F (x / |u|) - M a_g e_x,  the same in y,
        F = max(k d^n (1 + alpha d'), 0) for d = |u| - u_gap > 0,
    with a_g = A sin(2 pi f t) along psi, integrated by classical RK4 with the fixed step h."""
    M, kb, cb = st.mass, st.stiffness, st.damping
    ex, ey = math.cos(math.radians(psi_deg)), math.sin(math.radians(psi_deg))
    w = 2 * math.pi * f

    def rhs(t, s):
        x, y, vx, vy = s
        ag = A * math.sin(w * t) if t <= t_end else 0.0
        fx = fy = 0.0
        u = math.sqrt(x * x + y * y)
        if u > r.gap:
            d, dd = u - r.gap, (x * vx + y * vy) / u
            F = r.stiffness * d ** r.exponent * (1 + r.damping * dd)
            F = F if F > 0 else 0.0
            fx, fy = F * x / u, F * y / u
        return np.array([vx, vy, (-kb * x - cb * vx - fx) / M - ag * ex, (-kb * y - cb * vy - fy) / M - ag * ey])

    n = int(round(t_end / h))
    s, t = np.zeros(4), 0.0
    out = [s.copy()]
    for _ in range(n):
        k1 = rhs(t, s)
        k2 = rhs(t + h / 2, s + h / 2 * k1)
        k3 = rhs(t + h / 2, s + h / 2 * k2)
        k4 = rhs(t + h, s + h * k3)
        s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        t += h
        out.append(s.copy())
    return np.arange(n + 1) * h, np.array(out)


def test_supports_alone_with_the_restrainer_match_a_hand_written_integrator():
    """Independent check: near resonance the plate reaches the restrainer 5 times (peak force 1.8e5 N).
    Measured: 4.2e-7 of the peak displacement (the in-house default, rtol 1e-7, against RK4 at 4e-5 s,
    which is converged: 2e-5 and 1e-5 s give 4.2e-7 too); the in-house run at rtol 1e-10 agrees to
    6.8e-9; energy balance residual 1.5e-10 of the input."""
    p = Params()
    st = with_restrainer(default_structure(p), p, True)
    A, f, psi, T = 3.0, 1.0, 30.0, 1.2
    run = simulate_seismic(p, st, Harmonic(A, f, psi, duration=T), dt_out=1e-3, device=False)
    t, s = _hand_integrated(st, st.restrainer, A, f, psi, T, 4e-5)
    assert np.max(run["restrainer_F"]) > 1e4  # it engaged, hard
    summary = seismic_summary(run)
    assert summary["restrainer"]["engagements"] >= 1
    every = int(round(1e-3 / 4e-5))
    x, y = s[::every, 0], s[::every, 1]
    assert np.allclose(run["t"], t[::every], atol=1e-12)
    err = max(np.max(np.abs(run["x"] - x)), np.max(np.abs(run["y"] - y))) / np.max(np.hypot(x, y))
    assert err < 2e-6, err
    # Newton on the plate: base shear (supports + restrainer) = -M a_abs
    shear = np.hypot(run["base_shear_x"], run["base_shear_y"])
    assert np.max(np.abs(run["base_shear_x"] + st.mass * run["ax_abs"])) < 1e-7 * np.max(shear)
    # the energy balance closes with the restrainer's stored and dissipated energy in it
    assert summary["energy"]["relative_residual"] < 1e-6 and summary["energy"]["restrainer_dissipated"] > 0


def test_with_the_device_the_restrainer_holds_the_plate_inside_the_rod_and_the_balance_closes():
    """A pulse that sends the plate past the rod's length without the restrainer (exit 4 in
    test_seismic) runs to its end with it; engagement events and energy are reported."""
    from nsd_core.ground.motions import Pulse
    p = Params()
    soft = Structure(mass=3743.8, radius_of_gyration=0.40825, stiffness=2.0e5, damping=0.0, support_radius=0.5)
    st = with_restrainer(soft, p, True)
    r = simulate_seismic(p, st, Pulse(1.2, 2.0, 2.0), duration=0.6)
    s = seismic_summary(r)
    assert r["t"][-1] == 0.6 and np.max(r["u"]) < p.rod_length
    ev = [e for e in s["events"] if e["kind"] == "restrainer_engaged"]
    assert ev and s["restrainer"]["engagements"] == len(ev) and ev[0]["impact_energy"] > 0
    assert ev[0]["peak_force"] == pytest.approx(np.max(r["restrainer_F"][(r["t"] >= ev[0]["start"]) &
                                                                         (r["t"] <= ev[0]["end"])]))
    assert s["energy"]["relative_residual"] < 1e-5, s["energy"]
    assert s["energy"]["restrainer_dissipated"] > 0


def test_output_times_land_on_the_end():
    t = output_times(0.3795, 1e-3)
    assert t[-1] == 0.3795 and len(t) == 381 and np.max(np.diff(t)) <= 1e-3
    assert len(output_times(2.0, 1e-3)) == 2001  # a whole number of intervals keeps its grid


@pytest.mark.slow
def test_mujoco_and_exudyn_with_the_restrainer_agree_with_the_in_house_engine():
    """Real MuJoCo and Exudyn, the restrainer engaged hard (gap 12 mm, two contacts, 2e5 N) while the
    device stays inside its working range: the same law through each engine's own force path.
    Measured with the hand-written models these replaced (du / dF_device / restrainer force / own energy
    residual): MuJoCo 2e-5 s 1.8e-4 / 1.9e-4 /
    6.0e-4 / 2.6e-3; Exudyn 1e-4 s 1.8e-5 / 2.6e-5 / 1.1e-4 / 6.4e-5."""
    from comparisons.engines.peers import ExudynEngine, MujocoEngine
    from comparisons.seismic import gate_metrics
    from nsd_core.ground.motions import Pulse
    p = Params()
    st = with_restrainer(default_structure(p), p, True, {"restrainer_gap": 0.012})
    gm = Pulse(0.5, 2.0, 2.0, azimuth_deg=30.0)
    ref = simulate_seismic(p, st, gm, duration=0.45)
    assert np.max(ref["restrainer_F"]) > 1e5 and not seismic_summary(ref)["outside_working_range"]
    for engine, settings, limit in ((MujocoEngine(), {"timestep": 2e-5}, 2e-3),
                                    (ExudynEngine(), {"step_size": 1e-4}, 2e-4)):
        other = engine.run_seismic(p, st, gm, duration=0.45, settings=settings)
        m = gate_metrics(ref, other)
        assert np.allclose(other["t"], ref["t"], atol=1e-12)
        assert m["max_du_rel"] < limit and m["max_dF_device_rel"] < 5 * limit, (engine.name, m)
        dF = np.max(np.abs(other["restrainer_F"] - ref["restrainer_F"])) / np.max(ref["restrainer_F"])
        assert dF < 10 * limit, (engine.name, dF)
        assert np.max(np.abs(other["E_residual"])) < 1e-2 * np.max(np.abs(other["E_input"])), engine.name


@pytest.mark.parametrize("table, words", [
    ("structure = { restrainer = \"yes\" }", "structure.restrainer = 'yes': must be true or false"),
    ("structure = { restrainer_gap = 0.05 }", "restrainer_gap = 0.05: must be < rod_length"),
    ("structure = { restrainer_exponent = 0.5 }", "restrainer_exponent = 0.5: must be a finite number >= 1"),
    ("structure = { restrainer_width = 1.0 }", "structure.restrainer_width: unknown"),
])
def test_a_case_file_restrainer_is_checked_when_read(tmp_path, table, words):
    from comparisons.config import load_cases
    f = tmp_path / "c.toml"
    f.write_text(f'[[case]]\nname = "s"\nmode = "seismic"\nground = "pulse:velocity=0.5,frequency=2"\n{table}\n')
    with pytest.raises(ParameterError, match=words.replace("(", r"\(")):
        load_cases(f)


def test_a_case_file_turns_the_restrainer_on(tmp_path):
    from comparisons.config import load_cases
    f = tmp_path / "c.toml"
    f.write_text('[[case]]\nname = "s"\nmode = "seismic"\nground = "pulse:velocity=0.5,frequency=2"\n'
                 'structure = { restrainer = true, restrainer_gap = 0.02 }\n')
    st = load_cases(f)[0].isolated_structure()
    assert st.restrainer.gap == 0.02 and st.restrainer.stiffness == default_restrainer(Params(), st).stiffness
