"""The MuJoCo builder (comparisons/builders/mujoco.py) on described mechanisms, against independent
solutions: the in-house builder at a tight tolerance, the IVP test set's Andrews reference, the exact
pendulum, and a force law registered by the test itself."""
from __future__ import annotations

import csv
import tomllib
import uuid
from pathlib import Path

import numpy as np
import pytest
from numba import njit

from comparisons.builders import mujoco as mj_builder
from comparisons.estimate import nominal_order, richardson_factor
from nsd_core.engine.problems.iftomm import pendulum_exact
from nsd_core.model import laws, semirecursive
from nsd_core.model.errors import ModelError
from nsd_core.model.load import load_model, parse_model

MODELS = Path(__file__).resolve().parents[1] / "models"
TIGHT = {"rtol": 1e-11, "atol": 1e-13}


def relative(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.fixture(scope="module")
def andrews():
    model = load_model(MODELS / "andrews.toml")
    case = tomllib.loads((MODELS / "andrews.toml").read_text())["case"][0]
    h = mj_builder.default_settings["timestep"]   # the case names no MuJoCo step: the default
    runs = [mj_builder.simulate(model, case["duration"], case["dt_out"], {"timestep": step}) for step in (h, h / 2)]
    inhouse = semirecursive.simulate(model, case["duration"], case["dt_out"], TIGHT)
    return model, runs, inhouse


def test_andrews_agrees_with_the_inhouse_builder_within_its_own_estimate(andrews):
    model, (run, half), inhouse = andrews
    factor = richardson_factor(nominal_order("mujoco", mj_builder.default_settings), 2.0)
    assert run.stats["steps"] * 2 == half.stats["steps"]
    for o in model.outputs:
        scale = np.max(np.abs(inhouse.outputs[o.name]))
        estimate = factor * np.max(np.abs(run.outputs[o.name] - half.outputs[o.name])) / scale
        error = relative(run.outputs[o.name], inhouse.outputs[o.name])
        # the in-house run's own error (~1e-9 of the scale at rtol 1e-11) is the floor
        assert error <= 3.0 * estimate + 1e-8, (o.name, error, estimate)
        assert error < 1e-4, (o.name, error)
    assert run.stats["closure_max"] < 1e-7
    assert run.stats["wall_time"] < 10.0


def test_andrews_agrees_with_the_test_set_reference(andrews):
    model, (run, half), _ = andrews
    with open(MODELS / "andrews_reference.csv") as fh:
        rows = list(csv.DictReader(fh))
    factor = richardson_factor(nominal_order("mujoco", mj_builder.default_settings), 2.0)
    for row in rows:
        k = int(np.argmin(np.abs(run.t - float(row["t"]))))
        assert abs(run.t[k] - float(row["t"])) < 1e-12
        for name, value in row.items():
            if name == "t":
                continue
            scale = np.max(np.abs(run.outputs[name]))
            estimate = factor * abs(run.outputs[name][k] - half.outputs[name][k])
            error = abs(run.outputs[name][k] - float(value))
            assert error <= 3.0 * estimate + 1e-8 * scale, (name, error, estimate)


def test_pendulum_a01_follows_the_exact_solution():
    model = load_model(MODELS / "iftomm_a01_pendulum.toml")   # a point mass: zero inertia, floored
    run = mj_builder.simulate(model, 5.0, 0.05, {"timestep": 5e-3})
    exact = pendulum_exact(run.t)
    assert np.max(np.abs(run.outputs["P1_x"] - exact[:, 0])) < 1e-6
    assert np.max(np.abs(run.outputs["P1_y"] - exact[:, 1])) < 1e-6
    # released at rest from y = 0: T = -m g y (energy conservation, m = 1 kg, g = 9.81)
    assert np.max(np.abs(run.outputs["kinetic"] + 9.81 * exact[:, 1])) < 1e-5
    assert np.max(np.abs(run.outputs["P1_y"] - exact[0, 1])) > 0.5   # it swings


def test_gravity_energy_matches_the_inhouse_definition():
    raw = tomllib.loads((MODELS / "iftomm_a01_pendulum.toml").read_text())
    raw.pop("case")
    raw["outputs"].append({"name": "gravity", "kind": "energy", "term": "gravity"})
    model = parse_model(raw, "a01_with_gravity_energy")
    run = mj_builder.simulate(model, 1.0, 0.1, {"timestep": 1e-3})
    # V = -m g . r_com = 9.81 y for a 1 kg point mass, gravity (0, -9.81, 0)
    assert np.allclose(run.outputs["gravity"], 9.81 * run.outputs["P1_y"], atol=1e-12)
    assert np.allclose(run.outputs["gravity"] + run.outputs["kinetic"], 0.0, atol=1e-6)


def test_slider_crank_drive_torque_matches_the_inhouse_engine():
    model = load_model(MODELS / "slider_crank.toml")
    run = mj_builder.simulate(model, 0.1, 2e-3, {"timestep": 2.5e-4})
    inhouse = semirecursive.simulate(model, 0.1, 2e-3, TIGHT)
    torque, ref = run.outputs["drive_torque"], inhouse.outputs["drive_torque"]
    assert np.max(np.abs(ref)) > 1.0                      # the drive does work both ways
    assert relative(torque, ref) < 1e-4, relative(torque, ref)   # same value, same sign
    for name in ("slider_x", "slider_v", "rod_angle"):
        assert relative(run.outputs[name], inhouse.outputs[name]) < 1e-4, name
    assert run.stats["tracking_error"] < 1e-12


@njit(cache=False)
def _cubic_spring(x, xd, p):
    """T = k3 (L - L0)^3."""
    return p[0] * (x - p[1]) ** 3


@njit(cache=False)
def _cubic_torsion(x, xd, p):
    """Q = -k3 q^3 - c q'."""
    return -p[0] * x ** 3 - p[1] * xd


def _cart_pendulum(spring: str, torsion: str) -> dict:
    """A cart on a slide with a pendulum on it: the cart held by a spring of law ``spring`` to the
    ground, the pendulum's hinge loaded by a joint law ``torsion``."""
    return {
        "model": {"name": "cart_pendulum", "gravity": [0.0, -9.81, 0.0]},
        "bodies": [
            {"name": "cart", "joint": {"type": "prismatic", "axis": [1.0, 0.0, 0.0]}, "mass": 2.0,
             "inertia": [0.01, 0.01, 0.01]},
            {"name": "arm", "parent": "cart", "joint": {"type": "revolute", "position": [0.0, 0.0, 0.0]},
             "mass": 0.5, "com": [0.0, -0.3, 0.0], "inertia": [0.004, 0.0001, 0.004]}],
        "forces": [
            {"name": "spring", "law": spring, "body_a": "cart", "point_a": [0.0, 0.0, 0.0],
             "body_b": "ground", "point_b": [-0.5, 0.0, 0.0], "parameters": {"k3": 2.0e4, "free_length": 0.4}},
            {"name": "torsion", "law": torsion, "joint": "arm", "parameters": {"k3": 3.0, "c": 0.05}}],
        "initial": {"coordinates": {"arm": 0.8}},
        "outputs": [
            {"name": "x", "kind": "coordinate", "joint": "cart"},
            {"name": "angle", "kind": "coordinate", "joint": "arm"},
            {"name": "tension", "kind": "force", "element": "spring"},
            {"name": "torque", "kind": "force", "element": "torsion"},
            {"name": "tip_vx", "kind": "point_velocity", "body": "arm", "point": [0.0, -0.6, 0.0]}],
    }


def test_a_law_registered_here_reaches_mujoco_unchanged():
    tag = uuid.uuid4().hex[:8]
    spring = laws.register(laws.Law(f"test_cubic_spring_{tag}", laws.POINTS, (
        laws.LawParameter("k3", "N/m^3", 0.0), laws.LawParameter("free_length", "m", 0.0)),
        _cubic_spring, "a cubic spring"))
    torsion = laws.register(laws.Law(f"test_cubic_torsion_{tag}", laws.JOINT, (
        laws.LawParameter("k3", "N m/rad^3", 0.0), laws.LawParameter("c", "N m s/rad", 0.0)),
        _cubic_torsion, "a cubic torsion spring with a dashpot"))
    try:
        model = parse_model(_cart_pendulum(spring.name, torsion.name), "cart_pendulum")
        run = mj_builder.simulate(model, 1.0, 0.01, {"timestep": 2e-4})
        inhouse = semirecursive.simulate(model, 1.0, 0.01, TIGHT)
    finally:
        laws.LAWS.pop(spring.name, None)
        laws.LAWS.pop(torsion.name, None)
    # the laws act: the spring (stretched 0.1 m at t = 0: 20 N) moves the cart, the torsion the arm
    assert abs(inhouse.outputs["tension"][0] - 20.0) < 1e-9
    assert np.ptp(inhouse.outputs["x"]) > 0.02 and np.max(np.abs(inhouse.outputs["torque"])) > 1.0
    for name in ("x", "angle", "tension", "torque", "tip_vx"):
        assert relative(run.outputs[name], inhouse.outputs[name]) < 1e-5, name


def test_unknown_or_bad_settings_are_one_line_model_errors():
    model = load_model(MODELS / "iftomm_a01_pendulum.toml")
    with pytest.raises(ModelError) as e:
        mj_builder.simulate(model, 0.1, 0.01, {"time_step": 1e-4})
    msg = str(e.value)
    assert "mujoco.time_step" in msg and "timestep" in msg and "integrator" in msg and "\n" not in msg
    with pytest.raises(ModelError, match=r"mujoco\.integrator = 'implicit': allowed: RK4, Euler"):
        mj_builder.simulate(model, 0.1, 0.01, {"integrator": "implicit"})
    with pytest.raises(ModelError, match=r"mujoco\.solref_factor = 1\.5: must be >= 2"):
        mj_builder.simulate(model, 0.1, 0.01, {"solref_factor": 1.5})
    with pytest.raises(ModelError, match=r"mujoco\.timestep = -0\.001: must be a number > 0"):
        mj_builder.simulate(model, 0.1, 0.01, {"timestep": -1e-3})


@njit(cache=False)
def _maxwell_tension(x, xd, s, p):
    """T = s: the tension of a spring k and a dashpot c in series (the state)."""
    return s


@njit(cache=False)
def _maxwell_rate(x, xd, s, p):
    """ds/dt = k L' - (k / c) s."""
    return p[0] * xd - p[0] / p[1] * s


def test_a_law_with_a_state_registered_here_reaches_mujoco_unchanged():
    tag = uuid.uuid4().hex[:8]
    maxwell = laws.register(laws.Law(f"test_maxwell_{tag}", laws.POINTS, (
        laws.LawParameter("k", "N/m", 0.0), laws.LawParameter("c", "N s/m", 0.0),
        laws.LawParameter("initial_tension", "N", -np.inf, default=0.0)),
        _maxwell_tension, "a Maxwell element", laws.StateSpec("tension", "N", "initial_tension"), _maxwell_rate))
    try:
        raw = _cart_pendulum("linear_spring_damper", "joint_spring_damper")
        raw["forces"] = [{"name": "maxwell", "law": maxwell.name, "body_a": "cart", "body_b": "ground",
                          "point_b": [-0.5, 0.0, 0.0], "parameters": {"k": 400.0, "c": 20.0, "initial_tension": 5.0}}]
        raw["outputs"][2:4] = [{"name": "tension", "kind": "force", "element": "maxwell"}]
        model = parse_model(raw, "cart_pendulum_maxwell")
        run = mj_builder.simulate(model, 1.0, 0.01, {"timestep": 2e-4})
        inhouse = semirecursive.simulate(model, 1.0, 0.01, TIGHT)
    finally:
        laws.LAWS.pop(maxwell.name, None)
    tension = inhouse.outputs["tension"]
    assert tension[0] == 5.0 and np.ptp(tension) > 1.0    # the state starts where given, and evolves
    for name in ("x", "angle", "tension", "tip_vx"):
        assert relative(run.outputs[name], inhouse.outputs[name]) < 1e-5, name


def test_euler_advances_a_state_along_its_element_s_actual_change():
    """With Euler the callback advances a law's state along its element's actual change of x since
    the last evaluation (comparisons.builders.mujoco_passive): a state whose rate is k x' (the Maxwell
    element with c -> infinity) then stays s_0 + k (L - L_0) to round-off on a prescribed path, where
    MuJoCo's own act += h rate(x_n, x'_n) lags it by one step's change (~k h |x'|: 0.05 N here)."""
    tag = uuid.uuid4().hex[:8]
    maxwell = laws.register(laws.Law(f"test_maxwell_euler_{tag}", laws.POINTS, (
        laws.LawParameter("k", "N/m", 0.0), laws.LawParameter("c", "N s/m", 0.0),
        laws.LawParameter("initial_tension", "N", -np.inf, default=0.0)),
        _maxwell_tension, "a Maxwell element", laws.StateSpec("tension", "N", "initial_tension"), _maxwell_rate))
    try:
        raw = _cart_pendulum("linear_spring_damper", "joint_spring_damper")
        raw["forces"] = [{"name": "maxwell", "law": maxwell.name, "body_a": "cart", "body_b": "ground",
                          "point_b": [-0.5, 0.0, 0.0], "parameters": {"k": 400.0, "c": 1e300, "initial_tension": 5.0}}]
        raw["prescribed"] = [{"name": "push", "joint": "cart", "motion": "harmonic", "centre": 0.0,
                              "amplitude": 0.05, "frequency": 2.0, "phase": 0.3}]
        raw["outputs"][2:4] = [{"name": "tension", "kind": "force", "element": "maxwell"}]
        model = parse_model(raw, "cart_pendulum_maxwell_driven")
        runs = [mj_builder.simulate(model, 0.5, 0.01, {"timestep": 2e-4, "integrator": "Euler", "passive": p})
                for p in ("compiled", "python")]
    finally:
        laws.LAWS.pop(maxwell.name, None)
    for run in runs:
        x = run.outputs["x"]
        assert np.ptp(x) > 0.05
        assert np.max(np.abs(run.outputs["tension"] - (5.0 + 400.0 * (x - x[0])))) < 1e-9


def test_spherical_universal_planar_and_translational_joints_follow_the_description():
    """Every multi-coordinate joint (two on a turning parent), tumbling under gravity from a general
    state: MuJoCo's joints of one body, applied in order, must turn each axis as the description's
    convention does. (Multi-coordinate bodies are leaves here: the in-house builder's to_tree cannot
    yet hang a body on one.)"""
    raw = {
        "model": {"name": "joint_zoo", "gravity": [0.0, -9.81, 0.0]},
        "bodies": [
            {"name": "ball", "joint": {"type": "spherical"}, "mass": 1.0, "com": [0.1, -0.3, 0.05],
             "inertia": [0.02, 0.01, 0.015, 0.001, -0.002, 0.0005]},
            {"name": "cross", "joint": {"type": "universal", "position": [0.1, -0.5, 0.1],
             "axis": [1.0, 0.2, 0.0], "axis2": [0.0, 0.3, 1.0]}, "mass": 0.7, "com": [0.0, -0.2, 0.03],
             "inertia": [0.01, 0.004, 0.01]},
            {"name": "arm", "joint": {"type": "revolute", "position": [0.5, 0.0, 0.0], "axis": [0.2, 0.1, 1.0]},
             "mass": 0.5, "com": [0.2, 0.0, 0.0], "inertia": [0.001, 0.006, 0.006]},
            {"name": "puck", "parent": "arm", "joint": {"type": "planar", "position": [0.4, 0.0, 0.0],
             "normal": [0.3, 1.0, 0.2]}, "mass": 0.4, "com": [0.05, 0.0, 0.02], "inertia": [0.002, 0.003, 0.004]},
            {"name": "bead", "parent": "arm", "joint": {"type": "translational", "position": [0.2, 0.1, 0.0]},
             "mass": 0.2, "inertia": [1e-4, 1e-4, 1e-4]}],
        "forces": [
            {"name": f"hold_{body}{k}", "law": "joint_spring_damper", "joint": body, "dof": k,
             "parameters": {"stiffness": 40.0, "damping": 0.2}} for body in ("puck", "bead") for k in range(3)],
        "initial": {"coordinates": {"ball": [0.3, -0.2, 0.4], "cross": [0.5, -0.3], "arm": 0.3, "puck": [0.05, -0.02, 0.3],
                                    "bead": [0.02, 0.01, -0.03]},
                    "velocities": {"ball": [1.0, -0.5, 2.0], "cross": [-1.0, 1.5], "arm": 2.0, "puck": [0.1, 0.2, -1.0],
                                   "bead": [0.0, 0.1, 0.2]}},
        "outputs": [{"name": f"{body}_{k}", "kind": "coordinate", "joint": body, "dof": k}
                    for body, n in (("ball", 3), ("cross", 2), ("puck", 3), ("bead", 3)) for k in range(n)]
        + [{"name": f"tip_{c}", "kind": "point", "body": "bead", "point": [0.0, 0.05, 0.0], "component": c} for c in "xyz"]
        + [{"name": "T", "kind": "energy", "term": "kinetic"}, {"name": "V", "kind": "energy", "term": "gravity"}],
    }
    model = parse_model(raw, "joint_zoo")
    run = mj_builder.simulate(model, 0.5, 0.01, {"timestep": 2e-4})
    inhouse = semirecursive.simulate(model, 0.5, 0.01, TIGHT)
    assert np.ptp(inhouse.outputs["ball_1"]) > 0.1 and np.ptp(inhouse.outputs["tip_y"]) > 0.05   # it moves
    for name in inhouse.outputs:
        assert relative(run.outputs[name], inhouse.outputs[name]) < 1e-5, (name, relative(run.outputs[name], inhouse.outputs[name]))


def test_bricard_revolute_closure_agrees_with_the_inhouse_builder():
    """A04: a revolute loop closure (two connects along the axis) with one redundant equation."""
    model = load_model(MODELS / "iftomm_a04_bricard.toml")
    run = mj_builder.simulate(model, 2.0, 0.05, {"timestep": 5e-3})
    inhouse = semirecursive.simulate(model, 2.0, 0.05, TIGHT)
    assert np.ptp(inhouse.outputs["P3_x"]) > 0.1
    for o in model.outputs:
        error = np.max(np.abs(run.outputs[o.name] - inhouse.outputs[o.name])) / o.scale
        assert error < 1e-5, (o.name, error)
    assert run.stats["closure_max"] < 1e-5
