"""The Exudyn builder's consistent start (comparisons/builders/exudyn_start.py) leaves no round-off in
the initial accelerations and multipliers that the run then carries as subnormal numbers (a slow path
of the processor's arithmetic: the device's circles ran 1.5x slower, the campaign's driven four-bars
1.4x). Real exudyn."""
from __future__ import annotations

import exudyn as exu
import numpy as np
import tomli_w

from comparisons.builders import exudyn as exudyn_builder
from comparisons.campaign.run import describe
from comparisons.engines.peers import ExudynEngine
from comparisons.model_cases import load_model_cases
from nsd_core.model.load import load_model
from nsd_core.device.drive import Drive
from nsd_core.device.params import Params

TINY = np.finfo(float).tiny   # the smallest normal double


def _subnormal_steps(monkeypatch, run) -> list:
    """The steps at which any of Exudyn's state vectors holds a subnormal number (every 100th step)."""
    found, original = [], exu.MainSystem.SetPreStepUserFunction
    ct = exu.ConfigurationType.Current

    def watch(mbs, function):
        count = [0]

        def pre_step(m, t):
            count[0] += 1
            if count[0] % 100 == 0:
                sd = m.systemData
                for v in (sd.GetODE2Coordinates(ct), sd.GetODE2Coordinates_t(ct), sd.GetODE2Coordinates_tt(ct),
                          sd.GetAECoordinates(ct)):
                    v = np.abs(np.asarray(v))
                    if np.any((v > 0) & (v < TINY)):
                        found.append(count[0])
                        break
            return function(m, t)
        return original(mbs, pre_step)
    monkeypatch.setattr(exu.MainSystem, "SetPreStepUserFunction", watch)
    run()
    return found


def test_the_circle_carries_no_subnormal_numbers(monkeypatch):
    """The device's circle from its centre (the consistent start's term is zero in 38 of 48 entries in
    exact arithmetic, ~1e-32 in the solve's): 6000 steps, none with a subnormal number in the state."""
    drive = Drive(0.015, 10.0, cycles=1, samples_per_cycle=100, path="circle")
    settings = {"step_size": 1e-4 / 6, "min_steps_per_cycle": 1}
    assert _subnormal_steps(monkeypatch, lambda: ExudynEngine().run(Params(), drive, settings)) == []


def test_a_driven_four_bar_carries_no_subnormal_numbers(monkeypatch, tmp_path):
    """The campaign's seed 95, a driven double-rocker: 5 of its 21 initial accelerations were round-off
    (8.4e-15 against a largest of 29, just above machine epsilon of it) and turned subnormal by step
    2700; its own case, none."""
    desc = describe(95)
    path = tmp_path / "m.toml"
    path.write_text(tomli_w.dumps(desc))
    model = load_model(path)
    case = load_model_cases(model, None, ["semirecursive", "exudyn"])[0]
    run = lambda: exudyn_builder.simulate(model, case.duration, case.dt_out, case.settings.get("exudyn"))  # noqa: E731
    assert _subnormal_steps(monkeypatch, run) == []
