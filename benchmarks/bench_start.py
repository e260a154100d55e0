"""The gate on a cold cache and on a warm one (docs/compilation.md): what a newcomer's first
``nsd compare`` costs, compilation included, and what the same command costs after.

    python benchmarks/bench_start.py --repeats 1 --out DIR       (nsd compare, every default case)
    python benchmarks/bench_start.py --short --out DIR           (nsd compare --engines semirecursive)

Per repeat: a fresh, empty cache folder (``XDG_CACHE_HOME``: numba's compiled kernels of the in-house
engine and of the peers' callbacks, matplotlib's font cache; ``NUMBA_CACHE_DIR`` unset), then

- cold: ``nsd compare --out ...`` in a fresh process, which compiles everything it uses;
- warm: the same command again in a fresh process, on the cache the cold run left.

Each keeps the command's wall seconds (what the user waits for, start to exit), its CPU seconds (the
process and its workers), its exit code, and from its results.json the compare's own wall seconds
(``total_wall_time``), the workers' start-up (``worker_warmup``: spawn and imports, and the warm-up
that compiles or loads the kernels before the first job) and each engine's remaining compile time.
The gate's verdict is kept too, but timing is this benchmark's subject: a FAIL does not stop it.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from nsd_core.device.results import versions
from nsd_core.common.files import atomic_write_json  # noqa: E402

FULL = ["compare"]
SHORT = ["compare", "--engines", "semirecursive"]


def timed_nsd(args: list[str], out: Path, env: dict, cwd: Path = ROOT) -> tuple[dict, dict | None]:
    """One fresh process of ``nsd ARGS --out OUT``: its exit code, wall and CPU seconds (the process and
    its workers), and the results.json it wrote (None, and the last stderr line as ``error``, if none)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "nsd_cli.main", *args, "--out", str(out)], cwd=cwd, env=env,
                       capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    row = {"exit_code": p.returncode, "command_wall_s": wall,
           "command_cpu_s": (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)}
    try:
        return row, json.loads((out / "results.json").read_text())
    except (OSError, ValueError):
        row["error"] = (p.stderr.strip().splitlines() or ["no results.json"])[-1][:300]
        return row, None


def run_once(args: list[str], cache: Path, out: Path) -> dict:
    """One fresh process of ``nsd ARGS --out OUT`` with ``cache`` as XDG_CACHE_HOME."""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(XDG_CACHE_HOME=str(cache), MPLBACKEND="Agg")
    row, res = timed_nsd(args, out, env)
    if res is None:
        return row
    compile_s: dict[str, float] = {}
    for per in res["runs"].values():
        for e, r in per.items():
            compile_s[e] = compile_s.get(e, 0.0) + float(r.get("compile_time") or 0.0)
    warm = res.get("worker_warmup") or {}
    row.update(verdict=res.get("verdict"), compare_wall_s=res.get("total_wall_time"),
               worker_startup_s=res.get("worker_startup_time"), worker_ready_s=warm.get("ready_s"),
               worker_warm_s=warm.get("warm_s"), worker_spawn_s=warm.get("spawn_s"),
               compile_in_runs_s=compile_s, workers=res.get("workers"))
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="folder for bench_start.json")
    ap.add_argument("--repeats", type=int, default=1, help="cold/warm pairs, each on its own empty cache")
    ap.add_argument("--short", action="store_true", help="the in-house engine alone: nsd compare --engines semirecursive")
    ap.add_argument("--args", default=None, help="other nsd arguments instead (without --out), e.g. 'compare --convergence'")
    a = ap.parse_args(argv)
    if a.repeats < 1:
        print(f"--repeats = {a.repeats}: must be >= 1", file=sys.stderr)
        return 2
    args = shlex.split(a.args) if a.args else (SHORT if a.short else FULL)
    load0 = os.getloadavg()
    pairs = []
    with tempfile.TemporaryDirectory() as tmp:
        for rep in range(a.repeats):
            cache = Path(tmp) / f"cache{rep}"
            cache.mkdir()
            pair = {}
            for state in ("cold", "warm"):
                pair[state] = run_once(args, cache, Path(tmp) / f"{state}{rep}")
                r = pair[state]
                print(f"repeat {rep + 1} {state}: exit {r['exit_code']}, {r['command_wall_s']:.1f} s wall, "
                      f"{r['command_cpu_s']:.1f} s CPU, compare {r.get('compare_wall_s') or float('nan'):.1f} s, "
                      f"workers ready {r.get('worker_ready_s') or float('nan'):.1f} s", flush=True)
            pairs.append(pair)

    def med(state, key):
        vals = [p[state][key] for p in pairs if p[state].get(key) is not None]
        return statistics.median(vals) if vals else None

    report = {"command": "nsd " + " ".join(args) + " --out DIR", "repeats": a.repeats, "pairs": pairs,
              "median": {s: {k: med(s, k) for k in ("command_wall_s", "command_cpu_s", "compare_wall_s",
                                                      "worker_ready_s", "worker_warm_s", "worker_spawn_s")}
                         for s in ("cold", "warm")},
              "machine": platform.platform(), "cpus": os.cpu_count(), "load_average_start": load0,
              "load_average_end": os.getloadavg(), "versions": versions(),
              "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime())}
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "bench_start.json", report)
    print(f"wrote {out / 'bench_start.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
