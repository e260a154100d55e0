"""One force law added in one place reaches all three engines: a law registered here (as a user
would: one function, one register call) drives a mechanism none of the engines has seen, and the gate's
rule finds the three engines consistent and converged."""
from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from comparisons.model_cases import ModelCase
from comparisons.model_compare import compare_model
from nsd_core.model import laws
from nsd_core.model.load import parse_model


@njit(cache=False)
def softening_strut(x, xd, p):
    """T = k (L - L0) - k3 (L - L0)^3 + c L': a strut that softens as it stretches (a test's own law)."""
    d = x - p[1]
    return p[0] * d - p[2] * d * d * d + p[3] * xd


@pytest.fixture
def strut_law():
    law = laws.register(laws.Law("test_softening_strut", laws.POINTS, (
        laws.LawParameter("k", "N/m", 0.0), laws.LawParameter("free_length", "m", 0.0),
        laws.LawParameter("k3", "N/m^3", 0.0), laws.LawParameter("c", "N s/m", 0.0)), softening_strut, "test"))
    yield law
    del laws.LAWS[law.name]


def slider_crank_with_strut() -> dict:
    """A slider-crank turned by gravity and the strut (no drive): crank, rod, slider, one point loop."""
    return {"model": {"gravity": [0.0, -9.81, 0.0]},
            "bodies": [
                {"name": "crank", "joint": {"type": "revolute"}, "mass": 0.8, "com": [0.05, 0.0, 0.0],
                 "inertia": [4e-4, 8e-4, 1.2e-3]},
                {"name": "rod", "parent": "crank", "joint": {"type": "revolute", "position": [0.1, 0.0, 0.0]},
                 "mass": 0.6, "com": [0.15, 0.0, 0.0], "inertia": [2e-4, 4.5e-3, 4.7e-3]},
                {"name": "slider", "joint": {"type": "prismatic", "axis": [1.0, 0.0, 0.0]}, "mass": 1.5,
                 "inertia": [1e-3, 1e-3, 1e-3]}],
            "loops": [{"name": "pin", "body_a": "rod", "point_a": [0.3, 0.0, 0.0], "body_b": "slider"}],
            "forces": [{"name": "strut", "law": "test_softening_strut", "body_a": "slider", "body_b": "ground",
                        "point_b": [0.6, 0.1, 0.0],
                        "parameters": {"k": 400.0, "free_length": 0.25, "k3": 2e4, "c": 1.0}}],
            "initial": {"coordinates": {"crank": 0.8, "rod": -1.0, "slider": 0.35}, "free": ["crank"]},
            "outputs": [{"name": "crank_angle", "kind": "coordinate", "joint": "crank"},
                        {"name": "slider_x", "kind": "coordinate", "joint": "slider"},
                        {"name": "strut_force", "kind": "force", "element": "strut"}]}


def test_a_law_added_in_one_place_passes_the_gate_in_three_engines(strut_law):
    model = parse_model(slider_crank_with_strut(), "inline")
    case = ModelCase("strut_1s", 1.0, 0.01, {"mujoco": {"timestep": 1e-3}, "exudyn": {"step_size": 5e-4}})
    s = compare_model(model, [case], ["semirecursive", "mujoco", "exudyn"], log=lambda *a: None)
    verdicts = s["cases"]["strut_1s"]["verdicts"]
    assert not s["cases"]["strut_1s"]["failures"], s["cases"]["strut_1s"]["failures"]
    for engine in ("semirecursive", "mujoco", "exudyn"):
        assert verdicts[engine]["pass"], (engine, verdicts[engine]["text"])
    runs = s["runs"]["strut_1s"]
    for engine in ("mujoco", "exudyn"):   # the law acts in each engine, and moves the mechanism
        assert np.ptp(runs[engine].outputs["strut_force"]) > 1.0
        assert np.ptp(runs[engine].outputs["crank_angle"]) > 0.1


def test_the_gate_sees_a_law_that_differs_in_one_engine(strut_law, monkeypatch):
    """The same mechanism with the strut 1 % stiffer in MuJoCo's model alone: MuJoCo disagrees beyond
    numerical error (the rule sees the modelling difference), the others still pass."""
    model = parse_model(slider_crank_with_strut(), "inline")
    from comparisons.builders import mujoco as mj
    real = mj.simulate

    def stiffer(m, duration, dt_out, settings=None):
        import dataclasses
        f = m.forces[0]
        p = f.parameters.copy()
        p[0] *= 1.01
        return real(dataclasses.replace(m, forces=(dataclasses.replace(f, parameters=p),)), duration, dt_out, settings)
    monkeypatch.setattr(mj, "simulate", stiffer)
    case = ModelCase("strut_1s", 1.0, 0.01, {"mujoco": {"timestep": 1e-3}, "exudyn": {"step_size": 5e-4}})
    s = compare_model(model, [case], ["semirecursive", "mujoco", "exudyn"], log=lambda *a: None)
    v = s["cases"]["strut_1s"]["verdicts"]
    assert not v["mujoco"]["pass"] and "disagrees beyond numerical error" in v["mujoco"]["text"]
    assert v["semirecursive"]["pass"] and v["exudyn"]["pass"]
