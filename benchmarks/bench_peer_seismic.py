"""The peers on the gate's seismic cases: wall and CPU seconds per model second of
each peer at the case's own settings, MuJoCo with its compiled passive forces and step loop (the default)
and with its Python ones (the check), Exudyn, and the in-house engine beside them; the aim is <= 1 wall s per model
second for each peer on a quiet machine.

    python benchmarks/bench_peer_seismic.py --repeats 3 --out DIR
    python benchmarks/bench_peer_seismic.py --short --out DIR     (one repeat, the first 0.1 model s)

Every run is one process's whole window after a tiny run of the same engine and settings (its
compilation and imports kept out, as the gate's warm workers do); runs of one case interleave the
variants so that each repeat sees the same load; the median of the repeats is kept with the load
average before and after. The runs' time histories are compared too: MuJoCo's native loop against its
Python loop (the same model: round-off apart), each as the largest difference over the columns
relative to the column's peak. The in-house engine runs its generated evaluation (NSD_EVALUATOR =
"generated", compiled in its warm-up run): under "auto" it would run the generic one unless a study
had compiled the generated one in this cache, so its time would depend on the cache's history
(0.29 against 0.09 wall s per model s on seismic_nf1_pulse; the same numbers, bit for bit).
"""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from comparisons.config import SeismicCase, load_cases  # noqa: E402
from comparisons.engines import REFERENCE, run_seismic_engine  # noqa: E402
from nsd_core.device.results import versions
from nsd_core.common.files import atomic_write_json  # noqa: E402

VARIANTS = {"mujoco": ("mujoco", {"passive": "compiled"}), "mujoco (python loop)": ("mujoco", {"passive": "python"}),
            "exudyn": ("exudyn", {}), REFERENCE: (REFERENCE, {})}


def _run(case: SeismicCase, engine: str, extra: dict, duration: float):
    settings = {**case.settings.get(engine, {}), **extra}
    st = case.isolated_structure()
    run_seismic_engine(engine, case.params_for(engine), st, case.ground, 0.004, case.dt_out, settings)  # warm
    w0, c0 = time.perf_counter(), time.process_time()
    r = run_seismic_engine(engine, case.params_for(engine), st, case.ground, duration, case.dt_out, settings)
    return time.perf_counter() - w0, time.process_time() - c0, r


def _largest_relative_difference(a, b) -> float:
    worst = 0.0
    for k in a.columns:
        if k in b.columns and k != "t":
            scale = float(np.max(np.abs(b.columns[k]))) or 1.0
            worst = max(worst, float(np.max(np.abs(a.columns[k] - b.columns[k]))) / scale)
    return worst


def main(argv=None) -> int:
    os.environ.setdefault("NSD_EVALUATOR", "generated")   # the in-house row (the docstring); not at import
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--short", action="store_true", help="one repeat of the first 0.1 model s of each case")
    a = ap.parse_args(argv)
    if a.repeats < 1:
        print(f"--repeats = {a.repeats}: must be >= 1", file=sys.stderr)
        return 2
    repeats = 1 if a.short else a.repeats
    cases = [c for c in load_cases() if isinstance(c, SeismicCase)]
    load0 = os.getloadavg()
    rows = []
    for case in cases:
        duration = min(0.1, case.model_duration) if a.short else case.model_duration
        per = {v: {"wall": [], "cpu": [], "load": []} for v in VARIANTS}
        results = {}
        for rep in range(repeats):
            for v, (engine, extra) in VARIANTS.items():
                load = os.getloadavg()[0]
                wall, cpu, r = _run(case, engine, extra, duration)
                per[v]["wall"].append(wall / duration)
                per[v]["cpu"].append(cpu / duration)
                per[v]["load"].append(load)
                results[v] = r
                print(f"{case.name} {v} #{rep + 1}: {wall / duration:.2f} wall s / model s, {cpu / duration:.2f} CPU s "
                      f"/ model s (load {load:.2f})", flush=True)
        for v, m in per.items():
            rows.append({"case": case.name, "variant": v, "model_s": duration,
                         "wall_s_per_model_s": statistics.median(m["wall"]),
                         "cpu_s_per_model_s": statistics.median(m["cpu"]), "load_1min": m["load"],
                         "settings": {**case.settings.get(VARIANTS[v][0], {}), **VARIANTS[v][1]}})
        rows.append({"case": case.name, "variant": "mujoco native vs python loop",
                     "largest_relative_difference": _largest_relative_difference(results["mujoco"],
                                                                                 results["mujoco (python loop)"])})
    report = {"repeats": repeats, "short": a.short, "rows": rows, "machine": platform.platform(),
              "cpus": os.cpu_count(), "load_average_start": load0, "load_average_end": os.getloadavg(),
              "versions": versions(), "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime())}
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "bench_peer_seismic.json", report)
    print(f"wrote {out / 'bench_peer_seismic.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
