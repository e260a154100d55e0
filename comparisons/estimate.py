"""Each engine's numerical error, estimated from the run itself (Richardson extrapolation).

A fixed-step peer runs twice on every case: at its case step h (the run the gate judges) and at a
companion step 2h (run label ``ENGINE_2h``). For a method of order p the error of the h run is,
asymptotically (e(h) ~ C h^p, so d(h, 2h) ~ (r^p - 1) e(h)),

    e(h) ~= d(h, 2h) / (r^p - 1),     r = steps(h) / steps(2h)  (2 when the step doubles exactly)

where d(h, 2h) is the same difference metric the gate uses, measured between the two runs of the
engine (no other engine's numbers enter). The companion is coarser, not finer: the pair costs 1.5x
the judged run instead of 3x (an h/2 companion), for an estimate of the same run with the same
meaning (docs/validation.md compares the two on the gate's cases). p is the order the method has on
this device (``nominal_order``): MuJoCo's Euler and implicit integrators 1, RK4 and Exudyn's
generalized-alpha and trapezoidal solvers 2 (RK4 is fourth order on smooth problems, but slack ropes
and contact make the force laws non-smooth, which limits any method to about second order; the lower
p gives the larger, safer estimate). A modelling error is the same at h and 2h, so it never enters
d: an engine that differs from the converged reference by much more than its estimate disagrees
with it about the model.

The in-house engine's estimate is its difference from the converged reference (its own run at rtol
1e-10: the same code at a far tighter tolerance), and the converged reference's own estimate is its
difference from a run at rtol 1e-11 (``comparisons.reference.CHECK_SETTINGS``).

The order observed against the converged reference, log2(e(2h) / e(h)), is kept as evidence: when
the engine agrees with the reference and the observed order lies more than one below p, the
estimate may be too small (the steps are not yet asymptotic) and the verdict says so.
"""
from __future__ import annotations

import math

# the setting each fixed-step peer's step is read from, and the settings that scale with it
STEP_SETTING = {"mujoco": "timestep", "exudyn": "step_size"}
COMPANION = 2   # the companion run's step over the judged run's
# an adaptive peer's tolerance ladder: (setting, factor, order). Its estimate is its difference from its
# own run at setting x factor (a far tighter tolerance: the same code, much nearer the exact solution),
# as the in-house engine's is its difference from its converged run; ``order`` the error's assumed
# power of the tolerance (1: error ~ rtol), for the tolerance a verdict says it needs
TOLERANCE_LADDER = {"symbolic": ("rtol", 0.01, 1.0)}
TIGHT_LABEL = "{engine}_tight"
# an adaptive peer's formulation companion on a description with loops: (setting, factor). The symbolic
# engine's multipliers come from a regularised solve whose bias no tolerance controls; near a singular
# position it outgrows the ladder's share (IFToMM A02: 3.7e-9 of scale against a ladder of 8.9e-10). Its
# difference from its own run at setting x factor is added to its estimate: an upper bound on the bias
# wherever the bias grows with the setting at least as setting^0.3 (e(10 mu) >= 2 e(mu)), as measured there
# (e = 3.7e-9, 2.1e-8, 1.8e-7 at mu = 1e-8, 1e-7, 1e-6)
FORMULATION_COMPANION = {"symbolic": ("regularisation", 10.0)}
FORMULATION_LABEL = "{engine}_regularised"
REFINED_LABEL = "{engine}_h{div}"


def nominal_order(engine: str, settings: dict) -> float:
    """The order p the error estimate assumes for ``engine`` with these (merged) settings."""
    if engine == "mujoco":
        return 2.0 if settings.get("integrator", "Euler") == "RK4" else 1.0
    return 2.0   # exudyn: generalized-alpha (second order), trapezoidal index 2 (second order)


def richardson_factor(order: float, ratio: float = 2.0) -> float:
    """r^p / (r^p - 1): a run's error over its difference from a run at a step r times smaller."""
    q = ratio ** order
    return q / (q - 1.0) if q > 1.0 else math.inf


def companion_factor(order: float, ratio: float = 2.0) -> float:
    """1 / (r^p - 1): a run's error over its difference from its companion at a step r times larger."""
    q = ratio ** order
    return 1.0 / (q - 1.0) if q > 1.0 else math.inf


def companion_times(engine: str, merged: dict) -> float:
    """The companion's step over the judged run's: COMPANION (coarser) where the method's nominal order
    is the order it shows, 1/2 (finer) for MuJoCo's Euler and implicit integrators. Their nominal order
    1 understates the 2 they show on a smooth drive; with the order understated, a coarser companion
    inflates the estimate by (2^q - 1) / (2^p - 2^(p - q)) (2x for p = 1, q = 2) and so halves the
    gate's power to see a modelling error, where a finer one does not."""
    return 0.5 if engine == "mujoco" and nominal_order(engine, merged) < 2.0 else float(COMPANION)


def step_used(step: float, dt_out: float | None) -> float:
    """The step a fixed-step peer really takes for a ``step`` setting: the largest that divides the output
    interval ``dt_out`` and is at most the setting (the setting itself when dt_out is None)."""
    if dt_out is None:
        return float(step)
    return float(dt_out) / max(1, math.ceil(float(dt_out) / float(step) - 1e-9))


def companion_label(engine: str, merged: dict, dt_out: float | None = None, coarse: bool = True) -> tuple[str, float]:
    """(label, step multiplier) of a peer's companion run with these (merged) settings: ``ENGINE_2h``
    at twice its step (``companion_times``) where ``coarse`` allows it, else ``ENGINE_h2`` at half of it,
    also where the judged step already spans the output interval ``dt_out`` (a step divides each
    interval: none coarser exists)."""
    times = companion_times(engine, merged) if coarse else 0.5
    step = float(merged[STEP_SETTING[engine]])
    if times > 1.0 and dt_out is not None and math.ceil(float(dt_out) / step - 1e-9) < 2:
        times = 0.5
    return (f"{engine}_h2", 0.5) if times < 1.0 else (f"{engine}_{COMPANION}h", times)


def pair_factor(order: float, stats_h: dict, stats_c: dict, coarser: bool = True) -> tuple[float, float]:
    """(factor, ratio): the judged run's error over its difference from its companion, from the step
    counts the two runs really had (the companion's ``coarser`` side when they do not say); inf when
    the two took the same steps (no estimate can be made from them)."""
    n_h, n_c = stats_h.get("steps"), stats_c.get("steps")
    if n_h and n_c:
        if n_h == n_c:
            return math.inf, 1.0
        coarser = n_c < n_h
    ratio = step_ratio(stats_h, stats_c)
    return (companion_factor(order, ratio) if coarser else richardson_factor(order, ratio)), ratio


def step_ratio(stats_a: dict, stats_b: dict) -> float:
    """The steps' ratio the two runs really had, the finer's count over the coarser's (the step divides
    each output interval, so a doubled or halved setting may not double or halve it exactly); 2 when
    the runs do not say."""
    n1, n2 = stats_a.get("steps"), stats_b.get("steps")
    if n1 and n2 and n1 != n2:
        return float(max(n1, n2)) / float(min(n1, n2))
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


def observed_order(e_coarse: float, e_fine: float, ratio: float = 2.0) -> float:
    """log_r(e(rh) / e(h)) of two errors against the reference (nan when undefined)."""
    if e_coarse > 0 and e_fine > 0 and ratio > 1:
        return math.log(e_coarse / e_fine) / math.log(ratio)
    return float("nan")


def pair_order(e_run: float, e_pair: float, stats_run: dict, stats_pair: dict, ratio: float) -> float:
    """The order observed against the reference from a run's and its companion's errors, whichever of
    the two is the finer (by their step counts)."""
    if (stats_pair.get("steps") or 0) > (stats_run.get("steps") or 0):
        return observed_order(e_run, e_pair, ratio)
    return observed_order(e_pair, e_run, ratio)


def step_needed(step: float, estimate: float, tolerance: float, order: float, margin: float = 0.8) -> float:
    """The step at which an error ``estimate`` at ``step`` falls to ``margin`` x ``tolerance``
    (error ~ step^order)."""
    if estimate <= 0 or not math.isfinite(estimate):
        return step
    return step * (margin * tolerance / estimate) ** (1.0 / order)
