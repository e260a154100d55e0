"""Run every case on every engine, measure the discrepancies, write results and the verdict.

Exit codes: 0 every metric within tolerance, 1 any outside, 3 an engine failed on a case (its own
message is kept for that case; every other case still runs and is written).
"""
from __future__ import annotations

import datetime as dt
import functools
import hashlib
import json
import subprocess
import time
from concurrent.futures import as_completed
from pathlib import Path
from typing import Any, Callable

from nsd_core.device.cycle import analyse
from nsd_core.device.results import RunResult, read_csv, versions, write_csv
from nsd_core.common.files import atomic_write_json
from nsd_core.engine.workers import default_workers, worker_pool

from comparisons.config import METRICS, Case, SeismicCase
from comparisons.engines import REFERENCE, run_job, run_seismic_job
from comparisons.warmup import job_warmup, spec as warm_spec
from comparisons.convergence import convergence_study
from comparisons.reference import CONVERGED, CONVERGED_SETTINGS, order_labels, run_spec, version_warnings, warn
from comparisons.judge import judge_case
from comparisons.verdict import estimate_labels
from comparisons.harness_rows import _converged_own, _metrics, _order_rows, _seismic_peaks

LIMITS_TEXT = ("PASS means every gated metric is within the tolerance file's fixed limits (a regression "
               "profile: limits derived on one device tell nothing of another)")
from nsd_core.compilation.numba_cache import source_fingerprint

ENGINE_COST = {"semirecursive": 1.0, "mujoco": 1.0, "exudyn": 3.0}  # rough relative cost, for scheduling


@functools.lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """A hash of the model and engine source (nsd_core, comparisons) and the installed versions: a
    kept run is reused only by the code that made it, never after an edit or an upgrade."""
    h = hashlib.sha256(json.dumps(versions(), sort_keys=True).encode())
    h.update(source_fingerprint(Path(__file__).resolve().parents[1]).encode())  # the numba cache's key too
    return h.hexdigest()[:16]


def job_key(case: Case, engine: str, order: dict | None = None) -> str:
    """What a kept run depends on: the engine (a run label: comparisons.reference.run_spec), its
    parameters, the drive (a seismic case: the ground input, duration, output interval, device,
    structure), its settings, the code."""
    _, params, settings = run_spec(case, engine, order)
    if isinstance(case, SeismicCase):
        text = json.dumps(["seismic", engine, params.to_dict(), case.params.to_dict(), case.spec,
                           case.ground.describe(), case.model_duration, case.dt_out, case.device, case.structure,
                           settings, code_fingerprint()], sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:20]
    d = case.drive
    drive = dict(d.describe(), samples_per_cycle=d.samples_per_cycle, minor=d.minor)
    if d._table is not None:  # a path read from a file: its content, not its name
        from nsd_core.device.drive import MAX_TABLE_BYTES
        from nsd_core.common.files import read_input_bytes
        drive["table"] = hashlib.sha256(read_input_bytes(d.path, "path", MAX_TABLE_BYTES)).hexdigest()
    text = json.dumps([engine, params.to_dict(), drive, settings, code_fingerprint()], sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def load_kept(out: Path, case: Case, engine: str, order: dict | None = None) -> dict | None:
    """A run an earlier call kept for exactly these inputs, or None."""
    from nsd_core.common.files import read_regular_text
    csv = run_csv(out, case, engine)
    try:
        rec = json.loads(read_regular_text(csv.with_suffix(".json"), "stored run"))
        if rec.get("key") != job_key(case, engine, order) or not csv.is_file():
            return None
        res = read_csv(csv, engine)
    except (OSError, ValueError):
        return None
    res.stats = rec.get("stats", {})
    return {"status": "ok", "result": res, "wall_time": rec.get("wall_time", 0.0)}


def run_csv(out: Path, case, engine: str) -> Path:
    """cycles/CASE__ENGINE.csv for a drive case, seismic/CASE__ENGINE.csv (nsd seismic's columns) for a seismic one."""
    return out / ("seismic" if isinstance(case, SeismicCase) else "cycles") / f"{case.name}__{engine}.csv"


def _model_time(case) -> float:
    return case.model_duration if isinstance(case, SeismicCase) else case.drive.cycles / case.drive.frequency


def git_revision() -> str:
    try:
        out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, timeout=10,
                             cwd=Path(__file__).resolve().parent)
        return out.stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def compare(cases: list[Case], engines: list[str], tolerances: dict[str, float], out_dir: str | Path,
            workers: int | None = None, log: Callable[[str], None] = print,
            convergence: dict | None = None, tally: dict | None = None, order: dict | None = None,
            warn: Callable[[str], None] = warn) -> dict[str, Any]:
    """Run, measure, and write ``out_dir/results.json`` and ``out_dir/cycles/CASE__ENGINE.csv``.

    Resumable: a run kept by an earlier, interrupted call with the same inputs (its CSV and its
    ``.json`` record with the same ``job_key``) is read back instead of run again. ``tally`` (a
    dict) is kept up to date with ``kept``, ``total`` and ``dir`` for the interrupt message.

    Every engine is gated against the converged reference (comparisons/reference.py), run once per
    case beside the engines and kept the same way; ``order`` (the case file's [order] table) adds
    each listed peer's step halved twice on one case, and gates the observed order."""
    out = Path(out_dir)
    derived = getattr(tolerances, "derived", {})
    warnings = version_warnings(derived, versions(), engines)
    for line in warnings:
        warn(line)
    rule = getattr(tolerances, "rule", None)   # None: the regression profile's fixed limits
    jobs = _jobs(cases, engines, order, rule)
    workers = workers or min(len(jobs), default_workers())
    started = time.perf_counter()
    book = _Runs(cases, engines, out, order, log, tally if tally is not None else {}, len(jobs))
    todo = [(c, e) for c, e in jobs if not book.resume(c, e)]
    startup, warmup = book.run(todo, workers) if todo else (None, None)
    summaries = {c: {**book.reference_runs[c], **book.runs[c]} for c in book.runs}
    verdict, metrics, order_evidence = _verdict(cases, engines, tolerances, rule, order, summaries, book.results)
    summary = {
        **verdict,
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"), "git_revision": git_revision(),
        "reference": REFERENCE, "engines": engines,
        "cases": [c.describe() for c in cases if not isinstance(c, SeismicCase)],
        "seismic_cases": [_seismic_describe(c, book.structures) for c in cases if isinstance(c, SeismicCase)],
        "tolerances": dict(tolerances), "tolerances_defaulted": list(getattr(tolerances, "defaulted", ())),
        "tolerances_by_engine": getattr(tolerances, "engines", {}),
        "metric_units": {k: v[0] for k, v in METRICS.items()},
        "params": cases[0].params.describe() if cases else [], "runs": book.runs, "metrics": metrics,
        "total_wall_time": time.perf_counter() - started, "workers": workers,
        "worker_startup_time": startup, "worker_warmup": warmup,
        "metric_definitions": {k: v[1] for k, v in METRICS.items()}, "versions": versions(),
        "converged_reference": {"label": CONVERGED, "engine": REFERENCE, "settings": dict(CONVERGED_SETTINGS),
                                "own": _converged_own(cases, book.results)},
        "reference_runs": book.reference_runs, "order": order_evidence,
        "limits_derived_on": derived, "limits_version_warnings": warnings}
    if convergence:
        log("  convergence study ...")
        summary["convergence"] = convergence_study(convergence, engines, workers)
    atomic_write_json(out / "results.json", summary)
    return summary


def _jobs(cases: list[Case], engines: list[str], order: dict | None, rule) -> list[tuple]:
    """Every (case, run label) a compare call runs, longest first: each engine, the converged reference
    and the order study's runs on each case, and under an estimated rule the error estimates' runs."""
    by_name = {c.name: c for c in cases}
    extra = [(c, CONVERGED) for c in cases] + [(by_name[n], lab) for n, lab in order_labels(order, engines)
                                                if n in by_name]
    if rule is not None:   # each peer at 2h and the reference's own check: the engines' error estimates
        extra += [j for j in estimate_labels(cases, engines) if j not in extra]
    jobs = [(c, e) for c in cases for e in engines] + extra
    # longest first: seismic runs cost ~10x a drive run per model second (loaded 2-core machine)
    jobs.sort(key=lambda j: -_cost(j[1]) * _model_time(j[0]) * (10.0 if isinstance(j[0], SeismicCase) else 1.0))
    return jobs


class _Runs:
    """The runs of one compare call: each engine's entry per case (the reference's runs apart), the
    results as read back from the CSVs written, and each seismic case's structure, derived once."""

    def __init__(self, cases, engines, out: Path, order, log, tally: dict, total: int):
        self.engines, self.out, self.order, self.log, self.tally = engines, out, order, log, tally
        self.runs: dict[str, dict[str, dict]] = {c.name: {} for c in cases}
        self.reference_runs = {c.name: {} for c in cases}   # converged, the companions and step-halved
        self.results: dict[tuple[str, str], RunResult] = {}
        self.structures: dict[str, Any] = {}
        tally.update(kept=0, total=total, dir=str(out))

    def resume(self, case: Case, engine: str) -> bool:
        """Read back the run an earlier call kept for exactly these inputs; False when there is none."""
        done = load_kept(self.out, case, engine, self.order)
        if done is not None:
            self.keep(case, engine, done, resumed=True)
        return done is not None

    def keep(self, case: Case, engine: str, job: dict, resumed: bool = False) -> None:
        """One finished job: its CSV and record written (a fresh run), its result read back, its entry and log line."""
        entry: dict[str, Any] = {"status": job["status"], "wall_time": job["wall_time"],
                                 "job_wall_time": job["wall_time"]}
        if job["status"] == "ok":
            res: RunResult = job["result"]
            self.results[(case.name, engine)] = res
            csv = run_csv(self.out, case, engine)
            if not resumed:  # the CSV first, then the record that marks it complete
                written = write_csv(csv, res)   # the numbers as the CSV reads back
                atomic_write_json(csv.with_suffix(".json"), {"key": job_key(case, engine, self.order), "engine": engine,
                                                             "stats": res.stats, "wall_time": job["wall_time"]})
            self.tally["kept"] += 1  # on disk (its record written): what the interrupt message counts
            if not resumed:
                # measure what was written, so a resumed run and an uninterrupted one agree exactly
                written.stats, res = res.stats, written
                self.results[(case.name, engine)] = res
            wall = res.stats.get("wall_time", job["wall_time"])
            # the integration alone; compilation (compile_time) and the job's start-up stay apart
            entry.update(csv=str(csv.relative_to(self.out)), stats=res.stats, resumed=resumed, wall_time=wall,
                         cpu_time=res.stats.get("cpu_time"), compile_time=res.stats.get("compile_time"))
            if isinstance(case, SeismicCase):
                entry.update(summary=_seismic_peaks(res), wall_time_per_model_second=wall / case.model_duration)
                rate = f"{entry['wall_time_per_model_second']:7.2f} s/model s"
            else:
                entry.update(summary=analyse(res, case.drive.amplitude, case.drive.frequency, case.drive.path),
                             wall_time_per_cycle=wall / case.drive.cycles)
                rate = f"{entry['wall_time_per_cycle']:7.2f} s/cycle"
            self.log(f"  {case.name:16s} {engine:14s} {'kept' if resumed else 'ok':6s} {rate}")
        else:
            entry["message"] = job["message"]
            self.log(f"  {case.name:16s} {engine:14s} FAILED {job['message']}")
        (self.runs if engine in self.engines else self.reference_runs)[case.name][engine] = entry

    def run(self, todo: list, workers: int) -> tuple:
        """Run the jobs not kept on warm workers, keeping each: (the workers' start-up [s], their warm-up)."""
        startup, pool_start = None, time.time()
        warm = job_warmup(warm_spec(engine, isinstance(c, SeismicCase), getattr(c, "drive", None), settings)
                          for c, e in todo for engine, _, settings in [run_spec(c, e, self.order)])
        with worker_pool(min(workers, len(todo)), warm=warm) as pool:
            futures = {self._submit(pool, c, e): (c, e) for c, e in todo}
            for fut in as_completed(futures):
                case, engine = futures[fut]
                job = fut.result()
                if job.get("started") is not None:   # spawning the workers and their imports
                    startup = min(startup if startup is not None else float("inf"), job["started"] - pool_start)
                self.keep(case, engine, job)
            return startup, pool.startup.summary()

    def _submit(self, pool, c, label):
        """One job on the pool: a drive run, or a seismic run on the case's structure."""
        e, params, settings = run_spec(c, label, self.order)
        if isinstance(c, SeismicCase):
            if c.name not in self.structures:   # derived once per case, the same for every engine
                self.structures[c.name] = c.isolated_structure()
            return pool.submit(run_seismic_job, e, params, self.structures[c.name], c.ground, c.duration,
                               c.dt_out, settings)
        return pool.submit(run_job, e, params, c.drive, settings)


def _verdict(cases, engines, tolerances, rule, order, summaries: dict, results: dict) -> tuple[dict, list, dict]:
    """(The verdict: exit code 3 an engine failed or nothing gated, 1 a gated metric out, else 0, the failures,
    the rule, each case's verdicts; every metric row; the observed order's evidence)."""
    verdicts: dict[str, dict] = {}
    if rule is None:
        metrics = _metrics(cases, engines, tolerances, summaries, results)
    else:
        metrics = []
        for c in cases:
            rows, verdicts[c.name] = judge_case(c, engines, results, summaries[c.name], rule)
            metrics += rows
    order_evidence = {}
    if order:
        rows, order_evidence = _order_rows(order, engines, {c.name: c for c in cases}, results, tolerances)
        for r in rows:   # under the estimated rule the observed order is evidence, each case has its own
            r["gated"] = r["gated"] and rule is None
        metrics += rows
    failed_engines = [(c, e) for c in summaries for e, r in summaries[c].items()
                      if r["status"] != "ok" and (rule is None or e in engines or e == CONVERGED)]
    failed_metrics = [m for m in metrics if m["gated"] and not m["pass"]]
    nothing_gated = not any(m["gated"] for m in metrics)  # never a vacuous PASS
    exit_code = 3 if failed_engines or nothing_gated else (1 if failed_metrics else 0)
    if rule is None:
        failures = [f"{m['case']}: {m['engine']} {m['metric']} = {m['value']:.3g} > {m['limit']:.3g}"
                    for m in failed_metrics]
    else:
        failures = [f"{c}: {e} {v['text']}" for c, per in verdicts.items() for e, v in per.items() if not v["pass"]]
    return {"verdict": {0: "PASS", 1: "FAIL", 3: "ERROR"}[exit_code], "exit_code": exit_code,
            "failures": failures + [f"{c}: {e} failed: {summaries[c][e]['message']}" for c, e in failed_engines]
            + (["nothing was gated: no metric of the tolerance file was measured"] if nothing_gated else []),
            "rule": rule.describe() if rule is not None else {"name": "limits", "text": LIMITS_TEXT},
            "verdicts": verdicts}, metrics, order_evidence


def _seismic_describe(c, structures: dict) -> dict:
    """A seismic case as run: its file entry, the ground motion's record metadata (set, id, event,
    station, window in record seconds, scale, rotation, time factor) and the structure used, with
    every value's provenance."""
    st = structures.get(c.name) or c.isolated_structure()
    return {**c.describe(), "ground": c.ground.describe(), "structure_used": st.to_dict(),
            "model_duration": c.model_duration}


def _cost(label: str) -> float:
    """Rough relative cost of a run label, for scheduling (a step divided by N costs N times, a step
    times N costs 1/N)."""
    from comparisons.reference import COARSER, HALVED
    if m := HALVED.fullmatch(label):
        return ENGINE_COST.get(m.group(1), 1.0) * int(m.group(2))
    if m := COARSER.fullmatch(label):
        return ENGINE_COST.get(m.group(1), 1.0) / int(m.group(2))
    return ENGINE_COST.get(label, 1.0)
