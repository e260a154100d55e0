"""A record set's IDA on a Dask cluster of local worker processes: the parallel efficiency from 1 to 2
workers and the scheduler's overhead per task, beside the local pool (docs/performance.md):

    python benchmarks/bench_dask.py [--records 1-6] [--workers 1,2] [--tasks 400] [--out FILE]

For each worker count k a ``distributed.LocalCluster`` of k worker processes (one thread each) is
started in this process and warmed (each worker imports the in-house engine and loads its compiled
kernels from numba's cache with a tiny seismic run, untimed). Then, in a child process,

    nsd ida --record-set farfield --records R --limit stroke=0.025 --engines semirecursive --scheduler ADDR

(the default hunt and fill, with and without the device; no cross-check: this times the set), and the
same command on ``--workers 2`` local processes (the pool, for comparison). Recorded per run: the
IDA's own elapsed seconds (``elapsed_this_run_s`` of ida.json: from the first job submitted to the last
result stored), the command's wall and CPU seconds, the runs and the sum of their own wall seconds.
Efficiency from 1 to k workers: T1 / (k Tk) on the IDA's elapsed seconds. The overhead per task: ``tasks``
empty tasks (a function that returns its argument) mapped onto the cluster and gathered, wall seconds
over ``tasks``: what the scheduler, the client and the transport cost a task, without the task.

On a machine with 2 CPUs only 1 and 2 workers can be measured honestly (4 worker processes would share
2 cores); the 2-to-4 aim needs a machine with 4 cores: run ``--workers 1,2,4`` there.
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


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _warm_worker() -> str:
    """On each Dask worker, untimed: the engine imported, its kernels loaded (a tiny seismic run)."""
    from nsd_core.ground.motions import Harmonic
    from nsd_core.structure.isolation import default_structure
    from nsd_core.device.params import Params
    from nsd_core.structure.seismic import simulate_seismic
    for device in (True, False):
        simulate_seismic(Params(), default_structure(), Harmonic(0.8, 2.0, 30.0, duration=0.05), device=device)
    return "warm"


def _identity(x):
    return x


def ida(records: str, extra: list[str]) -> dict:
    """``nsd ida`` over the far-field records in a child process: its own numbers and the command's."""
    with tempfile.TemporaryDirectory(prefix="bench_dask_") as tmp:
        cmd = [sys.executable, "-m", "nsd_cli", "ida", "--record-set", "farfield", "--records", records,
               "--limit", "stroke=0.025", "--engines", "semirecursive", "--out", tmp, *extra]
        load0, cpu0, t0 = os.getloadavg()[0], _children_cpu(), time.perf_counter()
        p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
        wall, cpu = time.perf_counter() - t0, _children_cpu() - cpu0
        if p.returncode not in (0, 3):
            sys.exit(f"nsd ida failed ({p.returncode}): {p.stderr.strip().splitlines()[-1:]}")
        index = json.loads((Path(tmp) / "ida.json").read_text())
        runs = [json.loads(f.read_text()) for f in Path(tmp).glob("designs/*/result.json")]
    return {"ida_elapsed_s": index["elapsed_this_run_s"], "command_wall_s": wall, "command_cpu_s": cpu,
            "runs": len(runs), "sum_of_run_wall_s": sum(r["wall_time"] for r in runs),
            "load_before": round(load0, 2), "load_after": round(os.getloadavg()[0], 2)}


def on_dask(k: int, records: str, tasks: int) -> dict:
    from distributed import Client, LocalCluster
    with LocalCluster(n_workers=k, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        client.run(_warm_worker)
        client.gather(client.map(_identity, range(50), pure=False))   # the transport's own first use, untimed
        t0 = time.perf_counter()
        client.gather(client.map(_identity, range(tasks), pure=False))
        per_task = (time.perf_counter() - t0) / tasks
        row = ida(records, ["--scheduler", cluster.scheduler_address])
    return {"workers": k, "where": "dask", "overhead_per_task_s": per_task, "empty_tasks": tasks, **row}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", default="1-6")
    ap.add_argument("--workers", default="1,2", help="Dask worker counts, comma separated")
    ap.add_argument("--tasks", type=int, default=400, help="empty tasks for the overhead per task")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "bench_dask.json"))
    a = ap.parse_args()
    try:
        counts = [int(x) for x in a.workers.split(",")]
    except ValueError:
        counts = []
    if not counts or min(counts) < 1 or a.tasks < 1:
        print(f"--workers {a.workers} --tasks {a.tasks}: worker counts must be integers >= 1, comma separated, "
              "and tasks >= 1", file=sys.stderr)
        raise SystemExit(2)
    load0 = os.getloadavg()
    from benchmarks.measure import _git_commit
    commit = _git_commit()
    rows = [on_dask(k, a.records, a.tasks) for k in counts]
    rows.append({"workers": 2, "where": "local pool", **ida(a.records, ["--workers", "2"])})
    t1 = next((r["ida_elapsed_s"] for r in rows if r["where"] == "dask" and r["workers"] == 1), None)
    for r in rows:
        if r["where"] == "dask" and t1:
            r["efficiency_from_1"] = t1 / (r["workers"] * r["ida_elapsed_s"])
    from nsd_core.device.results import versions
    from nsd_core.common.files import atomic_write_json
    cpus = os.cpu_count() or 1
    load1 = os.getloadavg()
    report = {
        "name": Path(a.out).stem,
        "command": f"nsd ida --record-set farfield --records {a.records} --limit stroke=0.025 --engines semirecursive "
                   f"--scheduler ADDR (LocalCluster of {a.workers} worker processes) and --workers 2",
        "exit_code": 0,
        "measured": {"date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()), "machine": platform.platform(),
                     "processor": platform.machine(), "cpus": cpus, "python": platform.python_version(),
                     "load_average_before": [round(x, 2) for x in load0],
                     "load_average_after": [round(x, 2) for x in load1],
                     "loaded": max(load0[0], load1[0]) > cpus, "versions": versions(), "git_commit": commit,
                     "wall_s": sum(r["command_wall_s"] for r in rows)},
        "data": {"records": a.records, "rows": rows,
                 "notes": "ida_elapsed_s: from the first job submitted to the last result stored (the Dask "
                          "workers warmed before, untimed; the local pool's start-up is inside its number); "
                          "efficiency_from_1 = T1 / (k Tk); overhead_per_task_s: empty tasks mapped and gathered"}}
    atomic_write_json(Path(a.out), report)
    for r in rows:
        eff = f", efficiency {r['efficiency_from_1']:.2f}" if "efficiency_from_1" in r else ""
        over = f", {r['overhead_per_task_s'] * 1e3:.2f} ms per empty task" if "overhead_per_task_s" in r else ""
        print(f"{r['where']} x{r['workers']}: {r['runs']} runs, IDA {r['ida_elapsed_s']:.1f} s{eff}{over}")
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
