"""A record set's per-record time on warm pool workers against a single warm run (docs/performance.md).

    python benchmarks/bench_record_set.py --repeats 3 --out DIR      (farfield records 1-4, window 0-3 s)
    python benchmarks/bench_record_set.py --short --out DIR          (records 1-2, window 0-2 s, 1 repeat)

The runs are those of ``nsd seismic --record-set SET --records ... --window T0,T1`` (each record with
and without the device, the in-house engine at its defaults), made by the same functions
(``nsd_core.study.seismic_set``). Per repeat, interleaved:

- single: each run alone in this process, warm (every run ran once before the first repeat), timed as
  the set times its runs (``run_record``'s wall seconds: reading the record, the integration, the
  summary);
- set: ``run_set`` on ``--workers`` pool workers into a fresh folder; each run's own wall seconds as its
  worker measured them (what the set's log prints per run), the set's elapsed seconds, and its workers'
  start-up (spawn and imports, and the warm-up before the first job), reported apart.

The ratio set / single per record (its runs summed, median over the repeats) is the aim's measure:
within 1.5 with 2 workers. Solver CPU seconds (``stats.cpu_time``) are kept beside the wall seconds.
"""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from nsd_core.structure.isolation import default_structure  # noqa: E402
from nsd_core.device.params import Params  # noqa: E402
from nsd_core.device.results import versions
from nsd_core.common.files import atomic_write_json  # noqa: E402
from nsd_core.study.seismic_set import parse_records, record_runs, run_record, run_set  # noqa: E402
from nsd_core.study.store import Store  # noqa: E402

AIM = 1.5


def sched_autogroup() -> bool | None:
    """Whether the Linux scheduler shares CPU time per session (then, on a loaded machine, the set's
    two workers share what this one command gets, and their wall seconds stretch; their CPU do not)."""
    try:
        return Path("/proc/sys/kernel/sched_autogroup_enabled").read_text().strip() == "1"
    except OSError:
        return None


def _runs(set_: str, records: str, window: tuple[float, float]):
    p = Params()
    return record_runs(set_, parse_records(records, set_), {"window": list(window)}, p.to_dict(),
                       default_structure(p).to_dict(), None, 1e-3, {}, "bench_record_set")


def _single(runs) -> dict[str, tuple[float, float]]:
    out = {}
    for r in runs:
        res = run_record(r)
        if res["status"] != "ok":
            raise SystemExit(f"{r.label}: {res['error']}")
        out[r.label] = (res["wall_time"], res["metrics"]["solver"]["cpu_time"])
    return out


def _set(runs, workers: int, tmp: Path) -> tuple[dict, dict]:
    index = run_set(runs, tmp, workers=workers, log=lambda s: None)
    store = Store(tmp)
    out = {}
    for r in runs:
        rec = store.load(r.key)
        if rec is None or rec["status"] != "ok":
            raise SystemExit(f"{r.label}: {rec and rec['error']}")
        out[r.label] = (rec["wall_time"], rec["metrics"]["solver"]["cpu_time"])
    return out, {"elapsed_s": index["elapsed_this_run_s"], "worker_startup": index["worker_startup"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="folder for bench_record_set.json")
    ap.add_argument("--set", default="farfield", help="FEMA P695 record set (default farfield)")
    ap.add_argument("--records", default=None, help="records, as nsd seismic --records (default 1-4; --short 1-2)")
    ap.add_argument("--window", default=None, help="T0,T1 record seconds (default 0,3; --short 0,2)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=None, help="default 3 (--short 1)")
    ap.add_argument("--short", action="store_true", help="two records, a 2 s window, one repeat")
    a = ap.parse_args(argv)
    repeats = a.repeats if a.repeats is not None else (1 if a.short else 3)
    records = a.records or ("1-2" if a.short else "1-4")
    window = tuple(float(x) for x in (a.window or ("0,2" if a.short else "0,3")).split(","))
    if repeats < 1 or a.workers < 2:
        print(f"--repeats = {repeats}, --workers = {a.workers}: need >= 1 and >= 2", file=sys.stderr)
        return 2
    runs = _runs(a.set, records, window)
    load0 = os.getloadavg()
    _single(runs)   # warm: this process's kernels and record files
    singles, sets, set_runs = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for rep in range(repeats):
            singles.append(_single(runs))
            per_run, info = _set(runs, a.workers, Path(tmp) / f"set{rep}")
            set_runs.append(per_run)
            sets.append(info)
            print(f"repeat {rep + 1}: set elapsed {info['elapsed_s']:.2f} s, start-up "
                  f"{(info['worker_startup'] or {}).get('ready_s', float('nan')):.2f} s", flush=True)
    by_record: dict[str, list[str]] = {}
    for r in runs:
        by_record.setdefault(f"{r.set}:{r.record}", []).append(r.label)
    rows = []
    for rec, labels in by_record.items():
        single = statistics.median(sum(s[lb][0] for lb in labels) for s in singles)
        in_set = statistics.median(sum(s[lb][0] for lb in labels) for s in set_runs)
        rows.append({"record": rec, "runs": labels, "single_wall_s": single, "set_wall_s": in_set,
                     "ratio_set_over_single": in_set / single,
                     "single_cpu_s": statistics.median(sum(s[lb][1] for lb in labels) for s in singles),
                     "set_cpu_s": statistics.median(sum(s[lb][1] for lb in labels) for s in set_runs),
                     "set_wall_s_each_repeat": [sum(s[lb][0] for lb in labels) for s in set_runs],
                     "single_wall_s_each_repeat": [sum(s[lb][0] for lb in labels) for s in singles]})
    worst = max(r["ratio_set_over_single"] for r in rows)
    report = {"set": a.set, "records": records, "window_record_s": list(window), "workers": a.workers,
              "repeats": repeats, "aim_ratio": AIM, "worst_ratio": worst, "met": worst <= AIM,
              "median_ratio": statistics.median(r["ratio_set_over_single"] for r in rows),
              "rows": rows, "set_runs": sets,
              "set_elapsed_s_median": statistics.median(s["elapsed_s"] for s in sets),
              "startup_ready_s_median": statistics.median((s["worker_startup"] or {}).get("ready_s", float("nan"))
                                                          for s in sets),
              "startup_warm_s_median": statistics.median((s["worker_startup"] or {}).get("warm_s", float("nan"))
                                                         for s in sets),
              "median_cpu_ratio": statistics.median(r["set_cpu_s"] / r["single_cpu_s"] for r in rows),
              "sched_autogroup": sched_autogroup(),
              "machine": platform.platform(), "cpus": os.cpu_count(), "load_average_start": load0,
              "load_average_end": os.getloadavg(), "versions": versions(),
              "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime())}
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "bench_record_set.json", report)
    for r in rows:
        print(f"{r['record']}: single {r['single_wall_s']:.3f} s, in the set {r['set_wall_s']:.3f} s, "
              f"ratio {r['ratio_set_over_single']:.2f}")
    print(f"worst ratio {worst:.2f} (aim <= {AIM}); wrote {out / 'bench_record_set.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
