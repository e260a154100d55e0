"""Where the cold gate's compilation goes (docs/performance.md): each item of the gate's worker warm-up
timed alone, one after another in one process, on an empty cache folder and then on the cache it left.

    python benchmarks/compile_units.py --out DIR

The items are those ``nsd compare`` gives its pool workers for the default cases
(``comparisons.warmup.job_warmup``: the in-house engine's units, each peer engine's tiny run per
kind of job, each in-house kind's tiny run), in the order a worker takes them. In the gate two
workers share the compiling (``compile_once.share_work``), so its warm-up takes about half the sum;
the peers' tiny runs run in both. Cold minus warm is an item's compilation; warm is what a worker
pays for it on every start. Wall and CPU seconds of the one process.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

CHILD = """
import json, sys, time
from functools import partial
from comparisons.config import DEFAULT_CASES, SeismicCase, load_cases
from comparisons.reference import CONVERGED, run_spec
from comparisons.warmup import job_warmup, spec
import nsd_core.compilation.worker_warmup as ww

specs = []
for c in load_cases(DEFAULT_CASES):
    for label in ("semirecursive", "mujoco", "exudyn", CONVERGED):
        engine, _, settings = run_spec(c, label, None)
        specs.append(spec(engine, isinstance(c, SeismicCase), getattr(c, "drive", None), settings))
rows = []

def what(fn):  # the item in words: a peer's tiny run (its path and named choices) or an in-house kind
    inner = fn.args[0] if fn.args and isinstance(fn.args[0], partial) else None
    if inner is None:
        return ""
    if inner.func.__name__ in ("run_job", "run_seismic_job"):
        settings = inner.args[-1] or {}
        shape = getattr(inner.args[2], "path", "") if inner.func.__name__ == "run_job" else "seismic"
        return " ".join([shape] + [f"{k}={v}" for k, v in sorted(settings.items()) if isinstance(v, str)])
    return " ".join(str(a) for a in inner.args if isinstance(a, str))

def timed(items):  # share_work's items, each timed alone (block=True: nothing is put off)
    for name, fn in items:
        t0, c0 = time.perf_counter(), time.process_time()
        fn(True)
        rows.append({"item": name, "what": what(fn), "wall_s": time.perf_counter() - t0,
                     "cpu_s": time.process_time() - c0})

ww.share_work = timed
warm = job_warmup(specs)
warm()
json.dump(rows, sys.stdout)
"""


def run(cache: str) -> list[dict]:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(XDG_CACHE_HOME=cache, MPLBACKEND="Agg", PYTHONPATH=str(ROOT))
    p = subprocess.run([sys.executable, "-c", CHILD], cwd=ROOT, env=env, capture_output=True, text=True, check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="out/bench")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as cache:
        cold, warm = run(cache), run(cache)
    rows = [{"item": c["item"], "what": c["what"], "cold_wall_s": c["wall_s"], "cold_cpu_s": c["cpu_s"], "warm_wall_s": w["wall_s"],
             "warm_cpu_s": w["cpu_s"]} for c, w in zip(cold, warm)]
    for r in rows:
        print(f"{r['item']:20s} {r['what']:28s} cold {r['cold_cpu_s']:6.2f} s CPU, warm {r['warm_cpu_s']:6.2f} s CPU")
    report = {"rows": rows, "cold_cpu_s": sum(r["cold_cpu_s"] for r in rows),
              "warm_cpu_s": sum(r["warm_cpu_s"] for r in rows)}
    print(f"sum: cold {report['cold_cpu_s']:.1f} s CPU, warm {report['warm_cpu_s']:.1f} s CPU")
    from nsd_core.common.files import atomic_write_json
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "compile_units.json", report)


if __name__ == "__main__":
    main()
