"""Record-set runs of the seismic mode (docs/seismic.md): the isolation effect over a FEMA P695 set.

Every record of a set runs twice on the in-house engine, on the device (plate, mass, supports and
device) and on the supports alone (``device=False``): the ratio of the two peaks is what the device
does for that record. Peer engines, when asked for, run the device case too.

Each run is a job of the sweep's store (``nsd_core.study.store``, ``designs/<key>/``) keyed by all its
inputs (set, record, scale, window, rotation, time factor, parameters, structure, output interval,
solver settings, engine) and ``code`` (the caller's fingerprint of the source and installed
versions), and runs through the sweep's runners (local processes or Dask): a killed set run resumes
where it stopped, and a record's result is computed once. A run that fails (the rod cannot reach,
a state outside the laws' validity, a solver failure) is stored as failed with its reason; the
other records still run. Outputs (written after every job is stored, each file atomically):

    set.csv, set.json                      one row per record (see SET_COLUMNS)
    records/<set>_<id>[_nodevice]/         seismic.csv, summary.json (as ``nsd seismic`` writes them),
                                           seismic_<engine>.csv for peers
"""
from __future__ import annotations

import csv
import hashlib
import io
import json
import re
import shutil
import sys
import time
import traceback
from dataclasses import asdict, dataclass, field
from functools import partial
from pathlib import Path
from typing import Callable

from nsd_core.device.params import ParameterError
from nsd_core.device.results import RunResult, first_nonfinite, read_csv
from nsd_core.common.files import atomic_copy, atomic_write_json, atomic_write_text
from nsd_core.study.store import Store
from nsd_core.study.sweep import run_stored

# how a failed run is classed, and the exit code the set run gives for it (nsd_cli.seismic)
REASONS = {"rod_reach": 4, "outside_validity": 4, "solver_failure": 3, "error": 3}
SET_COLUMNS = [  # name, unit ("" for text)
    ("set", ""), ("id", ""), ("earthquake", ""), ("station", ""), ("magnitude", "-"), ("pulse", ""),
    ("pga", "m/s^2"), ("peak_u", "m"), ("peak_u_nodevice", "m"), ("peak_u_ratio", "-"),
    ("peak_a_abs", "m/s^2"), ("peak_a_abs_nodevice", "m/s^2"), ("peak_a_abs_ratio", "-"),
    ("residual_u", "m"), ("energy_residual", "-"), ("outside_working_range", ""), ("rod_reach_t", "s"),
    ("status", ""), ("reason", ""),
]
BUILDING_COLUMNS = [  # with a building on the slab (docs/building.md): the worst story / floor
    ("peak_drift_ratio", "-"), ("peak_drift_ratio_nodevice", "-"), ("peak_drift_ratio_ratio", "-"),
    ("peak_floor_a_abs", "m/s^2"), ("peak_floor_a_abs_nodevice", "m/s^2"),
]
PEER_COLUMNS = ("du", "dF", "da")  # per peer engine: max|difference| / max over the record (comparisons.seismic)


@dataclass(frozen=True)
class RecordRun:
    """One engine's run of one record of a set, with or without the device."""
    set: str
    record: int
    device: bool
    ground: dict        # fema_record's options: scale, time_factor, window, rotate_deg, normalised
    params: dict        # Params.to_dict()
    structure: dict     # Structure's numbers (mass, radius_of_gyration, stiffness, damping, support_radius)
    duration: float | None
    dt_out: float
    engine: str = "semirecursive"
    settings: dict = field(default_factory=dict)
    code: str = ""      # fingerprint of the code and versions: a kept run is reused by the same code only

    @property
    def key(self) -> str:
        return hashlib.sha256(json.dumps(asdict(self), sort_keys=True).encode()).hexdigest()[:20]

    @property
    def folder(self) -> str:
        return f"{self.set}_{self.record}" + ("" if self.device else "_nodevice")

    @property
    def label(self) -> str:
        return self.folder + ("" if self.engine == "semirecursive" else f"@{self.engine}")


def parse_records(text: str | None, set_: str) -> list[int]:
    """'1,3,5-7' -> [1, 3, 5, 6, 7] within the set's IDs (None: all of them); ParameterError otherwise."""
    from nsd_core.ground.records import SETS, set_name
    ids = SETS[set_name(set_)][1]
    if text is None:
        return list(ids)
    allowed = f"IDs {ids.start}..{ids.stop - 1} of {set_name(set_)}, as a list like 1,3,5-7"
    out: list[int] = []
    for item in text.split(","):
        m = re.fullmatch(r"\s*(\d+)\s*(?:-\s*(\d+)\s*)?", item)
        if not m:
            raise ParameterError(f"--records {text!r}: {item.strip()!r} is not an ID or a range; allowed: {allowed}")
        lo, hi = int(m.group(1)), int(m.group(2) or m.group(1))
        if lo > hi or lo not in ids or hi not in ids:
            raise ParameterError(f"--records {text!r}: {item.strip()} lies outside the set; allowed: {allowed}")
        out.extend(i for i in range(lo, hi + 1) if i not in out)
    return out


def record_runs(set_: str, records: list[int], ground: dict, params: dict, structure: dict,
                duration: float | None, dt_out: float, settings: dict, code: str,
                peers: tuple[str, ...] = ()) -> list[RecordRun]:
    """Per record: the device run, the supports-alone run, and a device run per peer engine.
    Every record's ground motion is built here once, so a window outside a record is bad input
    (ParameterError) before anything runs."""
    from nsd_core.ground.records import fema_record, set_name
    set_ = set_name(set_)
    runs = []
    for rid in records:
        fema_record(set_, rid, **ground)
        common = dict(set=set_, record=rid, ground=ground, params=params, structure=structure, duration=duration,
                      dt_out=dt_out, code=code)
        runs.append(RecordRun(device=True, settings=settings, **common))
        runs.append(RecordRun(device=False, settings=settings, **common))
        runs.extend(RecordRun(device=True, engine=e, **common) for e in peers)
    return runs


def worst_building_peak(summary: dict, key: str) -> float | None:
    """The worst story's or floor's peak ``key`` (peak_drift_ratio, peak_floor_acceleration) in a run's
    summary (None: no building on the slab)."""
    b = summary.get("building")
    if not isinstance(b, dict) or not b.get(key):
        return None
    return max(p["value"] for p in b[key])


def peak_drift_ratio(summary: dict) -> float | None:
    """The worst story's peak drift ratio in a run's summary (None: no building on the slab)."""
    return worst_building_peak(summary, "peak_drift_ratio")


def _failure(err: Exception) -> tuple[str, float | None]:
    """(reason, time) of a failed run: the engine's errors name the time as 't = ... s'."""
    from nsd_core.device.drive import DriveError
    from nsd_core.structure.seismic import RodReachError
    from nsd_core.common.errors import SolverError
    m = re.search(r"t = ([-+0-9.eE]+) s", str(err))
    t = float(m.group(1)) if m else None
    if isinstance(err, RodReachError):
        return "rod_reach", t
    if isinstance(err, DriveError):
        return "outside_validity", t
    if isinstance(err, SolverError):
        return "solver_failure", t
    return "error", t


def run_record(r: RecordRun, run_engine: Callable | None = None, keep_partial: bool = False) -> dict:
    """Run one record on one engine (in a worker); never raises for the run's own failure; keep_partial:
    a stopped run's series up to its stop under "partial" (not stored).

    ``run_engine(name, params, structure, ground, duration=, dt_out=, settings=) -> RunResult`` runs
    a peer engine (comparisons.engines.run_seismic_engine: the study layer knows only the in-house engine)."""
    start = time.perf_counter()
    try:
        from nsd_core.ground.records import fema_record
        from nsd_core.structure.isolation import Structure
        from nsd_core.device.params import Params
        from nsd_core.device.results import versions
        from nsd_core.structure.seismic import seismic_summary, simulate_seismic
        params, structure = Params(**r.params), Structure(**r.structure)
        motion = fema_record(r.set, r.record, **r.ground)
        if r.engine == "semirecursive":
            result = simulate_seismic(params, structure, motion, duration=r.duration, dt_out=r.dt_out,
                                      device=r.device, **r.settings)
        elif run_engine is None:
            raise ParameterError(f"engine {r.engine!r}: this set run was given no runner for other engines")
        else:
            result = run_engine(r.engine, params, structure, motion, duration=r.duration, dt_out=r.dt_out,
                                settings=r.settings or None)
        bad = first_nonfinite(result.columns)
        if bad:
            from nsd_core.common.errors import SolverError
            raise SolverError(f"a non-finite output: {bad}")
        summary = {"ground": motion.describe(), "structure": structure.to_dict(), "device": r.device,
                   **seismic_summary(result), "solver": result.stats, "wall_time": result.stats.get("wall_time"),
                   "versions": versions(), "params": params.describe()}
        return {"status": "ok", "error": None, "metrics": summary, "files": {"seismic.csv": result},
                "wall_time": time.perf_counter() - start}
    except Exception as e:  # noqa: BLE001 - the run failed; record it and let the set go on
        reason, t = _failure(e)
        out = {"status": "failed", "error": f"{type(e).__name__}: {e}".splitlines()[0],
               "metrics": {"reason": reason, "t": t}, "traceback": traceback.format_exc(limit=6),
               "wall_time": time.perf_counter() - start}
        if keep_partial:
            out["partial"] = getattr(e, "partial", None)
        return out


def run_set(runs: list[RecordRun], out: str | Path, workers: int = 1, scheduler=None, retry_failed: bool = False,
            scheduler_timeout: float = 10.0,
            log: Callable[[str], None] | None = None, run_engine: Callable | None = None,
            compare: Callable[[RunResult, RunResult], dict] | None = None, tally: dict | None = None) -> dict:
    """Run every record run not yet stored, store each as it finishes, then write the set's outputs.
    ``compare(reference, peer) -> {du, dF, da, ...}`` measures a peer against the in-house run."""
    log = log or (lambda s: print(s, file=sys.stderr, flush=True))
    store = Store(out)
    store.remove_stale_temps()  # a killed run's half-written files (no worker runs yet)
    startup: dict = {}
    elapsed = run_stored(runs, store, partial(run_record, run_engine=run_engine), workers, scheduler, retry_failed,
                         log, tally, f"seismic set: {len(runs)} runs ({len({(r.set, r.record) for r in runs})} records)",
                         scheduler_timeout, set_warmup(runs, run_engine), startup)
    index = write_set(runs, store, compare)
    index["elapsed_this_run_s"] = elapsed
    index["worker_startup"] = startup or None   # this run's workers: spawn, imports, warm-up (not in set.json)
    return index


def set_warmup(runs: list[RecordRun], run_engine: Callable | None = None):
    """A worker's warm-up for these runs (nsd_core.compilation.worker_warmup.warm_worker): the in-house seismic
    kernels of each solver setting, the record sets' files, and a tiny run of each peer engine."""
    from nsd_core.structure.isolation import default_structure
    from nsd_core.device.params import Params
    from nsd_core.compilation.warmup import TINY_DT_OUT, TINY_DURATION, tiny_ground
    from nsd_core.compilation.worker_warmup import kind, warm_worker
    kinds = sorted({kind("seismic", r.settings) for r in runs if r.engine == "semirecursive"})
    peers = {(r.engine, repr(sorted(r.settings.items()))): (r.engine, r.settings) for r in runs
             if r.engine != "semirecursive" and run_engine is not None}
    calls = [partial(run_engine, e, Params(), default_structure(Params()), tiny_ground(), duration=TINY_DURATION,
                     dt_out=TINY_DT_OUT, settings=s or None) for e, s in peers.values()]
    return partial(warm_worker, tuple(kinds), tuple(sorted({r.set for r in runs})), tuple(calls))


def _copy(src: Path, dest: Path) -> None:
    atomic_copy(src, dest)


def write_set(runs: list[RecordRun], store: Store, compare=None) -> dict:
    """records/<folder>/ per run, set.csv and set.json from what the store holds; returns set.json's
    content. Deterministic: a resumed set run writes the same bytes as an uninterrupted one."""
    root = store.root
    by_record: dict[tuple[str, int], dict[str, RecordRun]] = {}
    for r in runs:
        by_record.setdefault((r.set, r.record), {})["nodevice" if not r.device else r.engine] = r
    rows, entries = [], []
    peers = sorted({r.engine for r in runs if r.engine != "semirecursive"})
    for (set_, rid), group in by_record.items():
        recs = {name: store.load(r.key) for name, r in group.items()}
        for name, r in group.items():  # the per-record folders, as nsd seismic writes them
            rec = recs[name]
            if rec is None or r.engine != "semirecursive":
                continue
            folder = root / "records" / r.folder
            summary = dict(rec["metrics"])
            if rec["status"] == "ok":
                _copy(store.folder(r.key) / "seismic.csv", folder / "seismic.csv")
                for peer in peers if r.device else ():
                    prec = recs.get(peer)
                    if prec and prec["status"] == "ok":
                        _copy(store.folder(group[peer].key) / "seismic.csv", folder / f"seismic_{peer}.csv")
                        if compare is not None:
                            summary.setdefault("engines", {})[peer] = {
                                **compare(read_csv(folder / "seismic.csv"), read_csv(folder / f"seismic_{peer}.csv")),
                                "wall_time": prec["metrics"].get("wall_time")}
                    elif prec:
                        summary.setdefault("engines", {})[peer] = {"status": "failed", "error": prec["error"]}
                from nsd_core.structure.seismic_warnings import apply_warnings
                apply_warnings(summary)   # as nsd seismic's summary.json has them
            else:
                summary = {"status": "failed", "error": rec["error"], **rec["metrics"]}
            atomic_write_json(folder / "summary.json", summary)
            recs[name] = {**rec, "summary": summary}
        row, entry = _row(set_, rid, group, recs, peers)
        rows.append(row)
        entries.append(entry)
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    columns = SET_COLUMNS + (BUILDING_COLUMNS if any(k in row for row in rows for k, _ in BUILDING_COLUMNS) else [])
    w.writerow([f"{n} [{u}]" if u else n for n, u in columns]
               + [f"{p}_{c} [-]" for p in peers for c in PEER_COLUMNS])
    for row in rows:
        w.writerow([_cell(row.get(n)) for n, _ in columns] + [_cell(row.get(f"{p}_{c}")) for p in peers
                                                              for c in PEER_COLUMNS])
    atomic_write_text(root / "set.csv", text.getvalue())
    first = runs[0] if runs else None
    counts = {s: sum(row["status"] == s for row in rows) for s in ["ok", "missing", *REASONS]}
    index = {"set": first.set if first else None, "records": [row["id"] for row in rows],
             "ground": first.ground if first else None, "structure": first.structure if first else None,
             "engines": ["semirecursive", *peers], "columns": dict(SET_COLUMNS), "counts": counts,
             "rows": rows, "entries": entries, "code": first.code if first else None,
             "notes": "peak_*_ratio = with the device / supports alone; energy_residual = the largest "
                      "|E_residual| / max|E_input| of the record's in-house runs; rod_reach_t: model time at "
                      "which |u| reached the rod's length (that run stopped)"}
    atomic_write_json(root / "set.json", index)
    return index


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.10g}"
    return str(v)


def _row(set_: str, rid: int, group: dict, recs: dict, peers: list[str]) -> tuple[dict, dict]:
    """One row of set.csv and the record's entry in set.json (folders, statuses, errors)."""
    from nsd_core.ground.records import record_metadata
    meta = record_metadata(set_, rid)
    row = {"set": set_, "id": rid, "earthquake": f"{meta.get('EarthquakeName', '')} ({meta.get('EarthquakeYear', '')})",
           "station": meta.get("RecordingStationName", ""), "magnitude": float(meta.get("EarthquakeMagnitude")),
           "pulse": "yes" if meta.get("pulse") else "no"}
    entry = {"set": set_, "id": rid, "runs": {}}
    worst, reasons = "ok", []
    for name, rec in recs.items():
        entry["runs"][name] = {"key": group[name].key, "status": rec["status"] if rec else "missing",
                               "folder": f"records/{group[name].folder}" if group[name].engine == "semirecursive"
                               else f"designs/{group[name].key}"}
        if rec is None:
            worst = worst if worst in REASONS else "missing"
            reasons.append(f"{name}: not run")
        elif rec["status"] != "ok":
            reason = rec["metrics"].get("reason", "error")
            if worst in ("ok", "missing") or REASONS[reason] < REASONS.get(worst, 0):
                worst = reason  # a solver failure (3) outranks a rod reach (4): the set is incomplete
            reasons.append(f"{'device' if name == 'semirecursive' else name}: {rec['error']}")
            entry["runs"][name]["error"] = rec["error"]
            if reason == "rod_reach" and name == "semirecursive":
                row["rod_reach_t"] = rec["metrics"].get("t")
    dev, nod = (recs.get(k) for k in ("semirecursive", "nodevice"))
    s_dev = dev["summary"] if dev and dev["status"] == "ok" else None
    s_nod = nod["summary"] if nod and nod["status"] == "ok" else None
    for s in (s_dev, s_nod):
        if s is not None:
            row["pga"] = s["peak_ground_acceleration"]["value"]
    if s_dev:
        row.update(peak_u=s_dev["peak_displacement"]["value"], peak_a_abs=s_dev["peak_absolute_acceleration"]["value"],
                   residual_u=s_dev["residual_displacement"]["u"],
                   outside_working_range="yes" if s_dev["outside_working_range"] else "no")
        for p in peers:
            m = s_dev.get("engines", {}).get(p, {})
            for c in PEER_COLUMNS:
                row[f"{p}_{c}"] = m.get(c)
    if s_nod:
        row.update(peak_u_nodevice=s_nod["peak_displacement"]["value"],
                   peak_a_abs_nodevice=s_nod["peak_absolute_acceleration"]["value"])
    if s_dev and s_nod:
        row["peak_u_ratio"] = row["peak_u"] / max(row["peak_u_nodevice"], 1e-300)
        row["peak_a_abs_ratio"] = row["peak_a_abs"] / max(row["peak_a_abs_nodevice"], 1e-300)
    for s, suffix in ((s_dev, ""), (s_nod, "_nodevice")):  # a building on the slab (docs/building.md)
        if s and isinstance(s.get("building"), dict):
            row["peak_drift_ratio" + suffix] = peak_drift_ratio(s)
            row["peak_floor_a_abs" + suffix] = worst_building_peak(s, "peak_floor_acceleration")
    if "peak_drift_ratio" in row and "peak_drift_ratio_nodevice" in row:
        row["peak_drift_ratio_ratio"] = row["peak_drift_ratio"] / max(row["peak_drift_ratio_nodevice"], 1e-300)
    residuals = [s["energy"]["relative_residual"] for s in (s_dev, s_nod) if s]
    row["energy_residual"] = max(residuals) if residuals else None
    if s_dev and s_dev["outside_working_range"]:  # complete, but not in the device's working range
        rod = {p["name"]: p["value"] for p in s_dev.get("params") or []}.get("rod_length")
        reasons.append(f"device: outside the working range (the ropes went slack; peak |u| "
                       f"{s_dev['peak_displacement']['value'] * 1e3:.3g} mm"
                       + (f" of the {rod * 1e3:.3g} mm rod)" if rod else ")"))
    from nsd_core.structure.seismic_warnings import run_warnings  # set.json: the runs' warnings (one home of the rules)
    rod = {p["name"]: p["value"] for p in (s_dev or s_nod or {}).get("params") or []}.get("rod_length")
    if dev and dev["status"] != "ok" and (dev["metrics"] or {}).get("reason") in ("rod_reach", "outside_validity"):
        stop = {"kind": dev["metrics"]["reason"], "t": dev["metrics"].get("t", float("nan"))}
        entry.setdefault("warnings", []).extend(f"device: {w['text']}" for w in run_warnings({"stopped": stop}))
    for s, name in ((s_dev, "device"), (s_nod, "nodevice")):
        if s:
            entry.setdefault("warnings", []).extend(f"{name}: {w['text']}"
                                                    for w in run_warnings({**s, "device": name == "device"}, rod))
    if not entry.get("warnings"):
        entry.pop("warnings", None)
    row["status"], row["reason"] = worst, "; ".join(reasons)
    return row, entry
