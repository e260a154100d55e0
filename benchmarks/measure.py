"""Run one measurement behind docs/validation.md or docs/performance.md and commit its JSON.

    python -m benchmarks.measure NAME [NAME ...]      (NAME: see MEASUREMENTS; `all` for every one)
    python -m benchmarks.measure --short NAME ...      (the benchmark's short mode, where it has one: SHORT)

Each measurement is a project command run as a user runs it, in a fresh process, into a temporary
folder; what the documents need is kept in ``benchmarks/results/NAME.json`` together with the
command, the date (UTC), the machine, its CPU count and load average before and after, the installed
versions and the git commit. ``python -m benchmarks.docs`` then regenerates the documents' tables
from these files. A run on a machine whose load average exceeded its CPU count (before the command; after
it, the CPU count + 1, the command's own processes counting there) is marked "loaded"
(its times are then longer than on a quiet machine; its accuracy figures are not affected).
"""
from __future__ import annotations

import csv
import datetime as dt
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
NSD = [sys.executable, "-m", "nsd_cli.main"]
PY = [sys.executable]

# name -> (command with OUT for the temporary folder, the file it writes, what to keep)
MEASUREMENTS = {
    "compare": (NSD + ["compare", "--convergence", "--out", "OUT"], "results.json", "compare"),
    # the per-run verdict on a variant no limit was derived for, as judged and after --refine; its power
    "compare_variant": (NSD + ["compare", "--set", "n_wires=8", "--set", "rope_stiffness=7.5e5", "--out", "OUT"],
                        "results.json", "compare"),
    "compare_variant_refine": (NSD + ["compare", "--set", "n_wires=8", "--set", "rope_stiffness=7.5e5", "--refine",
                                      "--out", "OUT"], "results.json", "compare"),
    "power": (NSD + ["compare", "--power", "--power-size", "0.001", "--power-profiles", "default", "--power-cases",
                     "A15mm_f1Hz,A15mm_f10Hz,A25.5mm_f10Hz,seismic_nf1_pulse", "--out", "OUT"], "power.json", "json"),
    "bench_verdict_cost": (PY + ["benchmarks/bench_verdict_cost.py", "--baseline", "cc555d9", "--repeats", "2",
                                 "--out", "OUT"], "bench_verdict_cost.json", "json"),
    # the README's first command (install, cold compare with its report) and the warm gate: the code
    # before the per-run verdict (cc555d9, fixed limits: bench_verdict_cost's baseline) against this one,
    # in fresh clones, side by side (benchmarks/bench_first_command.py)
    "bench_first_command": (PY + ["benchmarks/bench_first_command.py", "--revisions", "cc555d9,HEAD", "--out", "OUT"],
                            "bench_first_command.json", "json"),
    # the README's test command in fresh clones on empty caches, three times (benchmarks/bench_test_command.py)
    "bench_test_command": (PY + ["benchmarks/bench_test_command.py", "--repeats", "3", "--out", "OUT"],
                           "bench_test_command.json", "json"),
    # nsd report on the default gate's folder under matplotlib 3.11 (its text shaping) and the pinned 3.10
    "bench_report": (PY + ["benchmarks/bench_report.py", "--matplotlib", "3.11.2,3.10.9", "--repeats", "3", "--out",
                           "OUT"], "bench_report.json", "json"),
    # a user's first nsd compare --model: on an empty cache, and a new description after nsd warm (bench_model_first)
    "bench_model_first": (PY + ["benchmarks/bench_model_first.py", "--out", "OUT"], "bench_model_first.json", "json"),
    # the peers' gate runs with subnormal numbers flushed (as shipped) and kept, side by side
    "bench_subnormals": (PY + ["benchmarks/bench_subnormals.py", "--repeats", "3", "--out", "OUT"],
                         "bench_subnormals.json", "json"),
    # Exudyn's compiled forces, revision against revision (the kernels' time and the runs that spend it)
    "bench_exudyn_forces": (PY + ["benchmarks/bench_exudyn_forces.py", "--revisions", "984438c,87c4a8e", "--repeats",
                                  "3", "--out", "OUT"], "bench_exudyn_forces.json", "json"),
    "tables": (NSD + ["tables", "--out", "OUT"], "tables.csv", "csv"),
    # every mechanism description in models/ through nsd compare --model, in every engine
    "bench_models": (PY + ["benchmarks/bench_models.py", "--out", "OUT"], "bench_models.json", "json"),
    # 300 generated mechanisms through every engine, each non-PASS refined and classified (docs/validation.md)
    "campaign": (PY + ["benchmarks/campaign.py", "--seeds", "0-299", "--out", "OUT"], "campaign.json", "json"),
    # (bench_model_builders, bench_described_gate, bench_gate_described: the peers' hand-written adapters
    # against their described models, side by side, before the adapters were removed; their results stay
    # in results/, their scripts in the git history)
    "benchmark": (NSD + ["benchmark", "--out", "OUT"], "results.json", "json"),
    "polar": (NSD + ["polar", "--out", "OUT"], "polar.json", "json"),
    # the device's two in-house models (hand-built: the product; description-built: the check) side by side
    "bench_device_models": (PY + ["benchmarks/bench_device_models.py", "--repeats", "3", "--out", "OUT"],
                            "bench_device_models.json", "json"),
    "bench_cycle": (PY + ["benchmarks/bench_cycle.py", "--no-compile", "--repeats", "3", "--out", "OUT"],
                    "bench_cycle.json", "json"),
    "bench_seismic": (PY + ["benchmarks/bench_seismic.py", "--no-compile", "--repeats", "3", "--out", "OUT"],
                      "bench_seismic.json", "json"),
    # one evaluation (generated and generic) and its parts; the cold and the warm gate, a record set on warm workers, the ratios at the 1e-4 aim
    "bench_rhs": (PY + ["benchmarks/bench_rhs.py", "--out", "OUT"], "bench_rhs.json", "json"),
    "bench_start": (PY + ["benchmarks/bench_start.py", "--repeats", "3", "--out", "OUT"], "bench_start.json", "json"),
    "compile_units": (PY + ["benchmarks/compile_units.py", "--out", "OUT"], "compile_units.json", "json"),
    "bench_record_set": (PY + ["benchmarks/bench_record_set.py", "--repeats", "3", "--out", "OUT"],
                         "bench_record_set.json", "json"),
    "work_precision": (PY + ["benchmarks/work_precision.py", "--to-aim", "--no-compile", "--repeats", "3", "--out",
                             "OUT"], "work_precision.json", "json"),
    # a newcomer's first commands on an empty cache (and how often each compiles); the peers per
    # model second on the gate's seismic cases
    "bench_cold": (PY + ["benchmarks/bench_cold.py", "--out", "OUT"], "bench_cold.json", "json"),
    "bench_peer_seismic": (PY + ["benchmarks/bench_peer_seismic.py", "--repeats", "3", "--out", "OUT"],
                           "bench_peer_seismic.json", "json"),
    # the gate's CSVs written with Python's "%.10g" and read back, against the compiled writer
    "bench_csv_text": (PY + ["benchmarks/bench_csv_text.py", "--repeats", "3", "--out", "OUT"],
                       "bench_csv_text.json", "json"),
}
MEASUREMENTS.update({
    # the symbolic engine: the derived equations of one small mechanism, and every benchmark description
    "symbolic_equations": (PY + ["benchmarks/bench_symbolic.py", "equations", "--out", "OUT"],
                           "symbolic_equations.json", "json"),
    "symbolic_models": (PY + ["benchmarks/bench_symbolic.py", "models", "--out", "OUT"], "symbolic_models.json", "json"),
    # the device's drive description in the symbolic engine (its case: two cycles at 1 Hz, A = 15 mm)
    "symbolic_device": (PY + ["benchmarks/bench_symbolic.py", "models", "--models", "nsd_drive", "--out", "OUT"],
                        "symbolic_models.json", "json"),
    # ten generated mechanisms with the symbolic engine as a 4th peer (and the referee where a peer disagrees)
    # the device's own description on paths, directions and parameter sets the gate was not tuned on
    "device_variants": (PY + ["benchmarks/device_variants.py", "--out", "OUT"], "device_variants.json", "json"),
    "campaign_symbolic": (PY + ["benchmarks/campaign.py", "--seeds", "0-9", "--engines",
                                "semirecursive,mujoco,exudyn,symbolic", "--workers", "1", "--timeout", "1200", "--out",
                                "OUT"], "campaign.json", "json"),
})
SHORT = ("bench_start", "bench_record_set", "work_precision", "bench_peer_seismic")   # their --short: fewer cases or records, 1 repeat


def _git_commit() -> str:
    p = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True)
    # the measurements' own JSON (written one after another by `measure A B ...`) is not code
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", ".",
                            ":(exclude)benchmarks/results"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    return p.stdout.strip() + (" (with uncommitted changes)" if dirty else "")


def _keep_compare(data: dict) -> dict:
    """The gate's verdict, every metric with its limit, each run's status, time and (in-house) evaluation,
    the convergence."""
    runs = {c: {e: {**{k: r.get(k) for k in ("status", "message", "wall_time", "cpu_time")},
                    "evaluation": (r.get("stats") or {}).get("evaluation")} for e, r in per.items()}
            for c, per in data["runs"].items()}
    keep = {"verdict": data.get("verdict"), "exit_code": data.get("exit_code"),
            "total_wall_time": data.get("total_wall_time"), "metrics": data["metrics"], "runs": runs,
            "cases": data.get("cases"), "rule": data.get("rule"), "verdicts": data.get("verdicts"),
            "refined": data.get("refined"), "failures": data.get("failures")}
    if "convergence" in data:
        keep["convergence"] = data["convergence"]
    return keep


def command(name: str, short: bool = False) -> list[str]:
    """The measurement's command; ``short``: its --short mode, with that mode's own repeat count."""
    cmd = MEASUREMENTS[name][0]
    if not short:
        return list(cmd)
    i = cmd.index("--repeats") if "--repeats" in cmd else None
    cmd = cmd[:i] + cmd[i + 2:] if i is not None else list(cmd)
    return cmd[:-2] + ["--short"] + cmd[-2:]


def measure(name: str, short: bool = False) -> dict:
    _, produced, kind = MEASUREMENTS[name]
    cmd = command(name, short)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        argv = [str(out) if a == "OUT" else a for a in cmd]
        commit = _git_commit()  # the code that runs (before, not after: edits during a run are not its code)
        load0, t0 = os.getloadavg(), time.perf_counter()
        env = {**os.environ, "MPLBACKEND": "Agg"}
        p = subprocess.run(argv, cwd=ROOT, capture_output=True, text=True, env=env)
        wall, load1 = time.perf_counter() - t0, os.getloadavg()
        if not (out / produced).is_file():
            raise SystemExit(f"{name}: {' '.join(argv)} exited {p.returncode} without {produced}:\n{p.stderr[-2000:]}")
        if kind == "csv":
            with open(out / produced, newline="") as f:
                data = list(csv.DictReader(f))
        else:
            data = json.loads((out / produced).read_text())
            if kind == "compare":
                data = _keep_compare(data)
    from nsd_core.device.results import versions
    cpus = os.cpu_count() or 1
    shown = " ".join("python" if a == sys.executable else a for a in cmd[:1]) + " " + " ".join(cmd[1:])
    rec = {"name": name, "command": shown.replace("python -m nsd_cli.main", "nsd").replace("OUT", "DIR"),
            "exit_code": p.returncode,
            "measured": {"date_utc": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M"),
                         "machine": platform.platform(), "processor": platform.machine(), "cpus": cpus,
                         "load_average_before": [round(x, 2) for x in load0],
                         "load_average_after": [round(x, 2) for x in load1],
                         "wall_s": wall,
                         "versions": versions(), "git_commit": commit},
            "data": data}
    from benchmarks.docs_common import loaded
    rec["measured"]["loaded"] = loaded(rec["measured"])
    return rec


def main(argv: list[str] | None = None) -> int:
    names = list(argv if argv is not None else sys.argv[1:]) or ["--help"]
    short = "--short" in names
    names = [n for n in names if n != "--short"] or ["--help"]
    if names[0] in ("-h", "--help"):
        print(__doc__.strip() + "\n\nmeasurements: " + ", ".join(MEASUREMENTS) + "; with --short: " + ", ".join(SHORT))
        return 0
    if names == ["all"]:
        names = [n for n in MEASUREMENTS if not short or n in SHORT]
    for n in names:
        if n not in MEASUREMENTS:
            print(f"measure: {n!r}: unknown; allowed: {', '.join(MEASUREMENTS)}, all", file=sys.stderr)
            return 2
        if short and n not in SHORT:
            print(f"measure: --short {n}: no short mode; those with one: {', '.join(SHORT)}", file=sys.stderr)
            return 2
    RESULTS.mkdir(parents=True, exist_ok=True)
    from nsd_core.common.files import atomic_write_json
    for n in names:
        print(f"measuring {n} ...", file=sys.stderr, flush=True)
        rec = measure(n, short)
        atomic_write_json(RESULTS / f"{n}.json", rec)
        m = rec["measured"]
        print(f"{n}: exit {rec['exit_code']}, {m['wall_s']:.1f} s, load {m['load_average_before'][0]} -> "
              f"{m['load_average_after'][0]} on {m['cpus']} CPUs{' (loaded)' if m['loaded'] else ''}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
