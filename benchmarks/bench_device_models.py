"""The device's two in-house models side by side (docs/architecture.md): the hand-built one (the product:
nsd_core.device.model.simulate) and the description-built one (the check: nsd_core.model.semirecursive on
device_description's TOML), on the gate's line-drive cases, at the same integrator and tolerances.

    python benchmarks/bench_device_models.py --repeats 3 --out DIR

Each run is timed by its own clock after a warm-up run of the same model in this process (compilation
is never in the numbers); the repeats alternate between the two models, and the median is kept. The
drive force F_x of the two is compared as a fraction of its peak (they are the same tree and laws).
"""
from __future__ import annotations

import argparse
import os
import statistics
import time
import tomllib
from pathlib import Path

import numpy as np

CASES = [("A15mm_f1Hz", 0.015, 1.0), ("A15mm_f10Hz", 0.015, 10.0), ("A25.5mm_f1Hz", 0.0255, 1.0),
         ("A25.5mm_f10Hz", 0.0255, 10.0)]
SETTINGS = {"method": "DOP853", "rtol": 1e-7, "atol": 1e-12, "max_step": 1e-3}   # the hand-built default


def hand_built(amplitude: float, frequency: float):
    from nsd_core.device.drive import Drive
    from nsd_core.device.model import simulate
    from nsd_core.device.params import Params
    drive = Drive(amplitude=amplitude, frequency=frequency, cycles=2, samples_per_cycle=500)
    start = time.perf_counter()
    r = simulate(Params(), drive, **SETTINGS)
    return time.perf_counter() - start, np.asarray(r["F_x"])


def description_built(amplitude: float, frequency: float):
    from nsd_core.device.describe import device_description
    from nsd_core.device.params import Params
    from nsd_core.model.load import parse_model
    from nsd_core.model.semirecursive import simulate as simulate_model
    model = parse_model(tomllib.loads(device_description(Params(), amplitude, frequency)))
    start = time.perf_counter()
    run = simulate_model(model, 2.0 / frequency, 1.0 / (500 * frequency), dict(SETTINGS))
    return time.perf_counter() - start, np.asarray(run.outputs["F_x"])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    from nsd_core.common.files import atomic_write_json
    hand_built(0.015, 100.0)          # warm-ups: compilation out of every number below
    description_built(0.015, 100.0)
    rows = []
    for name, amp, f in CASES:
        times = {"hand_built": [], "description_built": []}
        for _ in range(a.repeats):
            th, fh = hand_built(amp, f)
            td, fd = description_built(amp, f)
            times["hand_built"].append(th)
            times["description_built"].append(td)
        n = min(len(fh), len(fd))
        rows.append({"case": name, "hand_built_s": statistics.median(times["hand_built"]),
                     "description_built_s": statistics.median(times["description_built"]),
                     "ratio": statistics.median(times["description_built"]) / statistics.median(times["hand_built"]),
                     "max_dF_x_rel": float(np.max(np.abs(fh[:n] - fd[:n])) / np.max(np.abs(fh))),
                     "all_s": times})
        print(f"{name}: hand-built {rows[-1]['hand_built_s']:.3f} s, description-built "
              f"{rows[-1]['description_built_s']:.3f} s ({rows[-1]['ratio']:.2f}x), F_x differs by "
              f"{rows[-1]['max_dF_x_rel']:.2e} of its peak")
    atomic_write_json(Path(a.out) / "bench_device_models.json",
                      {"settings": SETTINGS, "repeats": a.repeats, "cpus": os.cpu_count(),
                       "load_after": os.getloadavg(), "rows": rows,
                       "units": {"hand_built_s": "s", "description_built_s": "s", "ratio": "-", "max_dF_x_rel": "-"}})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
