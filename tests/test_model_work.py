"""Output kind ``work``: the work done on a mechanism by a force element, the excitation or the drives,
integrated inside each engine's time stepping; with the ``energy`` outputs it makes each engine's own
energy balance, E_kinetic + E_gravity - sum of every work = const, on any description.

Bounds, each from the engine's own error rule, not from its output:
- in-house (adaptive DOP853, the work as quadrature states under the same error control): every
  accepted step's local error is at most rtol times the state's scale, so the balance's global error is
  at most the steps' count x rtol x the peak input work;
- MuJoCo (RK4) and Exudyn (generalized-alpha): the powers' trapezoid over the steps is second order,
  as both integrators: the residual falls ~4x per halving of the step (>= 3x asserted), and at the
  case's step it is within the device's seismic gate's bound on an energy balance, 1e-2 of the peak
  input work.
Leaving one element's work out breaks each balance by orders of magnitude (so the bound can fail).
"""
from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from comparisons.builders import exudyn as exudyn_builder
from comparisons.builders import mujoco as mujoco_builder
from nsd_core.model import semirecursive
from nsd_core.model.assemble import DriveWorkSystem, system_of
from nsd_core.model.errors import ModelError
from nsd_core.model.load import parse_model

ROOT = Path(__file__).resolve().parents[1]
GATE_BOUND = 1e-2   # the device's seismic gate: energy-balance residual / peak input work
# (model, duration [s], MuJoCo settings, Exudyn settings): the models' own case steps
CASES = {
    "nsd_seismic": (0.2, {"timestep": 1e-4, "solref_factor": 2.0}, {"step_size": 1e-3}),
    "fourbar_spring": (1.0, {"timestep": 5e-3}, {"step_size": 5e-4}),
    "nsd_drive": (0.25, {"timestep": 5e-5}, {"step_size": 1e-3}),   # drive mode: two prescribed slides
}


def raw_model(name: str) -> dict:
    return tomllib.loads((ROOT / "models" / f"{name}.toml").read_text())


def with_work(name: str):
    """The model with its energies and a work output per force element, excitation and drives."""
    raw = raw_model(name)
    outs = [{"name": "E_kin", "kind": "energy", "term": "kinetic"},
            {"name": "E_grav", "kind": "energy", "term": "gravity"}]
    outs += [{"name": f"W_{f['name']}", "kind": "work", "element": f["name"]} for f in raw.get("forces", [])]
    if "excitation" in raw:
        outs.append({"name": "W_excitation", "kind": "work", "source": "excitation"})
    if raw.get("prescribed"):
        outs.append({"name": "W_drive", "kind": "work", "source": "drive"})
    raw["outputs"] = raw.get("outputs", []) + outs
    return parse_model(raw, name), raw["case"][0]["dt_out"]


def balance(run, leave_out: str = "") -> tuple[float, float]:
    """(max |E(t) - E(0) - sum W(t)|, peak |W| over the work outputs), one work left out on request."""
    o = run.outputs
    works = {k: v for k, v in o.items() if k.startswith("W_")}
    e = o["E_kin"] + o["E_grav"]
    r = e - e[0] - sum(v for k, v in works.items() if k != leave_out)
    return float(np.max(np.abs(r))), max(float(np.max(np.abs(v))) for v in works.values())


def check_fails_without_each(run, bound: float) -> None:
    """Each element whose work matters (peak above 100x the bound) breaks the balance when left out."""
    _, peak = balance(run)
    big = [k for k, v in run.outputs.items() if k.startswith("W_") and np.max(np.abs(v)) > 100 * bound * peak]
    assert big
    for k in big:
        assert balance(run, leave_out=k)[0] > 100 * bound * peak, k


@pytest.mark.parametrize("name", sorted(CASES))
def test_in_house_balance_within_its_tolerance(name):
    model, dt_out = with_work(name)
    duration = CASES[name][0]
    run = semirecursive.simulate(model, duration, dt_out)
    res, peak = balance(run)
    bound = run.stats["steps"] * run.stats["rtol"]
    assert res <= bound * peak, (res / peak, bound)
    check_fails_without_each(run, bound)


@pytest.mark.parametrize("engine", ["mujoco", "exudyn"])
@pytest.mark.parametrize("name", sorted(CASES))
def test_peer_balance_second_order_and_within_gate(name, engine):
    model, dt_out = with_work(name)
    duration, mj, ex = CASES[name]
    builder, settings, key = ((mujoco_builder, mj, "timestep") if engine == "mujoco" else
                              (exudyn_builder, ex, "step_size"))
    runs = [builder.simulate(model, duration, dt_out, {**settings, key: settings[key] / f}) for f in (1, 2)]
    (res_h, peak), (res_h2, _) = balance(runs[0]), balance(runs[1])
    assert res_h <= GATE_BOUND * peak, res_h / peak
    assert res_h / res_h2 >= 3.0, (res_h / peak, res_h2 / peak)   # second order in the step
    check_fails_without_each(runs[0], res_h / peak)


def test_three_engines_agree_on_the_work_within_their_error():
    """fourbar_spring's spring work: each peer's distance from the in-house run at rtol 1e-12 within 3x
    its own error estimate (Richardson from h and h/2, order 2: |W_h - W_h/2| x 4/3), the gate's rule."""
    model, dt_out = with_work("fourbar_spring")
    duration, mj, ex = CASES["fourbar_spring"]
    ref = semirecursive.simulate(model, duration, dt_out, {"rtol": 1e-12, "atol": 1e-14}).outputs["W_spring"]
    for builder, settings, key in ((mujoco_builder, mj, "timestep"), (exudyn_builder, ex, "step_size")):
        w_h, w_h2 = (builder.simulate(model, duration, dt_out, {**settings, key: settings[key] / f}).outputs["W_spring"]
                     for f in (1, 2))
        estimate = 4.0 / 3.0 * float(np.max(np.abs(w_h - w_h2)))
        assert float(np.max(np.abs(w_h - ref))) <= 3.0 * estimate, builder.name
        assert estimate <= 1e-2 * float(np.max(np.abs(ref))), builder.name


def test_every_force_path_gives_the_same_work():
    """MuJoCo's python path equals its compiled one to round-off; Exudyn's connectors its compiled forces
    to Newton's tolerance, its predicted forces within its own error (a different discretisation)."""
    model, dt_out = with_work("nsd_seismic")
    names = [o.name for o in model.outputs if o.kind == "work"]
    compiled = mujoco_builder.simulate(model, 0.02, dt_out, {"timestep": 1e-4, "solref_factor": 2.0})
    python = mujoco_builder.simulate(model, 0.02, dt_out, {"timestep": 1e-4, "solref_factor": 2.0, "passive": "python"})
    scale = max(float(np.max(np.abs(compiled.outputs[k]))) for k in names)
    for k in names:
        assert np.max(np.abs(compiled.outputs[k] - python.outputs[k])) <= 1e-10 * scale, k
    runs = {f: exudyn_builder.simulate(model, 0.1, dt_out, {"step_size": 2.5e-4, "forces": f})
            for f in ("compiled", "connectors", "predicted")}
    scale = max(float(np.max(np.abs(runs["compiled"].outputs[k]))) for k in names)
    for k in names:
        assert np.max(np.abs(runs["compiled"].outputs[k] - runs["connectors"].outputs[k])) <= 1e-7 * scale, k
        assert np.max(np.abs(runs["compiled"].outputs[k] - runs["predicted"].outputs[k])) <= 1e-3 * scale, k
    for run in runs.values():
        assert balance(run)[0] <= GATE_BOUND * balance(run)[1]


def test_no_work_output_leaves_the_in_house_state_unchanged():
    """Zero overhead when none is declared: no extra states, no drive-work system."""
    model = parse_model(raw_model("slider_crank"), "slider_crank")
    system, _ = system_of(model)
    assert system.n_extra == 0 and not isinstance(system, DriveWorkSystem)
    model, _ = with_work("slider_crank")
    system, _ = system_of(model)
    assert system.n_extra == 1 and isinstance(system, DriveWorkSystem)


def _parse_with_output(name: str, output: dict):
    raw = raw_model(name)
    raw["outputs"] = raw["outputs"] + [{"name": "W", "kind": "work", **output}]
    return parse_model(raw, name)


@pytest.mark.parametrize("name, output, message", [
    ("fourbar_spring", {"element": "sprung"}, "outputs.W.element = 'sprung': must name a force element; allowed: spring"),
    ("fourbar_spring", {"element": ["spring"]}, "outputs.W.element = ['spring']: must name a force element"),
    ("nsd_seismic", {"source": "ground"}, "outputs.W.source = 'ground': allowed: excitation"),
    ("fourbar_spring", {"source": "excitation"},
     "outputs.W.source = 'excitation': allowed: (none: no [excitation], no [[prescribed]])"),
    ("slider_crank", {"source": "excitation"}, "outputs.W.source = 'excitation': allowed: drive"),
    ("nsd_seismic", {"source": ["excitation"]}, "outputs.W.source = ['excitation']: allowed: excitation"),
    ("fourbar_spring", {"element": "spring", "source": "drive"},
     "outputs.W: give exactly one of element (a force element) or source (excitation, drive)"),
    ("fourbar_spring", {}, "outputs.W: give exactly one of element (a force element) or source (excitation, drive)"),
    ("fourbar_spring", {"element": "spring", "term": "kinetic", "sorce": "x"}, "outputs.W.sorce: unknown field"),
])
def test_hostile_work_outputs_one_line(name, output, message):
    with pytest.raises(ModelError) as e:
        _parse_with_output(name, output)
    text = str(e.value)
    assert message in text and "\n" not in text
