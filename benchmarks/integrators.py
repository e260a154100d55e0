"""Which integrator and tolerance for the device: error against the rtol 1e-10 reference vs time.

    python benchmarks/integrators.py [--repeats 3] [--implicit] [--out out/bench]

For each Figure 6 case and each setting of a ladder (explicit pairs of the compiled backend, with
and without the old max_step = 1e-3; with ``--implicit`` scipy's Radau and LSODA on the same
reduced equations through the "scipy" backend, where steps and right-hand sides are what counts,
not wall time), prints and writes max|dF|/max|F| on the last cycle, the median wall time per cycle,
steps and right-hand-side evaluations. Interleaved repeats; quote with the machine's load.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from refcompare import discrepancy, in_house_reference  # noqa: E402

from nsd_core.device.drive import Drive  # noqa: E402
from nsd_core.device.model import simulate  # noqa: E402
from nsd_core.device.params import Params  # noqa: E402

CASES = [(0.015, 1.0), (0.015, 10.0), (0.0255, 1.0), (0.0255, 10.0)]
EXPLICIT = [dict(method=m, rtol=r, atol=1e-12, max_step=np.inf) for m in ("DOP853", "RK45")
            for r in (1e-4, 1e-5, 1e-6, 1e-7)] + [dict(method="DOP853", rtol=1e-7, atol=1e-12, max_step=1e-3)]
IMPLICIT = [dict(method=m, rtol=r, atol=1e-9, max_step=np.inf, backend="scipy") for m in ("Radau", "LSODA")
            for r in (1e-4, 1e-6)]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--implicit", action="store_true")
    ap.add_argument("--cases", default="0,1,2,3")
    ap.add_argument("--out", default="out/bench")
    args = ap.parse_args()
    p = Params()
    simulate(p, Drive(0.015, 10.0, cycles=1, samples_per_cycle=100))
    rows = []
    for ci in [int(c) for c in args.cases.split(",")]:
        A, f = CASES[ci]
        d = Drive(A, f, cycles=2, samples_per_cycle=2000)
        ref, _ = in_house_reference(p, d)
        ladder = EXPLICIT + (IMPLICIT if args.implicit else [])
        times = [[] for _ in ladder]
        cpu = [[] for _ in ladder]
        res = [None] * len(ladder)
        for rep in range(args.repeats):
            for k, s in enumerate(ladder):
                if rep and s.get("backend") == "scipy":
                    continue  # minutes per run in Python: once is enough for steps and error
                t0, c0 = time.perf_counter(), time.process_time()
                res[k] = simulate(p, d, **s)
                times[k].append((time.perf_counter() - t0) / d.cycles)
                cpu[k].append((time.process_time() - c0) / d.cycles)
        for s, r, ts, cs in zip(ladder, res, times, cpu):
            acc = discrepancy(r, ref, d)
            row = dict(amplitude=A, frequency=f, **{k: (v if np.isfinite(v) else None) if isinstance(v, float) else v
                                                     for k, v in s.items()},
                       dF=acc["dF"], s_per_cycle=statistics.median(ts), cpu_s_per_cycle=statistics.median(cs),
                       steps=r.stats["steps"], nfev=r.stats["nfev"])
            rows.append(row)
            print(f"A={A} f={f:4.1f} {s['method']:6s} rtol={s['rtol']:.0e} max_step={s['max_step']:<6g} "
                  f"{s.get('backend', 'compiled'):8s} dF={acc['dF']:.2e} {1e3 * row['s_per_cycle']:8.1f} ms/cycle wall "
                  f"{1e3 * row['cpu_s_per_cycle']:8.1f} ms/cycle CPU "
                  f"steps={row['steps']} nfev={row['nfev']}", flush=True)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "integrators.json").write_text(json.dumps({"load_average": os.getloadavg(), "rows": rows}, indent=2))


if __name__ == "__main__":
    main()
