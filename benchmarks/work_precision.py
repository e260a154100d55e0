"""Work-precision of the three engines on the default cases (the diagram of Hairer & Wanner).

    .venv/bin/python benchmarks/work_precision.py --out out/run/work_precision
    .venv/bin/python benchmarks/work_precision.py --out /tmp/wp --repeats 1 --quick --no-compile
    .venv/bin/python benchmarks/work_precision.py --to-aim --no-compile --repeats 3 --out DIR   (the ratios)
    .venv/bin/python benchmarks/work_precision.py --short --no-compile --out DIR                (two cases, 1 repeat)

For every default case of comparisons/cases.toml (2 cycles, the last one compared) each engine runs a
ladder of settings (LADDERS: tolerances for the in-house model, step sizes for MuJoCo and Exudyn),
plus the case's own default settings; the error of a run is max|F - F_ref| / max|F_ref| on the last
cycle against the in-house model at rtol 1e-10 (benchmarks/refcompare.py) and its work is the CPU
time per cycle (time.process_time around ``engine.run``, model construction included, divided by
the number of cycles; median over ``--repeats``), every engine warmed up first (``warm_up``: imports and
compilation are in no timed run). The runs are interleaved: each repeat visits every
case and, within a case, the engines in turn rung by rung, so a load change on the machine hits all
engines alike. A rung whose step is the same as an earlier one's (the step divides the output
interval, so at 10 Hz every step >= 5e-5 s is 5e-5 s) is not run twice.

Per case and engine, ``at_aim`` is the cheapest rung with error <= the aim (1e-4) over all the
repeats (median CPU), and ``ratio_best_peer_over_in_house`` the CPU time of the faster peer at the aim
over the in-house model's, outputs included (every run writes the case's samples with the reaction
force). ``--to-aim`` measures just that, in one interleaved run: per case, the first repeat walks each
engine's sub-ladders (an integrator or method: its steps or tolerances from the cheapest) up to the
first rung within the aim, the engines in turn rung by rung; the later repeats run only the rungs
within the aim, again interleaved (a peer's rung that cost more than PRUNE x the best peer's within
the aim on the first repeat is not repeated: it cannot be the best peer).

Compilation is measured apart (``compile``): for each engine a fresh Python process runs a short
drive twice, with numba's cache as it is (``warm``: loading cached machine code) and with an
empty cache directory (``cold``: compiling everything, as on a fresh install); the first run minus
the second is that engine's start-up cost, not counted in any per-cycle time.
The JSON (``work_precision.json``) is read by the report's work-precision page.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from nsd_core.engine.codegen import prefer_generated
from comparisons.config import SeismicCase, load_cases
from comparisons.engines import get_engine
from comparisons.engines.base import EngineError
from nsd_core.common.files import atomic_write_json

from refcompare import discrepancy, in_house_reference

AIM = 1e-4
PRUNE = 2.0   # --to-aim: a peer's rung costing more than this x the best peer within the aim is not repeated
SHORT_CASES = ("A15mm_f10Hz", "circle_A15mm_f10Hz")   # --short: two of the default cases, one repeat
ENGINES = ("semirecursive", "mujoco", "exudyn")
LADDERS = {
    "semirecursive": ([{"rtol": r, "max_step": 1.0} for r in (1e-3, 1e-4, 1e-5, 1e-6)]
                      + [{"method": "RK45", "rtol": r, "max_step": 1.0} for r in (1e-3, 1e-4, 1e-5, 1e-6)]),
    "mujoco": ([{"integrator": "Euler", "timestep": h} for h in (1e-4, 5e-5, 2.5e-5, 1e-5, 5e-6)]
               + [{"integrator": "RK4", "timestep": h} for h in (1e-4, 5e-5, 2.5e-5)]),
    "exudyn": [{"step_size": h, "min_steps_per_cycle": 1} for h in (1e-3, 5e-4, 2.5e-4, 1.25e-4, 6.25e-5, 2.5e-5)],
}
QUICK = {"semirecursive": [{"rtol": 1e-3, "max_step": 1.0}], "mujoco": [{"integrator": "Euler", "timestep": 5e-5}],
         "exudyn": [{"step_size": 2.5e-4, "min_steps_per_cycle": 1}]}
START_CODE = """
import sys, time, json
t0 = time.perf_counter(); c0 = time.process_time()
from comparisons.engines import get_engine
from nsd_core.device.drive import Drive
from nsd_core.device.params import Params
e = get_engine(sys.argv[1]); d = Drive(0.015, 10.0, cycles=1, samples_per_cycle=100)
t1 = time.perf_counter(); e.run(Params(), d); t2 = time.perf_counter(); e.run(Params(), d); t3 = time.perf_counter()
print(json.dumps({"import_s": t1 - t0, "first_run_s": t2 - t1, "second_run_s": t3 - t2}))
"""


def step_key(engine: str, drive, settings: dict):
    """The step actually used (rungs with the same one are the same run); None for adaptive engines."""
    dt_out = 1.0 / (drive.frequency * drive.samples_per_cycle)
    if engine == "mujoco":
        n = max(1, math.ceil(dt_out / float(settings["timestep"]) - 1e-9))   # as comparisons.builders.mujoco
        return settings["integrator"], dt_out / n
    if engine == "exudyn":   # the builder's step: the setting capped per cycle, dividing the output interval
        from comparisons.engines.described import builder_settings
        n = max(1, math.ceil(dt_out / builder_settings("exudyn", settings, drive.frequency)["step_size"] - 1e-9))
        return dt_out / n
    return None


def compile_times(engines) -> dict:
    """Start-up cost per engine in fresh processes: warm numba cache and an empty (cold) one."""
    out = {}
    root = Path(__file__).resolve().parent.parent
    for e in engines:
        out[e] = {}
        for mode in ("warm", "cold"):
            env = dict(os.environ, PYTHONPATH=str(root))
            with tempfile.TemporaryDirectory() as cache:
                if mode == "cold":
                    env["NUMBA_CACHE_DIR"] = cache
                try:
                    p = subprocess.run([sys.executable, "-c", START_CODE, e], env=env, capture_output=True,
                                       text=True, timeout=900, cwd=root)
                    if p.returncode != 0:
                        raise ValueError(f"exit {p.returncode}: {(p.stderr.strip().splitlines() or [''])[-1]}")
                    r = json.loads(p.stdout.strip().splitlines()[-1])
                    r["startup_s"] = r["first_run_s"] - r["second_run_s"]
                except (subprocess.SubprocessError, ValueError, IndexError) as exc:
                    r = {"error": f"{type(exc).__name__}: {' '.join(str(exc).split())[:200]}"}
            out[e][mode] = r
            print(f"  {e} {mode}: {r}", flush=True)
    return out


def group_of(settings: dict) -> tuple:
    """A rung's sub-ladder: its named choices (MuJoCo's integrator, the in-house method); along one,
    a finer step or a tighter tolerance costs more."""
    return tuple(sorted((k, v) for k, v in settings.items() if isinstance(v, str)))


def _rungs(case, ladders: dict, to_aim: bool) -> dict:
    drive = case.drive
    rungs = {e: [] for e in ladders}
    for e, ladder in ladders.items():
        seen = set()
        order = ladder + [None] if to_aim else [None] + ladder   # None: the case's default settings
        for rung in order:
            s = dict(case.settings.get(e, {})) if rung is None else {**case.settings.get(e, {}), **rung}
            key = step_key(e, drive, {**get_engine(e).default_settings, **s})
            if key is not None and key in seen and rung is not None:
                continue
            seen.add(key)
            rungs[e].append({"engine": e, "settings": s, "case_default": rung is None, "cpu": [], "wall": []})
    return rungs


def _run(case, ref, row: dict, first: bool) -> None:
    drive = case.drive
    c0, t0 = time.process_time(), time.perf_counter()
    try:
        r = get_engine(row["engine"]).run(case.params, drive, row["settings"])
    except EngineError as exc:
        row["error"] = str(exc)
        return
    row["cpu"].append((time.process_time() - c0) / drive.cycles)
    row["wall"].append((time.perf_counter() - t0) / drive.cycles)
    if first:
        row.update(discrepancy(r, ref, drive))
        row["step_used"] = r.stats.get("timestep", r.stats.get("step_size"))
    print(f"  {case.name} {row['engine']:13s} {row['settings']}  dF {row.get('dF', float('nan')):.2e}  "
          f"cpu/cycle {row['cpu'][-1]:.3f} s", flush=True)


def _walk_to_aim(case, ref, rungs: dict) -> None:
    """The first repeat of ``--to-aim``: each engine's sub-ladders from the cheapest rung, the engines
    in turn rung by rung, each sub-ladder stopped at its first rung within the aim; a peer's rung is
    not run once the same engine's last rung already cost more than PRUNE x the best peer within the
    aim so far (finer steps cost more: it cannot be the best peer)."""
    done, last = set(), {}
    depth = max(len(v) for v in rungs.values())
    for i in range(depth):
        for e in ENGINES:
            if e not in rungs or i >= len(rungs[e]):
                continue
            row = rungs[e][i]
            group = (e, group_of(row["settings"]))
            best = _best_peer_cpu(rungs)
            if group in done:
                row["skipped"] = "a cheaper rung of its sub-ladder reached the aim"
                continue
            if e != "semirecursive" and best is not None and last.get(e, 0.0) > PRUNE * best:
                row["skipped"] = f"its engine's last rung cost more than {PRUNE:g} x the best peer within the aim"
                continue
            _run(case, ref, row, True)
            if row["cpu"]:
                last[e] = row["cpu"][-1]
            if row.get("dF", math.inf) <= AIM:
                done.add(group)


def _best_peer_cpu(rungs: dict, key=lambda r: r["cpu"][0]):
    at = [key(r) for e in rungs if e != "semirecursive" for r in rungs[e] if r["cpu"] and r.get("dF", math.inf) <= AIM]
    return min(at) if at else None


def warm_up(cases, ladders: dict) -> float:
    """Each engine's tiny run of every path kind and sub-ladder the cases will use, so that no timed
    run holds an import or a compilation (the in-house kernels, MuJoCo's and Exudyn's callbacks);
    returns the seconds this took."""
    from nsd_core.device.params import Params
    from nsd_core.compilation.warmup import tiny_drive
    from nsd_core.engine.timing import PATHS
    t0 = time.perf_counter()
    paths = sorted({c.drive.path if c.drive.path in PATHS else "line" for c in cases})
    for e, ladder in ladders.items():
        groups = {group_of(s): s for s in ladder + [c.settings.get(e, {}) for c in cases]}
        for s in groups.values():
            choice = {k: v for k, v in s.items() if isinstance(v, str)}
            for path in paths:
                try:
                    get_engine(e).run(Params(), tiny_drive(path), choice or None)
                except EngineError:
                    pass
    return time.perf_counter() - t0


def run_case(case, ladders: dict, repeats: int, to_aim: bool = False) -> dict:
    """Every rung of every engine, ``repeats`` times, interleaved (a repeat visits the engines in turn
    rung by rung). ``to_aim``: the first repeat walks each sub-ladder only up to the aim
    (``_walk_to_aim``); the later ones run only the rungs within the aim, bar a peer's costing more
    than PRUNE x the best peer's on the first repeat."""
    drive = case.drive
    ref, note = in_house_reference(case.params, drive)
    rungs = _rungs(case, ladders, to_aim)
    depth = max(len(v) for v in rungs.values())
    for rep in range(repeats):
        if to_aim and rep == 0:
            _walk_to_aim(case, ref, rungs)
            continue
        best = _best_peer_cpu(rungs) if to_aim else None
        for i in range(depth):
            for e in ENGINES:
                if e not in rungs or i >= len(rungs[e]) or rungs[e][i].get("error"):
                    continue
                row = rungs[e][i]
                if to_aim and (not row["cpu"] or row.get("dF", math.inf) > AIM):
                    continue
                if to_aim and e != "semirecursive" and best is not None and row["cpu"][0] > PRUNE * best:
                    row["skipped_repeats"] = f"cost more than {PRUNE:g} x the best peer within the aim"
                    continue
                _run(case, ref, row, rep == 0)
    runs = []
    for e in rungs:
        for row in rungs[e]:
            if row["cpu"]:
                row["cpu_per_cycle"] = statistics.median(row["cpu"])
                row["wall_per_cycle"] = statistics.median(row["wall"])
                row["repeats"] = len(row["cpu"])
            runs.append(row)
    at_aim = {}
    for e in rungs:
        ok = [r for r in runs if r["engine"] == e and "dF" in r and r["dF"] <= AIM and r.get("repeats") == repeats]
        if ok:
            best = min(ok, key=lambda r: r["cpu_per_cycle"])
            at_aim[e] = {k: best[k] for k in ("settings", "cpu_per_cycle", "wall_per_cycle", "dF", "step_used",
                                               "repeats")}
    peers = [(at_aim[e]["cpu_per_cycle"], e) for e in ("mujoco", "exudyn") if e in at_aim]
    ratio = (min(peers)[0] / at_aim["semirecursive"]["cpu_per_cycle"]) if peers and "semirecursive" in at_aim else None
    return {"name": case.name, "amplitude": drive.amplitude, "frequency": drive.frequency, "cycles": drive.cycles,
            "samples_per_cycle": drive.samples_per_cycle, "path": drive.path, "reference": note, "runs": runs,
            "at_aim": at_aim, "best_peer": min(peers)[1] if peers else None,
            "ratio_best_peer_over_in_house": ratio}


def main(argv=None) -> int:
    # the in-house engine as the studies run it (the generated evaluation); here, not at import, so that
    # importing this module (a test does) leaves the environment alone
    prefer_generated()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="folder for work_precision.json")
    ap.add_argument("--cases", default=None, help="case file (default: comparisons/cases.toml)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--engines", nargs="+", default=list(ENGINES), choices=ENGINES)
    ap.add_argument("--only", nargs="+", default=None, help="case names to run (default: all)")
    ap.add_argument("--quick", action="store_true", help="one rung per engine (a smoke run)")
    ap.add_argument("--to-aim", action="store_true",
                    help="walk each sub-ladder only up to the aim, repeat only the rungs within it (the ratios)")
    ap.add_argument("--short", action="store_true",
                    help=f"--to-aim on {', '.join(SHORT_CASES)} with one repeat (unless --repeats/--only say)")
    ap.add_argument("--no-compile", action="store_true", help="skip the start-up measurement")
    ap.add_argument("--compile-only", action="store_true",
                    help="only measure the start-up and add it to an existing work_precision.json in --out")
    a = ap.parse_args(argv)
    if a.short:
        a.to_aim = True
        a.only = a.only or list(SHORT_CASES)
        a.repeats = a.repeats if any(x.startswith("--repeats") for x in (argv if argv is not None else sys.argv)) else 1
    if a.repeats < 1:
        print(f"--repeats = {a.repeats}: must be >= 1", file=sys.stderr)
        return 2
    out = Path(a.out) / "work_precision.json"
    if a.compile_only:
        report = json.loads(out.read_text()) if out.is_file() else {}
        report["compile"] = compile_times(a.engines)
        atomic_write_json(out, report)
        print(f"wrote {out}")
        return 0
    ladders = {e: (QUICK if a.quick else LADDERS)[e] for e in a.engines}
    # drive cycles only: a seismic case has no cycle to compare (benchmarks/bench_seismic.py times it)
    cases = [c for c in load_cases(a.cases) if (a.only is None or c.name in a.only) and not isinstance(c, SeismicCase)]
    report = {"aim": AIM, "metric": "last cycle max|F - F_ref| / max|F_ref|, F_ref: in-house rtol 1e-10",
              "work": "CPU seconds per cycle (process_time, model construction included), median",
              "machine": platform.platform(), "cpus": os.cpu_count(), "load_average_start": os.getloadavg(),
              "repeats": a.repeats, "to_aim": a.to_aim, "prune": PRUNE if a.to_aim else None,
              "ladders": ladders, "cases": []}
    report["warm_up_s"] = warm_up(cases, ladders)   # imports and compilation: before any timed run
    for case in cases:
        print(f"case {case.name}", flush=True)
        report["cases"].append(run_case(case, ladders, a.repeats, a.to_aim))
        atomic_write_json(out, report)   # partial results survive an interruption
    report["load_average_end"] = os.getloadavg()
    if not a.no_compile:
        report["compile"] = compile_times(a.engines)
    atomic_write_json(out, report)
    for c in report["cases"]:
        aim = {e: f"{v['cpu_per_cycle']:.3f} s ({v['dF']:.1e})" for e, v in c["at_aim"].items()}
        ratio = c["ratio_best_peer_over_in_house"]
        print(f"{c['name']}: at the aim {aim}; best peer / in-house = {ratio if ratio is None else round(ratio, 2)}")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
