"""Wall and CPU seconds per model second of the in-house seismic mode, and its compile time.

    python benchmarks/bench_seismic.py [--repeats 3] [--scipy] [--no-compile] [--out out/bench]

- cases: a FEMA P695 record window (nearfield-pulse:1, record seconds 10-13, the pulse) and a whole
  record (nearfield-pulse:1, full length, scaled by WHOLE_SCALE so the plate stays within the rod's
  reach), at the default solver settings (DOP853, rtol 1e-7, max_step 1e-3, outputs every 1 ms),
  ``repeats`` times after a warm-up, interleaved; median. ``--scipy`` adds the scipy-driven path on
  the window (the reference the compiled one replaced).
- compile: a fresh process with an empty numba cache (NUMBA_CACHE_DIR) runs a short seismic window;
  a second fresh process on that now-warm cache runs it again. Their difference is compilation.
Single-machine numbers: quote them with the machine's load (recorded in the JSON).
"""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from compile_time import compile_times  # noqa: E402

from nsd_core.engine.codegen import prefer_generated
from nsd_core.ground.records import fema_record
from nsd_core.structure.isolation import default_structure
from nsd_core.device.params import Params
from nsd_core.common.files import atomic_write_json
from nsd_core.structure.seismic import seismic_summary, simulate_seismic

WHOLE_SCALE = 0.2  # 0.3 reaches the rod (|u| = l_d at 2.78 s): exit 4
CASES = {"window nearfield-pulse:1 [10, 13] s": dict(window=(10.0, 13.0)),
         f"whole record nearfield-pulse:1, scale {WHOLE_SCALE}": dict(scale=WHOLE_SCALE)}
FIRST_RUN = ("import time; t0 = time.perf_counter(); from nsd_core.structure.seismic import simulate_seismic; "
             "from nsd_core.ground.motions import Harmonic; from nsd_core.structure.isolation import default_structure; "
             "from nsd_core.device.params import Params; "
             "simulate_seismic(Params(), default_structure(), Harmonic(0.8, 2.0, 30.0, duration=0.05)); "
             "print(time.perf_counter() - t0)")


def main() -> None:
    # the in-house engine as the studies run it (the generated evaluation); here, not at import, so that
    # importing this module (a test does) leaves the environment alone
    prefer_generated()
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--scipy", action="store_true", help="also time the scipy-driven path on the window")
    ap.add_argument("--no-compile", action="store_true", help="skip the cold-cache compile measurement")
    ap.add_argument("--out", default="out/bench")
    args = ap.parse_args()
    report = {"machine": platform.platform(), "cpus": os.cpu_count(), "load_average_start": os.getloadavg()}
    if not args.no_compile:
        report["compile"] = compile_times(FIRST_RUN)
        print("compile [s]: " + ", ".join(f"{k} {v:.1f}" for k, v in report["compile"].items()))
    p, s = Params(), default_structure()
    runs = {name: fema_record("nearfield-pulse", 1, **kw) for name, kw in CASES.items()}
    backends = {name: "auto" for name in runs}
    if args.scipy:
        name = next(iter(CASES))
        runs[name + " (scipy path)"] = runs[name]
        backends[name + " (scipy path)"] = "scipy"
    simulate_seismic(p, s, runs[next(iter(runs))], duration=0.05)  # warm-up: load compiled code
    wall = {k: [] for k in runs}
    cpu = {k: [] for k in runs}
    last = {}
    for _ in range(max(1, args.repeats)):
        for name, gm in runs.items():  # interleaved, so load changes hit every case alike
            t0, c0 = time.perf_counter(), time.process_time()
            last[name] = simulate_seismic(p, s, gm, backend=backends[name])
            wall[name].append(time.perf_counter() - t0)
            cpu[name].append(time.process_time() - c0)
    rows = []
    for name, r in last.items():
        T = r.stats["model_time"]
        summ = seismic_summary(r)
        row = {"case": name, "backend": r.stats["backend"], "model_s": T, "runs": len(wall[name]),
               "median_wall_s": statistics.median(wall[name]), "median_cpu_s": statistics.median(cpu[name]),
               "wall_s_per_model_s": statistics.median(wall[name]) / T,
               "cpu_s_per_model_s": statistics.median(cpu[name]) / T, "steps": r.stats["steps"],
               "nfev": r.stats["nfev"], "peak_u_m": summ["peak_displacement"]["value"],
               "energy_relative_residual": summ["energy"]["relative_residual"],
               "outside_working_range": summ["outside_working_range"]}
        rows.append(row)
        print(f"{name}: {T:.2f} model s, median {row['median_wall_s']:.2f} s wall, {row['median_cpu_s']:.2f} s CPU: "
              f"{row['wall_s_per_model_s']:.3f} wall s / model s, {row['cpu_s_per_model_s']:.3f} CPU s / model s; "
              f"{row['steps']} steps, {row['nfev']} rhs, peak |u| {1e3 * row['peak_u_m']:.2f} mm, "
              f"energy residual {row['energy_relative_residual']:.1e}")
    report["cases"] = rows
    report["load_average_end"] = os.getloadavg()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "bench_seismic.json", report)


if __name__ == "__main__":
    main()
