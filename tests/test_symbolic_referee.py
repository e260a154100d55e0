"""The symbolic engine as the campaign's referee (comparisons.campaign.referee): a peer whose model is
wrong (MuJoCo with the coupler 3 % heavier in its input alone) disagrees with the converged reference,
and the referee, run on that case, sides with the reference."""
from __future__ import annotations

import dataclasses
from pathlib import Path

from comparisons.builders import mujoco as mj
from comparisons.campaign.referee import disagreeing, referee
from comparisons.model_cases import ModelCase
from comparisons.model_compare import compare_model
from nsd_core.model.load import load_model

MODELS = Path(__file__).resolve().parents[1] / "models"


def test_the_referee_sides_with_the_reference_against_a_wrong_peer(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    model = load_model(MODELS / "fourbar_spring.toml")
    real = mj.simulate

    def heavier(m, duration, dt_out, settings=None):
        b = m.bodies[1]
        return real(dataclasses.replace(m, bodies=(m.bodies[0], dataclasses.replace(b, mass=b.mass * 1.03),
                                                   *m.bodies[2:])), duration, dt_out, settings)
    monkeypatch.setattr(mj, "simulate", heavier)
    case = ModelCase("fourbar_1s", 1.0, 0.01, {"mujoco": {"timestep": 1e-3}})
    s = compare_model(model, [case], ["semirecursive", "mujoco"], log=lambda *a: None)
    assert disagreeing(s) == {"fourbar_1s": ["mujoco"]}, s["cases"]["fourbar_1s"]["verdicts"]
    found = referee(model, [case], s)["fourbar_1s"]["mujoco"]
    assert found["side"] == "reference", found
    assert found["agrees_with_reference"] and not found["agrees_with_peer"]
    assert found["symbolic_vs_peer_ratio"] > 1.0
