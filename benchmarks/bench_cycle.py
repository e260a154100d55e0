"""Wall time per cycle of the in-house model, its compile time, accuracy, and the paper-sweep time.

    python benchmarks/bench_cycle.py [--repeats 3] [--sweep] [--out out/bench]

- compile: a fresh process with an empty numba cache (NUMBA_CACHE_DIR) runs one short drive; a
  second fresh process on that now-warm cache runs it again. Their difference is compilation.
- per cycle: each Figure 6 case (2 cycles, 2000 samples per cycle, as ``nsd compare``) at the
  default solver settings, ``repeats`` times after a warm-up, interleaved across cases; median.
- accuracy: max|dF| / max|F| on the last cycle against the same model at rtol 1e-10
  (benchmarks/refcompare.py), the harness's measure.
- ``--sweep``: ``nsd sweep --paper`` (41 designs, all local cores) in a fresh process, warm cache.
- ``--paths``: the default cases off the line (circle, figure eight), compiled backend against the
  scipy-driven one at the same settings, interleaved; CPU per cycle and their agreement.
Single-machine numbers: quote them with the machine's load (recorded in the JSON).
"""
from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from compile_time import compile_times  # noqa: E402
from refcompare import discrepancy, in_house_reference  # noqa: E402

import numpy as np  # noqa: E402

from nsd_core.engine.codegen import prefer_generated  # noqa: E402
from nsd_core.device.drive import Drive  # noqa: E402
from nsd_core.device.model import DEFAULT_SOLVER, simulate  # noqa: E402
from nsd_core.device.params import Params
from nsd_core.common.files import atomic_write_json  # noqa: E402

CASES = [(0.015, 1.0), (0.015, 10.0), (0.0255, 1.0), (0.0255, 10.0)]
PATH_CASES = [dict(amplitude=0.015, frequency=10.0, path="circle"), dict(amplitude=0.022, frequency=10.0, path="circle"),
              dict(amplitude=0.015, frequency=10.0, path="figure8", minor=0.0075)]  # comparisons/cases.toml
FIRST_RUN = ("import time; t0 = time.perf_counter(); from nsd_core.device.model import simulate; "
             "from nsd_core.device.drive import Drive; from nsd_core.device.params import Params; "
             "simulate(Params(), Drive(0.015, 10.0, cycles=1, samples_per_cycle=100)); "
             "print(time.perf_counter() - t0)")


def sweep_time(workers: int) -> tuple[float, float]:
    """(wall, CPU of all its processes) seconds of ``nsd sweep --paper`` in a fresh process."""
    nsd = Path(sys.executable).with_name("nsd")
    with tempfile.TemporaryDirectory() as out:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run([str(nsd), "sweep", "--paper", "--workers", str(workers), "--out", out], check=True,
                       capture_output=True)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        return wall, (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)


def path_times(repeats: int) -> list[dict]:
    """Compiled against scipy-driven backend on the paths off the line (CPU s per cycle, median)."""
    p, rows = Params(), []
    drives = [Drive(**c, cycles=2, samples_per_cycle=2000) for c in PATH_CASES]
    cpu = {(i, b): [] for i in range(len(drives)) for b in ("compiled", "scipy")}
    last = {}
    for _ in range(repeats):
        for i, d in enumerate(drives):
            for b in ("compiled", "scipy"):
                c0 = time.process_time()
                last[i, b] = simulate(p, d, backend=b)
                cpu[i, b].append((time.process_time() - c0) / d.cycles)
    for i, (c, d) in enumerate(zip(PATH_CASES, drives)):
        a, b = last[i, "compiled"], last[i, "scipy"]
        scale = max(np.max(np.abs(b["F_x"])), np.max(np.abs(b["F_y"])))
        diff = max(np.max(np.abs(a["F_x"] - b["F_x"])), np.max(np.abs(a["F_y"] - b["F_y"]))) / scale
        row = {**c, "compiled_cpu_s_per_cycle": statistics.median(cpu[i, "compiled"]),
               "scipy_cpu_s_per_cycle": statistics.median(cpu[i, "scipy"]), "dF_compiled_vs_scipy": float(diff)}
        rows.append(row)
        print(f"{c['path']} A = {c['amplitude']} m, f = {c['frequency']} Hz: compiled "
              f"{1e3 * row['compiled_cpu_s_per_cycle']:.1f} ms/cycle CPU, scipy {1e3 * row['scipy_cpu_s_per_cycle']:.1f}"
              f" ms/cycle CPU, max|dF| compiled vs scipy / max|F| = {diff:.2g}")
    return rows


def main() -> None:
    # the in-house engine as the studies run it (the generated evaluation); here, not at import, so that
    # importing this module (a test does) leaves the environment alone
    prefer_generated()
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--sweep", action="store_true", help="also time nsd sweep --paper (warm cache)")
    ap.add_argument("--paths", action="store_true", help="also the paths off the line: compiled vs scipy backend")
    ap.add_argument("--no-compile", action="store_true", help="skip the cold-cache compile measurement")
    ap.add_argument("--out", default="out/bench")
    args = ap.parse_args()
    report = {"machine": platform.platform(), "cpus": os.cpu_count(), "load_average_start": os.getloadavg(),
              "solver": DEFAULT_SOLVER}
    if not args.no_compile:
        report["compile"] = compile_times(FIRST_RUN)
        print("compile [s]: " + ", ".join(f"{k} {v:.1f}" for k, v in report["compile"].items()))
    p = Params()
    simulate(p, Drive(0.015, 10.0, cycles=1, samples_per_cycle=100))  # warm-up: load compiled code
    drives = [Drive(A, f, cycles=2, samples_per_cycle=2000) for A, f in CASES]
    times = {i: [] for i in range(len(CASES))}
    cpu = {i: [] for i in range(len(CASES))}
    results = {}
    for _ in range(max(3, args.repeats)):
        for i, d in enumerate(drives):  # interleaved, so load changes hit every case alike
            t0, c0 = time.perf_counter(), time.process_time()
            results[i] = simulate(p, d)
            times[i].append((time.perf_counter() - t0) / d.cycles)
            cpu[i].append((time.process_time() - c0) / d.cycles)
    rows = []
    for i, ((A, f), d) in enumerate(zip(CASES, drives)):
        ref, _ = in_house_reference(p, d)
        acc = discrepancy(results[i], ref, d)
        st = results[i].stats
        row = {"amplitude": A, "frequency": f, "median_s_per_cycle": statistics.median(times[i]),
               "min_s_per_cycle": min(times[i]), "median_cpu_s_per_cycle": statistics.median(cpu[i]),
               "runs": len(times[i]), "steps": st["steps"], "nfev": st["nfev"], "evaluation": st.get("evaluation"),
               "dF": acc["dF"], "dA": acc["dA"]}
        rows.append(row)
        print(f"A = {A} m, f = {f:4.1f} Hz: median {1e3 * row['median_s_per_cycle']:.1f} ms/cycle wall "
              f"(min {1e3 * row['min_s_per_cycle']:.1f}), {1e3 * row['median_cpu_s_per_cycle']:.1f} ms/cycle CPU, "
              f"{st['steps']} steps, {st['nfev']} rhs / 2 cycles, "
              f"dF = {acc['dF']:.2g}")
    report["cases"] = rows
    if args.sweep:
        report["sweep_paper_s"], report["sweep_paper_cpu_s"] = sweep_time(os.cpu_count() or 1)
        print(f"nsd sweep --paper: {report['sweep_paper_s']:.1f} s wall, {report['sweep_paper_cpu_s']:.1f} s CPU "
              f"in all processes, on {os.cpu_count()} cores (warm cache)")
    if args.paths:
        report["paths"] = path_times(max(3, args.repeats))
    report["load_average_end"] = os.getloadavg()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "bench_cycle.json", report)


if __name__ == "__main__":
    main()
