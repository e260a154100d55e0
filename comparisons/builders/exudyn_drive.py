"""What the pre-step function of comparisons.builders.exudyn sets before each step, at every step's end
time, computed a block of steps at a time: the prescribed motions' joint offsets (``offsets`` at one
time, ``DriveTable``) and the excitation's loads -m a_g (``GroundTable``, whose accelerations the work of
the excitation reads too).

Exudyn's pre-step function gets the end time of step n (0-based) as (n + 1) * h, h = duration / steps;
the table is computed at those times with each motion's ``table`` (nsd_core.model.description.
Prescribed.table: the same floats as the motion at one time), so a step reads its offsets instead of
calling every motion. A time that differs from the table's (another solver's clock) is computed as
before, at that time.
"""
from __future__ import annotations

import numpy as np

BLOCK = 4096   # steps a block: 4096 x 6 offsets a driven joint (~1 MB as Python lists)


def offsets(slots: dict, t: float, J: np.ndarray | None, derivative: int = 0) -> list[float]:
    """The six offsets at t (or their ``derivative``-th time derivative, 0 or 2): the prescribed coordinates
    in the joint frame, translations turned by J (the joint frame, when Exudyn reads them in global
    coordinates; None: as they are)."""
    out = [0.0] * 6
    for k, p in slots.items():
        out[k] = p(t)[derivative]
    if J is not None:
        out[:3] = [float(v) for v in J @ np.asarray(out[:3])]
    return out


def offset_rows(slots: dict, times: np.ndarray, J: np.ndarray | None) -> list[list[float]]:
    """``offsets`` at every time of ``times``, one list a time (each motion over all times at once)."""
    out = np.zeros((len(times), 6))
    for k, p in slots.items():
        out[:, k] = p.table(times)[0]
    rows = out.tolist()
    if J is not None:   # as ``offsets``: the three translations of each row turned by J
        for r in rows:
            r[:3] = [float(v) for v in J @ np.asarray(r[:3])]
    return rows


class _StepTable:
    """Rows computed at the end times of a block of steps of size h (``steps`` in all), a block at a
    time: ``_rows(times)`` gives them; ``_index(n, t)`` is step n's row, or None when Exudyn's time t
    is not the table's (another solver's clock: the caller computes at t itself)."""

    def __init__(self, build, h: float, steps: int):
        self.build, self.h, self.steps = build, h, steps
        self.first, self.times, self.rows = 0, [], []

    def _rows(self, times: np.ndarray) -> list:
        raise NotImplementedError

    def _index(self, n: int, t: float) -> int | None:
        i = n - self.first
        if not 0 <= i < len(self.times):   # the block of steps from n on
            times = np.arange(n + 1, min(n + BLOCK, self.steps) + 1) * self.h
            self.first, self.times, self.rows = n, times.tolist(), self._rows(times)
            i = 0
        return i if self.times[i] == t else None


class DriveTable(_StepTable):
    """The driven joints' offsets (Build.driven: (joint, slots, J)) at the end of every step, set in
    Exudyn by ``set(n, t)`` before step n."""

    def __init__(self, build, h: float, steps: int):
        super().__init__(build, h, steps)
        self.joints = [joint for joint, _, _ in build.driven]

    def _rows(self, times: np.ndarray) -> list:
        return [offset_rows(slots, times, J) for _, slots, J in self.build.driven]

    def set(self, n: int, t: float) -> None:
        """The offsets for step n, which ends at t (Exudyn's time)."""
        i = self._index(n, t)
        if i is None:   # not the table's time: the motions at t itself
            self.build.drive(t)
            return
        set_parameter = self.build.mbs.SetObjectParameter
        for joint, rows in zip(self.joints, self.rows):
            set_parameter(joint, "offsetUserFunctionParameters", rows[i])


class GroundTable(_StepTable):
    """The excitation's a_g = (a_x, a_y, 0) at the end of every step (the ground motion's series over a
    block of times: the same floats as Excitation.acceleration at each); ``set(n, t)`` sets the ground
    loads (Build.ground_loads) to -a_g before step n, which ends at t."""

    def _rows(self, times: np.ndarray) -> list:
        return self.build.excitation.accelerations(times).tolist()   # lists: what Exudyn's loads take

    def acceleration(self, t: float) -> list[float]:
        """a_g(t) from the table when t is one of its times (the last block's), else at t itself."""
        i = int(round(t / self.h)) - 1 - self.first
        if 0 <= i < len(self.times) and self.times[i] == t:
            return self.rows[i]
        return self.build.excitation.acceleration(t).tolist()

    def set(self, n: int, t: float) -> None:
        """The loads for step n, which ends at t (Exudyn's time)."""
        i = self._index(n, t)
        a = self.rows[i] if i is not None else self.build.excitation.acceleration(t).tolist()
        load = [-a[0], -a[1], -a[2]]
        set_parameter = self.build.mbs.SetLoadParameter
        for ld in self.build.ground_loads:
            set_parameter(ld, "loadVector", load)
