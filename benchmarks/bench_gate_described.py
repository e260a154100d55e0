"""The gate itself on its drive and seismic cases, once through the peers' hand-written adapters and
once through their description builders (``model = "described"``: comparisons/engines/described.py,
described_seismic.py), by the same rule and every metric of the gate (force, loop work, peak, regions,
closure, tracking, energy balance; seismic: displacement, device force, peaks, floors): the evidence
issue 32 asks for before an adapter goes.

Writes two cases files from comparisons/cases.toml (its cases, unchanged; the second with ``model =
"described"`` for both peers: for the drive cases in ``[defaults.settings]``, with Exudyn's
``builder_forces``; for the seismic cases, which take no [defaults] settings, in each case's own
``settings``), runs ``nsd compare --cases FILE`` on each, and keeps per case and peer: the verdict and
its text, every gated metric with its bound, and the h run's CPU seconds (a warm worker's, so load
affects it less than wall time).

Then each drive case's cost, interleaved in this one process, adapter then described, each peer's whole
run timed from outside (CPU seconds of ``run_engine``, the model's build included for both paths: a
drive adapter's own ``cpu_time`` stat covers its stepping only, so the first table's ratios lean
against the builders), the fastest of ``--repeats`` rounds. Then the seismic cases' cost, interleaved in this one process so that load affects both paths alike:
per case and peer, after one untimed warm-up of each path (its compilation), ``--repeats`` rounds of
the adapter's run then the described run (comparisons.engines.run_seismic_engine: the model's build
included), each run's CPU seconds and its wall seconds per model second, with the load average.

    python -m benchmarks.bench_gate_described --out benchmarks/results/bench_gate_described.json
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import tomli_w

ROOT = Path(__file__).resolve().parents[1]
PEERS = ("mujoco", "exudyn")


def cases_file(folder: Path, described: bool, exudyn_forces: str, modes=("drive", "seismic"),
               seismic_forces: str = "compiled") -> Path:
    raw = tomllib.loads((ROOT / "comparisons" / "cases.toml").read_text())
    raw = {"defaults": raw.get("defaults", {}), "case": [c for c in raw["case"] if c.get("mode", "drive") in modes]}
    # each model named (the peers' default is "described": comparisons.engines.base.DEFAULT_MODEL)
    model = "described" if described else "adapter"
    forces = {"drive": {"builder_forces": exudyn_forces} if described else {},
              "seismic": {"builder_forces": seismic_forces} if described else {}}
    settings = raw["defaults"].setdefault("settings", {})
    settings["mujoco"] = {**settings.get("mujoco", {}), "model": model}
    settings["exudyn"] = {**settings.get("exudyn", {}), "model": model, **forces["drive"]}
    for c in raw["case"]:   # a seismic case takes no [defaults] settings: its own
        if c.get("mode") == "seismic":
            own = c.setdefault("settings", {})
            own["mujoco"] = {**own.get("mujoco", {}), "model": model}
            own["exudyn"] = {**own.get("exudyn", {}), "model": model, **forces["seismic"]}
    path = folder / ("cases_described.toml" if described else "cases_adapters.toml")
    path.write_text(tomli_w.dumps(raw))
    return path


def compare(cases: Path, out: Path) -> dict:
    cmd = [sys.executable, "-m", "nsd_cli.main", "compare", "--cases", str(cases), "--out", str(out)]
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if not (out / "results.json").is_file():
        raise SystemExit(f"nsd compare exited {p.returncode} without results.json: {p.stderr.strip()[-400:]}")
    return {"exit_code": p.returncode, **json.loads((out / "results.json").read_text())}


def metrics(res: dict, case: str, engine: str) -> dict:
    """Every gated metric of one engine on one case against the reference: value, bound, pass."""
    return {r["metric"]: {"value": r["value"], "estimate": r.get("estimate"), "bound": r.get("bound"),
                          "tolerance": r.get("tolerance"), "pass": r["pass"]}
            for r in res.get("metrics", []) if r.get("case") == case and r.get("engine") == engine
            and r.get("reference") == "converged"}


def seismic_timing(repeats: int) -> dict:
    """Each seismic case's runs, adapter then described, interleaved (see the module's docstring)."""
    from comparisons.config import SeismicCase, load_cases
    from comparisons.engines import run_seismic_engine
    from nsd_core.device.warmup import TINY_DT_OUT, TINY_DURATION, tiny_ground
    out = {}
    for case in (c for c in load_cases() if isinstance(c, SeismicCase)):
        st, row = case.isolated_structure(), {}
        for e in PEERS:
            given = case.settings.get(e, {})
            paths = {"adapter": {**given, "model": "adapter"}, "described": {**given, "model": "described"}}
            for settings in paths.values():   # compile this structure's code once, untimed
                run_seismic_engine(e, case.params_for(e), st, tiny_ground(), TINY_DURATION, TINY_DT_OUT, settings)
            runs = {p: [] for p in paths}
            for _ in range(repeats):
                for path, settings in paths.items():
                    load = os.getloadavg()[0]
                    t0 = time.perf_counter()
                    r = run_seismic_engine(e, case.params_for(e), st, case.ground, case.duration, case.dt_out, settings)
                    wall = time.perf_counter() - t0
                    runs[path].append({"cpu_s": r.stats["cpu_time"], "wall_s_per_model_s": wall / case.model_duration,
                                       "load_before": load})
                    print(f"{case.name:24s} {e:7s} {path:10s} cpu {r.stats['cpu_time']:7.2f} s  wall "
                          f"{wall / case.model_duration:7.2f} s/model s  (load {load:.1f})", flush=True)
            best = {p: min(x["cpu_s"] for x in v) for p, v in runs.items()}
            row[e] = {"runs": runs, "cpu_ratio_described_over_adapter": best["described"] / best["adapter"]}
        out[case.name] = {"model_duration_s": case.model_duration, **row}
    return out


def drive_timing(repeats: int) -> dict:
    """Each drive case's runs, adapter then described, interleaved in this one process, each timed from
    outside (CPU seconds of the whole ``run_engine`` call, the model's build included, for both paths:
    the adapters' own ``cpu_time`` covers their stepping only). An untimed run of the warm-up's tiny
    drive first compiles each path's code (run_engine's warm-up is then cached)."""
    from comparisons.config import Case, load_cases
    from comparisons.engines import run_engine
    from nsd_core.device.warmup import tiny_drive
    out = {}
    for case in (c for c in load_cases() if isinstance(c, Case)):
        row = {}
        for e in PEERS:
            given = case.settings.get(e, {})
            paths = {"adapter": {**given, "model": "adapter"}, "described": {**given, "model": "described"}}
            for settings in paths.values():
                run_engine(e, case.params_for(e), tiny_drive("line" if case.drive.is_line else "circle"), settings)
            runs = {p: [] for p in paths}
            for _ in range(repeats):
                for path, settings in paths.items():
                    load = os.getloadavg()[0]
                    t0, c0 = time.perf_counter(), time.process_time()
                    run_engine(e, case.params_for(e), case.drive, settings)
                    cpu, wall = time.process_time() - c0, time.perf_counter() - t0
                    runs[path].append({"cpu_s": cpu, "wall_s": wall, "load_before": load})
                    print(f"{case.name:24s} {e:7s} {path:10s} cpu {cpu:7.3f} s  wall {wall:7.3f} s  (load {load:.1f})",
                          flush=True)
            best = {p: min(x["cpu_s"] for x in v) for p, v in runs.items()}
            row[e] = {"runs": runs, "cpu_ratio_described_over_adapter": best["described"] / best["adapter"]}
        out[case.name] = row
    return out


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="JSON file (or folder) to write")
    ap.add_argument("--exudyn-forces", default="predicted", choices=("compiled", "predicted"))
    ap.add_argument("--exudyn-seismic-forces", default="compiled", choices=("compiled", "predicted"))
    ap.add_argument("--modes", default="drive,seismic", help="the cases' modes to run: drive, seismic or both")
    ap.add_argument("--repeats", type=int, default=2, help="interleaved rounds of the drive and seismic timing (0: none)")
    args = ap.parse_args(argv)
    modes = tuple(m.strip() for m in args.modes.split(","))
    rows, loads = {}, {}
    with tempfile.TemporaryDirectory(prefix="bench_gate_described_") as tmp:
        tmp = Path(tmp)
        for described in (False, True):
            label = "described" if described else "adapters"
            loads[label] = [os.getloadavg()[0]]
            res = compare(cases_file(tmp, described, args.exudyn_forces, modes, args.exudyn_seismic_forces),
                          tmp / label)
            loads[label].append(os.getloadavg()[0])
            rows[label] = {"exit_code": res["exit_code"], "verdict": res["verdict"], "failures": res.get("failures"),
                           "cases": {
                case: {e: {"pass": v[e]["pass"], "text": v[e]["text"],
                           "cpu_s": res["runs"][case][e].get("cpu_time"),
                           "wall_s": res["runs"][case][e].get("wall_time"), "metrics": metrics(res, case, e)}
                       for e in PEERS if e in v}
                for case, v in res["verdicts"].items()}}
    def cpu(label, case, e):   # None where that run has no verdict (an engine's failure: its text says why)
        return rows[label]["cases"].get(case, {}).get(e, {}).get("cpu_s")
    ratio = {case: {e: (cpu("described", case, e) / cpu("adapters", case, e)
                        if cpu("described", case, e) and cpu("adapters", case, e) else None)
                    for e in PEERS} for case in rows["adapters"]["cases"]}
    timing = seismic_timing(args.repeats) if "seismic" in modes and args.repeats > 0 else {}
    drive = drive_timing(args.repeats) if "drive" in modes and args.repeats > 0 else {}
    out = {"exudyn_forces": args.exudyn_forces,
           "exudyn_seismic_forces": args.exudyn_seismic_forces, "load_average_before_after": loads, "runs": rows,
           "cpu_ratio_described_over_adapter": ratio, "seismic_timing_interleaved": timing,
           "drive_timing_interleaved": drive,
           "machine": {"cpus": os.cpu_count(), "when": time.strftime("%Y-%m-%d %H:%M:%S")}}
    target = Path(args.out)
    if target.suffix != ".json":
        target = target / "bench_gate_described.json"
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(json.dumps(out, indent=1) + "\n")
    for case, r in ratio.items():
        print(case, {e: tuple(rows[label]["cases"].get(case, {}).get(e, {}).get("pass") for label in rows)
                     + (r[e] and round(r[e], 2),) for e in PEERS})
    return out


if __name__ == "__main__":
    main()
