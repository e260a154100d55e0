"""Bounds on the work a model description asks for, checked before any engine runs (each a
``ModelError``: one line with the bound, exit 2). Why each number: docs/limits.md ("A described
mechanism's size and work").

- sizes, counted on the raw tables before any of them is parsed: bodies (each body has one joint),
  loops, force elements (laws), prescribed coordinates, outputs, cases;
- per case: output samples x outputs (the values every run keeps in memory), and the in-house
  engine's least number of steps, duration / max_step (its step never exceeds max_step).
"""
from __future__ import annotations

from nsd_core.model.errors import ModelError

# The in-house engine's evaluation costs ~n^3 above ~100 bodies (measured on a 2-core machine, a
# chain of revolute joints: 2.6 ms at 100 bodies, 18 ms at 200, 57 ms at 300 per evaluation, ~12 a
# step): at 200 bodies a 1 s case at the default max_step (100 steps) already takes ~25 s a run.
MAX_BODIES = 200
MAX_LOOPS = 200          # each closes 3-6 constraint equations, solved with the bodies' coordinates
MAX_FORCES = 1000        # each a law evaluated at every evaluation (the largest shipped: 25)
MAX_PRESCRIBED = 200     # at most one per joint coordinate worth driving; the largest shipped: 2
MAX_OUTPUTS = 1000       # each a column of every run's CSV and of the comparison (the largest shipped: 16)
MAX_CASES = 100          # each case runs every engine two or three times
MAX_VALUES = 20_000_000  # output samples x outputs of one run: 160 MB of doubles, kept for ~7 runs a case
MAX_INHOUSE_STEPS = 1_000_000   # duration / max_step: ~0.8 ms a step on a 3-body four-bar, ~13 min a run

SIZES = (("bodies", MAX_BODIES), ("loops", MAX_LOOPS), ("forces", MAX_FORCES), ("prescribed", MAX_PRESCRIBED),
         ("outputs", MAX_OUTPUTS))


def check_sizes(raw: dict) -> None:
    """Refuse a description with more tables of a kind than its bound (counted before parsing them)."""
    for key, bound in SIZES:
        items = raw.get(key)
        if isinstance(items, list) and len(items) > bound:
            raise ModelError(f"[[{key}]]: {len(items)} tables; at most {bound} (a bound on the work a description "
                             "may ask for: docs/limits.md)")


def check_case_count(where: str, items: list) -> None:
    if len(items) > MAX_CASES:
        raise ModelError(f"{where}: {len(items)} [[case]] tables; at most {MAX_CASES} (docs/limits.md)")


def check_case_work(where: str, duration: float, dt_out: float, n_outputs: int, settings: dict | None) -> None:
    """One case's work: output samples x outputs, and the in-house engine's least step count
    (``settings``: the in-house engine's settings merged with its defaults, or None when it does not run)."""
    samples = round(duration / dt_out) + 1
    if samples * n_outputs > MAX_VALUES:
        raise ModelError(f"{where}.dt_out = {dt_out!r}: {samples} samples x {n_outputs} outputs = "
                         f"{samples * n_outputs:.3g} values a run; at most {MAX_VALUES:.3g} (a larger dt_out, a "
                         "shorter duration or fewer outputs)")
    max_step = (settings or {}).get("max_step")
    if isinstance(max_step, (int, float)) and not isinstance(max_step, bool) and max_step > 0:
        steps = duration / float(max_step)
        if steps > MAX_INHOUSE_STEPS:
            raise ModelError(f"{where}.duration = {duration:g}: at least {steps:.3g} in-house steps (max_step "
                             f"{max_step:g} s); at most {MAX_INHOUSE_STEPS:.3g} (a shorter duration or a larger "
                             "semirecursive max_step)")
