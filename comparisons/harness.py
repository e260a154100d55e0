"""Run every case on every engine, measure the discrepancies, write results and the verdict.

Exit codes: 0 every metric within tolerance, 1 any outside, 3 an engine failed on a case (its own
message is kept for that case; every other case still runs and is written).
"""
from __future__ import annotations

import datetime as dt
import multiprocessing
import os
import subprocess
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any, Callable

from nsd_core.device.cycle import analyse
from nsd_core.device.results import RunResult, atomic_write_json, versions, write_csv

from comparisons.config import METRICS, Case
from comparisons.engines import REFERENCE, run_job
from comparisons.convergence import convergence_study
from comparisons.metrics import own_metrics, pair_metrics
from comparisons.energy import energy_balance_rel
from nsd_core.device.geometry import device_geometry

ENGINE_COST = {"semirecursive": 1.0, "mujoco": 1.0, "exudyn": 3.0}  # rough relative cost, for scheduling




def git_revision() -> str:
    try:
        out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, timeout=10,
                             cwd=Path(__file__).resolve().parent)
        return out.stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def compare(cases: list[Case], engines: list[str], tolerances: dict[str, float], out_dir: str | Path,
            workers: int | None = None, log: Callable[[str], None] = print,
            convergence: dict | None = None) -> dict[str, Any]:
    """Run, measure, and write ``out_dir/results.json`` and ``out_dir/cycles/CASE__ENGINE.csv``."""
    out = Path(out_dir)
    jobs = [(c, e) for c in cases for e in engines]
    jobs.sort(key=lambda j: -ENGINE_COST.get(j[1], 1.0) * j[0].drive.cycles / j[0].drive.frequency)
    workers = workers or min(len(jobs), os.cpu_count() or 1)
    runs: dict[str, dict[str, dict]] = {c.name: {} for c in cases}
    results: dict[tuple[str, str], RunResult] = {}
    started = time.perf_counter()
    ctx = multiprocessing.get_context("spawn")  # MuJoCo's callbacks are process-global: one per process
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        futures = {pool.submit(run_job, e, c.params_for(e), c.drive, c.settings.get(e, {})): (c, e) for c, e in jobs}
        for fut in as_completed(futures):
            case, engine = futures[fut]
            job = fut.result()
            entry: dict[str, Any] = {"status": job["status"], "wall_time": job["wall_time"]}
            if job["status"] == "ok":
                res: RunResult = job["result"]
                results[(case.name, engine)] = res
                csv = out / "cycles" / f"{case.name}__{engine}.csv"
                write_csv(csv, res)
                entry.update(csv=str(csv.relative_to(out)), stats=res.stats,
                             summary=analyse(res, case.drive.amplitude, case.drive.frequency),
                             wall_time_per_cycle=res.stats.get("wall_time", job["wall_time"]) / case.drive.cycles)
                log(f"  {case.name:16s} {engine:14s} ok     {entry['wall_time_per_cycle']:7.2f} s/cycle")
            else:
                entry["message"] = job["message"]
                log(f"  {case.name:16s} {engine:14s} FAILED {job['message']}")
            runs[case.name][engine] = entry
    metrics = _metrics(cases, engines, tolerances, runs, results)
    failed_engines = [(c, e) for c in runs for e, r in runs[c].items() if r["status"] != "ok"]
    failed_metrics = [m for m in metrics if m["gated"] and not m["pass"]]
    exit_code = 3 if failed_engines else (1 if failed_metrics else 0)
    summary = {
        "verdict": {0: "PASS", 1: "FAIL", 3: "ERROR"}[exit_code], "exit_code": exit_code,
        "failures": [f"{m['case']}: {m['engine']} {m['metric']} = {m['value']:.3g} > {m['limit']:.3g}"
                     for m in failed_metrics] + [f"{c}: {e} failed: {runs[c][e]['message']}" for c, e in failed_engines],
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"), "git_revision": git_revision(),
        "reference": REFERENCE, "engines": engines, "cases": [c.describe() for c in cases],
        "tolerances": dict(tolerances), "tolerances_by_engine": getattr(tolerances, "engines", {}),
        "metric_units": {k: v[0] for k, v in METRICS.items()},
        "params": cases[0].params.describe() if cases else [], "runs": runs, "metrics": metrics,
        "total_wall_time": time.perf_counter() - started, "workers": workers,
    }
    summary["versions"] = versions()
    if convergence:
        log("  convergence study ...")
        summary["convergence"] = convergence_study(convergence, engines, workers)
    atomic_write_json(out / "results.json", summary)
    return summary


def limit_for(tolerances, engine, case, metric):
    """Per-engine-and-case limits when the tolerances have them (config.Tolerances), else the flat one."""
    return tolerances.limit(engine, case, metric) if hasattr(tolerances, "limit") else tolerances.get(metric)


def _metrics(cases, engines, tolerances, runs, results) -> list[dict]:
    """Every engine against the reference (gated) and every other pair (reported, not gated)."""
    rows = []
    others = [e for e in engines if e != REFERENCE]
    pairs = [(e, REFERENCE, True) for e in others if REFERENCE in engines]
    pairs += [(a, b, False) for i, a in enumerate(others) for b in others[i + 1:]]
    for c in cases:
        for e in engines:
            if (c.name, e) in results:
                own = own_metrics(results[(c.name, e)])
                own["energy_balance_rel"] = energy_balance_rel(results[(c.name, e)], device_geometry(c.params),
                                                               c.drive.frequency, c.drive.unit_vector)
                for k, v in own.items():
                    if (lim := limit_for(tolerances, e, c.name, k)) is not None:
                        rows.append(_row(c.name, e, None, k, v, lim, True))
        for a, b, gated in pairs:
            if (c.name, a) in results and (c.name, b) in results:
                ra, rb = runs[c.name][a]["summary"], runs[c.name][b]["summary"]
                m = pair_metrics(results[(c.name, a)], results[(c.name, b)], ra, rb, c.drive.amplitude,
                                 c.drive.frequency)
                for k, v in m.items():
                    if (lim := limit_for(tolerances, a, c.name, k)) is not None:
                        rows.append(_row(c.name, a, b, k, v, lim, gated))
    return rows


def _row(case, engine, reference, metric, value, limit, gated):
    return {"case": case, "engine": engine, "reference": reference, "metric": metric, "value": value,
            "limit": limit, "pass": bool(value <= limit), "gated": gated}
