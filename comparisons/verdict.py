"""The gate's rule: two verdicts per case and engine, from the engines' own error estimates.

- **consistent**: the engine's difference from the converged reference is within k x (its own
  estimated numerical error + the reference's own error), metric by metric. Otherwise it *disagrees
  beyond numerical error*: the engines differ about the model (a modelling or implementation
  difference), whatever their steps.
- **accurate enough**: the engine's error, the larger of its own estimate and its difference from
  the converged reference, is within the engineering tolerance of each metric (the tolerance file's
  ``[engineering]`` table: a fraction of the reference's peak force, peak displacement, ...).
  Otherwise it is *not converged at these settings*, and the step its estimate asks for is given.

PASS = every engine consistent and accurate enough on every case. The estimates are made in the run
(``comparisons.estimate``): nothing here was derived on the nominal device, so a variant of the
device, a user's case file or another mechanism gets a verdict of the same meaning.

A scalar difference (a peak, the loop work) can cancel by chance between the h and 2h runs. Two
guards: its estimate is at least ``beta`` x the estimate of the max-norm difference of the same
quantity (``SCALAR_OF``); and its bound is at least what the max-norm metric's bound implies for it
(``IMPLIED``: a peak's difference is at most the max-norm difference, |max|a| - max|b|| <= max|a - b|;
the loop work's at most the force's times the path's length), so a scalar is never called a modelling
difference that the numerical error of its own quantity can explain. A floor below which differences are round-off (``FLOOR``) keeps two equal runs
from failing on 0 <= 0.

A pair whose observed order is far below its method's (``stalled_order``) did not fall with the step: a
modelling difference does not, but neither does an error not yet in its asymptotic range, whose estimate
at the method's order is then too small. A difference beyond its bound there, but within the bound the
pair gives at first order (``first_order_growth`` x the bound), is *undecided*; ``--refine`` runs a third,
finer step, and a refined pair that has still not fallen disagrees.
"""
from __future__ import annotations

import math

import numpy as np

from comparisons.engines import get_engine
from comparisons.estimate import (STEP_SETTING, companion_factor, companion_label, nominal_order, pair_factor,
                                  pair_order, richardson_factor, step_needed)

CONVERGED, CHECK = "converged", "converged_check"
FLOOR = 1e-12                      # relative differences below this are round-off
OWN = ("closure_max", "tracking_error", "energy_balance_rel", "energy_residual_rel")   # an engine's own checks
ENERGY = ("energy_balance_rel", "energy_residual_rel")
# scalar differences that can cancel by chance -> the max-norm difference that bounds their estimate
SCALAR_OF = {"peak_force_rel": "max_dF_rel", "loop_area_rel": "max_dF_rel", "peak_u_rel": "max_du_rel",
             "peak_a_rel": "max_da_rel"}
# a scalar metric -> the factor by which its max-norm metric's bound bounds it (peaks: the same quantity and
# scale; the loop work's factor, peak force x path length / work, is the case's: comparisons.judge)
IMPLIED = {"peak_force_rel": 1.0, "peak_u_rel": 1.0, "peak_a_rel": 1.0}
PRIMARY = {"drive": "max_dF_rel", "seismic": "max_du_rel"}   # the metric whose fall gives the observed order
# the engineering tolerance's default (fraction of the quantity's peak; m for closure and tracking)
ENGINEERING = {"max_dF_rel": 1e-3, "rms_dF_rel": 1e-3, "loop_area_rel": 1e-3, "peak_force_rel": 1e-3,
               "region_shift_rel": 2e-2, "closure_max": 1e-6, "tracking_error": 1e-6, "energy_balance_rel": 1e-2,
               "max_du_rel": 1e-3, "max_dF_device_rel": 1e-3, "peak_u_rel": 1e-3, "peak_a_rel": 1e-3,
               "energy_residual_rel": 1e-2, "max_dfloor_rel": 1e-3, "max_ddrift_rel": 1e-3, "max_dfloor_a_rel": 1e-3}
K, BETA = 3.0, 0.1


def merged_settings(engine: str, case) -> dict:
    """A peer's settings on ``case`` over its defaults (the seismic defaults on a seismic case: one
    driven by a ground motion, not a drive)."""
    eng = get_engine(engine)
    defaults = eng.default_settings if hasattr(case, "drive") else eng.seismic_default_settings
    return {**defaults, **(case.settings.get(engine) or {})}


def peer_label(engine: str, case) -> str:
    """The run label of a peer's companion run on ``case`` (the second run of its estimate:
    comparisons.estimate.companion_label)."""
    return companion_label(engine, merged_settings(engine, case))[0]


def estimate_labels(cases, engines) -> list[tuple]:
    """The extra runs the estimates need: each peer's companion on each case, the reference's check."""
    peers = [e for e in engines if e in STEP_SETTING]
    return [(c, peer_label(e, c)) for c in cases for e in peers] + [(c, CHECK) for c in cases]


class Rule:
    """The rule's constants as the tolerance file states them (``[engineering]``, ``[verdict]``)."""

    def __init__(self, engineering: dict | None = None, k: float = K, beta: float = BETA):
        self.engineering = {**ENGINEERING, **(engineering or {})}
        self.k, self.beta = float(k), float(beta)

    def describe(self) -> dict:
        return {"name": "estimated", "k": self.k, "beta": self.beta, "engineering": dict(self.engineering),
                "text": pass_sentence(self.k)}


def pass_sentence(k: float = K) -> str:
    """What PASS means, in one sentence (page 1 of the report, the command's last lines)."""
    return (f"PASS means every engine agrees with the converged in-house reference to within {k:g} x the "
            "numerical error estimated from its own runs (so any remaining difference is numerical, not a "
            "difference in the model), and that error is within the engineering tolerance of every metric.")


def _finite(x) -> float:
    return float(x) if x is not None and math.isfinite(float(x)) else math.inf


def case_verdicts(case, kind: str, engines: list[str], values: dict, estimates: dict, ref_error: dict,
                  scales: dict, evidence: dict, rule: Rule, floors: dict | None = None,
                  ref_own: dict | None = None, reference_rtol: float | None = None,
                  implied: dict | None = None) -> tuple[list[dict], dict]:
    """Rows (one per engine and metric) and verdicts (one per engine) of one case.

    values[e]: metric -> e's difference from the converged reference (own checks: their value);
    estimates[e]: metric -> e's estimated error (None: not estimated); ref_error: metric -> the
    reference's own error; scales: metric -> (scale, unit) to state a tolerance in units;
    evidence[e]: step, order, observed order, ratio, setting (for the step needed); floors: metric -> the
    resolution below which a difference is not measurable (a region boundary: two output samples);
    ref_own: the converged reference's own checks (its energy balance: the output grid's quadrature error);
    reference_rtol: the converged reference's rtol, as said in a verdict (None: not said); implied: scalar
    metric -> the factor its max-norm metric's bound is multiplied by to bound it (over ``IMPLIED``)."""
    rows, verdicts = [], {}
    factors = {**IMPLIED, **(implied or {})}
    for e in engines:
        if e not in values:
            continue
        ev = evidence.get(e, {})
        # a stalled pair, before any refinement: undecided within the bound it gives at first order
        stalled = stalled_order(ev) is not None and not ev.get("refined")
        growth = first_order_growth(ev) if stalled else 1.0
        erows = []
        for metric, value in values[e].items():
            if metric not in rule.engineering:
                continue
            tol = rule.engineering[metric]
            value = _finite(value)
            if metric in OWN:
                # the energy balances are quadratures on the output grid: the converged reference's own value is
                # that grid's error, which no engine can beat; an engine is judged on what it adds to it
                floor = (ref_own or {}).get(metric, 0.0) if metric in ENERGY else 0.0
                erows.append(_row(case, e, None, metric, value, None, floor if metric in ENERGY else None, None, tol,
                                  None, value - floor <= tol, scales))
                continue
            bound, est, ref = _bound(rule, estimates.get(e, {}), ref_error, floors, metric)
            base = SCALAR_OF.get(metric)
            bound_from = None
            if base in values[e] and metric in factors:   # what the max-norm metric's bound allows this scalar
                by_base = factors[metric] * _bound(rule, estimates.get(e, {}), ref_error, floors, base)[0]
                if by_base > bound:
                    bound, bound_from = by_base, base
            consistent = value <= bound
            # a consistent engine's error is also at least its distance from the reference; an inconsistent
            # one's distance holds the modelling difference, so its own estimate alone says how converged it is
            err = max(est, value) if consistent else est
            erows.append(_row(case, e, CONVERGED, metric, value, est, ref, bound, tol, consistent, err <= tol, scales))
            companion = (ev.get("companion") or {}).get(metric)   # the same model at the companion's step
            erows[-1].update(bound_from=bound_from, companion=None if companion is None else _finite(companion),
                             stalled=stalled and value <= growth * bound)
        rows += erows
        verdicts[e] = _verdict(e, erows, ev, rule, reference_rtol)
    return rows, verdicts


def stalled_order(ev: dict) -> float | None:
    """The observed order of a peer's pair where it is far below its method's (p_obs < p - 1) on an
    error above round-off: the difference did not fall with the step as the method's error does, so
    the pair alone cannot tell a modelling difference (which does not fall) from steps not yet
    asymptotic (an estimate too small); None otherwise."""
    p_obs, p = ev.get("observed_order"), ev.get("order")
    if p and p_obs is not None and math.isfinite(p_obs) and p_obs < p - 1.0 and ev.get("primary_error", 0.0) > FLOOR * 1e3:
        return p_obs
    return None


def first_order_growth(ev: dict) -> float:
    """How much larger a pair's estimate is at first order than at its method's order p: the factor
    (judged run's error over the pair's difference) at order 1 over that at p, for the pair's step
    ratio r and side (a coarser companion: (r^p - 1) / (r - 1), 3 for p = 2 and r = 2); 1 where the
    evidence does not say."""
    p, r, f = ev.get("order"), ev.get("ratio") or 2.0, ev.get("factor")
    if not p or p <= 1.0 or not f or not math.isfinite(f) or r <= 1.0:
        return 1.0
    coarser = math.isclose(f, companion_factor(p, r), rel_tol=1e-9)
    one = companion_factor(1.0, r) if coarser else richardson_factor(1.0, r)
    return one / f if math.isfinite(one) else 1.0


def _bound(rule: Rule, estimates: dict, ref_error: dict, floors: dict | None, metric: str) -> tuple:
    """(bound, estimate, reference's error) of one metric: k x (its estimate + the reference's error), at
    least its round-off or resolution floor."""
    est = estimates.get(metric)
    est = _finite(est) if est is not None else math.inf
    ref = ref_error.get(metric, 0.0) or 0.0
    return rule.k * (est + ref) + max(FLOOR, (floors or {}).get(metric, 0.0)), est, ref


def _row(case, engine, reference, metric, value, est, ref, bound, tol, consistent, accurate, scales) -> dict:
    scale, unit = scales.get(metric, (None, None))
    return {"case": case, "engine": engine, "reference": reference, "metric": metric, "value": value,
            "estimate": est, "reference_error": ref, "bound": bound, "tolerance": tol,
            "tolerance_abs": tol * scale if scale else None, "scale": scale, "unit": unit,
            "consistent": consistent, "accurate": bool(accurate),
            "limit": bound if bound is not None else tol, "limit_source": "estimate" if bound is not None else "tolerance",
            "pass": bool((consistent is not False) and accurate), "gated": True}


def _verdict(engine: str, rows: list[dict], ev: dict, rule: Rule, reference_rtol: float | None = None) -> dict:
    """One engine's verdict on one case, in words."""
    # a difference beyond the bound where the engine's own estimate is itself over the tolerance is undecided:
    # that estimate is not yet asymptotic (a step far from converged), so the bound it gives is no measure of a
    # modelling difference; the engine is not converged, and a finer step (--refine) decides it
    beyond = [r for r in rows if r["consistent"] is False]
    # a difference beyond the bound that the engine's own companion run (the same model at the other step) is
    # within moves with the step as no modelling difference does; one from a pair whose observed order is far
    # below the method's did not fall with the step, as a modelling difference does not, but neither does an
    # error not yet asymptotic: either way the two runs cannot tell; --refine (a third, finer step) decides
    moving = [r for r in beyond if r["accurate"] and row_word(r) == "UNDECIDED"]
    incons = [r for r in beyond if r["accurate"] and r not in moving]
    undecided = [r for r in beyond if not r["accurate"]]
    inacc = [r for r in rows if not r["accurate"]]
    out = {"consistent": None if (undecided or moving) and not incons else not incons, "accurate": not inacc,
           "pass": not beyond and not inacc,
           "order": ev.get("order"), "observed_order": ev.get("observed_order"), "step": ev.get("step"),
           "setting": ev.get("setting"), "k": rule.k, "needs": None, "uncertain": None}
    parts = []
    missing = ev.get("note", "") if ev.get("note", "").startswith("no error estimate") else ""
    if missing:
        incons, inacc = [], [r for r in rows if r["estimate"] is None or not math.isfinite(r["estimate"] or 0.0)
                             or not r["accurate"]]
        out.update(consistent=None, accurate=False, **{"pass": False})
        parts.append(missing)
    if incons:
        r = max(incons, key=lambda r: r["value"] / r["bound"] if r["bound"] else math.inf)
        ratio = r["value"] / r["bound"]
        out["worst_consistency"] = {"metric": r["metric"], "ratio": ratio}
        of = (f"the bound {r['bound_from']}'s bound implies for it" if r.get("bound_from") else
              f"its bound {rule.k:g} x (estimated error {r['estimate']:.2g} + reference's {r['reference_error']:.2g})")
        parts.append(f"disagrees beyond numerical error: {r['metric']} = {r['value']:.3g} is {ratio:.3g}x {of}")
    if inacc and not missing:
        steps = sorted((r for r in inacc if r["metric"] not in OWN), key=lambda r: -_error(r) / r["tolerance"])
        own = sorted((r for r in inacc if r["metric"] in OWN), key=lambda r: -_error(r) / r["tolerance"])
        if steps:
            text = "not converged at these settings: " + _items(steps)
            # the setting answers for the share of the error it controls (an adaptive peer's ladder share;
            # its formulation's share does not fall with a tighter tolerance): none advised when that share is
            # within the tolerance
            err = (ev.get("ladder_share") or {}).get(steps[0]["metric"], _error(steps[0]))
            if ev.get("setting") and ev.get("step") and err > steps[0]["tolerance"]:
                need = step_needed(ev["step"], err, steps[0]["tolerance"], ev["order"])
                out["needs"] = {ev["setting"]: need}
                text += f"; needs {ev['setting']} <= {need:.3g}" + ("" if ev["setting"] == "rtol" else " s")
            parts.append(text)
        if own:   # closure, tracking, energy balance: the engine's own checks, whatever the cause
            parts.append("its own check over tolerance: " + _items(own))
    if moving and not incons:
        parts.append(_undecided_text(max(moving, key=lambda r: r["value"] / r["bound"]), ev, out))
    if undecided and not incons:
        r = max(undecided, key=lambda r: r["value"] / r["bound"] if r["bound"] else math.inf)
        out["undecided"] = {"metric": r["metric"], "ratio": r["value"] / r["bound"]}
        parts.append(f"whether it agrees is undecided until it converges: {r['metric']} = {r['value']:.3g} is "
                     f"{r['value'] / r['bound']:.3g}x its bound, from an estimate over tolerance (--refine)")
    unresolved = [r for r in rows if r["metric"] not in OWN and (r["reference_error"] or 0.0) > r["tolerance"]]
    if unresolved:
        r = max(unresolved, key=lambda r: r["reference_error"] / r["tolerance"])
        at = "its rtol" if reference_rtol is None else f"rtol {reference_rtol:g}"
        out["reference_unresolved"] = True
        parts.append(f"the converged reference itself is not converged to the tolerance on this case ({r['metric']}: "
                     f"its own error {r['reference_error']:.3g} at {at} > {r['tolerance']:.3g})")
    p_obs = stalled_order(ev)
    if not incons and p_obs is not None and "stalled" not in (out.get("undecided") or {}):
        out["uncertain"] = (f"estimate uncertain: observed order {p_obs:.2f} against the assumed {ev['order']:g} "
                            "(the steps may not be asymptotic; --refine checks at a finer step)")
    elif incons and p_obs is not None:
        parts.append(f"the difference did not fall with the step at the refined pair either (observed order "
                     f"{p_obs:.2f} against {ev['order']:g})" if ev.get("refined") else
                     f"the difference did not fall with the step (observed order {p_obs:.2f} against "
                     f"{ev['order']:g}) and is beyond even the bound its pair gives at first order")
    if not parts:
        rs = [r for r in rows if r["bound"]]
        worst = max(rs, key=lambda r: r["value"] / r["bound"]) if rs else None
        parts.append("consistent and accurate enough" + (
            f" (largest: {worst['metric']} at {worst['value'] / worst['bound']:.2g} of its bound)" if worst else ""))
    out["text"] = "; ".join(parts + ([out["uncertain"]] if out["uncertain"] else []))
    return out


def _undecided_text(r: dict, ev: dict, out: dict) -> str:
    """Why a difference beyond its bound is undecided (its companion within the bound, or a stalled
    pair), recorded in ``out["undecided"]``."""
    ratio = r["value"] / r["bound"]
    head = f"whether it agrees is undecided: {r['metric']} = {r['value']:.3g} is {ratio:.3g}x its bound, but "
    if r.get("companion") is not None and r["companion"] <= r["bound"]:
        out["undecided"] = {"metric": r["metric"], "ratio": ratio, "companion": r["companion"]}
        return head + (f"its companion run, the same model at another step, is within it ({r['companion']:.3g}): "
                       "the difference moves with the step (--refine decides)")
    p_obs = stalled_order(ev)
    out["undecided"] = {"metric": r["metric"], "ratio": ratio, "stalled": True, "observed_order": p_obs}
    return head + (f"it did not fall with the step (observed order {p_obs:.2f} against the method's "
                   f"{ev['order']:g}) and is within the bound its pair gives at first order "
                   f"({first_order_growth(ev) * r['bound']:.3g}): a modelling difference, or steps not yet "
                   "asymptotic; the two runs cannot tell which (--refine runs half the step: a modelling "
                   "difference stays beyond its bound there)")


def row_word(r: dict) -> str:
    """A gated row's own verdict in one word, as ``_verdict`` reads it: "ok" within its bound,
    "DISAGREES" beyond it, "UNDECIDED" beyond it where the engine's estimate is over the tolerance or its
    companion run is within the bound (the difference moves with the step) or its pair stalled (observed
    order far below the method's, before any refinement); a row without a bound "ok"."""
    if r.get("consistent") is not False:
        return "ok"
    moving = r.get("companion") is not None and r["companion"] <= r["bound"]
    return "UNDECIDED" if not r["accurate"] or moving or r.get("stalled") else "DISAGREES"


def _items(rows: list[dict]) -> str:
    """Up to three metrics' errors against their tolerances, in units."""
    items = []
    for r in rows[:3]:
        err = _error(r)
        item = f"{r['metric']} error {err:.3g} > {r['tolerance']:.3g}"
        if r["tolerance_abs"] is not None:
            item += f" ({_units(err * r['scale'], r['unit'])} > {_units(r['tolerance_abs'], r['unit'])})"
        items.append(item)
    return ", ".join(items) + (f" and {len(rows) - 3} more" if len(rows) > 3 else "")


def _error(r: dict) -> float:
    """A row's error: a consistent engine's is at least its distance from the reference; an inconsistent
    one's distance holds the modelling difference, so its own estimate alone; an own check its value
    beyond the converged reference's own (the output grid's quadrature)."""
    if r["metric"] in OWN:
        return r["value"] - (r["reference_error"] or 0.0) if r["metric"] in ENERGY else r["value"]
    return max(r["estimate"] or 0.0, r["value"]) if r["consistent"] is not False else r["estimate"]


def _units(value: float, unit: str) -> str:
    if unit == "m":
        return f"{value * 1e3:.3g} mm"
    return f"{value:.3g} {unit}"


def peer_evidence(engine: str, case_settings: dict, stats_h: dict, stats_pair: dict, e_h: float, e_pair: float,
                  seismic: bool) -> dict:
    """The step, order and observed order of a peer's two runs on one case (the judged run at h and its
    companion; ``e_*``: each one's difference from the converged reference)."""
    eng = get_engine(engine)
    merged = {**(eng.seismic_default_settings if seismic else eng.default_settings), **(case_settings or {})}
    p = nominal_order(engine, merged)
    factor, ratio = pair_factor(p, stats_h, stats_pair)
    setting = STEP_SETTING[engine]
    step = stats_h.get(setting) or merged[setting]
    return {"order": p, "ratio": ratio, "factor": factor, "setting": setting, "step": float(step),
            "observed_order": pair_order(e_h, e_pair, stats_h, stats_pair, ratio), "primary_error": e_h}


def estimate_from_pair(diff_pair: dict, factor: float, beta: float) -> dict:
    """Each metric's estimated error from its difference between the run and its companion (x
    ``factor``); a scalar one at least beta x the estimate of the max-norm difference it derives from."""
    out = {k: factor * _finite(v) for k, v in diff_pair.items()}
    for k, base in SCALAR_OF.items():
        if k in out and base in out:
            out[k] = max(out[k], beta * out[base])
    return out


def drive_scales(ref, frequency: float, amplitude: float) -> dict:
    """metric -> (the quantity's peak in the reference, unit): the tolerance in units."""
    from comparisons.metrics import _work
    from nsd_core.device.cycle import phase_resample
    F = np.column_stack([phase_resample(ref, frequency, c) for c in ("F_x", "F_y")])
    peak = float(np.max(np.linalg.norm(F, axis=1)))
    work = abs(_work(ref, frequency))
    return {"max_dF_rel": (peak, "N"), "rms_dF_rel": (peak, "N"), "peak_force_rel": (peak, "N"),
            "loop_area_rel": (work, "J"), "region_shift_rel": (amplitude, "m"),
            "closure_max": (1.0, "m"), "tracking_error": (1.0, "m"), "energy_balance_rel": (work, "J")}


def seismic_scales(ref) -> dict:
    """metric -> (the quantity's peak in the reference, unit) for a seismic case."""
    def peak(a, b):
        return float(np.max(np.hypot(ref[a], ref[b])))
    out = {"max_du_rel": (peak("x", "y"), "m"), "peak_u_rel": (peak("x", "y"), "m"),
           "max_dF_device_rel": (peak("device_Fx", "device_Fy"), "N"),
           "peak_a_rel": (peak("ax_abs", "ay_abs"), "m/s^2"), "closure_max": (1.0, "m")}
    if "E_input" in ref.columns:
        out["energy_residual_rel"] = (float(np.max(np.abs(ref["E_input"]))), "J")
    if "floor1_x" in ref.columns:
        n = 1
        while f"floor{n + 1}_x" in ref.columns:
            n += 1
        for key, (cx, cy, unit) in {"max_dfloor_rel": ("floor{}_x", "floor{}_y", "m"),
                                    "max_ddrift_rel": ("drift{}_x", "drift{}_y", "m"),
                                    "max_dfloor_a_rel": ("floor{}_ax_abs", "floor{}_ay_abs", "m/s^2")}.items():
            # the largest floor's peak: the worst floor's relative difference is in units at most this large
            out[key] = (max(peak(cx.format(i), cy.format(i)) for i in range(1, n + 1)), unit)
    return out
