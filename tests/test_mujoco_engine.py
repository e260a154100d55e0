"""The MuJoCo engine on real MuJoCo (no mocks): rest equilibrium, loop closure, quasi-static agreement."""
from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from comparisons.engines.base import EngineError
from comparisons.engines.mujoco_engine import MujocoEngine, build_mjcf
from nsd_core.device.drive import Drive
from nsd_core.device.geometry import device_geometry
from nsd_core.device.params import ParameterError, Params
from nsd_core.device.quasistatic import quasi_static_path
from independent_reference import rod_force_from_wall_balance

P = Params()


@pytest.fixture(scope="module")
def rest():
    """20 ms at u == 0 on the 50 Hz output grid (2000 Euler steps)."""
    return MujocoEngine().run(P, Drive(0.001, 50.0, cycles=1, samples_per_cycle=100), zero_drive=True)


@pytest.fixture(scope="module")
def drive10():
    """One 10 Hz cycle at A = 0.015 m with the default settings (10 000 Euler steps)."""
    d = Drive(0.015, 10.0, cycles=1, samples_per_cycle=200)
    return d, MujocoEngine().run(P, d)


def test_mjcf_is_built_from_params():
    g = device_geometry(P)
    s = dict(MujocoEngine.default_settings)
    model = mujoco.MjModel.from_xml_string(build_mjcf(g, Drive(0.01, 1.0), s, 1e-5))
    assert model.nq == 8 and model.nv == 7 and model.neq == 1
    assert model.eq_type[0] == mujoco.mjtEq.mjEQ_CONNECT
    assert model.body("cap").mass[0] == pytest.approx(P.cap_mass)
    assert model.body("wall").pos[2] == pytest.approx(P.spring_length)
    assert model.body("cap").pos[2] == pytest.approx(P.spring_length + P.rod_length)


def test_rest_state_is_the_precompressed_equilibrium(rest):
    g = device_geometry(P)
    # the spring pushes with F_press (Eq. 18 at x_pre, zeta_0). The soft connect (solimp d = 0.9999)
    # carries the rod's ~3.8 kN with a gap of a few nanometres, which moves the wall by ~7e-9 m and
    # the push by ~2 mN: 1e-2 N (3e-6 of F_press) is the bound; a rest state out of balance by a
    # newton would ring the 250 Hz mode with newton-scale force swings.
    np.testing.assert_allclose(rest["spring_push"], P.precompression_force, rtol=0, atol=1e-2)
    # the ropes together pull the cap down with F_press - W
    rope_v = g.rope_cap_points + [0.0, 0.0, g.cap_rest_z] - g.rope_base_points
    cos_v = rope_v[:, 2] / np.linalg.norm(rope_v, axis=1)
    pull = rest.stack("rope") @ cos_v
    np.testing.assert_allclose(pull, P.precompression_force - P.carried_weight, rtol=0, atol=1e-2)
    # cap and wall do not move (the soft connect settles by a nanometre at most)
    assert np.max(np.abs(rest["cap_z"] - g.cap_rest_z)) < 1e-8
    assert np.max(np.abs(rest["wall_z"] - g.wall_rest_z)) < 1e-8
    # no drive force, no wire stress, the hysteretic spring state stays at zeta_0
    assert np.max(np.abs(rest["F"])) < 1e-6
    # the nanometre settling of the soft connect strains the stiff wires by ~1e-7 (E A / L = 3.5e6 N/m)
    stress = np.column_stack([rest[f"wire{j}_stress"] for j in range(P.n_wires)])
    assert np.max(np.abs(stress)) < 2e4 and np.max(np.abs(stress)) * device_geometry(P).wire.area < 0.1
    np.testing.assert_allclose(rest["spring_zeta"], g.spring_zeta0, atol=1e-2)
    assert rest.stats["closure_max"] < 1e-8   # measured 4.9e-9 m


def test_callback_is_restored(rest):
    assert mujoco.get_mjcb_passive() is None


def test_loop_stays_closed_and_drive_is_exact(drive10):
    _, r = drive10
    # solref = 2 h, solimp d = 0.9999: the connect opens by ~1e-8 m under ~2 kN of rod force
    assert r.stats["closure_max"] < 5e-8
    assert np.max(r["closure"]) < 5e-8
    assert r.stats["tracking_error"] < 1e-9
    assert r.stats["steps"] == 10000


def test_rod_force_agrees_with_the_wall_balance(drive10):
    """The rod's share of F (the residual of the drive joint's equation) against the value the
    rod's Newton-Euler equations give when loaded by the wall's vertical balance (spring, wires,
    the wall's weight and acceleration): a different equation, no shared code. Measured 1.5e-4 of
    the peak at 10 Hz (finite-difference accelerations on 200 samples); 3e-4 is the bound."""
    _, r = drive10
    rod = rod_force_from_wall_balance(r)
    assert np.max(np.abs(rod - r["F_rod"])) < 3e-4 * np.max(np.abs(r["F"]))


def test_agrees_with_quasi_static_at_10hz(drive10):
    """At 10 Hz the wall, rod and cap accelerate vertically (the loop's height changes by ~2.4 mm
    twice a cycle, ~40 m/s^2 on ~1 kg) and the 250 Hz vertical mode is excited: the dynamic force
    differs from the quasi-static one (with m_c u'' added) by a few tenths of a percent of the peak
    (measured 0.42 %), so 0.6 % of the peak is the bound."""
    d, r = drive10
    qs = quasi_static_path(P, r["u"], d.direction_deg, u_ddot=d.displacement(r["t"])[2])
    peak = np.max(np.abs(qs["F"]))
    assert np.max(np.abs(r["F"] - qs["F"])) < 0.006 * peak
    assert np.max(np.abs(r["wall_z"] - qs["z_w"])) < 2e-5
    np.testing.assert_allclose(r["spring_push"], qs["spring_push"], atol=0.01 * P.precompression_force)


def test_rk4_agrees_with_euler():
    d = Drive(0.015, 10.0, cycles=1, samples_per_cycle=200)
    short = dict(timestep=5e-5, integrator="RK4")
    r4 = MujocoEngine().run(P, d, short)
    r1 = MujocoEngine().run(P, d, {"commit_every": 10})
    peak = np.max(np.abs(r1["F"]))
    assert np.max(np.abs(r4["F"] - r1["F"])) < 1e-3 * peak


def test_unknown_setting_and_instability_are_reported():
    d = Drive(0.001, 50.0, cycles=1, samples_per_cycle=100)
    with pytest.raises(ParameterError):
        MujocoEngine().run(P, d, {"no_such_setting": 1})
    with pytest.raises(EngineError, match="unstable"):
        MujocoEngine().run(P, Drive(0.01, 50.0, cycles=1, samples_per_cycle=100), {"closure_limit": 1e-15})
    assert mujoco.get_mjcb_passive() is None
    assert math.isfinite(MujocoEngine.default_settings["timestep"])
