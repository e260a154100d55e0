"""The Exudyn builder's pre-step function (comparisons/builders/exudyn.py, exudyn_drive.py,
exudyn_compiled.CompiledForces.stepper): the prescribed offsets read from a table computed before the
steps, and the compiled pre-step call on views of Exudyn's vectors, give bit for bit what the motions
called at each step's time and the copying call (``CompiledForces.advance``) give. Real exudyn."""
from __future__ import annotations

import numpy as np

from comparisons.builders import exudyn as exudyn_builder
from comparisons.builders import exudyn_drive
from comparisons.builders.exudyn_compiled import CompiledForces
from comparisons.engines.described import described_model
from comparisons.engines.peers import ExudynEngine
from nsd_core.device.drive import Drive
from nsd_core.device.params import Params
from nsd_core.model.description import Prescribed
from nsd_core.model.load import load_model
from tests.conftest import ROOT

TIMES = np.arange(1, 4001) * (0.1 / 4000)   # step end times as the pre-step gets them: (n + 1) h


def _motions() -> list:
    """A harmonic, a constant speed and the device's plate path (line, circle, figure-8; x and y)."""
    out = list(load_model(ROOT / "models" / "nsd_drive.toml").prescribed)
    out.append(Prescribed("slide", "cap", 0, "constant_speed", {"start": 0.1, "speed": 0.37}))
    for drive in (Drive(0.015, 10.0), Drive(0.022, 10.0, path="circle"), Drive(0.015, 10.0, path="figure8", minor=0.0075)):
        out += described_model(Params(), drive)[0].prescribed
    return out


def test_a_motions_table_is_the_motion_at_each_time():
    """Prescribed.table: (q, q', q'') at every time, each float the call at that time gives."""
    for p in _motions():
        assert np.array_equal(p.table(TIMES), np.array([p(t) for t in TIMES.tolist()]).T), p.name


def test_offset_rows_are_the_offsets_at_each_time():
    """exudyn_drive.offset_rows against ``offsets`` time by time, the translations as they are and
    turned by a joint frame J (Exudyn's global offsets)."""
    x, y = _motions()[-2:]
    slots = {0: x, 2: y, 4: x}
    J = np.linalg.qr(np.random.default_rng(3).standard_normal((3, 3)))[0]
    for frame in (None, J):
        rows = exudyn_drive.offset_rows(slots, TIMES, frame)
        assert rows == [exudyn_drive.offsets(slots, t, frame) for t in TIMES.tolist()]


def _per_step(monkeypatch) -> None:
    """The pre-step as it was: every motion called at Exudyn's time, Exudyn's vectors copied each step."""
    class AtEachTime(exudyn_drive.DriveTable):
        def set(self, n, t):
            self.build.drive(t)
    monkeypatch.setattr(exudyn_builder, "DriveTable", AtEachTime)
    monkeypatch.setattr(CompiledForces, "stepper", lambda self, mbs, h, predict: lambda: self.advance(mbs, h, predict))


def test_the_pre_step_tables_give_the_per_step_run_bit_for_bit(monkeypatch):
    """A drive-mode run (the device's circle at 10 Hz, 2000 steps, forces "predicted") reads every
    step's offsets from the table (Exudyn's time is the table's: no step falls back to the motions)
    and writes the same columns, bit for bit, as the run that calls the motions at every step and
    copies Exudyn's vectors."""
    drive, settings = Drive(0.022, 10.0, cycles=1, samples_per_cycle=100, path="circle"), \
        {"step_size": 5e-5, "min_steps_per_cycle": 1}
    calls = []
    original = exudyn_builder.Build.drive
    monkeypatch.setattr(exudyn_builder.Build, "drive", lambda self, t: (calls.append(t), original(self, t)))
    fast = ExudynEngine().run(Params(), drive, settings)
    assert fast.stats["steps"] == 2000 and calls == []
    _per_step(monkeypatch)
    slow = ExudynEngine().run(Params(), drive, settings)
    assert len(calls) == 2000
    assert fast.columns.keys() == slow.columns.keys()
    for k in fast.columns:
        assert np.array_equal(fast.columns[k], slow.columns[k]), k


def test_a_described_model_runs_the_same_with_the_tables(monkeypatch):
    """The harmonic drive of models/nsd_drive.toml, forces "compiled" (the laws' commit in the pre-step
    call): the same outputs, bit for bit, as the per-step pre-step."""
    model = load_model(ROOT / "models" / "nsd_drive.toml")
    fast = exudyn_builder.simulate(model, 0.05, 0.005, {"step_size": 2.5e-4})
    _per_step(monkeypatch)
    slow = exudyn_builder.simulate(model, 0.05, 0.005, {"step_size": 2.5e-4})
    for k in fast.outputs:
        assert np.array_equal(fast.outputs[k], slow.outputs[k]), k
