"""The MuJoCo builder (comparisons/builders/mujoco.py) on the description features of the seismic mode:
the ground-acceleration excitation, per-direction points elements, planar_translation joints and a
line element whose points coincide; against closed forms and the in-house description run. Both
passive paths (compiled, python) run the closed-form checks."""
from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

from comparisons.builders import mujoco as mj_builder
from comparisons.builders.mujoco_mjcf import build_mjcf
from comparisons.estimate import nominal_order, richardson_factor
from nsd_core.model import semirecursive
from nsd_core.model.load import load_model, parse_model

MODELS = Path(__file__).resolve().parents[1] / "models"
PATHS = ("compiled", "python")


def peak_error(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def _slider(forces: list, **extra) -> dict:
    """A 1.5 kg puck on a planar_translation joint (normal z, 0.5 m above the ground's origin)."""
    return {"model": {"name": "puck", "gravity": [0.0, 0.0, -9.81]},
            "bodies": [{"name": "puck", "joint": {"type": "planar_translation", "position": [0.0, 0.0, 0.5],
                                                  "normal": [0.0, 0.0, 1.0]},
                        "mass": 1.5, "com": [0.02, -0.01, 0.03], "inertia": [1e-3, 1e-3, 2e-3]}],
            "forces": forces,
            "outputs": [{"name": "x", "kind": "coordinate", "joint": "puck", "dof": 0},
                        {"name": "y", "kind": "coordinate", "joint": "puck", "dof": 1}],
            **extra}


def test_planar_translation_is_two_slides_along_the_plane_axes():
    for normal, axes in (([0.0, 0.0, 1.0], [[1, 0, 0], [0, 1, 0]]), ([1.0, 0.0, 0.0], [[0, 1, 0], [0, 0, 1]])):
        raw = _slider([])
        raw["bodies"][0]["joint"]["normal"] = normal
        model = parse_model(raw, "puck")
        s = mj_builder.merged_settings(None)
        m = mujoco.MjModel.from_xml_string(build_mjcf(model, s, 1e-3, {}, {}))
        assert m.njnt == 2 and list(m.jnt_type) == [mujoco.mjtJoint.mjJNT_SLIDE] * 2
        assert np.allclose(m.jnt_axis, axes, atol=1e-15), (normal, m.jnt_axis)


@pytest.mark.parametrize("passive", PATHS)
def test_per_direction_springs_give_each_direction_its_own_frequency(passive):
    """Two springs along x and along y, their ground points far off the puck's line of motion: with a
    direction each acts on its own coordinate, x = x0 cos(w_x t), y = y0 cos(w_y t) exactly (along the
    line between the points they would couple x and y and change both frequencies)."""
    kx, ky, m = 1.5 * (2 * math.pi * 3.0) ** 2, 1.5 * (2 * math.pi * 4.5) ** 2, 1.5
    raw = _slider([
        {"name": "kx", "law": "linear_spring_damper", "body_a": "puck", "point_a": [0.1, 0.0, 0.0],
         "body_b": "ground", "point_b": [0.1, 0.4, 0.3], "direction": [2.0, 0.0, 0.0],
         "parameters": {"stiffness": kx, "free_length": 0.0}},
        {"name": "ky", "law": "linear_spring_damper", "body_a": "ground", "point_a": [-0.3, 0.2, 0.9],
         "body_b": "puck", "point_b": [0.0, 0.2, 0.0], "direction": [0.0, -1.0, 0.0],
         "parameters": {"stiffness": ky, "free_length": 0.0}}],
        initial={"coordinates": {"puck": [0.01, -0.02]}})
    raw["outputs"].append({"name": "kx_tension", "kind": "force", "element": "kx"})
    model = parse_model(raw, "puck")
    run = mj_builder.simulate(model, 1.0, 0.01, {"timestep": 1e-3, "passive": passive})
    t = run.t
    assert peak_error(run.outputs["x"], 0.01 * np.cos(math.sqrt(kx / m) * t)) < 1e-5
    assert peak_error(run.outputs["y"], -0.02 * np.cos(math.sqrt(ky / m) * t)) < 1e-5
    # the law sees x = (p_a - p_b) . e: the puck's own x here (the points' offsets are across e)
    assert peak_error(run.outputs["kx_tension"], kx * 0.01 * np.cos(math.sqrt(kx / m) * t)) < 1e-5


def _sdof_under_ground_motion(ground: str) -> dict:
    """The puck on springs along x and y (3 Hz, 5 Hz), the frame moving with the ground."""
    forces = [{"name": f"k{c}", "law": "joint_spring_damper", "joint": "puck", "dof": k,
               "parameters": {"stiffness": 1.5 * (2 * math.pi * f) ** 2}} for k, (c, f) in enumerate((("x", 3.0), ("y", 5.0)))]
    return _slider(forces, excitation={"type": "ground_acceleration", "ground": ground})


@pytest.mark.parametrize("passive", PATHS)
def test_the_excitation_gives_the_relative_motions_exact_solution_at_rk4s_order(passive):
    """x'' + w_n^2 x = -a_g(t), a_g = A sin(w t) (cos az, sin az), from relative rest: x = -A_x (sin w t
    - (w / w_n) sin w_n t) / (w_n^2 - w^2). No constraint here, so RK4 is fourth order if the load is
    evaluated at each stage's time; a load held over the step (MuJoCo's gravity set once a step) would
    make it first order, ~1e-2 of the peak at these steps."""
    A, f, az = 1.5, 2.0, math.radians(30.0)
    model = parse_model(_sdof_under_ground_motion(f"harmonic:amplitude={A},frequency={f},azimuth=30,duration=1"),
                        "puck")
    w = 2 * math.pi * f
    for t in (0.1, 0.37):   # the excitation is the one this test assumes
        assert np.allclose(model.excitation.acceleration(t), [A * math.sin(w * t) * math.cos(az),
                                                              A * math.sin(w * t) * math.sin(az), 0.0], rtol=1e-14)
    runs = [mj_builder.simulate(model, 0.9, 0.01, {"timestep": h, "passive": passive}) for h in (2e-3, 1e-3)]
    errors = []
    for run in runs:
        e = 0.0
        for name, wn, a in (("x", 2 * math.pi * 3.0, A * math.cos(az)), ("y", 2 * math.pi * 5.0, A * math.sin(az))):
            exact = -a * (np.sin(w * run.t) - w / wn * np.sin(wn * run.t)) / (wn ** 2 - w ** 2)
            e = max(e, peak_error(run.outputs[name], exact))
        errors.append(e)
    assert errors[0] < 1e-5, errors
    assert errors[0] / errors[1] > 10.0, errors   # fourth order: 16


@pytest.mark.parametrize("passive", PATHS)
def test_a_stop_whose_points_coincide_gives_finite_output(passive):
    """The restrainer's form: a Hunt-Crossley stop between the puck's origin and the ground point
    under it. At rest the two points coincide (no direction): zero force, no NaN; launched from there,
    the stop catches the puck at its gap."""
    stop = {"name": "stop", "law": "hunt_crossley_stop", "body_a": "puck", "body_b": "ground",
            "point_b": [0.0, 0.0, 0.5], "parameters": {"gap": 0.01, "stiffness": 1e7, "exponent": 1.5, "damping": 0.5}}
    raw = _slider([stop])
    raw["outputs"].append({"name": "stop_force", "kind": "force", "element": "stop"})
    rest = mj_builder.simulate(parse_model(raw, "puck"), 0.05, 0.01, {"timestep": 1e-4, "passive": passive})
    for name, y in rest.outputs.items():
        assert np.all(y == 0.0), (name, y)
    raw["initial"] = {"velocities": {"puck": [0.5, 0.2]}}
    moving = mj_builder.simulate(parse_model(raw, "puck"), 0.1, 0.001, {"timestep": 1e-5, "passive": passive})
    assert all(np.all(np.isfinite(y)) for y in moving.outputs.values())
    assert moving.outputs["stop_force"][0] == 0.0 and np.max(moving.outputs["stop_force"]) > 10.0
    assert np.max(np.hypot(moving.outputs["x"], moving.outputs["y"])) < 0.0115


@pytest.fixture(scope="module")
def seismic():
    """models/nsd_seismic.toml over 0.2 s: MuJoCo (RK4) at h, h/2, h/4 and the in-house builder."""
    model = load_model(MODELS / "nsd_seismic.toml")
    h = 5e-5
    runs = [mj_builder.simulate(model, 0.2, 1e-3, {"timestep": h / k}) for k in (1, 2, 4)]
    inhouse = semirecursive.simulate(model, 0.2, 1e-3, {"rtol": 1e-11, "atol": 1e-13})
    return model, runs, inhouse


def test_nsd_seismic_agrees_with_the_inhouse_builder_within_mujocos_own_estimate(seismic):
    model, (run, half, _), inhouse = seismic
    factor = richardson_factor(nominal_order("mujoco", mj_builder.default_settings), 2.0)
    assert np.max(np.abs(inhouse.outputs["u_x"])) > 1e-3   # the ground moves the plate
    for o in model.outputs:
        scale = o.scale or np.max(np.abs(inhouse.outputs[o.name]))
        estimate = factor * np.max(np.abs(run.outputs[o.name] - half.outputs[o.name])) / scale
        error = np.max(np.abs(run.outputs[o.name] - inhouse.outputs[o.name])) / scale
        assert error <= 3.0 * estimate + 1e-8, (o.name, error, estimate)
        assert error < 1e-3, (o.name, error)
    assert run.stats["closure_max"] < 1e-6


def test_nsd_seismic_converges_at_the_order_its_estimate_assumes(seismic):
    """RK4 with the soft loop closure: second order (comparisons.estimate.nominal_order), the
    excitation included; measured on the plate's motion, h = 5e-5 s, h/2, h/4."""
    model, runs, inhouse = seismic
    for name in ("u_x", "u_y", "rope0_tension"):
        e = [np.max(np.abs(r.outputs[name] - inhouse.outputs[name])) for r in runs]
        orders = np.log2(np.array(e[:-1]) / np.array(e[1:]))
        assert np.all((orders > 1.7) & (orders < 2.4)), (name, e, orders)
