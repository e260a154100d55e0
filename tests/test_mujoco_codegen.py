"""The MuJoCo builder's compiled path (comparisons/builders/mujoco_codegen.py: a passive callback generated
from the description, mujoco_kernels' native loop) against its Python reference path
(``passive = "python"``): the same outputs to round-off, laws registered here included."""
from __future__ import annotations

import ctypes
import uuid
from pathlib import Path

import mujoco
import numpy as np
import pytest
from numba import cfunc, types

from comparisons.builders import mujoco as mj_builder
from comparisons.builders import mujoco_cabi, mujoco_codegen
from nsd_core.model import laws
from nsd_core.model.assemble import initial_state
from nsd_core.model.errors import ModelError
from nsd_core.model.load import load_model, parse_model
from tests.test_model_mujoco import _cart_pendulum, _cubic_spring, _cubic_torsion, _maxwell_rate, _maxwell_tension

MODELS = Path(__file__).resolve().parents[1] / "models"


def both(model, duration, dt_out, settings):
    return [mj_builder.simulate(model, duration, dt_out, {**settings, "passive": p}) for p in ("compiled", "python")]


def assert_same(model, compiled, python, rtol=1e-11, drive_rtol=2e-11):
    """Every output within rtol of its peak |value|: the two paths sum the same terms in another order, so
    they part by round-off that grows over the steps (on an Intel Xeon here: 1.9e-12 of a floor
    acceleration's peak on the building, where 1e-12 had held on the machine the limits were first set on).
    A drive force is the difference of two terms ~1e6 times larger (the heavy virtual drive's feed-forward
    A q'' and A q'', A = 1e6 x the coordinate's inertia): its rounding reached 6.1e-12 of the force's peak
    (the device, Euler). A defect in either path is far above: a law value in the wrong column read 0."""
    assert compiled.stats["passive"] == "compiled" and python.stats["passive"] == "python"
    for o in model.outputs:
        a, b = compiled.outputs[o.name], python.outputs[o.name]
        scale = max(float(np.max(np.abs(b))), o.scale, 1e-300)
        tol = drive_rtol if o.kind == "drive_force" else rtol
        assert np.max(np.abs(a - b)) <= tol * scale, (o.name, float(np.max(np.abs(a - b)) / scale))
    assert abs(compiled.stats["tracking_error"] - python.stats["tracking_error"]) < 1e-12
    assert compiled.stats["closure_max"] == pytest.approx(python.stats["closure_max"], rel=1e-6, abs=1e-15)


@pytest.mark.parametrize("integrator", ["RK4", "Euler"])
def test_the_device_description_runs_the_same_compiled_and_in_python(integrator):
    model = load_model(MODELS / "nsd_drive.toml")
    compiled, python = both(model, 0.02, 0.002, {"timestep": 1e-5, "integrator": integrator})
    assert np.ptp(python.outputs["F_x"]) > 10.0 and np.ptp(python.outputs["spring_tension"]) > 1.0   # it moves
    assert_same(model, compiled, python)
    # the states (wire stresses, the spring's zeta) are integrated by MuJoCo from the generated rates
    assert abs(compiled.outputs["spring_tension"][-1] - compiled.outputs["spring_tension"][0]) > 1.0


def test_andrews_runs_the_same_compiled_and_in_python():
    model = load_model(MODELS / "andrews.toml")
    compiled, python = both(model, 0.01, 1e-4, {"timestep": 1e-5})
    assert np.ptp(python.outputs["beta"]) > 0.05   # the mechanism turns
    assert_same(model, compiled, python)


def test_a_law_registered_here_reaches_the_compiled_callback():
    tag = uuid.uuid4().hex[:8]
    spring = laws.register(laws.Law(f"test_cg_cubic_spring_{tag}", laws.POINTS, (
        laws.LawParameter("k3", "N/m^3", 0.0), laws.LawParameter("free_length", "m", 0.0)), _cubic_spring, "cubic"))
    torsion = laws.register(laws.Law(f"test_cg_cubic_torsion_{tag}", laws.JOINT, (
        laws.LawParameter("k3", "N m/rad^3", 0.0), laws.LawParameter("c", "N m s/rad", 0.0)), _cubic_torsion, "cubic"))
    try:
        model = parse_model(_cart_pendulum(spring.name, torsion.name), "cart_pendulum")
        text, bound = mujoco_codegen.source(mujoco_codegen.laws_of(model))
        compiled, python = both(model, 0.5, 0.01, {"timestep": 2e-4})
    finally:
        laws.LAWS.pop(spring.name, None)
        laws.LAWS.pop(torsion.name, None)
    # the generated source calls this file's functions, bound by name
    assert any(fn is _cubic_spring for fn in bound.values()) and any(fn is _cubic_torsion for fn in bound.values())
    assert "_cubic_spring" in text and "_cubic_torsion" in text
    assert np.max(np.abs(python.outputs["torque"])) > 1.0 and np.ptp(python.outputs["x"]) > 0.02
    assert_same(model, compiled, python)


def test_a_law_with_a_state_registered_here_reaches_the_compiled_callback():
    tag = uuid.uuid4().hex[:8]
    maxwell = laws.register(laws.Law(f"test_cg_maxwell_{tag}", laws.POINTS, (
        laws.LawParameter("k", "N/m", 0.0), laws.LawParameter("c", "N s/m", 0.0),
        laws.LawParameter("initial_tension", "N", -np.inf, default=0.0)),
        _maxwell_tension, "Maxwell", laws.StateSpec("tension", "N", "initial_tension"), _maxwell_rate))
    try:
        raw = _cart_pendulum("linear_spring_damper", "joint_spring_damper")
        raw["forces"] = [{"name": "maxwell", "law": maxwell.name, "body_a": "cart", "body_b": "ground",
                          "point_b": [-0.5, 0.0, 0.0], "parameters": {"k": 400.0, "c": 20.0, "initial_tension": 5.0}}]
        raw["outputs"][2:4] = [{"name": "tension", "kind": "force", "element": "maxwell"}]
        model = parse_model(raw, "cart_pendulum_maxwell")
        compiled, python = both(model, 0.5, 0.01, {"timestep": 2e-4})
    finally:
        laws.LAWS.pop(maxwell.name, None)
    assert compiled.outputs["tension"][0] == 5.0 and np.ptp(python.outputs["tension"]) > 1.0
    assert_same(model, compiled, python)


def test_parameters_do_not_change_the_generated_source_but_laws_from_another_module_do():
    """The source is the set of laws (generated.law_set): the model layer's own, and every law of each
    module that registers one of the description's; rope is the device's."""
    raw = _cart_pendulum("linear_spring_damper", "joint_spring_damper")
    raw["forces"][0]["parameters"] = {"stiffness": 100.0, "free_length": 0.4}
    raw["forces"][1]["parameters"] = {"stiffness": 3.0}
    a = parse_model(raw, "a")
    raw["forces"][0]["parameters"] = {"stiffness": 250.0, "free_length": 0.3, "damping": 2.0}
    b = parse_model(raw, "b")
    raw["forces"][0]["law"] = "rope"
    raw["forces"][0]["parameters"] = {"stiffness": 100.0, "free_length": 0.4}
    c = parse_model(raw, "c")
    key = {n: mujoco_codegen.fingerprint(*mujoco_codegen.source(mujoco_codegen.laws_of(x)))
           for n, x in (("a", a), ("b", b), ("c", c))}
    assert key["a"] == key["b"] != key["c"]


@cfunc(types.void(types.voidptr, types.voidptr))
def _other_passive(m, d):
    """Someone else's mjcb_passive (C: MuJoCo's model compiler cannot call a Python one)."""


def test_the_previous_callbacks_are_restored():
    model = load_model(MODELS / "iftomm_a01_pendulum.toml")
    mujoco.set_mjcb_passive(_other_passive.ctypes)
    try:
        run = mj_builder.simulate(model, 0.1, 0.01, {"timestep": 1e-3})
        assert mujoco.get_mjcb_passive() is _other_passive.ctypes and mujoco.get_mjcb_act_dyn() is None
    finally:
        mujoco.set_mjcb_passive(None)
    assert np.ptp(run.outputs["P1_y"]) > 0.01


def test_the_struct_offsets_point_at_the_bindings_arrays():
    model = load_model(MODELS / "nsd_drive.toml")
    m, d, _ = mj_builder._compile(model, mj_builder.merged_settings(None), 1e-4, initial_state(model), 5)
    n = max(mujoco_cabi.data_offsets().values()) + 1
    words = np.ctypeslib.as_array((ctypes.c_uint64 * n).from_address(d._address))
    for field, at in mujoco_cabi.data_offsets().items():
        if field == "time":
            d.time = 0.375
            assert words.view(np.float64)[at] == 0.375
        else:
            assert int(words[at]) == getattr(d, field).ctypes.data, field


def test_a_bad_passive_setting_is_a_one_line_model_error():
    model = load_model(MODELS / "iftomm_a01_pendulum.toml")
    with pytest.raises(ModelError, match=r"^mujoco\.passive = 'native': allowed: compiled, python$"):
        mj_builder.simulate(model, 0.1, 0.01, {"passive": "native"})



@pytest.mark.parametrize("name", ["nsd_seismic", "nsd_building"])
def test_the_seismic_descriptions_run_the_same_compiled_and_in_python(name):
    """The excitation (-m a_g at each stage's time), per-direction story springs, planar_translation
    floors and the restrainer, whose two points coincide at the start (nsd_building)."""
    model = load_model(MODELS / f"{name}.toml")
    compiled, python = both(model, 0.05, 0.005, {"timestep": 5e-5})
    assert np.ptp(python.outputs["u_x"]) > 1e-6 and np.ptp(python.outputs["u_y"]) > 1e-6   # the ground moves it
    if name == "nsd_building":
        assert np.ptp(python.outputs["floor3_x"]) > 1e-6
    assert_same(model, compiled, python)


def test_the_ground_motion_an_excitation_a_direction_and_the_counts_are_data():
    """A ground motion's numbers, an excitation, a direction, the number of elements and bodies live in
    userdata: every such description reuses the compiled callback of its set of laws."""
    raw = _cart_pendulum("linear_spring_damper", "joint_spring_damper")
    raw["forces"][0]["parameters"] = {"stiffness": 100.0, "free_length": 0.4}
    raw["forces"][1]["parameters"] = {"stiffness": 3.0}

    def key(**extra):
        model = parse_model({**raw, **extra}, "k")
        return mujoco_codegen.fingerprint(*mujoco_codegen.source(mujoco_codegen.laws_of(model)))
    harmonic = {"excitation": {"ground": "harmonic:amplitude=1,frequency=2"}}
    pulse = {"excitation": {"ground": "pulse:velocity=0.5,frequency=1,gamma=2,phase=0"}}
    forces = [{**raw["forces"][0], "direction": [1.0, 0.0, 0.0]}, raw["forces"][1]]
    more = raw["forces"] + [{**raw["forces"][0], "name": "second_spring"}]
    assert len({key(), key(**harmonic), key(**pulse), key(forces=forces), key(forces=more)}) == 1


def _callback_key(name: str) -> str:
    return mujoco_codegen.fingerprint(*mujoco_codegen.source(mujoco_codegen.laws_of(load_model(MODELS / f"{name}.toml"))))


def test_the_device_drive_its_seismic_models_and_building_share_one_callback():
    """The gate's MuJoCo descriptions (the drive, the isolated device, the building with its restrainer)
    are one set of laws: one module, compiled once; a mechanism of the model layer's laws alone has its own."""
    keys = {name: _callback_key(name) for name in ("nsd_drive", "nsd_seismic", "nsd_building", "andrews")}
    assert keys["nsd_drive"] == keys["nsd_seismic"] == keys["nsd_building"] != keys["andrews"]
    assert {law.name for law in mujoco_codegen.laws_of(load_model(MODELS / "nsd_building.toml"))} >= {
        "rope", "sma_wire", "push_spring", "hunt_crossley_stop", "linear_spring_damper"}


def test_a_stray_match_past_the_struct_is_not_taken_for_a_field():
    """The offset search reads words past mjData into the heap, where one may hold a field's address by
    chance (a CI run: act's address found 192 words after its own, the two probes then disagreed): the
    field is the last of the first run of adjacent matches (its zero-size aliases), never a later one."""
    import numpy as np
    from comparisons.builders.mujoco_cabi import data_offsets, field_word
    assert field_word(np.array([5, 20088, 20280]), 20086) == 20088
    assert field_word(np.array([20090, 20091, 20092, 20300]), 20086) == 20092   # aliases, then the field
    offsets = data_offsets()
    assert offsets["qvel"] == offsets["qpos"] + 1 and offsets["act"] < offsets["xmat"]
