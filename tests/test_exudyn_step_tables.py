"""The Exudyn builder's per-step tables and readers (comparisons/builders/exudyn_drive.py GroundTable,
exudyn_work.Work during the solve): the same floats as the one-time-at-a-time paths they replace."""
from __future__ import annotations

import tomllib
from types import SimpleNamespace

import numpy as np

from comparisons.builders import exudyn as exudyn_builder
from comparisons.builders import exudyn_work
from comparisons.builders.exudyn_drive import BLOCK, GroundTable
from nsd_core.model.excitation import parse_excitation
from nsd_core.model.load import parse_model
from tests.test_model_exudyn_seismic import SDOF


def test_the_ground_table_holds_the_excitations_accelerations():
    """Every step's end time across two blocks, for a closed form and a record: the table's a_g is
    Excitation.acceleration's at that time, to the bit; a time off the table is computed at itself."""
    for spec in ({"ground": "harmonic:amplitude=2,frequency=3,azimuth=30,duration=10"},
                 {"record": {"set": "nearfield-pulse", "id": 1, "scale": 0.4, "rotate": 20}}):
        exc = parse_excitation({"type": "ground_acceleration", **spec})
        h, steps = 1.3e-4, BLOCK + 50
        table = GroundTable(SimpleNamespace(excitation=exc), h, steps)
        for n in (0, 1, 17, BLOCK - 1, BLOCK, BLOCK + 49):
            table._index(n, (n + 1) * h)   # the block holding step n
            t = (n + 1) * h
            assert table.acceleration(t) == exc.acceleration(t).tolist(), (spec, n)
        t_off = 0.5 * h + 7 * h   # not a step's end: the motion at that time
        assert table.acceleration(t_off) == exc.acceleration(t_off).tolist()
        assert np.any(np.abs(exc.accelerations(np.arange(1, 200) * h)[:, :2]) > 0.0), spec


def test_the_work_read_during_the_solve_is_the_work_read_after_it(monkeypatch):
    """The work outputs (the excitation's and each element's, integrated over the steps) with the
    compiled values read through Exudyn's own vectors during the solve, and with every step read
    through copies (``live`` False): the same numbers, to the bit."""
    model = parse_model(tomllib.loads(SDOF + WORK_OUTPUTS))
    settings = {"step_size": 1e-3, "forces": "compiled"}
    live = exudyn_builder.simulate(model, 0.4, 0.01, settings)
    step = exudyn_work.Work.step
    monkeypatch.setattr(exudyn_work.Work, "step", lambda self, t, live=True: step(self, t, False))
    copied = exudyn_builder.simulate(model, 0.4, 0.01, settings)
    for name in ("work_sx", "work_sy", "work_excitation"):
        assert np.array_equal(live.outputs[name], copied.outputs[name]), name
        assert np.max(np.abs(live.outputs[name])) > 1e-3, name   # the ground did work on the body


WORK_OUTPUTS = """
[[outputs]]
name = "work_sx"
kind = "work"
element = "sx"
[[outputs]]
name = "work_sy"
kind = "work"
element = "sy"
[[outputs]]
name = "work_excitation"
kind = "work"
source = "excitation"
"""
