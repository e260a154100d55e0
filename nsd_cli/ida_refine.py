"""The IDA cross-check's one refinement (docs/ida.md, "Cross-check"): a peer that is *not converged*
on a whole record at its step (its own error estimate, or its difference from the in-house run, over
the tolerance while the two agree within the rule's margin) runs the record once more at the step its
own runs ask for, with its companion run, and is judged again on that pair, as ``nsd compare
--refine`` does for a gate case. A peer that *disagrees* is not refined: no step mends a difference
its own error does not explain.

The step is extrapolated from the finer run of the pair (the judged run at h where its companion
runs at 2h, the companion where it runs at h/2: comparisons.estimate.companion_times), whose error is
measured (its difference from the in-house run, at least its own estimate), down to ``MARGIN`` x the
tolerance, at the order the record shows between the two steps (log2 of the two differences), never
above the method's nor below 1: where the error falls more slowly than the method's order (the ropes
going slack and taut through a whole record) the step is the finer for it. At most ``MAX_REFINE`` x the steps of the first run.

Measured on the far-field median record (15 at its limit intensity, 16.9 model s), Exudyn's device
force against the in-house run at rtol 1e-10: 1.4e-2 of its peak at the first step 1e-4 s, 1.6e-3 at
2.5e-5 s, 1.1e-3 at 2e-5 s (an order of about 1.5 over that range, against generalized-alpha's 2):
the step its first estimate asks for at order 2 (2.2e-5 s) would fail again.
"""
from __future__ import annotations

import math

MAX_REFINE = 8.0   # the refined run's steps at most 8 x the first's (as nsd compare --refine)
MARGIN = 0.8       # the step's target: 0.8 x the tolerance (comparisons.estimate.step_needed's margin)


def refined_step(step: float, verdict: dict, diff: dict, diff_pair: dict, order: float,
                 times: float = 0.5) -> float | None:
    """The step the refined pair runs at (``asked_step``, not below ``step / MAX_REFINE``), or None
    when none is needed or none can help."""
    asked = asked_step(step, verdict, diff, diff_pair, order, times)
    return None if asked is None else max(asked, step / MAX_REFINE)


def asked_step(step: float, verdict: dict, diff: dict, diff_pair: dict, order: float,
               times: float = 0.5) -> float | None:
    """The step the first pair's errors ask for (the module's docstring), uncapped; None when none is
    needed (a PASS) or none can help (a disagreement).

    ``step``: the first run's; ``verdict``: its judgment (``ida_check.judged``: per metric its
    estimate, tolerance, consistent, accurate); ``diff``, ``diff_pair``: the judged run's and its
    companion's differences from the in-house run per metric; ``order``: the method's nominal order;
    ``times``: the companion's step over the judged run's (0.5 or 2)."""
    estimates = verdict.get("estimates") or {}
    if verdict.get("verdict") != "FAIL" or not estimates:
        return None
    if not all(v["consistent"] for v in estimates.values()):
        return None   # a disagreement: the engines differ about the model, not by their steps
    asked = []
    for m, v in estimates.items():
        if v["accurate"]:
            continue
        d, d2 = (diff[m], diff_pair[m]) if times < 1.0 else (diff_pair[m], diff[m])   # coarser, finer
        p = order if not (d > d2 > 0) else min(order, max(1.0, math.log2(d / d2)))
        # the finer run's error: measured, or its estimate (the judged run's, scaled to h/2 for that run)
        error_fine = max(d2, v["estimate"] / 2.0 ** order) if times < 1.0 else max(d2, v["estimate"])
        if not error_fine > 0 or not math.isfinite(error_fine):
            continue
        fine = 0.5 * step if times < 1.0 else step
        asked.append(fine * min(1.0, MARGIN * v["tolerance"] / error_fine) ** (1.0 / p))
    return min(asked) if asked else None
