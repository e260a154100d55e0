"""The gate's drive cases side by side, before any hand-written adapter goes (issue 32): each peer
through its hand-written adapter (comparisons/engines) and through its description builder
(comparisons/builders) on the case written as a description (nsd_core.device.describe with the case's
own plate path), at the case's own step and integrator, and at half that step.

Both are judged by the gate's rule on its first metric, the steady cycle's max |F - F_ref| over the
peak |F_ref| (the force as the vector (F_x, F_y)), against the gate's converged in-house reference
(rtol 1e-10) and its check (rtol 1e-11): estimate = Richardson from the h and h/2 runs (the order the
gate assumes: MuJoCo Euler 1, RK4 2, Exudyn 2); consistent = difference <= 3 (estimate + reference's
error); accurate = max(estimate, difference) <= 1e-3. Wall time: the h run's stepping (each engine's
stats["wall_time"]; compilation and the model's build are apart; one warm-up run of each path first).
Only the peers' settings the builders share with the adapters are passed on (step, integrator).

    python -m benchmarks.bench_described_gate --out benchmarks/results/bench_described_gate.json
"""
from __future__ import annotations

import argparse
import json
import os
import time
import tomllib
from pathlib import Path

import numpy as np

from comparisons.engines import get_engine
from comparisons.estimate import nominal_order, refined_settings, richardson_factor, step_ratio
from nsd_core.device.cycle import last_cycle

K, TOLERANCE = 3.0, 1e-3
SHARED = {"mujoco": ("timestep", "integrator"), "exudyn": ("step_size",)}
STEP = {"mujoco": "timestep", "exudyn": "step_size"}


def _force(t, Fx, Fy, frequency):
    c = last_cycle(np.asarray(t), frequency)
    return np.column_stack([np.asarray(Fx)[c], np.asarray(Fy)[c]])


def _diff(F, F_ref) -> float:
    return float(np.max(np.linalg.norm(F - F_ref, axis=1)) / np.max(np.linalg.norm(F_ref, axis=1)))


def adapter_run(engine: str, case, settings: dict):
    from comparisons.engines import run_engine
    r = run_engine(engine, case.params, case.drive, settings)
    return _force(r["t"], r["F_x"], r["F_y"], case.drive.frequency), r.stats


def described_run(engine: str, case, settings: dict):
    import importlib
    from nsd_core.device.describe import device_description
    from nsd_core.model.load import parse_model
    d = case.drive
    text = device_description(case.params, d.amplitude, d.frequency, d.direction_deg, d.cycles, d.samples_per_cycle,
                              drive=d, case="")
    model = parse_model(tomllib.loads(text))
    builder = importlib.import_module(f"comparisons.builders.{engine}")
    run = builder.simulate(model, d.duration, 1.0 / (d.frequency * d.samples_per_cycle), settings)
    return _force(run.t, run.outputs["F_x"], run.outputs["F_y"], d.frequency), run.stats


def main(argv=None) -> dict:
    from comparisons.config import Case, load_cases
    from comparisons.reference import CHECK_SETTINGS, CONVERGED_SETTINGS
    from nsd_core.device.model import simulate
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="JSON file (or folder) to write")
    ap.add_argument("--cases", default=None, help="comma-separated case names (default: every drive case)")
    args = ap.parse_args(argv)
    cases = [c for c in load_cases() if isinstance(c, Case)]
    if args.cases:
        cases = [c for c in cases if c.name in args.cases.split(",")]
    out = {"rule": f"max|F - F_ref|/peak <= {K:g} (estimate + reference's error), max(estimate, difference) <= {TOLERANCE:g}",
           "machine": {"cpus": os.cpu_count(), "when": time.strftime("%Y-%m-%d %H:%M:%S")}, "cases": {}}
    warmed = set()
    for case in cases:
        f = case.drive.frequency
        ref = simulate(case.params, case.drive, **CONVERGED_SETTINGS)
        chk = simulate(case.params, case.drive, **CHECK_SETTINGS)
        F_ref = _force(ref["t"], ref["F_x"], ref["F_y"], f)
        ref_err = _diff(_force(chk["t"], chk["F_x"], chk["F_y"], f), F_ref)
        row = {"reference_error": ref_err, "engines": {}}
        for engine in ("mujoco", "exudyn"):
            given = case.settings.get(engine, {})
            merged = {**get_engine(engine).default_settings, **given}   # the adapter's settings in full
            shared = {k: merged[k] for k in SHARED[engine] if k in merged}
            if engine == "exudyn" and merged.get("min_steps_per_cycle"):   # the adapter's step cap per cycle
                shared["step_size"] = min(float(merged["step_size"]), 1.0 / (merged["min_steps_per_cycle"] * f))
            runs = [("adapter", adapter_run, given), ("described", described_run, shared)]
            if engine == "exudyn":   # the forces once a step at its predicted end (the adapter's scheme)
                runs.append(("described_predicted", described_run, {**shared, "forces": "predicted"}))
            if engine == "mujoco":   # the builder's own integrator, at the case's step and at twice it
                h = float(shared["timestep"])
                runs += [("described_rk4", described_run, {"timestep": h, "integrator": "RK4"}),
                         ("described_rk4_2h", described_run, {"timestep": 2 * h, "integrator": "RK4"})]
            for path, fn, settings in runs:
                if (engine, fn) not in warmed:   # compile or load every kernel before anything is timed
                    fn(engine, case, settings)
                    warmed.add((engine, fn))
                if path == "adapter":   # the gate's own halving (every cap on the step halves too)
                    half = refined_settings(engine, merged, given, 2.0)
                else:
                    half = {**settings, STEP[engine]: float(settings[STEP[engine]]) / 2}
                order = nominal_order(engine, {**shared, **settings})
                load = os.getloadavg()[0]
                F_h, st_h = fn(engine, case, settings)
                F_h2, st_h2 = fn(engine, case, half)
                d_h, d_h2 = _diff(F_h, F_ref), _diff(F_h2, F_ref)
                est = _diff(F_h, F_h2) * richardson_factor(order, step_ratio(st_h, st_h2))
                row["engines"].setdefault(engine, {})[path] = {
                    "settings": settings, "order": order, "difference": d_h, "difference_h2": d_h2, "estimate": est,
                    "consistent": d_h <= K * (est + ref_err), "accurate": max(est, d_h) <= TOLERANCE,
                    "wall_s": st_h.get("wall_time"), "steps": st_h.get("steps"), "load_before": load}
                r = row["engines"][engine][path]
                r["passes"] = bool(r["consistent"] and r["accurate"])
                print(f"{case.name:22s} {engine:7s} {path:16s} diff {d_h:.2e} est {est:.2e} "
                      f"{'PASS' if r['passes'] else 'FAIL'} {r['wall_s']:.3f} s (load {load:.1f})", flush=True)
            mine = row["engines"][engine]
            a = mine["adapter"]
            for path, r in list(mine.items()):
                if path != "adapter":
                    r["time_ratio"] = r["wall_s"] / a["wall_s"]
            passing = [r["time_ratio"] for p, r in mine.items() if p != "adapter" and r["passes"]]
            mine["best_passing_time_ratio"] = min(passing) if passing else None
        out["cases"][case.name] = row
    target = Path(args.out)
    if target.suffix != ".json":
        target = target / "bench_described_gate.json"
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(json.dumps(out, indent=1) + "\n")
    return out


if __name__ == "__main__":
    main()
