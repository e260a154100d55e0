"""``nsd compare --model FILE``: a described mechanism cross-validated in every engine (docs/models.md).

Every engine builds the mechanism from the same description (nsd_core.model) through its builder
(``BUILDERS``: one module each, ``simulate(model, duration, dt_out, settings) -> ModelRun``); no line
here or in a builder knows which mechanism it runs. The verdict is the gate's rule
(comparisons.verdict): each engine's difference from the converged in-house reference within
k x its own error estimate (peers: Richardson from their runs at h and h/2; the in-house engine: its
difference from the converged run), and that error within each output's engineering tolerance
(the output's ``tolerance``, a fraction of its ``scale``: given, or the reference's peak |value|).
With a reference solution (a case's ``reference``), every engine and the converged reference are
also judged against it, within their estimated error plus the solution's stated accuracy.
"""
from __future__ import annotations

import importlib
import math
import time

import numpy as np

from comparisons.estimate import (FORMULATION_COMPANION, FORMULATION_LABEL, STEP_SETTING, TIGHT_LABEL,
                                  TOLERANCE_LADDER, companion_label, nominal_order, pair_factor, pair_order,
                                  step_used)
from comparisons.model_cases import ModelCase
from comparisons.verdict import FLOOR, Rule, case_verdicts, pass_sentence
from nsd_core.model.description import Model
from nsd_core.model.run import ModelRun

BUILDERS = {"semirecursive": "nsd_core.model.semirecursive", "mujoco": "comparisons.builders.mujoco",
            "exudyn": "comparisons.builders.exudyn", "symbolic": "comparisons.builders.symbolic"}
REFERENCE = "semirecursive"
CONVERGED, CHECK = "converged", "converged_check"
CONVERGED_SETTINGS = {"rtol": 1e-12, "atol": 1e-14}
CHECK_SETTINGS = {"rtol": 1e-13, "atol": 1e-15}
OWN_TOLERANCE = {"closure_max": 1e-6, "tracking_error": 1e-6}   # m (or rad): the engines' own checks
SOLUTION = " vs solution"


def companion(case: ModelCase, engine: str) -> tuple[str, dict]:
    """(label, settings) of a fixed-step peer's companion run on ``case``: the second run of its
    estimate, at half its step. A described mechanism's order is not known beforehand: where a
    non-smooth law holds a method below its nominal order q < p, a coarser companion would
    underestimate the error 2^(p - q) times more than a finer one (comparisons.estimate)."""
    own = dict(case.settings.get(engine, {}))
    merged = {**builder(engine).default_settings, **own}
    key = STEP_SETTING[engine]
    label, times = companion_label(engine, merged, case.dt_out, coarse=False)
    # half the step the judged run takes: a setting above the output interval steps at dt_out / n, and
    # half of that setting could be the same step (two identical runs, no estimate)
    return label, {**own, key: step_used(float(merged[key]), case.dt_out) * times}


def builder(engine: str):
    return importlib.import_module(BUILDERS[engine])


def run_plan(model: Model, case: ModelCase, engines: list[str]) -> list[tuple[str, str, dict]]:
    """(label, engine, settings) of every run a case needs: each engine at its case settings, each
    fixed-step peer again at half its step (its estimate's companion), an adaptive peer at a tighter
    tolerance and, on a description with loops, at its formulation companion's setting, and the
    converged reference and its check."""
    plan = []
    for e in engines:
        own = dict(case.settings.get(e, {}))
        plan.append((e, e, own))
        if e in STEP_SETTING:
            label, settings = companion(case, e)
            plan.append((label, e, settings))
        if e in TOLERANCE_LADDER:   # an adaptive peer: once more at a far tighter tolerance (its estimate)
            plan.append((TIGHT_LABEL.format(engine=e), e, tightened(e, own)))
        if e in FORMULATION_COMPANION and model.loops:
            key, factor = FORMULATION_COMPANION[e]
            value = {**builder(e).default_settings, **own}[key] * factor
            plan.append((FORMULATION_LABEL.format(engine=e), e, {**own, key: value}))
    base = dict(case.settings.get(REFERENCE, {}))
    plan += [(CONVERGED, REFERENCE, {**base, **CONVERGED_SETTINGS}), (CHECK, REFERENCE, {**base, **CHECK_SETTINGS})]
    return plan


def tightened(engine: str, own: dict) -> dict:
    """An adaptive peer's settings one rung down its tolerance ladder (rtol and atol x the factor)."""
    key, factor, _ = TOLERANCE_LADDER[engine]
    merged = {**builder(engine).default_settings, **own}
    out = {**own, key: merged[key] * factor}
    if "atol" in merged:
        out["atol"] = merged["atol"] * factor
    return out


def run_one(model: Model, case: ModelCase, engine: str, settings: dict) -> dict:
    """One run, never raising: a failure comes back as data and is reported for its case."""
    start = time.perf_counter()
    try:
        run = builder(engine).simulate(model, case.duration, case.dt_out, settings)
        bad = [k for k, v in run.outputs.items() if not np.all(np.isfinite(v))]
        if bad:
            raise RuntimeError(f"a non-finite output: {bad[0]}")
        return {"status": "ok", "run": run, "wall_time": time.perf_counter() - start}
    except Exception as e:  # noqa: BLE001 (an engine's failure is that case's, the others go on)
        msg = " ".join(f"{type(e).__name__}: {e}".split())
        return {"status": "error", "message": msg[:500], "wall_time": time.perf_counter() - start}


def scales(model: Model, ref: ModelRun) -> dict:
    """output -> (scale, unit): the output's ``scale``, else the converged reference's peak |value|."""
    out = {}
    for o in model.outputs:
        peak = float(np.max(np.abs(ref.outputs[o.name])))
        out[o.name] = (o.scale or peak or 1.0, o.unit)
    for k in OWN_TOLERANCE:
        out[k] = (1.0, "m")
    return out


def differences(a: ModelRun, b: ModelRun, sc: dict, skip: dict | None = None) -> dict:
    """output -> max over the samples of |a - b| / scale, the samples ``skip`` names for an output left out."""
    skip = skip or {}
    return {k: float(np.max(np.delete(np.abs(a.outputs[k] - b.outputs[k]), skip.get(k, ())), initial=0.0)) / sc[k][0]
            for k in a.outputs}


JUMP_PROBE = 1e-10      # s: each side of an output time at which a prescribed acceleration is probed
JUMP_RELATIVE = 1e-5    # a jump: |q''(t+) - q''(t-)| above this fraction of the largest |q''| probed


def acceleration_jumps(model: Model, t: np.ndarray) -> dict:
    """output -> the sample indices where it is two-valued: a drive force at an output time at which any
    prescribed acceleration jumps (a ramp's end). The force there has a left and a right limit, and an
    engine whose clock lands one round-off either side of the time reports either (a fixed-step peer's
    n h against the reference's t): that sample measures the jump, not the engines."""
    jumps = set()
    for p in model.prescribed:
        left, right = p.table(np.asarray(t, float) - JUMP_PROBE)[2], p.table(np.asarray(t, float) + JUMP_PROBE)[2]
        peak = max(float(np.max(np.abs(left), initial=0.0)), float(np.max(np.abs(right), initial=0.0)))
        jumps |= set(np.flatnonzero(np.abs(right - left) > JUMP_RELATIVE * peak).tolist()) if peak > 0 else set()
    index = np.array(sorted(jumps), dtype=np.int64)
    return {o.name: index for o in model.outputs if o.kind == "drive_force" and index.size}


def roundoff_floors(model: Model, sc: dict) -> dict:
    """output -> the difference below which it is round-off, as a fraction of its scale: FLOOR of the
    largest scale among the outputs of its unit. A quantity that is zero in exact arithmetic (the force
    across a line drive) is computed from terms as large as its siblings (the drive's other force, the
    springs' tensions), and its round-off is relative to those, not to the scale it is judged in."""
    largest: dict = {}
    for o in model.outputs:
        largest[sc[o.name][1]] = max(largest.get(sc[o.name][1], 0.0), sc[o.name][0])
    floors = {o.name: FLOOR * largest[sc[o.name][1]] / sc[o.name][0] for o in model.outputs}
    return {**floors, **{k + SOLUTION: v for k, v in floors.items()}}


def solution_differences(run: ModelRun, case: ModelCase, sc: dict, skip: dict | None = None) -> dict:
    ref, skip = case.reference, skip or {}
    out = {}
    for k, v in ref.columns.items():
        d = np.abs(run.outputs[k][ref.index] - v)
        keep = ~np.isin(ref.index, skip.get(k, ()))
        out[k + SOLUTION] = float(np.max(d[keep], initial=0.0)) / sc[k][0]
    return out


def judge(model: Model, case: ModelCase, engines: list[str], runs: dict, rule: Rule) -> tuple[list, dict]:
    """Rows and verdicts of one case from its runs (label -> ModelRun)."""
    conv, check = runs[CONVERGED], runs[CHECK]
    sc = scales(model, conv)
    skip = acceleration_jumps(model, conv.t)
    ref_error = differences(check, conv, sc, skip)
    values, estimates, evidence = {}, {}, {}
    for e in engines:
        if e not in runs:
            continue
        d = differences(runs[e], conv, sc, skip)
        shares_reference = False
        values[e] = {**d, "closure_max": runs[e].stats.get("closure_max", 0.0)}
        if model.prescribed:
            values[e]["tracking_error"] = runs[e].stats.get("tracking_error", 0.0)
        if e in STEP_SETTING and companion(case, e)[0] in runs:
            pair = runs[companion(case, e)[0]]
            p = nominal_order(e, {**builder(e).default_settings, **case.settings.get(e, {})})
            factor, ratio = pair_factor(p, runs[e].stats, pair.stats)
            estimates[e] = {k: factor * v for k, v in differences(runs[e], pair, sc, skip).items()}
            primary = max(d, key=lambda k: d[k])
            d2 = differences(pair, conv, sc, skip)
            key = STEP_SETTING[e]
            evidence[e] = {"order": p, "ratio": ratio, "factor": factor, "setting": key,
                           "step": float(runs[e].stats.get(key) or {**builder(e).default_settings,
                                                                  **case.settings.get(e, {})}[key]),
                           "observed_order": pair_order(d[primary], d2[primary], runs[e].stats, pair.stats, ratio),
                           "primary_error": d[primary], "companion": d2, "refined": e in case.refined}
        elif e in TOLERANCE_LADDER and (found := adaptive_estimate(model, case, e, runs, sc, skip)) is not None:
            estimates[e], evidence[e] = found
        elif e == REFERENCE:   # the in-house engine: its estimate is its distance from the converged run
            estimates[e] = dict(d)
            shares_reference = True
            evidence[e] = {}
        else:   # a companion run failed (said as the case's failure): no estimate, so no verdict of agreement
            estimates[e] = {k: math.inf for k in d}
            evidence[e] = {"note": "no error estimate: a companion run of its estimate failed"}
        if case.reference is not None:
            sol = solution_differences(runs[e], case, sc, skip)
            values[e].update(sol)
            # the in-house engine's estimate is its distance from the converged run, whose own error (ref_error)
            # it shares when the two coincide: against a solution its error is at most the sum
            own = 1.0 if shares_reference else 0.0
            estimates[e].update({k: estimates[e][k[: -len(SOLUTION)]] + own * ref_error[k[: -len(SOLUTION)]]
                                 for k in sol})
            if "ladder_share" in evidence[e]:
                evidence[e]["ladder_share"].update({k: evidence[e]["ladder_share"][k[: -len(SOLUTION)]] for k in sol})
    if case.reference is not None:   # the converged reference against the solution, within its own error
        sol = solution_differences(conv, case, sc, skip)
        values[CONVERGED] = sol
        estimates[CONVERGED] = {k: ref_error[k[: -len(SOLUTION)]] for k in sol}
        evidence[CONVERGED] = {}
        ref_error = {**ref_error, **{k: case.reference.accuracy for k in sol}}
    names = [e for e in engines if e in values] + ([CONVERGED] if CONVERGED in values else [])
    sc_all = {**sc, **{k + SOLUTION: v for k, v in sc.items()}}
    return case_verdicts(case.name, "model", names, values, estimates, ref_error, sc_all, evidence, rule,
                         floors=roundoff_floors(model, sc), reference_rtol=CONVERGED_SETTINGS["rtol"])


def adaptive_estimate(model: Model, case: ModelCase, engine: str, runs: dict, sc: dict,
                      skip: dict | None = None) -> tuple[dict, dict] | None:
    """(metric -> estimate, evidence) of an adaptive peer: its difference from its tolerance ladder's run,
    plus, on a description with loops, its difference from its formulation companion (estimate.py says
    why); None when a run it needs is missing. The evidence keeps the ladder's share apart
    (``ladder_share``): the rtol a verdict advises answers for that share alone, since a tighter
    tolerance does not lower the formulation's."""
    tight, other = TIGHT_LABEL.format(engine=engine), FORMULATION_LABEL.format(engine=engine)
    needs_other = engine in FORMULATION_COMPANION and bool(model.loops)
    if engine not in runs or tight not in runs or (needs_other and other not in runs):
        return None
    key, factor, order = TOLERANCE_LADDER[engine]
    merged = {**builder(engine).default_settings, **case.settings.get(engine, {})}
    est = differences(runs[engine], runs[tight], sc, skip)
    evidence = {"order": order, "setting": key, "step": float(merged[key]), "ladder": factor}
    if needs_other:
        share = differences(runs[engine], runs[other], sc, skip)
        setting, times = FORMULATION_COMPANION[engine]
        evidence["formulation"] = {"setting": setting, "factor": times}
        evidence["ladder_share"] = dict(est)
        est = {k: v + share.get(k, 0.0) for k, v in est.items()}
    return est, evidence


def excluded(model: Model, t: np.ndarray, log, case: str) -> dict:
    """output -> the output times [s] its differences leave out (``acceleration_jumps``), said once."""
    out = {k: [float(t[i]) for i in idx] for k, idx in acceleration_jumps(model, t).items()}
    if out:
        times = sorted({x for v in out.values() for x in v})
        log(f"  {case}: {', '.join(out)} at t = {', '.join(f'{x:.6g}' for x in times)} s left out: a prescribed "
            "acceleration jumps there, so each drive force has two values (its left and right limits)")
    return out


def model_rule(model: Model, k: float) -> Rule:
    """The rule with each output's tolerance (and the own checks')."""
    eng = {o.name: o.tolerance for o in model.outputs}
    eng.update({o.name + SOLUTION: o.tolerance for o in model.outputs})
    eng.update(OWN_TOLERANCE)
    return Rule(eng, k=k)


def compare_model(model: Model, cases: list[ModelCase], engines: list[str], k: float = 3.0,
                  log=print) -> dict:
    """Run every case on every engine, judge it, and return the summary (runs kept under 'runs')."""
    rule = model_rule(model, k)
    summary = {"model": model.name, "model_file": model.path, "source": model.source, "engines": engines,
               "rule": {**rule.describe(), "text": pass_sentence(k)}, "cases": {}, "rows": [], "runs": {}}
    for case in cases:
        runs, failures, timing = {}, {}, {}
        for label, engine, settings in run_plan(model, case, engines):
            log(f"  {case.name}: {label} ...")
            res = run_one(model, case, engine, settings)
            timing[label] = {"wall_time": res["wall_time"]}
            if res["status"] == "ok":
                runs[label] = res["run"]
                timing[label].update({k_: v for k_, v in res["run"].stats.items() if isinstance(v, (int, float, str))})
                if "derive_time" in res["run"].stats:   # a derived engine: its derivation, generation and run
                    st = res["run"].stats
                    log(f"  {case.name}: {label}: derived in {st['derive_time']:.2f} s, generated in "
                        f"{st['codegen_time']:.2f} s (cache {st['cache']}), ran in {st['wall_time']:.2f} s")
            else:
                failures[label] = res["message"]
        entry = {"duration": case.duration, "dt_out": case.dt_out, "failures": failures, "runs": timing,
                 "reference": None if case.reference is None else
                 {"file": case.reference.path, "source": case.reference.source, "accuracy": case.reference.accuracy}}
        if CONVERGED in runs and CHECK in runs:
            ok = [e for e in engines if e in runs]
            rows, verdicts = judge(model, case, ok, runs, rule)
            summary["rows"] += rows
            entry["verdicts"] = verdicts
            entry["excluded_samples"] = excluded(model, runs[CONVERGED].t, log, case.name)
        else:
            entry["verdicts"] = {}
        for e in engines:
            if e in failures:
                entry["verdicts"][e] = {"pass": False, "consistent": None, "accurate": False, "failed": True,
                                        "text": f"failed: {failures[e]}"}
        summary["cases"][case.name] = entry
        summary["runs"][case.name] = runs
    verdicts = [v for c in summary["cases"].values() for v in c["verdicts"].values()]
    failed = any(c["failures"] for c in summary["cases"].values())
    summary["passed"] = bool(verdicts) and all(v["pass"] for v in verdicts) and not failed
    summary["exit_code"] = 3 if failed else (0 if summary["passed"] else 1)
    return summary


def table(summary: dict) -> str:
    """One line per case and engine: PASS/FAIL and the verdict in words."""
    lines = [f"model {summary['model']} ({summary['model_file']})"]
    for name, c in summary["cases"].items():
        for e, v in c["verdicts"].items():
            lines.append(f"  {name:<24} {e:<14} {'PASS' if v['pass'] else 'FAIL'}  {v.get('text', '')}")
    return "\n".join(lines)


def finite(x):
    return x if x is None or not isinstance(x, float) or math.isfinite(x) else None
