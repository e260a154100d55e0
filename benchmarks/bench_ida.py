"""Wall and CPU seconds of an incremental dynamic analysis over the 14 near-field pulse records, with
and without the device, on 2 local workers (docs/performance.md):

    python benchmarks/bench_ida.py [--limit stroke=0.025] [--workers 2] [--records 1-14]
                                   [--out benchmarks/results/bench_ida.json]

runs ``nsd ida --record-set nearfield-pulse --records 1-14 --limit stroke=0.025 --engines semirecursive
--workers 2 --out <fresh temporary folder>`` (the default hunt and fill; the cross-check engines left
out: this times the IDA itself) in a child process after a warm-up child that loads the compiled
engine from numba's cache, so no compilation is in the number. Recorded beside the wall seconds:
the CPU seconds of the command and its workers (user + system, from the children's rusage), the load
average before and after (on a machine shared with other work the wall time is a loaded number: say
so when quoting it), the runs, the model seconds they simulated and the sum of their own wall times.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # benchmarks.measure, when run as a script
WARM = ("from nsd_core.structure.seismic import simulate_seismic; from nsd_core.ground.motions import Harmonic; "
        "from nsd_core.structure.isolation import default_structure; from nsd_core.device.params import Params; "
        "[simulate_seismic(Params(), default_structure(), Harmonic(0.8, 2.0, 30.0, duration=0.05), device=d) "
        "for d in (True, False)]")


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--limit", default="stroke=0.025")
    ap.add_argument("--workers", default="2")
    ap.add_argument("--records", default="1-14")
    ap.add_argument("--record-set", default="nearfield-pulse", help="farfield: its 22 pairs")
    ap.add_argument("--engines", default="semirecursive", help="semirecursive,mujoco,exudyn with --extra "
                    "'--cross-check median': the peers re-run the median record")
    ap.add_argument("--extra", default="", help="more nsd ida options, space-separated")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "bench_ida.json"))
    args = ap.parse_args()
    subprocess.run([sys.executable, "-c", WARM], check=True, cwd=ROOT)  # numba's cache loaded/filled, untimed
    nsd = [sys.executable, "-m", "nsd_cli"]
    with tempfile.TemporaryDirectory(prefix="bench_ida_") as tmp:
        cmd = ["ida", "--record-set", args.record_set, "--records", args.records, "--limit", args.limit,
               "--engines", args.engines, "--workers", args.workers, "--out", tmp] + args.extra.split()
        from benchmarks.measure import _git_commit
        commit = _git_commit()  # the code that runs
        load_before, cpu0 = os.getloadavg(), _children_cpu()
        t0 = time.perf_counter()
        proc = subprocess.run(nsd + cmd, cwd=ROOT, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        cpu, load_after = _children_cpu() - cpu0, os.getloadavg()
        if proc.returncode not in (0, 3):
            sys.exit(f"nsd ida failed ({proc.returncode}): {proc.stderr.strip().splitlines()[-1:]}")
        index = json.loads((Path(tmp) / "ida.json").read_text())
        runs = [json.loads(p.read_text()) for p in Path(tmp).glob("designs/*/result.json")]
    model_s = sum((r["metrics"].get("solver") or {}).get("model_time", 0.0) for r in runs if r["status"] == "ok")
    from nsd_core.device.results import versions
    cpus = os.cpu_count() or 1
    # the schema of benchmarks/measure.py (name, command, measured, data): benchmarks.docs reads it
    report = {
        "name": Path(args.out).stem, "command": "nsd " + " ".join(c if c != cmd[-1] else "DIR" for c in cmd),
        "exit_code": proc.returncode,
        "measured": {"date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()), "machine": platform.platform(),
                     "processor": platform.machine(), "cpus": cpus, "python": platform.python_version(),
                     "load_average_before": [round(x, 2) for x in load_before],
                     "load_average_after": [round(x, 2) for x in load_after],
                     "loaded": max(load_before[0], load_after[0]) > cpus, "wall_s": wall, "cpu_s": cpu,
                     "versions": versions(), "git_commit": commit},
        "data": {
            "runs": len(runs), "runs_ok": sum(r["status"] == "ok" for r in runs),
            "runs_stopped": sum(r["status"] != "ok" for r in runs), "model_seconds_completed_runs": model_s,
            "sum_of_run_wall_s": sum(r["wall_time"] for r in runs),
            "cross_check": index.get("cross_check"), "cross_check_cost": index.get("cross_check_cost"),
            "elapsed_cross_check_s": index.get("elapsed_cross_check_s"),
            "fragility": index["fragility"], "hunt": index["hunt"], "traces": [
                {k: t[k] for k in ("name", "runs", "limit_im", "below_im", "censored_at", "undetermined")}
                for t in index["traces"]],
            "notes": "wall_s: the whole command (worker start-up included, compilation excluded by a warm-up); "
                     "cpu_s: user + system of the command and its workers; model_seconds_completed_runs leaves "
                     "out the runs stopped by the rod's length (their simulated time is not stored)"},
    }
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(report, indent=2) + "\n")
    print(f"{report['data']['runs']} runs in {wall:.1f} s wall, {cpu:.1f} s CPU (load {load_before[0]:.2f} -> "
          f"{load_after[0]:.2f}); wrote {out}")


if __name__ == "__main__":
    main()
