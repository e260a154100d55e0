"""An adaptive peer's error estimate (comparisons.model_compare.adaptive_estimate): its tolerance ladder's
share plus, on a description with loops, its formulation companion's (the regularisation of the
symbolic engine's multipliers, which no tolerance controls); a missing companion leaves no estimate,
never a verdict of agreement."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from comparisons.estimate import FORMULATION_LABEL, TIGHT_LABEL, step_needed
from comparisons.model_cases import ModelCase
from comparisons.model_compare import CHECK, CONVERGED, adaptive_estimate, judge, model_rule, run_plan, scales
from nsd_core.model.load import load_model
from nsd_core.model.run import ModelRun

MODELS = Path(__file__).resolve().parents[1] / "models"
CASE = ModelCase("c", 1.0, 0.1, {})


def _runs(model, offsets: dict) -> dict:
    """label -> a ModelRun whose every output is sin(t) + offset (the converged run's offset 0)."""
    t = np.linspace(0.0, 1.0, 11)
    return {label: ModelRun("symbolic", t, {o.name: np.sin(t) + off for o in model.outputs},
                            {o.name: o.unit for o in model.outputs}, {})
            for label, off in offsets.items()}


def test_the_formulation_companion_is_planned_only_where_there_are_loops():
    looped, free = load_model(MODELS / "fourbar_spring.toml"), load_model(MODELS / "iftomm_a01_pendulum.toml")
    assert looped.loops and not free.loops
    plan = {label: s for label, _, s in run_plan(looped, CASE, ["semirecursive", "symbolic"])}
    assert plan[FORMULATION_LABEL.format(engine="symbolic")] == {"regularisation": 1e-7}
    assert plan[TIGHT_LABEL.format(engine="symbolic")] == {"rtol": 1e-12, "atol": 1e-14}
    labels = [label for label, _, _ in run_plan(free, CASE, ["semirecursive", "symbolic"])]
    assert FORMULATION_LABEL.format(engine="symbolic") not in labels and TIGHT_LABEL.format(engine="symbolic") in labels


def test_the_estimate_adds_the_formulation_share_and_keeps_the_ladders_apart():
    model = load_model(MODELS / "fourbar_spring.toml")
    runs = _runs(model, {CONVERGED: 0.0, "symbolic": 1e-9, "symbolic_tight": 1e-9 + 2e-10,
                         "symbolic_regularised": 1e-9 - 3e-9})
    sc = scales(model, runs[CONVERGED])
    est, ev = adaptive_estimate(model, CASE, "symbolic", runs, sc)
    for o in model.outputs:
        assert np.isclose(est[o.name] * sc[o.name][0], 2e-10 + 3e-9, rtol=1e-6), (o.name, est[o.name])
        assert np.isclose(ev["ladder_share"][o.name] * sc[o.name][0], 2e-10, rtol=1e-6)
    assert ev["formulation"]["setting"] == "regularisation" and ev["setting"] == "rtol"


def _verdict(model, tight: float, regularised: float) -> dict:
    """The symbolic engine's verdict on a run equal to the converged one, its companions off by these
    fractions of each output's scale."""
    t = np.linspace(0.0, 1.0, 11)
    sc = scales(model, _runs(model, {CONVERGED: 0.0})[CONVERGED])
    runs = {label: ModelRun("symbolic", t, {o.name: np.sin(t) + off * sc[o.name][0] for o in model.outputs},
                            {o.name: o.unit for o in model.outputs}, {})
            for label, off in {CONVERGED: 0.0, CHECK: 0.0, "symbolic": 0.0, "symbolic_tight": tight,
                               "symbolic_regularised": regularised}.items()}
    return judge(model, CASE, ["symbolic"], runs, model_rule(model, 3.0))[1]["symbolic"]


def test_the_rtol_advised_answers_for_the_ladders_share_alone():
    model = load_model(MODELS / "fourbar_spring.toml")
    # the formulation's share over the tolerance, the ladder's far within: no tolerance would lower it
    v = _verdict(model, tight=1e-9, regularised=0.05)
    assert v["text"].startswith("not converged at these settings") and "needs" not in v["text"], v["text"]
    assert v["needs"] is None
    # the ladder's share over it (a loose rtol, where both companions move with the integration's error):
    # the rtol it needs, from the ladder's share 0.05 (error ~ rtol), not from the whole estimate 0.1
    v = _verdict(model, tight=0.05, regularised=0.05)
    assert f"needs rtol <= {step_needed(1e-10, 0.05, 1e-3, 1.0):.3g}" in v["text"], v["text"]
    assert np.isclose(v["needs"]["rtol"], step_needed(1e-10, 0.05, 1e-3, 1.0), rtol=1e-9, atol=0.0)
    assert not np.isclose(v["needs"]["rtol"], step_needed(1e-10, 0.1, 1e-3, 1.0), rtol=1e-3, atol=0.0)


def test_a_missing_companion_leaves_no_estimate_and_no_pass():
    model = load_model(MODELS / "fourbar_spring.toml")
    runs = _runs(model, {CONVERGED: 0.0, CHECK: 0.0, "symbolic": 1e-3, "symbolic_tight": 1e-3})
    sc = scales(model, runs[CONVERGED])
    assert adaptive_estimate(model, CASE, "symbolic", runs, sc) is None   # its regularised run failed
    _, verdicts = judge(model, CASE, ["symbolic"], runs, model_rule(model, 3.0))
    assert not verdicts["symbolic"]["pass"] and verdicts["symbolic"]["consistent"] is None
    assert verdicts["symbolic"]["text"].startswith("no error estimate"), verdicts["symbolic"]["text"]
