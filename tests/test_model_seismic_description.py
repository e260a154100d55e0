"""The seismic features of the model description: a ground-acceleration excitation, per-direction
elements, planar_translation joints, against closed forms; the device's seismic and building modes
written as descriptions against the hand-built in-house seismic mode (a different formulation: no
loop closure, its own force assembly); bad input is one line."""
from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from nsd_core.model.errors import ModelError
from nsd_core.model.load import parse_model
from nsd_core.model.semirecursive import simulate

MODELS = Path(__file__).resolve().parents[1] / "models"
TIGHT = {"rtol": 1e-11, "atol": 1e-13}


def _oscillator(k: float, m: float, ground: str, kind: str = "prismatic") -> dict:
    joint = {"type": kind, "axis": [1.0, 0.0, 0.0]} if kind == "prismatic" else {"type": kind, "normal": [0.0, 0.0, 1.0]}
    return {"model": {"gravity": [0.0, 0.0, -9.81]},
            "excitation": {"type": "ground_acceleration", "ground": ground},
            "bodies": [{"name": "mass", "joint": joint, "mass": m, "inertia": [0.1, 0.1, 0.2]}],
            "forces": [{"name": "k", "law": "joint_spring_damper", "joint": "mass", "dof": 0,
                        "parameters": {"stiffness": k}}],
            "outputs": [{"name": "x", "kind": "coordinate", "joint": "mass", "dof": 0}]}


def test_a_mass_on_a_spring_under_harmonic_ground_acceleration_follows_the_closed_form():
    """x'' + w0^2 x = -A sin(w t) from rest: x = -A (sin wt - (w/w0) sin w0 t) / (w0^2 - w^2); the
    excitation is -m a_g on the body, along the azimuth (here X), and gravity is held by the joint."""
    k, m, A, f = 400.0, 2.0, 1.5, 1.7
    r = simulate(parse_model(_oscillator(k, m, f"harmonic:amplitude={A},frequency={f},duration=5")), 3.0, 0.01, TIGHT)
    w0, w = math.sqrt(k / m), 2 * math.pi * f
    exact = -A * (np.sin(w * r.t) - (w / w0) * np.sin(w0 * r.t)) / (w0 ** 2 - w ** 2)
    assert np.max(np.abs(exact)) > 0.01
    assert np.max(np.abs(r.outputs["x"] - exact)) < 1e-9 * np.max(np.abs(exact))


def test_per_direction_springs_act_along_their_axes_only():
    """A puck on a planar_translation joint held by a spring along X (k_x) and one along Y (k_y),
    released from (x0, y0): each coordinate rings at its own frequency, x0 cos(sqrt(k_x/m) t) and
    y0 cos(sqrt(k_y/m) t); a spring along the line would couple them."""
    m, kx, ky = 0.5, 200.0, 800.0
    d = {"bodies": [{"name": "puck", "joint": {"type": "planar_translation", "normal": [0.0, 0.0, 1.0]},
                     "mass": m, "inertia": [0.01, 0.01, 0.02]}],
         "forces": [{"name": f"s{a}", "law": "linear_spring_damper", "body_a": "puck", "body_b": "ground",
                     "point_a": [0.0, 0.0, 0.0], "point_b": [0.3, -0.2, 0.0], "direction": e,
                     "parameters": {"stiffness": k, "free_length": 0.0}}
                    for a, e, k in (("x", [2.0, 0.0, 0.0], kx), ("y", [0.0, 1.0, 0.0], ky))],
         "initial": {"coordinates": {"puck": [0.31, -0.19]}},
         "outputs": [{"name": "x", "kind": "coordinate", "joint": "puck", "dof": 0},
                     {"name": "y", "kind": "coordinate", "joint": "puck", "dof": 1},
                     {"name": "Tx", "kind": "force", "element": "sx"}]}
    r = simulate(parse_model(d), 1.0, 0.01, TIGHT)
    assert np.max(np.abs(r.outputs["x"] - (0.3 + 0.01 * np.cos(math.sqrt(kx / m) * r.t)))) < 1e-10
    assert np.max(np.abs(r.outputs["y"] - (-0.2 + 0.01 * np.cos(math.sqrt(ky / m) * r.t)))) < 1e-10
    assert np.max(np.abs(r.outputs["Tx"] - kx * (r.outputs["x"] - 0.3))) < 1e-8   # x = (p_a - p_b) . e


def test_a_stop_whose_points_coincide_at_rest_gives_no_force_and_no_nan():
    """The restrainer's form: a Hunt-Crossley stop between a body's centre and the ground's, at rest
    on it (distance 0, no direction), then pushed past its gap by the ground."""
    d = _oscillator(50.0, 1.0, "harmonic:amplitude=8,frequency=1,duration=3", kind="planar_translation")
    d["forces"].append({"name": "stop", "law": "hunt_crossley_stop", "body_a": "mass", "body_b": "ground",
                        "parameters": {"gap": 0.05, "stiffness": 1e6, "exponent": 1.5}})
    d["outputs"].append({"name": "F", "kind": "force", "element": "stop"})
    r = simulate(parse_model(d), 1.5, 0.005, {"rtol": 1e-9, "atol": 1e-12})
    assert np.all(np.isfinite(r.outputs["x"])) and r.outputs["F"][0] == 0.0
    assert np.max(r.outputs["F"]) > 0.0 and np.max(np.abs(r.outputs["x"])) < 0.06   # it engaged and held


def _device_seismic(stories: int, duration: float):
    from nsd_core.structure.building import building_from
    from nsd_core.structure.describe_seismic import seismic_description
    from nsd_core.ground.motions import parse_ground_spec
    from nsd_core.structure.isolation import Structure, structure_with
    from nsd_core.device.params import Params
    from nsd_core.structure.restrainer import default_restrainer
    from nsd_core.structure.seismic import simulate_seismic
    params = Params().replace(n_wires=6, rope_stiffness=6e5)   # a variant, not the nominal device
    st = structure_with(params, {})
    if stories:
        st = Structure(**{**st.__dict__, "restrainer": default_restrainer(params, st),
                          "building": building_from(st.mass, {"stories": stories})})
    ground = "harmonic:amplitude=1.2,frequency=2.5,azimuth=35,duration=1"
    model = parse_model(tomllib.loads(seismic_description(params, st, ground, duration)))
    run = simulate(model, duration, 1e-3, {"rtol": 1e-10, "atol": 1e-13})
    ref = simulate_seismic(params, st, parse_ground_spec(ground), duration=duration, dt_out=1e-3, rtol=1e-10, atol=1e-13)
    return run, ref


# two stories: 29 s of the README's test command (a fresh clone, 2026-11-28), slow mark; the device alone
# (stories = 0) stays in the default run
@pytest.mark.parametrize("stories", [0, pytest.param(2, marks=pytest.mark.slow)])
def test_the_seismic_description_is_the_hand_built_seismic_mode(stories):
    """The device (a variant) in seismic mode, written as data, against the in-house seismic mode
    built by hand (nsd_core.structure.seismic): relative displacement, turn, cap height and, with a
    building, every floor, to 1e-7 of each peak (both at rtol 1e-10; measured ~1e-8) and, for an output
    whose peak is small against the others (the turn: 1.4e-5 rad), to what the two runs' absolute
    tolerance resolves, 1e-13 a step over their ~300 steps (measured 1.5e-12 rad on the turn)."""
    run, ref = _device_seismic(stories, 0.3)
    pairs = [("u_x", "x"), ("u_y", "y"), ("theta", "theta"), ("cap_z", "cap_z")]
    pairs += [(f"floor{i}_{a}", f"floor{i}_{a}") for i in range(1, stories + 1) for a in "xy"]
    for mine, theirs in pairs:
        r = np.asarray(ref[theirs])
        assert np.max(np.abs(r)) > 0.0, theirs
        assert np.max(np.abs(run.outputs[mine] - r)) < 1e-7 * np.max(np.abs(r)) + 300 * 1e-13, mine


def test_the_committed_seismic_descriptions_load():
    for name in ("nsd_seismic", "nsd_building"):
        m = parse_model(tomllib.loads((MODELS / f"{name}.toml").read_text()))
        assert m.excitation is not None and m.excitation.acceleration(0.1)[2] == 0.0
    assert {b.joint.type for b in m.bodies} >= {"planar", "planar_translation", "prismatic", "universal"}


BAD = [
    ("excitation field", lambda d: d["excitation"].update(wind=1), "[excitation].wind: unknown field"),
    ("excitation kind", lambda d: d["excitation"].update(type="ground_velocity"), "[excitation].type = 'ground_velocity'"),
    ("both", lambda d: d["excitation"].update(record={"set": "farfield", "id": 1}), "[excitation]: give exactly one"),
    ("ground spec", lambda d: d["excitation"].update(ground="harmonic:amplitude=900,frequency=1"), "[excitation].ground harmonic: amplitude"),
    ("record id", lambda d: (d["excitation"].pop("ground"), d["excitation"].update(record={"set": "farfield", "id": 40})),
     "[excitation].record: record = 40"),
    ("record set", lambda d: (d["excitation"].pop("ground"), d["excitation"].update(record={"set": "moon", "id": 1})),
     "[excitation].record: record set = 'moon'"),
    ("direction zero", lambda d: d["forces"].__setitem__(0, {
        "name": "k", "law": "linear_spring_damper", "direction": [0, 0, 0], "body_a": "mass",
        "parameters": {"stiffness": 1.0, "free_length": 0.0}}), "forces.k.direction = [0, 0, 0]: must be a non-zero vector"),
    ("direction on a joint law", lambda d: d["forces"][0].update(direction=[1, 0, 0]), "forces.k.direction: law 'joint_spring_damper' acts on a joint"),
    ("dof", lambda d: d["outputs"][0].update(dof=2), "outputs.x.dof = 2: must be a whole number in [0, 1]"),
]


@pytest.mark.parametrize("label,change,expected", BAD, ids=[b[0] for b in BAD])
def test_a_bad_seismic_description_is_one_line_naming_the_field(label, change, expected):
    d = copy.deepcopy(_oscillator(1.0, 1.0, "harmonic:amplitude=1,frequency=1", kind="planar_translation"))
    change(d)
    with pytest.raises(ModelError) as e:
        parse_model(d)
    assert expected in str(e.value) and "\n" not in str(e.value), str(e.value)


@pytest.mark.parametrize("name,stories", [("nsd_seismic", 0), ("nsd_building", 3)])
def test_the_committed_seismic_descriptions_are_the_generators(name, stories):
    """models/nsd_seismic.toml and nsd_building.toml are what their recorded command writes (the
    nominal device, the default structure; the building with the default restrainer)."""
    from nsd_core.structure.describe_seismic import seismic_description, structure_for
    from nsd_core.device.params import Params
    text = (MODELS / f"{name}.toml").read_text()
    command = next(line[4:] for line in text.splitlines() if line.startswith("#   python -m"))
    ground = "harmonic:amplitude=1,frequency=2,azimuth=30,duration=1"
    assert f"--ground '{ground}' --duration 1" in command
    assert text == seismic_description(Params(), structure_for(Params(), stories, stories > 0), ground, 1.0, 1e-3,
                                       name, command)
