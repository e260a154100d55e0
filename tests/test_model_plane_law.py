"""A plane law (two slide coordinates of one joint, a two-component state: the baseline isolators'
bidirectional hysteresis, nsd_core.model.laws) in the description and in every builder.

Expected numbers come from the in-house device model's own run without the device
(``simulate_seismic(..., device=False)``, which integrates the isolator's z as two ODE states), never
from the builders under test; the compiled MuJoCo callback against its readable Python path; bad
input: one line naming the element, the field, the value and what is allowed, exit 2.
"""
from __future__ import annotations

import copy
import subprocess
import sys
import tomllib

import numpy as np
import pytest

from nsd_core.structure.describe_isolator import isolator_description
from nsd_core.model.errors import ModelError
from nsd_core.model.load import parse_model

GROUND = "harmonic:amplitude=2.5,frequency=1.2,azimuth=30,duration=0.6"


def _structure(kind: str):
    from nsd_core.structure.isolation import designed_structure
    from nsd_core.structure.isolators import sized
    s = designed_structure(True)
    return s.with_isolator(sized(kind, s.mass))


def _raw(kind="bilinear", duration=0.6) -> dict:
    return tomllib.loads(isolator_description(_structure(kind), GROUND, duration, 1e-3))


def _in_house_reference(kind: str):
    from comparisons.seismic import parse_ground
    from nsd_core.device.params import Params
    from nsd_core.structure.seismic import simulate_seismic
    return simulate_seismic(Params(), _structure(kind), parse_ground(GROUND, "--ground"), device=False, rtol=1e-11,
                            atol=1e-14)


@pytest.mark.parametrize("kind", ["bilinear", "friction-pendulum"])
def test_the_in_house_builder_runs_the_isolator_description_as_the_device_model_does(kind):
    from nsd_core.model import semirecursive
    ref = _in_house_reference(kind)
    r = semirecursive.simulate(parse_model(_raw(kind)), 0.6, 1e-3, {"rtol": 1e-11, "atol": 1e-14})
    o = r.outputs
    assert np.max(np.hypot(ref["isolator_zx"], ref["isolator_zy"])) > 0.9   # the isolator yielded
    assert np.max(np.hypot(o["u_x"] - ref["x"], o["u_y"] - ref["y"])) < 1e-6 * np.max(ref["u"])
    assert np.max(np.abs(o["z_x"] - ref["isolator_zx"])) < 1e-5 and np.max(np.abs(o["z_y"] - ref["isolator_zy"])) < 1e-5
    Q = _structure(kind).isolator
    k_d = Q.stiffness
    support = np.hypot(k_d * o["u_x"] - o["hysteresis_x"] - ref["support_Fx"], k_d * o["u_y"] - o["hysteresis_y"]
                       - ref["support_Fy"])
    assert np.max(support) < 1e-5 * np.max(np.hypot(ref["support_Fx"], ref["support_Fy"]))


@pytest.mark.parametrize("integrator,timestep", [("Euler", 2e-5), ("RK4", 1e-4)])
def test_mujoco_compiled_and_python_passive_paths_agree_on_a_plane_law(integrator, timestep):
    from comparisons.builders import mujoco
    raw = _raw("friction-pendulum", 0.3)
    raw["outputs"].append({"name": "w", "kind": "work", "element": "isolator"})
    m = parse_model(raw)
    s = {"timestep": timestep, "integrator": integrator}
    a = mujoco.simulate(m, 0.3, 1e-3, {**s, "passive": "python"}).outputs
    b = mujoco.simulate(m, 0.3, 1e-3, {**s, "passive": "compiled"}).outputs
    assert np.max(np.abs(a["z_x"])) > 0.5 and np.max(np.abs(a["w"])) > 0.0
    for k in a:
        assert np.max(np.abs(a[k] - b[k])) <= 1e-9 * max(np.max(np.abs(a[k])), 1e-12), k


@pytest.mark.parametrize("forces", ["compiled", "connectors", "predicted"])
def test_exudyn_runs_a_plane_law_on_each_force_path(forces):
    """Each Exudyn force path against the in-house device model's run without the device, the work of
    the hysteretic element against the in-house builder's (second order at 1e-4 s)."""
    from comparisons.builders import exudyn
    from nsd_core.model import semirecursive
    ref = _in_house_reference("bilinear")
    raw = _raw("bilinear", 0.6)
    raw["outputs"].append({"name": "w", "kind": "work", "element": "isolator"})
    m = parse_model(raw)
    o = exudyn.simulate(m, 0.6, 1e-3, {"step_size": 1e-4, "forces": forces}).outputs
    w = semirecursive.simulate(m, 0.6, 1e-3, {"rtol": 1e-11, "atol": 1e-14}).outputs["w"]
    assert np.max(np.hypot(o["u_x"] - ref["x"], o["u_y"] - ref["y"])) < 1e-4 * np.max(ref["u"])
    assert np.max(np.abs(o["z_x"] - ref["isolator_zx"])) < 1e-3 and np.max(np.abs(o["z_y"] - ref["isolator_zy"])) < 1e-3
    assert w[-1] < 0.0 and np.max(np.abs(o["w"] - w)) < 1e-3 * np.max(np.abs(w))


def test_exudyn_connectors_refuse_a_plane_law_on_a_joint_off_the_ground_the_compiled_path_runs_it():
    """A carrier on a slide with the plate on it: the connectors path says it cannot (one line), the
    compiled path runs it and agrees with the in-house builder."""
    from comparisons.builders import exudyn
    from nsd_core.model import semirecursive
    raw = _raw("bilinear", 0.3)
    plate = raw["bodies"][0]
    plate["parent"] = "carrier"
    raw["bodies"].insert(0, {"name": "carrier", "joint": {"type": "prismatic", "position": [0.0, 0.0, 0.0],
                                                          "axis": [0.0, 0.0, 1.0]}, "mass": 100.0,
                             "inertia": [1.0, 1.0, 1.0]})
    raw["forces"].append({"name": "carrier_spring", "law": "joint_spring_damper", "joint": "carrier", "dof": 0,
                          "parameters": {"stiffness": 1e5}})
    m = parse_model(raw)
    with pytest.raises(ModelError) as e:
        exudyn.simulate(m, 0.3, 1e-3, {"step_size": 1e-4, "forces": "connectors"})
    assert "forces.isolator.joint = 'plate': Exudyn's connectors apply a plane law on a joint to the ground only" in str(e.value)
    o = exudyn.simulate(m, 0.3, 1e-3, {"step_size": 1e-4, "forces": "compiled"}).outputs
    r = semirecursive.simulate(m, 0.3, 1e-3, {"rtol": 1e-11, "atol": 1e-14}).outputs
    assert np.max(np.abs(r["z_x"])) > 0.5
    assert np.max(np.hypot(o["u_x"] - r["u_x"], o["u_y"] - r["u_y"])) < 1e-4 * np.max(np.hypot(r["u_x"], r["u_y"]))


def test_the_work_of_a_plane_law_is_its_power_integrated():
    """The in-house work output of the hysteretic element against the trapezoid of Q . u' from its own
    force and velocity outputs (a different quadrature: agreement to its error)."""
    from nsd_core.model import semirecursive
    raw = _raw("bilinear", 0.6)
    raw["outputs"].append({"name": "w", "kind": "work", "element": "isolator"})
    o = semirecursive.simulate(parse_model(raw), 0.6, 1e-4, {"rtol": 1e-11, "atol": 1e-14}).outputs
    p = o["hysteresis_x"] * o["v_x"] + o["hysteresis_y"] * o["v_y"]
    trap = np.concatenate([[0.0], np.cumsum(0.5 * 1e-4 * (p[1:] + p[:-1]))])
    assert o["w"][-1] < 0.0   # the hysteresis dissipates
    assert np.max(np.abs(o["w"] - trap)) < 1e-4 * np.max(np.abs(o["w"]))


def _mutate(change) -> dict:
    d = copy.deepcopy(_raw())
    change(d)
    return d


def _iso(d):
    return next(f for f in d["forces"] if f["name"] == "isolator")


def _out(d, name):
    return next(o for o in d["outputs"] if o["name"] == name)


BAD = [
    ("dofs missing", lambda d: _iso(d).pop("dofs"), "forces.isolator.dofs = None: must be two different slide "
                                                    "coordinates of plate's planar joint (x, y); its slides: [0, 1]"),
    ("dofs same", lambda d: _iso(d).update(dofs=[0, 0]), "forces.isolator.dofs = [0, 0]: must be two different"),
    ("dofs turn", lambda d: _iso(d).update(dofs=[0, 2]), "forces.isolator.dofs = [0, 2]"),
    ("dofs float", lambda d: _iso(d).update(dofs=[0.0, 1]), "forces.isolator.dofs = [0.0, 1]"),
    ("dofs one", lambda d: _iso(d).update(dofs=1), "forces.isolator.dofs = 1"),
    ("dof given", lambda d: _iso(d).update(dof=0), "forces.isolator.dof: law 'bidirectional_hysteresis' acts on two "
                                                   "slide coordinates of a joint (joint, dofs)"),
    ("dofs on a joint law", lambda d: d["forces"][0].update(dofs=[0, 1]),
     "forces.support_x.dofs: law 'joint_spring_damper' acts on a joint coordinate (joint, dof)"),
    ("points", lambda d: _iso(d).update(body_a="plate"), "forces.isolator.body_a: law 'bidirectional_hysteresis'"),
    ("exponent", lambda d: _iso(d)["parameters"].update(exponent=1.0),
     "forces.isolator.parameters.exponent = 1.0: must be a number >= 2, <= 50 [-]"),
    ("yield", lambda d: _iso(d)["parameters"].update(yield_displacement=0.0),
     "forces.isolator.parameters.yield_displacement = 0.0: must be a number >= 1e-12 [m]"),
    ("initial z", lambda d: _iso(d)["parameters"].update(initial_zx=1.5),
     "forces.isolator.parameters.initial_zx = 1.5: must be a number >= -1, <= 1 [-]"),
    ("strength missing", lambda d: _iso(d)["parameters"].pop("strength"),
     "forces.isolator.parameters.strength: missing; law 'bidirectional_hysteresis' needs it [N]"),
    ("force component", lambda d: _out(d, "hysteresis_x").pop("component"),
     "outputs.hysteresis_x.component = None: allowed: x, y (element 'isolator' acts on the plane of plate's "
     "coordinates [0, 1])"),
    ("state component z", lambda d: _out(d, "z_y").update(component="z"), "outputs.z_y.component = 'z': allowed: x, y"),
    ("component of a scalar", lambda d: d["outputs"].append({"name": "s", "kind": "force", "element": "support_x",
                                                             "component": "x"}),
     "outputs.s.component = 'x': element 'support_x' has one value (no components)"),
]


@pytest.mark.parametrize("label,change,expected", BAD, ids=[b[0] for b in BAD])
def test_a_bad_plane_element_is_one_line_naming_the_field(label, change, expected):
    with pytest.raises(ModelError) as e:
        parse_model(_mutate(change))
    msg = str(e.value)
    assert expected in msg and "\n" not in msg, msg


def test_a_bad_plane_element_in_a_model_file_is_exit_2_nothing_written(tmp_path):
    text = isolator_description(_structure("bilinear"), GROUND, 0.6, 1e-3).replace("dofs = [0, 1]", "dofs = [1, 2]")
    (tmp_path / "iso.toml").write_text(text)
    out = tmp_path / "never"
    p = subprocess.run([sys.executable, "-m", "nsd_cli.main", "compare", "--model", str(tmp_path / "iso.toml"),
                        "--out", str(out)], capture_output=True, text=True, timeout=600)
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode == 2 and len(lines) == 1 and "forces.isolator.dofs = [1, 2]" in lines[0], p.stderr
    assert not out.exists()


def test_nsd_compare_model_judges_the_isolator_description_in_three_engines(tmp_path):
    """The gate's rule on a plane law: each peer within 3 x its own error estimate of the converged
    in-house reference, that error within the tolerance (the real engines, nothing mocked)."""
    import json
    path = tmp_path / "iso.toml"
    path.write_text(isolator_description(_structure("friction-pendulum"), GROUND, 0.4, 1e-3))
    p = subprocess.run([sys.executable, "-m", "nsd_cli.main", "compare", "--model", str(path), "--out",
                        str(tmp_path / "out")], capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stdout + p.stderr
    v = json.loads((tmp_path / "out" / "results.json").read_text())["cases"]["nsd_isolator_0.4s"]["verdicts"]
    assert {e for e in v if v[e]["pass"]} >= {"semirecursive", "mujoco", "exudyn"}, v
