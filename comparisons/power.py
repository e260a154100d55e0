"""Detection power of the gate: small modelling errors injected into one engine's own model.

For each injection (engines/perturb.py), each perturbed engine and each chosen case, the engine runs
with its case settings plus ``perturb`` and is measured against the converged reference exactly as
the gate measures it (same metrics, same limits: comparisons/reference.py). A row records the largest value/limit ratio
and the metric that gave it, and whether the gate failed. An injection is *seen* when it fails the
gate in at least one case. Injections that pass are tried again 10x larger (the ``ladder``), so
the report can say the smallest error of that kind the gate sees. ``scaled(spec, size)`` gives the
list at another size (``nsd compare --power --power-size``); ``combine`` puts the tables of several
profiles (default, strict) side by side, one line per error.
"""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Any, Callable

from nsd_core.device.cycle import analyse
from nsd_core.device.geometry import device_geometry
from nsd_core.common.files import atomic_write_json
from nsd_core.engine.workers import default_workers, worker_pool

from comparisons.config import SeismicCase
from comparisons.engines import REFERENCE, run_job, run_seismic_job
from comparisons.engines.perturb import KINDS, check, describe, perturbed
from comparisons.harness_rows import limit_for
from comparisons.judge import differences, judge_case, own_checks
from comparisons.reference import CHECK, CONVERGED, CONVERGED_SETTINGS, halved_settings, run_spec
from comparisons.estimate import companion_label
from comparisons.verdict import merged_settings
from comparisons.warmup import job_warmup, spec as warm_spec
from nsd_core.device.params import ParameterError

# the injected errors (docs/validation.md): each body's mass +-1 %, each kind of attachment point moved 0.2 mm (up and
# radially), the rod +-0.2 mm, gravity off, one rope's stiffness +-1 %, the spring's constants
# +-1 %, the wires' area +-1 %, two mis-set rest states
INJECTIONS: list[dict] = (
    [{"what": f"{b}_mass", "by": s * 0.01} for b in ("cap", "wall", "rod") for s in (1, -1)]
    + [{"what": p, "index": 0, "axis": a, "by": 2e-4}
       for p in ("rope_base_point", "rope_cap_point", "wire_cap_point", "wire_wall_point") for a in ("z", "x")]
    + [{"what": "rod_length", "by": s * 2e-4} for s in (1, -1)]
    + [{"what": "gravity", "by": -1.0}]
    + [{"what": "rope_stiffness", "index": 0, "by": s * 0.01} for s in (1, -1)]
    + [{"what": f"spring_{k}", "by": s * 0.01} for k in ("kse", "ksd", "beta", "gamma") for s in (1, -1)]
    + [{"what": "wire_area", "by": s * 0.01} for s in (1, -1)]
    + [{"what": "rest_ignores_weight"}, {"what": "spring_zeta0", "by": 0.01}]
)


LISTED_SIZE = 0.01   # the relative size of the listed errors; their lengths (0.2 mm) scale with it


def scaled(spec: dict, size: float) -> dict:
    """The listed error at another size: relative ones (masses, stiffnesses, constants) become
    +-size, lengths scale by size / 1 %; gravity off and the mis-set rest state are on/off and stay."""
    if "by" not in spec or spec["what"] == "gravity":
        return dict(spec)
    by = spec["by"]
    if KINDS[spec["what"]][0] == "m":
        return {**spec, "by": by * size / LISTED_SIZE}
    return {**spec, "by": size if by > 0 else -size}


def _limits_verdict(case, engine: str, tolerances, run, ref, run_summary, ref_summary) -> dict[str, Any]:
    """The regression profile's fixed limits: the largest value/limit ratio of the run's metrics."""
    values = {**differences(case, run, ref, run_summary, ref_summary), **own_checks(case, run)}
    ratios = {k: v / lim for k, v in values.items() if (lim := limit_for(tolerances, engine, case.name, k))}
    worst = max(ratios, key=ratios.get)
    return {"failed": any(r > 1.0 for r in ratios.values()), "metric": worst, "ratio": ratios[worst],
            "value": values[worst], "values": values, "failing": sorted(k for k, r in ratios.items() if r > 1.0)}


def _rule_verdict(case, engine: str, rule, jobs: dict, refs: dict) -> dict[str, Any]:
    """The estimated rule on one perturbed engine: its runs at h and 2h against the nominal converged
    reference and its check (comparisons.judge); seen when the verdict fails."""
    results, entries = {}, {}
    for label, job in {**refs, **jobs}.items():
        if job["status"] == "ok":
            results[(case.name, label)] = job["result"]
        entries[label] = {"status": job["status"], "stats": job["result"].stats if job["status"] == "ok" else {},
                          "summary": job.get("summary"), "message": job.get("message")}
    rows, verdicts = judge_case(case, [engine], results, entries, rule)
    v = verdicts[engine]
    gated = [r for r in rows if r["gated"] and r["engine"] == engine]
    ratios = {r["metric"]: (r["value"] / r["bound"] if r.get("bound") else r["value"] / r["tolerance"]) for r in gated}
    worst = max(ratios, key=ratios.get)
    kind = "disagrees" if v["consistent"] is False else (
        "undecided" if v["consistent"] is None and v.get("undecided") and v["accurate"] else
        "not converged" if not v["pass"] else "-")
    return {"failed": not v["pass"], "metric": worst, "ratio": ratios[worst],
            "value": next(r["value"] for r in gated if r["metric"] == worst), "verdict": v["text"], "kind": kind,
            "failing": sorted(r["metric"] for r in gated if not r["pass"])}


def _submit(pool, case, engine: str, params, settings: dict):
    if isinstance(case, SeismicCase):
        return pool.submit(run_seismic_job, engine, params, case.isolated_structure(), case.ground, case.duration,
                           case.dt_out, settings)
    return pool.submit(run_job, engine, params, case.drive, settings)


def _result(case, fut) -> dict:
    job = fut.result()
    if job["status"] == "ok" and not isinstance(case, SeismicCase):
        job["summary"] = analyse(job["result"], case.drive.amplitude, case.drive.frequency)
    return job


def _applies(case, spec: dict) -> bool:
    """An injection the case's mode can take (isolated_mass: seismic only)."""
    try:
        check(spec)
        perturbed(device_geometry(case.params), spec, seismic=isinstance(case, SeismicCase))
        return True
    except ParameterError:
        return False


def power_study(cases: list, engines: list[str], tolerances, out_dir: str | Path,
                injections: list[dict] | None = None, workers: int | None = None, ladder: bool = True,
                log: Callable[[str], None] = print) -> dict[str, Any]:
    """Run every injection on every engine and case; write ``out_dir/power.json``; return the summary.
    Under the estimated rule (a tolerance file with [engineering]) each perturbed engine also runs at
    2h, so its estimate is its own; under fixed limits the run alone is measured."""
    injections = INJECTIONS if injections is None else injections
    rule = getattr(tolerances, "rule", None)
    started = time.perf_counter()
    workers = workers or default_workers()
    rows: list[dict] = []
    ref_labels = [CONVERGED] + ([CHECK] if rule is not None else [])
    warm = job_warmup([warm_spec(REFERENCE, isinstance(c, SeismicCase), getattr(c, "drive", None), CONVERGED_SETTINGS)
                       for c in cases]
                      + [warm_spec(e, isinstance(c, SeismicCase), getattr(c, "drive", None), c.settings.get(e, {}))
                         for c in cases for e in engines])
    with worker_pool(workers, warm=warm) as pool:  # spawn; workers end with their parent, warm
        ref_jobs = {(c.name, lab): _submit(pool, c, *run_spec(c, lab)) for c in cases for lab in ref_labels}

        expected: dict[tuple[str, float], int] = {}

        def submit(spec, scale):
            s = {k: v * scale if k == "by" else v for k, v in spec.items()}
            out = []
            for c in cases:
                for e in engines:
                    if not _applies(c, s):
                        continue
                    settings = {**c.settings.get(e, {}), "perturb": s}
                    futs = {e: _submit(pool, c, e, c.params_for(e), settings)}
                    if rule is not None:
                        pc = dataclasses.replace(c, settings={**c.settings, e: settings})
                        label, times = companion_label(e, merged_settings(e, pc))
                        futs[label] = _submit(pool, c, e, c.params_for(e), halved_settings(pc, e, 1.0 / times))
                    out.append((c, e, spec, s, scale, futs))
            expected[(describe(spec), scale)] = len(out)   # the runs this size of this error takes
            return out

        pending = [j for spec in injections for j in submit(spec, 1.0)]
        refs: dict[str, dict] = {}
        for (name, lab), fut in ref_jobs.items():
            case = next(c for c in cases if c.name == name)
            job = _result(case, fut)
            if job["status"] != "ok":
                raise RuntimeError(f"reference failed on {name}: {job['message']}")
            refs.setdefault(name, {})[lab] = job
        while pending:
            c, e, spec, s, scale, futs = pending.pop(0)
            jobs = {lab: _result(c, f) for lab, f in futs.items()}
            row = {"case": c.name, "engine": e, "injection": describe(spec), "applied": describe(s),
                   "perturb": s, "scale": scale}
            bad = [j for j in jobs.values() if j["status"] != "ok"]
            if bad:   # a run that fails has not detected anything: reported, never "seen"
                row.update(failed=False, metric="run error", ratio=0.0, value=None, error=bad[0]["message"])
            elif rule is not None:
                row.update(_rule_verdict(c, e, rule, jobs, refs[c.name]))
            else:
                ref = refs[c.name][CONVERGED]
                row.update(_limits_verdict(c, e, tolerances, jobs[e]["result"], ref["result"], jobs[e].get("summary"),
                                           ref.get("summary")))
            rows.append(row)
            log(f"  {row['applied']:32s} {e:8s} {c.name:22s} {'FAIL' if row['failed'] else 'pass'} "
                f"{row['metric']} x{row['ratio']:.3g}")
            seen = [r for r in rows if r["injection"] == row["injection"] and r["scale"] == scale]
            if ladder and scale < 100 and len(seen) == expected[(row["injection"], scale)] \
                    and not any(r["failed"] for r in seen):
                pending += submit(spec, scale * 10)   # not seen at this size: try 10x larger
    table = summarise(rows, injections)
    out = {"cases": [c.describe() for c in cases], "engines": engines, "rows": rows, "table": table,
           "rule": rule.describe() if rule is not None else {"name": "limits"},
           "all_seen": all(t["seen_at_nominal"] for t in table), "wall_time": time.perf_counter() - started}
    atomic_write_json(Path(out_dir) / "power.json", out)
    return out


def summarise(rows: list[dict], injections: list[dict]) -> list[dict]:
    """One line per injection: seen at its listed size? by which engine/case/metric; smallest seen."""
    table = []
    for spec in injections:
        name = describe(spec)
        mine = [r for r in rows if r["injection"] == name]
        nominal = [r for r in mine if r["scale"] == 1.0]
        best = max(nominal, key=lambda r: r["ratio"]) if nominal else None
        seen_scales = sorted({r["scale"] for r in mine if r["failed"]})
        # the metrics move in proportion to a small error, so the gate's threshold for this kind of
        # error is about the listed size / (value/limit); a linear estimate, not a measurement
        threshold = None
        if best and best["ratio"] not in (None, float("inf")) and best["ratio"] > 0 and "by" in spec:
            threshold = abs(spec["by"]) / best["ratio"]
        per_engine = {}
        for r in nominal:
            per_engine[r["engine"]] = max(per_engine.get(r["engine"], 0.0), r["ratio"])
        table.append({"injection": name, "seen_at_nominal": any(r["failed"] for r in nominal),
                      "run_errors": [f"{r['engine']} {r['case']}: {r['error']}" for r in nominal if r.get("error")],
                      "weakest_engine_ratio": min(per_engine.values()) if per_engine else None,
                      "engines_seeing": sorted({r["engine"] for r in nominal if r["failed"]}),
                      "best_metric": best["metric"] if best else None, "best_ratio": best["ratio"] if best else None,
                      "best_case": best["case"] if best else None,
                      "smallest_seen_scale": seen_scales[0] if seen_scales else None,
                      "threshold_estimate": threshold})
    return table


def format_power(out: dict) -> str:
    lines = [f"{'injection':34s} {'seen':5s} {'by':14s} {'metric':18s} {'value/limit':>11s}  smallest seen  threshold~"]
    for t in out["table"]:
        small = "-" if t["smallest_seen_scale"] is None else f"x{t['smallest_seen_scale']:g} of listed"
        lines.append(f"{t['injection']:34s} {'yes' if t['seen_at_nominal'] else 'NO':5s} "
                     f"{','.join(t['engines_seeing']) or '-':14s} {t['best_metric'] or '-':18s} "
                     f"{t['best_ratio'] or 0:11.3g}  {small:13s}  {threshold_text(t)}")
    lines += [f"RUN ERROR ({t['injection']}) {e}" for t in out["table"] for e in t.get("run_errors", [])]
    return "\n".join(lines)


def threshold_text(t: dict) -> str:
    """The linear estimate of the smallest error of that kind the gate sees, in the error's unit."""
    th, name = t.get("threshold_estimate"), t["injection"]
    if th is None:
        return "-"
    return f"{th * 1e3:.2g} mm" if " mm" in name else f"{th * 100:.2g} %"


def combine(outs: dict[str, dict]) -> list[dict]:
    """One line per error: for each profile (name -> power_study output) seen or not, the value/limit
    of the engine that saw it most and of the one that saw it least."""
    names = [t["injection"] for t in next(iter(outs.values()))["table"]]
    lines = []
    for i, name in enumerate(names):
        line = {"injection": name}
        for prof, out in outs.items():
            t = out["table"][i]
            line[prof] = {"seen": t["seen_at_nominal"], "best_ratio": t["best_ratio"], "best_metric": t["best_metric"],
                          "engines_seeing": t["engines_seeing"], "weakest_engine_ratio": t["weakest_engine_ratio"]}
        lines.append(line)
    return lines


def format_profiles(lines: list[dict], profiles: list[str]) -> str:
    head = f"{'injection':34s}" + "".join(f" {p + ': seen':>14s} {'max ratio':>10s} {'min engine':>10s}" for p in profiles)
    out = [head]
    for ln in lines:
        row = f"{ln['injection']:34s}"
        for p in profiles:
            d = ln[p]
            row += (f" {('yes ' + ','.join(d['engines_seeing'])) if d['seen'] else 'NO':>14s} "
                    f"{d['best_ratio'] or 0:10.3g} {d['weakest_engine_ratio'] or 0:10.3g}")
        out.append(row)
    return "\n".join(out)
