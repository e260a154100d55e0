"""The gate's engine interface over the description builders (comparisons/engines/described.py,
``model = "described"``): the same columns as the adapters, from the peers' own runs of the device's
description, agreeing with the in-house model; a bad choice is one line before any run."""
from __future__ import annotations

import numpy as np
import pytest

from comparisons.engines import run_engine
from comparisons.engines.base import check_settings
from nsd_core.device.drive import Drive
from nsd_core.device.model import simulate
from nsd_core.device.params import ParameterError, Params


@pytest.mark.parametrize("engine,settings", [("mujoco", {"timestep": 2.5e-5}),
                                             ("exudyn", {"step_size": 2.5e-5, "builder_forces": "predicted"})])
def test_a_described_peer_gives_the_adapters_columns_and_the_in_house_force(engine, settings):
    """A variant (6 wires, stiffer ropes) on a circle at 10 Hz: every column the gate reads is there,
    with the adapter's units, and over the steady (third) cycle, the one the gate compares, the drive
    force agrees with the in-house model within 1e-3 of its peak (the gate's tolerance). (The circle's
    ramp ends with a jump in acceleration at t = 1/f, where the drive force is two-valued: Exudyn
    reports the force of the step that ends there, the in-house model the one after it.)"""
    from nsd_core.device.cycle import last_cycle
    params = Params().replace(n_wires=6, rope_stiffness=6e5)
    drive = Drive(amplitude=0.015, frequency=10.0, path="circle", cycles=3, samples_per_cycle=400)   # as the gate
    ref = simulate(params, drive, rtol=1e-10)
    adapter = run_engine(engine, params, drive, {k: v for k, v in settings.items() if k != "builder_forces"} | {"model": "adapter"})
    run = run_engine(engine, params, drive, {**settings, "model": "described"})
    assert set(adapter.columns) <= set(run.columns) and run.stats["model"] == "described"
    assert all(run.units[c] == adapter.units[c] for c in adapter.columns)
    c = last_cycle(np.asarray(ref["t"]), drive.frequency)
    peak = np.max(np.hypot(ref["F_x"], ref["F_y"])[c])
    assert np.max(np.hypot(run["F_x"] - ref["F_x"], run["F_y"] - ref["F_y"])[c]) < 1e-3 * peak
    assert np.max(np.abs(run["wire5_stress"] - adapter["wire5_stress"])) < 1e-2 * np.max(np.abs(adapter["wire5_stress"]))
    assert np.max(np.abs(run["closure"])) < 1e-6


@pytest.mark.parametrize("engine,key,value", [("mujoco", "model", "generated"), ("exudyn", "builder_forces", "fast")])
def test_a_bad_model_choice_is_one_line(engine, key, value):
    from comparisons.engines import get_engine
    with pytest.raises(ParameterError) as e:
        check_settings(get_engine(engine), {key: value}, f"case x: settings.{engine}")
    assert f"case x: settings.{engine}.{key} = {value!r}: allowed:" in str(e.value) and "\n" not in str(e.value)


@pytest.mark.parametrize("perturb", [{"what": "cap_mass", "by": 0.01},
                                     {"what": "rope_stiffness", "index": 1, "by": 0.05},
                                     {"what": "rest_ignores_weight"}, {"what": "rod_length", "by": 2e-4}])
def test_an_injected_modelling_error_reaches_the_described_model(perturb):
    """The gate's detection power (comparisons/power.py) injects an error into one peer's model: the
    described model carries it as the adapter does. On the 10 Hz line, MuJoCo's force departs from
    its unperturbed run by what the adapter's departs, within 2 % (the error itself is 1e-3 to 6e-3
    of the peak, against a step error of 5e-5)."""
    drive = Drive(amplitude=0.015, frequency=10.0, cycles=2, samples_per_cycle=200)
    runs = {m: [run_engine("mujoco", Params(), drive, {"timestep": 5e-5, "model": m, **extra})
                for extra in ({}, {"perturb": perturb})] for m in ("adapter", "described")}
    shift = {m: np.max(np.abs(p["F"] - n["F"])) for m, (n, p) in runs.items()}
    assert shift["described"] > 5e-4 * np.max(np.abs(runs["adapter"][0]["F"]))
    assert abs(shift["described"] - shift["adapter"]) < 0.02 * shift["adapter"]


@pytest.mark.parametrize("path", ["line", "circle", "figure8"])
def test_the_step_loops_table_of_a_device_path_is_the_path_itself(path):
    """MuJoCo's compiled loop reads the prescribed motion from a table made in one call of the drive's
    compiled path (comparisons.builders.mujoco_compiled.motion_table): the same numbers, to the bit, as
    the description's motion evaluated one time at a time."""
    from comparisons.builders.mujoco_compiled import motion_table
    from comparisons.engines.described import described_model
    drive = Drive(amplitude=0.015, frequency=10.0, path=path, cycles=2, samples_per_cycle=100)
    model, _ = described_model(Params(), drive)
    t = np.linspace(0.0, drive.duration, 1001)
    for p in model.prescribed:
        assert np.array_equal(motion_table(p, t), np.array([p(x) for x in t]).T)


def test_a_variants_first_described_run_warms_up_for_its_own_shape():
    """A described model's code is generated per shape (ropes, wires): a variant's first run warms up
    for its shape (its compile_time is the warm-up's) instead of compiling inside its timed run; a
    second run of the same shape warms nothing."""
    drive = Drive(amplitude=0.005, frequency=10.0, cycles=1, samples_per_cycle=50)
    s = {"timestep": 1e-4, "model": "described"}
    times = [run_engine("mujoco", p, drive, s).stats["compile_time"]
             for p in (Params().replace(n_wires=5), Params().replace(n_wires=7), Params().replace(n_wires=7))]
    assert times[0] > 0.0 and times[1] > 0.0 and times[2] == 0.0
