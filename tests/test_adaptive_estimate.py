"""An adaptive peer's error estimate (comparisons.model_compare.adaptive_estimate): its tolerance ladder's
share plus, on a description with loops, its formulation companion's (the regularisation of the
symbolic engine's multipliers, which no tolerance controls); a missing companion leaves no estimate,
never a verdict of agreement."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from comparisons.estimate import FORMULATION_LABEL, TIGHT_LABEL
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


def test_the_estimate_adds_the_formulation_share_and_drops_the_rtol_advice_it_would_not_fix():
    model = load_model(MODELS / "fourbar_spring.toml")
    runs = _runs(model, {CONVERGED: 0.0, "symbolic": 1e-9, "symbolic_tight": 1e-9 + 2e-10,
                         "symbolic_regularised": 1e-9 - 3e-9})
    sc = scales(model, runs[CONVERGED])
    est, ev = adaptive_estimate(model, CASE, "symbolic", runs, sc)
    for o in model.outputs:
        assert np.isclose(est[o.name] * sc[o.name][0], 2e-10 + 3e-9, rtol=1e-6), (o.name, est[o.name])
    assert ev["formulation"]["setting"] == "regularisation" and "setting" not in ev   # no rtol would lower it
    # the ladder's share the larger: the rtol advice stays
    runs["symbolic_regularised"] = runs["symbolic_tight"]
    _, ev = adaptive_estimate(model, CASE, "symbolic", runs, sc)
    assert ev["setting"] == "rtol"


def test_a_missing_companion_leaves_no_estimate_and_no_pass():
    model = load_model(MODELS / "fourbar_spring.toml")
    runs = _runs(model, {CONVERGED: 0.0, CHECK: 0.0, "symbolic": 1e-3, "symbolic_tight": 1e-3})
    sc = scales(model, runs[CONVERGED])
    assert adaptive_estimate(model, CASE, "symbolic", runs, sc) is None   # its regularised run failed
    _, verdicts = judge(model, CASE, ["symbolic"], runs, model_rule(model, 3.0))
    assert not verdicts["symbolic"]["pass"] and verdicts["symbolic"]["consistent"] is None
    assert verdicts["symbolic"]["text"].startswith("no error estimate"), verdicts["symbolic"]["text"]
