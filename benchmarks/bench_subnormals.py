"""The peers' runs of the gate's cases with subnormal numbers flushed (as shipped) and kept
(comparisons.builders.subnormals; docs/performance.md).

    python benchmarks/bench_subnormals.py --repeats 3 --out DIR

For each default case (drive and seismic) and each peer (MuJoCo, Exudyn), in one process after a
warm-up run: the run's CPU seconds with the builders' flush on and with it replaced by a block that
changes nothing, alternating, the least of ``--repeats`` each; the count of subnormal entries (0 <
|x| < 2.2e-308) in the run's outputs either way; and the largest difference between the two runs'
outputs, each column over its own largest value.
"""
from __future__ import annotations

import argparse
import contextlib
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from comparisons.builders import exudyn as exudyn_builder, mujoco_compiled  # noqa: E402
from comparisons.builders.subnormals import flushed  # noqa: E402
from comparisons.config import SeismicCase, load_cases  # noqa: E402
from comparisons.engines import run_engine, run_seismic_engine  # noqa: E402
from nsd_core.common.files import atomic_write_json  # noqa: E402

TINY = np.finfo(float).tiny
BUILDERS = (mujoco_compiled, exudyn_builder)
PEERS = ("mujoco", "exudyn")   # the engines whose step loops flush (the builders above)


def _run(case, engine: str, keep: bool):
    """One run; ``keep``: the builders' flush replaced by a block that changes nothing."""
    nothing = contextlib.nullcontext
    for b in BUILDERS:
        b.flushed = nothing if keep else flushed
    s = dict(case.settings.get(engine, {}))
    t0 = time.process_time()
    if isinstance(case, SeismicCase):
        r = run_seismic_engine(engine, case.params, case.isolated_structure(), case.ground, case.duration,
                               case.dt_out, s)
    else:
        r = run_engine(engine, case.params, case.drive, s)
    return time.process_time() - t0, {k: np.asarray(v, dtype=float) for k, v in r.columns.items()}


def _subnormal(cols: dict) -> int:
    return int(sum(np.count_nonzero((np.abs(v) > 0) & (np.abs(v) < TINY)) for v in cols.values()))


def _largest_difference(a: dict, b: dict) -> float:
    worst = 0.0
    for k, x in a.items():
        scale = float(np.nanmax(np.abs(x))) if x.size else 0.0
        if scale > 0:
            worst = max(worst, float(np.nanmax(np.abs(x - b[k]))) / scale)
    return worst


def measure(engines: list[str], repeats: int) -> list[dict]:
    rows = []
    for engine in engines:
        cases = load_cases()
        _run(cases[0], engine, keep=False)   # warm-up: imports, compiled code loaded
        for case in cases:
            cpu = {False: [], True: []}
            cols = {}
            for _ in range(repeats):
                for keep in (True, False):
                    t, cols[keep] = _run(case, engine, keep)
                    cpu[keep].append(t)
            rows.append({"engine": engine, "case": case.name, "cpu_s_kept": min(cpu[True]),
                         "cpu_s_flushed": min(cpu[False]), "ratio": min(cpu[True]) / min(cpu[False]),
                         "subnormal_kept": _subnormal(cols[True]), "subnormal_flushed": _subnormal(cols[False]),
                         "largest_difference": _largest_difference(cols[True], cols[False])})
            print(json.dumps(rows[-1]), flush=True)
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--engines", default="mujoco,exudyn")
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    if a.repeats < 1:
        print(f"bench_subnormals: --repeats {a.repeats}: allowed: 1 or more", file=sys.stderr)
        return 2
    engines = a.engines.split(",")
    bad = [e for e in engines if e not in PEERS]
    if bad:
        print(f"bench_subnormals: --engines {bad[0]!r}: allowed: {', '.join(PEERS)}", file=sys.stderr)
        return 2
    rows = measure(engines, a.repeats)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "bench_subnormals.json", {"repeats": a.repeats, "rows": rows})
    return 0


if __name__ == "__main__":
    sys.exit(main())
