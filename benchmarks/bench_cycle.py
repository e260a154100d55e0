"""Wall time per cycle of the in-house semirecursive model on the four Figure 6 cases.

    python benchmarks/bench_cycle.py [--repeats 3] [--out out/bench]

Runs each case for 2 cycles (the default drive) ``repeats`` times after one warm-up (numba's
compilation is cached on disk, so the warm-up measures a steady process), and reports the median
wall time per cycle, steps and right-hand-side evaluations. Single process, one core.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from pathlib import Path

from nsd_core.device.model import simulate
from nsd_core.device.drive import Drive
from nsd_core.device.params import Params

CASES = [(0.015, 1.0), (0.015, 10.0), (0.0255, 1.0), (0.0255, 10.0)]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default="out/bench")
    args = ap.parse_args()
    p = Params()
    simulate(p, Drive(0.015, 10.0, cycles=1, samples_per_cycle=100))  # warm-up: load compiled kernels
    rows = []
    for A, f in CASES:
        times, stats = [], None
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            r = simulate(p, Drive(A, f, cycles=2, samples_per_cycle=2000))
            times.append((time.perf_counter() - t0) / 2)
            stats = r.stats
        row = {"amplitude": A, "frequency": f, "median_s_per_cycle": statistics.median(times),
               "min_s_per_cycle": min(times), "steps": stats["steps"], "nfev": stats["nfev"],
               "method": stats["method"], "rtol": stats["rtol"]}
        rows.append(row)
        print(f"A = {A} m, f = {f:4.1f} Hz: median {row['median_s_per_cycle']:.2f} s/cycle "
              f"(min {row['min_s_per_cycle']:.2f}), {row['steps']} steps, {row['nfev']} rhs evaluations / 2 cycles")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "bench_cycle.json").write_text(json.dumps({"machine": platform.platform(), "cpus": os.cpu_count(),
                                                      "load_average": os.getloadavg(), "cases": rows}, indent=2))


if __name__ == "__main__":
    main()
