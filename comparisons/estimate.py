"""Each engine's numerical error, estimated from the run itself (Richardson extrapolation).

A fixed-step peer runs twice on every case: at its case step h (the run the gate judges) and at h/2
(run label ``ENGINE_h2``). For a method of order p the error of the h run is, asymptotically,

    e(h) ~= d(h, h/2) * r^p / (r^p - 1),     r = steps(h/2) / steps(h)  (2 when the step halves exactly)

where d(h, h/2) is the same difference metric the gate uses, measured between the two runs of the
engine (no other engine's numbers enter). p is the order the method has on this device
(``nominal_order``): MuJoCo's Euler and implicit integrators 1, RK4 and Exudyn's generalized-alpha
and trapezoidal solvers 2 (RK4 is fourth order on smooth problems, but slack ropes and contact make
the force laws non-smooth, which limits any method to about second order; the lower p gives the
larger, safer estimate). A modelling error is the same at h and h/2, so it never enters d: an engine
that differs from the converged reference by much more than its estimate disagrees with it about
the model.

The in-house engine's estimate is its difference from the converged reference (its own run at rtol
1e-10: the same code at a far tighter tolerance), and the converged reference's own estimate is its
difference from a run at rtol 1e-11 (``comparisons.reference.CHECK_SETTINGS``).

The order observed against the converged reference, log2(e(h) / e(h/2)), is kept as evidence: when
the engine agrees with the reference and the observed order lies more than one below p, the
estimate may be too small (the steps are not yet asymptotic) and the verdict says so.
"""
from __future__ import annotations

import math

# the setting each fixed-step peer's step is read from, and the settings that scale with it
STEP_SETTING = {"mujoco": "timestep", "exudyn": "step_size"}
# an adaptive peer's tolerance ladder: (setting, factor, order). Its estimate is its difference from its
# own run at setting x factor (a far tighter tolerance: the same code, much nearer the exact solution),
# as the in-house engine's is its difference from its converged run; ``order`` the error's assumed
# power of the tolerance (1: error ~ rtol), for the tolerance a verdict says it needs
TOLERANCE_LADDER = {"symbolic": ("rtol", 0.01, 1.0)}
TIGHT_LABEL = "{engine}_tight"
REFINED_LABEL = "{engine}_h{div}"


def nominal_order(engine: str, settings: dict) -> float:
    """The order p the error estimate assumes for ``engine`` with these (merged) settings."""
    if engine == "mujoco":
        return 2.0 if settings.get("integrator", "Euler") == "RK4" else 1.0
    return 2.0   # exudyn: generalized-alpha (second order), trapezoidal index 2 (second order)


def richardson_factor(order: float, ratio: float = 2.0) -> float:
    """r^p / (r^p - 1): the h run's error over its difference from the run at h / r."""
    q = ratio ** order
    return q / (q - 1.0) if q > 1.0 else math.inf


def step_ratio(stats_h: dict, stats_h2: dict) -> float:
    """The steps' ratio the two runs really had (the step divides each output interval, so a halved
    setting may not halve the step exactly); 2 when the runs do not say."""
    n1, n2 = stats_h.get("steps"), stats_h2.get("steps")
    if n1 and n2 and n2 > n1:
        return float(n2) / float(n1)
    return 2.0


def refined_settings(engine: str, merged: dict, case_settings: dict, div: float) -> dict:
    """The case's settings of ``engine`` with its step divided by ``div``: every cap on the step scales
    with it (Exudyn's ``min_steps_per_cycle``), so the step used is divided too."""
    out = dict(case_settings or {})
    key = STEP_SETTING[engine]
    out[key] = float(merged[key]) / div
    if engine == "exudyn" and "min_steps_per_cycle" in merged:
        out["min_steps_per_cycle"] = int(math.ceil(float(merged["min_steps_per_cycle"]) * div))
    return out


def observed_order(e_h: float, e_h2: float, ratio: float = 2.0) -> float:
    """log_r(e(h) / e(h/r)) of two errors against the reference (nan when undefined)."""
    if e_h > 0 and e_h2 > 0 and ratio > 1:
        return math.log(e_h / e_h2) / math.log(ratio)
    return float("nan")


def step_needed(step: float, estimate: float, tolerance: float, order: float, margin: float = 0.8) -> float:
    """The step at which an error ``estimate`` at ``step`` falls to ``margin`` x ``tolerance``
    (error ~ step^order)."""
    if estimate <= 0 or not math.isfinite(estimate):
        return step
    return step * (margin * tolerance / estimate) ** (1.0 / order)
