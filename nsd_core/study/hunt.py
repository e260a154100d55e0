"""Which intensity to run next in an incremental dynamic analysis (IDA) of one record.

Hunt and fill, after Vamvatsikos and Cornell (2002), "Incremental dynamic analysis", Earthquake
Engineering and Structural Dynamics 31(3), Section 5 ("the hunt & fill tracing algorithm"):

1. hunt: run at ``start``, then step up with growing steps, IM_k = IM_{k-1} + step + (k - 1) growth
   (growth = step / 2, the paper's 0.1 g step with 0.05 g increment), until a run reaches the limit
   state;
2. bracket: halve the interval between the highest level that did not reach it and the lowest that
   did (or between 0 and that level when the first run already reached it) until the interval is
   at most ``resolution`` times its upper end;
3. fill (``Hunt.fill``, on by default; nsd p695 turns it off): with the runs the budget has left, halve
   the largest gap between the levels that did not reach the limit (from IM = 0), so the IDA curve
   below the limit is drawn evenly.

``bracket_state`` says whether a record's bracket ended within the resolution, or why not (the
budget spent first, the limit never reached).

At most ``max_runs`` runs per record. ``--levels L1,L2,...`` instead runs the given levels upwards
and stops at the first one that reaches the limit (a stripe analysis with the same stopping rule).

Everything here is a pure function of the record's history (level, reached) in the order run, so a
resumed IDA retraces the same levels and finds them in the store. The limit intensity of a record is
the lowest level observed to reach the limit (Baker 2015, "the IM at which each ground motion first
causes" the limit state); a record that never reaches it is right-censored at its highest level.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from nsd_core.device.params import ParameterError

GROWTH = 0.5  # step increment / step (Vamvatsikos and Cornell 2002: 0.1 g step, 0.05 g increment)
# Bounds (docs/limits.md, nsd ida): an intensity level lies in IM_RANGE m/s^2 (100 m/s^2 ~ 10 g, beyond any
# recorded motion); a record is scaled by level / IM at scale 1 within SCALE_RANGE (nsd seismic --scale's
# bounds): --levels and --start beyond it are refused, a hunt stops (the record censored) where its next
# level would leave either range. At most LEVELS_MAX levels (the bound of --max-runs).
IM_RANGE = (1e-3, 100.0)
LEVELS_MAX = 100
RESOLUTION_MIN = 1e-3   # a finer bracket than 0.1 % of the level is below what the runs can tell apart


def tidy(level: float) -> float:
    """A level rounded to 9 significant digits: the same level every time it is computed (job keys)."""
    return float(f"{level:.9g}")


@dataclass(frozen=True)
class Hunt:
    """Hunt-and-fill settings, in the intensity measure's unit (m/s^2)."""
    start: float = 0.25      # first level
    step: float = 0.25       # first step up (the next steps grow by GROWTH * step each)
    max_runs: int = 6        # runs per record and configuration, all phases together (a whole record costs
                             # ~0.1-1 wall s per model s: 6 runs x 14 records x 2 configurations ~ 10 min on 2 cores)
    resolution: float = 0.1  # bracket until (hi - lo) <= resolution * hi
    fill: bool = True        # after the bracket, fill the gaps below the limit with the runs left

    def __post_init__(self):
        lo, hi = IM_RANGE
        for name in ("start", "step"):   # a step below the smallest level would repeat a level (9 digits)
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and lo <= v <= hi):
                raise ParameterError(f"--{name} = {v!r}: must be a finite number in [{lo:g}, {hi:g}] m/s^2")
        if not (isinstance(self.max_runs, int) and 2 <= self.max_runs <= 100):
            raise ParameterError(f"--max-runs = {self.max_runs!r}: must be a whole number in 2..100")
        r = self.resolution
        if not (isinstance(r, (int, float)) and math.isfinite(r) and RESOLUTION_MIN <= r < 1):
            raise ParameterError(f"--resolution = {r!r}: must be a number in [{RESOLUTION_MIN:g}, 1) (fraction of "
                                 "the level)")


def bracket(history: list[tuple[float, bool]]) -> tuple[float, float | None]:
    """(lo, hi): hi the lowest level that reached the limit (None: none did), lo the highest level
    below hi that did not (0.0 when none)."""
    reached = [lv for lv, r in history if r]
    hi = min(reached) if reached else None
    below = [lv for lv, r in history if not r and (hi is None or lv < hi)]
    return (max(below) if below else 0.0), hi


def next_hunt_level(h: Hunt, history: list[tuple[float, bool]]) -> float | None:
    """The next level to run after ``history`` [(level, reached)] in the order run; None: done."""
    if len(history) >= h.max_runs:
        return None
    if not history:
        return tidy(h.start)
    lo, hi = bracket(history)
    if hi is None:  # hunt: step up from the last level, each step GROWTH * step longer than the one before
        k = len(history)
        level = tidy(history[-1][0] + h.step * (1.0 + GROWTH * (k - 1)))
        return level if level <= IM_RANGE[1] else None  # beyond the bound: the record is censored there
    if hi - lo > h.resolution * hi:  # bracket
        return tidy(0.5 * (lo + hi))
    if not h.fill:
        return None
    safe = sorted({0.0, *(lv for lv, r in history if not r and lv < hi)})  # fill below the limit
    gaps = [(b - a, a, b) for a, b in zip(safe, safe[1:])]
    if not gaps:
        return None
    width, a, b = max(gaps, key=lambda g: (g[0], -g[1]))  # the widest gap, the lowest of equal ones
    if width <= h.resolution * hi:
        return None  # the curve below the limit is as fine as the bracket: nothing left worth a run
    return tidy(0.5 * (a + b))


def bracket_state(h: Hunt | None, history: list[tuple[float, bool]]) -> dict:
    """A record's bracket after its runs: lo, hi (None: never reached), width (hi - lo) / hi, and
    whether it is within ``h.resolution`` ("resolved"), or why not: "budget" (max_runs spent first),
    "never reached" (censored: no level reached the limit), "stopped" (the hunt ended otherwise)."""
    lo, hi = bracket(history)
    if hi is None:
        return {"lo": lo, "hi": None, "width": None, "resolved": False, "why": "never reached"}
    width = (hi - lo) / hi
    ok = h is not None and width <= h.resolution * (1 + 1e-9)
    why = "resolved" if ok else ("budget" if h is not None and len(history) >= h.max_runs else "stopped")
    return {"lo": lo, "hi": hi, "width": width, "resolved": ok, "why": why}


def next_stripe_level(levels: list[float], history: list[tuple[float, bool]]) -> float | None:
    """Given levels upwards, stopping at the first that reaches the limit."""
    if any(r for _, r in history):
        return None
    done = {lv for lv, _ in history}
    rest = [lv for lv in sorted(levels) if lv not in done]
    return rest[0] if rest else None


def parse_levels(text: str) -> list[float]:
    """'0.5,1,2' -> [0.5, 1.0, 2.0] (> 0, finite, distinct); ParameterError otherwise."""
    out = []
    items = text.split(",")
    if len(items) > LEVELS_MAX:
        raise ParameterError(f"--levels: {len(items)} levels; at most {LEVELS_MAX} (each a run per record and "
                             "configuration)")
    for item in items:
        try:
            v = float(item)
        except ValueError:
            raise ParameterError(f"--levels {text[:60]!r}: {item.strip()!r} is not a number; allowed: "
                                 f"levels in [{IM_RANGE[0]:g}, {IM_RANGE[1]:g}] m/s^2, as a list like 0.5,1,2") from None
        if not (math.isfinite(v) and IM_RANGE[0] <= v <= IM_RANGE[1]):
            raise ParameterError(f"--levels {text[:60]!r}: {item.strip()} must be a finite number in "
                                 f"[{IM_RANGE[0]:g}, {IM_RANGE[1]:g}] m/s^2")
        if tidy(v) in out:
            raise ParameterError(f"--levels {text[:60]!r}: {item.strip()} is given twice")
        out.append(tidy(v))
    return sorted(out)
