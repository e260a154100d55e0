"""The device in drive mode (1 Hz, A = 15 mm, 2 cycles, h = 1e-5 s) side by side in one process: (a) the
hand-written MuJoCo adapter (comparisons.engines.mujoco_engine: numba C callback and native loop) and
(b) the MuJoCo description builder (comparisons.builders.mujoco) on models/nsd_drive.toml with its
compiled path (generated callback, native loop), Euler (the adapter's integrator) and RK4 (the
builder's default). Wall time of the stepping only (each engine's stats["wall_time"]: compilation,
cache loading and the model build happen before its clock starts; one warm-up run of each first),
median of ``--repeats`` runs, interleaved so that a change of machine load hits every engine alike;
the load average is recorded beside each run. F_x of each builder run against the adapter's, relative
to the adapter's peak |F_x|.

    python -m benchmarks.bench_model_builders --out benchmarks/results/bench_model_builders.json
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
AMPLITUDE, FREQUENCY, CYCLES, SAMPLES, STEP = 0.015, 1.0, 2, 500, 1e-5


def adapter(cycles: int = CYCLES):
    from comparisons.engines.mujoco_engine import MujocoEngine
    from nsd_core.device.drive import Drive
    from nsd_core.device.params import Params
    drive = Drive(amplitude=AMPLITUDE, frequency=FREQUENCY, cycles=cycles, samples_per_cycle=SAMPLES)
    r = MujocoEngine().run(Params(), drive, {"timestep": STEP})
    return r["t"], r["F_x"], r.stats["wall_time"]


def builder(integrator: str, passive: str = "compiled", cycles: int = CYCLES):
    from comparisons.builders import mujoco as mj_builder
    from nsd_core.model.load import load_model
    model = load_model(ROOT / "models" / "nsd_drive.toml")
    run = mj_builder.simulate(model, cycles / FREQUENCY, 1.0 / (FREQUENCY * SAMPLES),
                              {"timestep": STEP, "integrator": integrator, "passive": passive})
    return run.t, run.outputs["F_x"], run.stats["wall_time"]


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="JSON file to write")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    cases = {"a_adapter": lambda: adapter(), "b_builder_euler": lambda: builder("Euler"),
             "b_builder_rk4": lambda: builder("RK4")}
    for f in (lambda: adapter(1), lambda: builder("Euler", cycles=1), lambda: builder("RK4", cycles=1)):
        f()   # warm-up: compile or load every kernel before anything is timed
    walls = {k: [] for k in cases}
    loads = {k: [] for k in cases}
    last = {}
    for _ in range(args.repeats):
        for k, f in cases.items():
            before = os.getloadavg()[0]
            t, F, wall = f()
            walls[k].append(wall)
            loads[k].append([before, os.getloadavg()[0]])
            last[k] = (t, F)
            print(f"{k}: {wall:.3f} s stepping (load {before:.1f})", flush=True)
    t_a, F_a = last["a_adapter"]
    peak = float(np.max(np.abs(F_a)))
    out = {"case": {"amplitude_m": AMPLITUDE, "frequency_hz": FREQUENCY, "cycles": CYCLES, "timestep_s": STEP,
                    "samples_per_cycle": SAMPLES, "model": "models/nsd_drive.toml"},
           "machine": {"cpus": os.cpu_count(), "when": time.strftime("%Y-%m-%d %H:%M:%S")},
           "peak_F_x_adapter_N": peak, "runs": {}}
    median_a = statistics.median(walls["a_adapter"])
    for k in cases:
        t, F = last[k]
        if len(t) != len(t_a) or np.max(np.abs(t - t_a)) > 1e-12:
            raise SystemExit(f"{k}: output times differ from the adapter's")
        med = statistics.median(walls[k])
        out["runs"][k] = {"wall_s": walls[k], "median_wall_s": med, "ratio_to_adapter": med / median_a,
                          "load_average_before_after": loads[k],
                          "max_abs_dF_x_over_peak": float(np.max(np.abs(F - F_a)) / peak)}
    target = Path(args.out)
    if target.suffix != ".json":   # a folder (python -m benchmarks.measure passes one)
        target = target / "bench_model_builders.json"
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(json.dumps(out, indent=1) + "\n")
    for k, r in out["runs"].items():
        print(f"{k:18s} median {r['median_wall_s']:.3f} s  x{r['ratio_to_adapter']:.2f}  "
              f"dF_x/peak {r['max_abs_dF_x_over_peak']:.2e}")
    return out


if __name__ == "__main__":
    main()
