"""The device written as a model description (nsd_core.device.describe) is the device: built by the
description's in-house builder it gives the hand-built device model's drive force."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nsd_core.device.describe import device_description
from nsd_core.device.drive import Drive
from nsd_core.device.model import simulate
from nsd_core.device.params import Params
from nsd_core.model.load import load_model, parse_model
from nsd_core.model.semirecursive import simulate as simulate_model

MODELS = Path(__file__).resolve().parents[1] / "models"


def test_the_committed_device_description_is_the_generators():
    assert (MODELS / "nsd_drive.toml").read_text() == device_description(Params(), 0.015, 1.0)


@pytest.mark.slow   # ~1 min alone (the description's laws called from Python), 3 min on a loaded machine
def test_device_description_gives_the_device_models_force_on_a_variant():
    """A variant (8 wires, stiffer ropes, 30 degrees): the description's run and the device model agree
    on the drive force to 1e-6 of its peak over 0.03 s at 10 Hz, past the ropes' slackening (the same
    laws and tree, written twice: as data and by hand; both adaptive at rtol 1e-10, whose steps differ
    and meet the laws' kinks differently: measured 1.0e-7 of the peak over half a cycle)."""
    import tomllib
    params = Params().replace(n_wires=8, rope_stiffness=7.5e5)
    model = parse_model(tomllib.loads(device_description(params, 0.0255, 10.0, 30.0)))
    run = simulate_model(model, 0.03, 1e-4, {"rtol": 1e-10, "atol": 1e-12, "max_step": 1e-3})
    ref = simulate(params, Drive(amplitude=0.0255, frequency=10.0, direction_deg=30.0, cycles=1, samples_per_cycle=1000),
                   rtol=1e-10)
    n = len(run.t)
    for col in ("F_x", "F_y"):
        peak = np.max(np.abs(ref["F_x"]))
        assert np.max(np.abs(run.outputs[col] - np.asarray(ref[col])[:n])) < 1e-6 * peak
    assert np.max(np.abs(run.outputs["cap_z"] - np.asarray(ref["cap_z"])[:n])) < 1e-10


def test_the_device_description_loads_with_its_laws():
    m = load_model(MODELS / "nsd_drive.toml")
    laws = {f.law.name for f in m.forces}
    assert laws == {"rope", "sma_wire", "push_spring"}
    assert [b.joint.type for b in m.bodies] == ["translational", "prismatic", "universal"]


@pytest.mark.parametrize("change,expected", [
    ({"path": "spiral"}, "prescribed.drive_x.path = 'spiral': allowed: line, circle, ellipse, figure8"),
    ({"component": "z"}, "prescribed.drive_x.component = 'z': allowed: x, y"),
    ({"frequency": float("nan")}, "prescribed.drive_x.frequency = nan: must be a number"),
    ({"amplitude": "big"}, "prescribed.drive_x.amplitude = 'big': must be a number"),
    ({"frequency": 0.0}, "prescribed.drive_x: frequency = 0.0: must be in [0.05, 100.0] Hz"),
    ({"path": "ellipse"}, "prescribed.drive_x: minor: missing"),
])
def test_a_bad_device_path_is_one_line_naming_the_field(change, expected):
    """motion = "device_path": each mistake named once (the field, the value, what is allowed)."""
    import tomllib
    from nsd_core.model.errors import ModelError
    d = tomllib.loads((MODELS / "nsd_drive.toml").read_text())
    d["prescribed"][0] = {"name": "drive_x", "joint": "cap", "dof": 0, "motion": "device_path", "path": "circle",
                          "amplitude": 0.01, "frequency": 1.0, "component": "x", **change}
    with pytest.raises(ModelError) as e:
        parse_model(d)
    assert str(e.value).startswith(expected) and "\n" not in str(e.value) and str(e.value).count("prescribed.") == 1
