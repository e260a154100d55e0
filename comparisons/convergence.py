"""Convergence study: each engine's discrepancy from a tight in-house reference as its step size
(or tolerance) shrinks, with the wall time each point cost. Defined in the case file:

    [convergence]
    case = "A15mm_f10Hz"         # a case of the file; run with `cycles` cycles
    cycles = 1
    reference = { rtol = 1e-10 } # semirecursive settings of the reference run
    [convergence.sweep]
    semirecursive = { setting = "rtol", values = [1e-5, 1e-6, 1e-7, 1e-8] }
    mujoco = { setting = "timestep", values = [4e-5, 2e-5, 1e-5, 5e-6] }
    exudyn = { setting = "step_size", values = [...], settings = { min_steps_per_cycle = 1 } }

The result shows whether a discrepancy is numerical error that vanishes or a floor.
"""
from __future__ import annotations

import dataclasses


from comparisons.config import Case
from comparisons.engines import REFERENCE, run_job
from comparisons.metrics import pair_metrics
from nsd_core.device.cycle import analyse




def convergence_study(spec: dict, engines: list[str], workers: int) -> dict:
    case: Case = spec["case"]
    drive = dataclasses.replace(case.drive, cycles=spec["cycles"])
    jobs = [(REFERENCE, spec["reference"], None)]
    for e in engines:
        if e in spec["sweep"]:
            s = spec["sweep"][e]
            fixed = {**case.settings.get(e, {}), **s.get("settings", {})}
            jobs += [(e, {**fixed, s["setting"]: v}, v) for v in s["values"]]
    from nsd_core.engine.workers import worker_pool
    from comparisons.warmup import job_warmup, spec as warm_spec
    with worker_pool(workers, warm=job_warmup(warm_spec(e, False, drive, s) for e, s, _ in jobs)) as pool:
        futs = [pool.submit(run_job, e, case.params_for(e), drive, settings) for e, settings, _ in jobs]
        outs = [f.result() for f in futs]
    if outs[0]["status"] != "ok":
        return {"error": f"reference run failed: {outs[0]['message']}"}
    ref = outs[0]["result"]
    ref_summary = analyse(ref, drive.amplitude, drive.frequency, drive.path)
    result: dict = {}
    for (e, settings, v), out in zip(jobs[1:], outs[1:]):
        entry = result.setdefault(e, {"setting": spec["sweep"][e]["setting"], "case": case.name,
                                      "reference": f"{REFERENCE} {spec['reference']}", "points": []})
        if out["status"] != "ok":
            entry["points"].append({"value": v, "error": out["message"]})
            continue
        r = out["result"]
        m = pair_metrics(r, ref, analyse(r, drive.amplitude, drive.frequency, drive.path), ref_summary, drive.amplitude,
                         drive.frequency)
        entry["points"].append({"value": v, "max_dF_rel": m["max_dF_rel"], "loop_area_rel": m["loop_area_rel"],
                                "wall_time": r.stats.get("wall_time", out["wall_time"]) / drive.cycles,
                                # warm: the engines record compilation apart (compile_time)
                                "cpu_time": (r.stats["cpu_time"] / drive.cycles if r.stats.get("cpu_time") is not None
                                             else None), "compile_time": r.stats.get("compile_time")})
    return result
