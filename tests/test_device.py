"""The device on the semirecursive engine: rest state, quasi-static agreement, consistency."""
from pathlib import Path

import numpy as np
import pytest

from nsd_core.device.cycle import analyse, steady_cycle
from nsd_core.device.model import simulate
from nsd_core.device.drive import Drive
from nsd_core.device.params import Params
from independent_reference import quasi_static_force, rod_force_from_wall_balance

P = Params()
ROD_BALANCE_10HZ = 8e-4   # measured 4.2e-4 at 10 Hz, A = 0.02 m: finite-difference accelerations, 200 samples


REST = str(Path(__file__).resolve().parent / "data" / "rest_path.csv")   # the plate held at x = y = 0 for 0.2 s


def test_rest_state_is_an_exact_equilibrium():
    r = simulate(P, Drive(0.0, 10.0, cycles=1, samples_per_cycle=100, path=REST))
    assert np.ptp(r["cap_z"]) < 1e-12 and np.ptp(r["wall_z"]) < 1e-12  # nothing moves, not by a micrometre
    # to round-off: 1e-10 of 3800 N is a wall displacement of ~1e-12 m against k_se
    np.testing.assert_allclose(r["spring_push"], P.precompression_force, rtol=1e-10)
    np.testing.assert_allclose(r.stack("rope").sum(1), P.precompression_force - P.carried_weight, rtol=1e-10)
    assert np.all(r.stack("wire") == 0.0)  # wires unstressed at rest
    assert np.max(np.abs(r["F"])) < 1e-9
    assert r.stats["closure_max"] < 1e-14


@pytest.mark.slow
def test_one_hertz_edge_of_working_range_matches_the_independent_quasi_static_reference():
    d = Drive(0.0255, 1.0, cycles=2, samples_per_cycle=500)
    r = simulate(P, d)
    q = quasi_static_force(r["u"], u_ddot=d.displacement(r["t"])[2])
    c = steady_cycle(r, 1.0)
    err = np.max(np.abs(r["F"][c] - q["F"][c])) / np.max(np.abs(q["F"][c]))
    assert err <= 1e-2  # the ropes go slack at the edge and the vertical mode rings: 1 %


def test_drive_force_equals_the_sum_of_its_parts():
    """F from the drive's multiplier (tau) equals m_c u'' + rod (lambda) + ropes + wires."""
    d = Drive(0.02, 10.0, cycles=1, samples_per_cycle=200)
    r = simulate(P, d)
    parts = r["F_rod"] + r["F_ropes"] + r["F_wires"]
    np.testing.assert_allclose(r["F_device"], parts, atol=1e-9 * np.max(np.abs(r["F"])))
    # the rod's share, recomputed from the wall's vertical balance and the rod's Newton-Euler
    # equations (no multiplier involved)
    rod = rod_force_from_wall_balance(r)
    assert np.max(np.abs(rod - r["F_rod"])) < ROD_BALANCE_10HZ * np.max(np.abs(r["F"]))


def test_same_inputs_same_numbers():
    d = Drive(0.015, 10.0, cycles=1, samples_per_cycle=100)
    a, b = simulate(P, d), simulate(P, d)
    assert np.array_equal(a["F"], b["F"]) and np.array_equal(a["wire0_stress"], b["wire0_stress"])


def test_direction_is_a_symmetry_of_the_four_fold_device():
    """With four ropes and four wires, driving along psi = 90 deg gives the psi = 0 cycle."""
    d0 = Drive(0.015, 10.0, 0.0, cycles=1, samples_per_cycle=200)
    d90 = Drive(0.015, 10.0, 90.0, cycles=1, samples_per_cycle=200)
    a, b = simulate(P, d0), simulate(P, d90)
    np.testing.assert_allclose(a["F"], b["F"], atol=1e-6 * np.max(np.abs(a["F"])))
    np.testing.assert_allclose(a["wire0_stress"], b["wire1_stress"], atol=1e-6 * np.max(np.abs(a["wire0_stress"])))


def test_edge_cycle_has_figure7_shape_and_reports_slack_ropes():
    d = Drive(0.0255, 10.0, cycles=2, samples_per_cycle=1000)
    s = analyse(simulate(P, d), d.amplitude, d.frequency)
    signs = [r["sign"] for r in s["stiffness_regions"]]
    assert signs[:2] == ["+", "-"]  # positive at the origin (wires), then the negative plateau
    assert signs[-1] == "+"         # positive again towards X_max
    assert s["outside_working_range"] and any(e["kind"] == "ropes_slack" for e in s["events"])
    assert 0.0245 < s["x_max"] <= 0.0255  # docs/model.md: the ropes go slack near 25.46 mm
