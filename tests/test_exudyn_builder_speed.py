"""The Exudyn builder's cheaper bookkeeping leaves every number as it was (speed is measured by
benchmarks, never asserted here): the outputs read from the recorded coordinates, all samples at once
(exudyn_replay.SeriesReader, ``outputs_from = "coordinates"``), against the reference reading of each
recorded state set back into Exudyn (``outputs_from = "exudyn"``); and the pre-step's one compiled call
(commit and predicted forces, CompiledForces.advance) against the commit and the Taylor prediction done
apart, as CompiledForces.predict does."""
from __future__ import annotations

import numpy as np
import pytest

from comparisons.builders import exudyn as exudyn_builder
from nsd_core.model.load import load_model, parse_model
from tests.conftest import ROOT

RUNS = [("nsd_drive", 0.1, 1e-3, 2.5e-4), ("nsd_seismic", 0.1, 1e-3, 2.5e-4), ("fourbar_spring", 0.5, 1e-2, 1e-3),
        ("slider_crank", 0.1, 1e-3, 2e-4)]


def agree(a, b, rtol=1e-12):
    """Every output of run b equals run a's to rtol of its peak; the closure and tracking statistics
    (round-off themselves) to 1e-12 m."""
    assert a.outputs.keys() == b.outputs.keys()
    for name, y in a.outputs.items():
        assert y.shape == b.outputs[name].shape, name
        assert np.max(np.abs(b.outputs[name] - y)) <= rtol * max(np.max(np.abs(y)), 1e-300), name
    for stat in ("closure_max", "tracking_error"):
        assert abs(a.stats[stat] - b.stats[stat]) <= 1e-12, stat


@pytest.mark.parametrize("forces", ["compiled", "predicted"])
@pytest.mark.parametrize("name,duration,dt_out,h", RUNS)
def test_outputs_from_the_coordinates_equal_exudyns(name, duration, dt_out, h, forces):
    model = load_model(ROOT / "models" / f"{name}.toml")
    settings = {"forces": forces, "step_size": h}
    reference = exudyn_builder.simulate(model, duration, dt_out, {**settings, "outputs_from": "exudyn"})
    agree(reference, exudyn_builder.simulate(model, duration, dt_out, settings))


def test_drive_forces_read_through_exudyn_where_its_multipliers_are_global():
    """A slider driven on a prismatic joint (all three translations locked: Exudyn's multipliers are
    global there, ForceLocal turns them) and a block driven along one axis of a translational joint
    (the multiplier in the joint frame, read as is)."""
    body = {"mass": 2.0, "com": [0.1, 0.0, 0.0], "inertia": [0.01, 0.02, 0.03]}
    raw = {"model": {"gravity": [-9.81, -3.0, 0.0]},
           "bodies": [{"name": "slider", "joint": {"type": "prismatic", "axis": [0.6, 0.8, 0.0]}, **body},
                      {"name": "block", "joint": {"type": "translational", "position": [0.0, 0.0, 1.0]}, **body}],
           "forces": [{"name": "spring", "law": "linear_spring_damper", "body_a": "slider", "point_a": [0.1, 0.0, 0.0],
                       "body_b": "block", "parameters": {"stiffness": 100.0, "damping": 1.0, "free_length": 0.5}}],
           "prescribed": [{"name": "move_slider", "joint": "slider", "motion": "harmonic", "amplitude": 0.1,
                           "frequency": 2.0},
                          {"name": "move_x", "joint": "block", "dof": 0, "motion": "harmonic", "amplitude": 0.05,
                           "frequency": 3.0}],
           "outputs": [{"name": "F_slider", "kind": "drive_force", "element": "move_slider"},
                       {"name": "F_x", "kind": "drive_force", "element": "move_x"},
                       {"name": "block_y", "kind": "coordinate", "joint": "block", "dof": 1}]}
    model = parse_model(raw, "driven")
    for forces in ("compiled", "predicted"):
        settings = {"forces": forces, "step_size": 1e-3}
        reference = exudyn_builder.simulate(model, 0.2, 0.01, {**settings, "outputs_from": "exudyn"})
        assert np.ptp(reference.outputs["F_slider"]) > 1.0 and np.ptp(reference.outputs["F_x"]) > 1.0
        agree(reference, exudyn_builder.simulate(model, 0.2, 0.01, settings))


def test_advance_is_the_commit_then_the_predicted_forces():
    """At a converged state of the device (its laws with states), the pre-step's one call gives the
    states, rates and force vector of the commit and CompiledForces.predict's Taylor step done apart."""
    model = load_model(ROOT / "models" / "nsd_drive.toml")
    s = exudyn_builder.check_settings({"forces": "predicted"}, model)
    kept = {}

    def hold(build):   # the Build of the run, to read its last state back
        kept["build"] = build
        return build
    original = exudyn_builder.Build
    try:
        exudyn_builder.Build = lambda *a: hold(original(*a))
        exudyn_builder.simulate(model, 0.05, 1e-3, {**s, "step_size": 2.5e-4})
    finally:
        exudyn_builder.Build = original
    build = kept["build"]
    cf, mbs, h = build.compiled, build.mbs, 2.5e-4
    sd, ix = mbs.systemData, cf.node_index(mbs)
    q, v, a = (np.asarray(x)[ix] for x in (sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t(),
                                          sd.GetODE2Coordinates_tt()))
    W, f = cf.W.copy(), np.zeros_like(cf.f)
    cf.gen.commit(q, v, cf.F, cf.I, W)
    cf.gen.evaluate(q + h * v + (0.5 * h * h) * a, v + h * a, cf.F, cf.I, W, f)
    cf.advance(mbs, h, True)
    assert np.array_equal(cf.W, W) and np.array_equal(cf.f, f)
    assert np.array_equal(np.asarray(mbs.GetObjectParameter(cf.object, "forceVector")), f)
    assert np.array_equal(build.states.s, W[cf.s_at:cf.s_at + cf.ns])   # the states the outputs read
