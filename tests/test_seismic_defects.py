"""Seismic defects fixed, each against arithmetic of its own here (docs/seismic.md, docs/design.md):
``nsd params`` lists the structure ``nsd seismic`` runs; a run stopped at the rod's reach records the
series' own (interpolated) capacity crossing, not its stop; W uses the design's g; the friction
pendulum is sized to the lead-rubber bearing's design point; a baseline past the design's stroke warns."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from nsd_cli.main import main
from nsd_core.device.params import Params

G = 9.80665
M, K_B = 3743.7968184920674, 147799.17422629456          # the design basis at model scale


def _row(text: str, name: str) -> str:
    return next(ln.split()[1] for ln in text.splitlines() if ln.split()[:1] == [name])


def test_params_lists_the_structure_nsd_seismic_runs(tmp_path, capsys):
    """--set n_wires=8: the listed M and k_b are the ones the run's summary.json holds (3743.8 kg,
    147.8 kN/m), not the device-derived 4119.6 kg / 162.63 kN/m."""
    assert main(["params", "--set", "n_wires=8"]) == 0
    listed = capsys.readouterr().out
    out = tmp_path / "s"
    assert main(["seismic", "--set", "n_wires=8", "--ground", "harmonic:amplitude=0.3,frequency=1,duration=0.05",
                 "--out", str(out)]) == 0
    st = json.loads((out / "summary.json").read_text())["structure"]
    assert _row(listed, "mass") == f"{st['mass']:.5g}" == "3743.8"
    assert _row(listed, "stiffness") == f"{st['stiffness']:.5g}" == f"{K_B:.5g}"
    assert _row(listed, "damping") == f"{st['damping']:.5g}"


def test_a_run_stopped_at_the_rods_reach_records_its_series_crossing_not_its_stop():
    """Near-field pulse 1, record seconds 2-3 at scale 16 stops at the rod's reach: the IDA's stored
    capacity time is where its series crosses X_max (linear between the two outputs around it, computed
    here from the same run's series), before the stop."""
    from nsd_core.ground.records import fema_record
    from nsd_core.structure.isolation import designed_structure
    from nsd_core.structure.seismic import RodReachError, simulate_seismic
    from nsd_core.study.ida import IdaRun, run_ida_point
    from nsd_core.study.limit_states import LimitStates, classify
    ground = {"scale": 16.0, "time_factor": math.sqrt(0.1), "window": [2.0, 3.0], "rotate_deg": 0.0, "normalised": True}
    st = designed_structure()
    numbers = {k: v for k, v in st.to_dict().items() if k != "provenance"}
    ls = LimitStates(capacity=0.02546109338901315, rod_length=0.03)
    r = IdaRun(set="nearfield-pulse", record=1, device=True, ground=ground, params=Params().to_dict(),
               structure=numbers, duration=None, dt_out=1e-3, states=ls.to_dict())
    out = run_ida_point(r)
    assert out["status"] == "failed" and out["metrics"]["reason"] == "rod_reach" and "partial" not in out
    with pytest.raises(RodReachError) as err:
        simulate_seismic(Params(), st, fema_record("nearfield-pulse", 1, **ground), dt_out=1e-3)
    s = err.value.partial
    t, u = np.asarray(s["t"]), np.asarray(s["u"])
    k = int(np.argmax(u >= ls.capacity))
    mine = t[k - 1] + (ls.capacity - u[k - 1]) / (u[k] - u[k - 1]) * (t[k] - t[k - 1])
    t_stop = out["metrics"]["t"]
    assert out["metrics"]["crossings"]["capacity"] == pytest.approx(mine, abs=1e-12)
    assert mine < t_stop
    state = classify({"status": "failed", "metrics": out["metrics"]}, ls, True)["capacity"]
    assert state["reached"] is True and state["t"] == pytest.approx(mine, abs=1e-12) and state["before_t"] == t_stop


def test_W_uses_the_design_s_g_everywhere():
    from nsd_core.structure.isolation import designed_structure
    from nsd_core.structure.isolators import sized
    from nsd_core.structure.restoring_force import weight
    st = designed_structure()
    assert weight(st) == pytest.approx(M * G, rel=1e-15)
    fps = sized("friction-pendulum", st.mass).provenance["full_scale"]
    assert fps["W_N"] == pytest.approx(M * 1e3 * G, rel=1e-15)


def test_the_friction_pendulum_is_sized_to_the_lead_rubber_bearing_s_design_point():
    """T_eff = T_D and beta_eff = 20 % at D_D, as the lead-rubber bearing (ASCE 7-16 17.8.5.2's
    k_eff = k_d + Q / D, beta_eff = 4 Q (D - D_y) / (2 pi k_eff D^2)), recomputed here: mu = Q / W
    = 1.67 %, R = W / k_d = 3.63 m full scale."""
    from nsd_core.structure.isolators import sized
    T = 2 * math.pi * math.sqrt(M / K_B)
    D = 0.1 * G * 0.25 * (T / math.sqrt(0.1)) / (4 * math.pi ** 2 * 1.5)      # D_D at model scale, 13.09 mm
    for kind in ("bilinear", "friction-pendulum"):
        iso = sized(kind, M)
        k_eff = iso.stiffness + iso.q_fast / D
        assert 2 * math.pi * math.sqrt(M / k_eff) == pytest.approx(T, rel=1e-12), kind
        beta = 4 * iso.q_fast * (D - iso.yield_displacement) / (2 * math.pi * k_eff * D * D)
        assert beta == pytest.approx(0.20, rel=1e-12), kind
    fps = sized("friction-pendulum", M)
    assert fps.q_fast / (M * G) == pytest.approx(0.016685, abs=1e-6)              # mu
    assert M * G / fps.stiffness / 0.1 == pytest.approx(3.6347, abs=1e-4)          # R full scale [m]
    assert fps.q_slow == fps.q_fast and fps.yield_displacement == pytest.approx(1e-4, rel=1e-12)


def test_a_baseline_past_the_design_stroke_warns(tmp_path, capsys):
    """The linear supports under a 1 Hz harmonic (0.4 m/s^2, 1 s) reach 27.35 mm: past the design's
    25.46 mm stroke, short of the rod's 30 mm: a warning in summary.json and on stderr."""
    from nsd_core.structure.seismic_warnings import run_warnings
    out = tmp_path / "lin"
    assert main(["seismic", "--ground", "harmonic:amplitude=0.4,frequency=1,duration=1", "--no-device",
                 "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert 0.02546 < s["peak_displacement"]["value"] < 0.03
    assert "beyond_design_stroke" in s["warning_kinds"] and "beyond_stroke" not in s["warning_kinds"]
    text = s["warnings"][s["warning_kinds"].index("beyond_design_stroke")]
    assert f"peak |u| = {s['peak_displacement']['value'] * 1e3:.4g} mm" in text and "stroke 25.46 mm" in text
    assert any("beyond the design stroke" in ln for ln in capsys.readouterr().err.splitlines())
    fps = {"device": False, "peak_displacement": {"value": 0.0258, "t": 12.0},
           "structure": {"isolator": {"kind": "friction-pendulum"}}}
    w = run_warnings(fps, 0.03)
    assert [x["kind"] for x in w] == ["beyond_design_stroke"] and "the friction-pendulum run" in w[0]["text"]
    assert run_warnings({**fps, "device": True}, 0.03) == []    # the device's own stroke warnings apply to it


@pytest.mark.slow   # a whole far-field record (~20 s of CPU)
def test_the_pendulum_period_sizing_went_past_the_stroke_on_far_field_1_and_now_warns():
    """The friction pendulum as it was sized before (pendulum period T_D: W/R = k_b; mu = 0.05) on
    far-field record 1 at the design level reaches 25.81 mm, past the 25.46 mm stroke: warned."""
    from nsd_core.ground.records import SIMILITUDE_TIME_FACTOR, fema_record
    from nsd_core.structure.isolation import designed_structure
    from nsd_core.structure.isolators import Isolator
    from nsd_core.structure.seismic import seismic_summary, simulate_seismic
    from nsd_core.structure.seismic_warnings import run_warnings
    from nsd_core.study.intensity import design_level_scale
    st = designed_structure(True)
    W = st.mass * G
    old = st.with_isolator(Isolator("friction-pendulum", st.stiffness, 0.0, 0.05 * W, 0.05 * W, 0.0, 1e-4, 2.0))
    scale = design_level_scale(fema_record("farfield", 1, scale=1.0, time_factor=SIMILITUDE_TIME_FACTOR))["scale"]
    r = simulate_seismic(Params(), old, fema_record("farfield", 1, scale=scale, time_factor=SIMILITUDE_TIME_FACTOR),
                         dt_out=1e-3, device=False)
    s = {"device": False, **seismic_summary(r), "structure": old.to_dict()}
    assert s["peak_displacement"]["value"] == pytest.approx(0.0258, abs=1e-4)
    assert [w["kind"] for w in run_warnings(s, 0.03)] == ["beyond_design_stroke"]
