"""Mechanisms the randomized campaign generated (comparisons.campaign; docs/validation.md) on which an engine
was wrong, kept as files: each test checks the defect's root stays fixed, against the in-house engine at
a tight tolerance (the converged reference) or between an engine's two paths."""
from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from comparisons.builders import exudyn as ex
from comparisons.builders import mujoco as mj
from nsd_core.model import semirecursive
from nsd_core.model.load import load_model

DATA = Path(__file__).resolve().parent / "data" / "campaign"
TIGHT = {"rtol": 1e-12, "atol": 1e-14}


def mechanism(seed: int, duration: float | None = None):
    path = DATA / f"seed_{seed}.toml"
    case = tomllib.loads(path.read_text())["case"][0]
    return load_model(path), duration or case["duration"], case["dt_out"]


def relative(run, ref, name, index=slice(None)) -> float:
    return float(np.max(np.abs(run.outputs[name][index] - ref.outputs[name][index])) / np.max(np.abs(ref.outputs[name])))


def test_exudyn_starts_a_harmonic_drive_with_its_acceleration():
    """A double-rocker driven harmonically: Exudyn's initial accelerations ignore the drive's (C_tt = 0),
    so its torque at t = 0 missed by 5.3e-2 of the peak at every step (exudyn_start)."""
    model, _, dt = mechanism(1)
    ref = semirecursive.simulate(model, 0.1, dt, TIGHT)
    for h in (1e-4, 5e-5):
        run = ex.simulate(model, 0.1, dt, {"step_size": h})
        assert relative(run, ref, "drive_torque", 0) < 1e-7
        assert relative(run, ref, "drive_torque") < 1e-4


def test_mujoco_records_each_law_after_a_plane_law_in_its_own_column():
    """A plane law takes three value columns; the compiled callback wrote later elements' values one
    column early, so their force outputs read 0 (the dynamics were right)."""
    model, _, dt = mechanism(30)
    compiled, python = (mj.simulate(model, 0.1, dt, {"passive": p}) for p in ("compiled", "python"))
    for name in ("spring0_out", "spring1_out", "b0_hysteresis_out"):
        assert relative(compiled, python, name) < 1e-9, name
    assert np.max(np.abs(compiled.outputs["spring1_out"])) > 1.0


def test_exudyn_slide_law_rate_on_a_turning_parent_converges():
    """A planar joint on a prismatic on a planar one, every slide on a spring-damper: the slide's rate
    carried an extra -w x rel, and Exudyn converged to another motion (3.8e-3 of b2's angle at every step)."""
    model, _, dt = mechanism(69)
    ref = semirecursive.simulate(model, 0.3, dt, TIGHT)
    errors = [max(relative(ex.simulate(model, 0.3, dt, {"step_size": h}), ref, n) for n in ("b2_q0", "tip", "tip_v"))
              for h in (1e-4, 5e-5)]
    assert errors[1] < 3e-5 and errors[0] / errors[1] > 3.0, errors   # second order, to the same motion


def test_mujoco_kinetic_energy_leaves_the_drive_armature_out_exactly():
    """A driven chain: 1/2 v^T M v less the virtual drive's armature share cancelled to ~7e-11 of the peak."""
    model, _, dt = mechanism(81)
    ref = semirecursive.simulate(model, 0.2, dt, TIGHT)
    assert relative(mj.simulate(model, 0.2, dt, {}), ref, "kinetic") < 1e-11


@pytest.mark.parametrize("seed", range(40))
def test_every_generated_description_loads_and_assembles(seed):
    """The generator's descriptions are valid (load, engines' checks) and their loops close at the start
    on the drawn branch (the initial guesses are within 0.02 rad of it)."""
    import tomli_w

    from comparisons.campaign.generate import Draws, generate
    from nsd_core.model.assemble import initial_state
    from nsd_core.model.load import parse_model

    desc = generate(Draws(seed))
    model = parse_model(tomllib.loads(tomli_w.dumps(desc)), f"seed_{seed}.toml")
    ex.check(model)
    state = initial_state(model)
    guesses = desc.get("initial", {}).get("coordinates", {})
    for body, value in guesses.items():
        if model.loops and not isinstance(value, list):
            assert abs(state.q[(body, 0)] - value) < 0.05, (body, state.q[(body, 0)], value)


class HypothesisDraws:
    """The generator's choices drawn by hypothesis (shrinkable: a failing description shrinks to a small one)."""

    def __init__(self, data):
        self.data = data

    def uniform(self, lo, hi):
        from hypothesis import strategies as st
        return self.data.draw(st.floats(lo, hi, allow_nan=False, allow_infinity=False))

    def integer(self, lo, hi):
        from hypothesis import strategies as st
        return self.data.draw(st.integers(lo, hi))

    def choice(self, options):
        from hypothesis import strategies as st
        return self.data.draw(st.sampled_from(list(options)))


def test_hypothesis_drawn_descriptions_load_and_assemble():
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    import tomli_w

    from comparisons.campaign.generate import generate
    from nsd_core.model.assemble import initial_state
    from nsd_core.model.load import parse_model

    @settings(max_examples=15, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
    @given(st.data())
    def check(data):
        desc = generate(HypothesisDraws(data))
        model = parse_model(tomllib.loads(tomli_w.dumps(desc)), "drawn.toml")
        ex.check(model)
        initial_state(model)
    check()


@pytest.mark.parametrize("argv", [["--seeds", "x-3"], ["--seeds", "5-2"], ["--workers", "0"], ["--timeout", "-1"],
                                  ["--timeout", "nan"]])
def test_the_campaign_refuses_bad_flags_in_one_line(argv, tmp_path, capsys):
    import importlib.util
    spec = importlib.util.spec_from_file_location("campaign", Path(__file__).resolve().parents[1] / "benchmarks" / "campaign.py")
    campaign = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(campaign)
    out = tmp_path / "out"
    assert campaign.main(argv + ["--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"campaign: {argv[0]}")
    assert not out.exists()
