"""The gate itself on its drive cases, once through the peers' hand-written adapters and once through
their description builders (``model = "described"``: comparisons/engines/described.py), by the same
rule and every metric of the gate (force, loop work, peak, regions, closure, tracking, energy
balance): the evidence issue 32 asks for before an adapter goes.

Writes two cases files from comparisons/cases.toml (its drive cases, unchanged; the second with
``[defaults.settings.mujoco] model = "described"`` and ``[defaults.settings.exudyn] model =
"described", builder_forces = ...``), runs ``nsd compare --cases FILE`` on each, and keeps per case and
peer: the verdict and its text, and the h run's CPU seconds (a warm worker's, so load affects it
less than wall time).

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


def cases_file(folder: Path, described: bool, exudyn_forces: str) -> Path:
    raw = tomllib.loads((ROOT / "comparisons" / "cases.toml").read_text())
    raw = {"defaults": raw.get("defaults", {}), "case": [c for c in raw["case"] if c.get("mode", "drive") == "drive"]}
    if described:
        settings = raw["defaults"].setdefault("settings", {})
        settings["mujoco"] = {**settings.get("mujoco", {}), "model": "described"}
        settings["exudyn"] = {**settings.get("exudyn", {}), "model": "described", "builder_forces": exudyn_forces}
    path = folder / ("cases_described.toml" if described else "cases_adapters.toml")
    path.write_text(tomli_w.dumps(raw))
    return path


def compare(cases: Path, out: Path) -> dict:
    cmd = [sys.executable, "-m", "nsd_cli.main", "compare", "--cases", str(cases), "--out", str(out)]
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if not (out / "results.json").is_file():
        raise SystemExit(f"nsd compare exited {p.returncode} without results.json: {p.stderr.strip()[-400:]}")
    return {"exit_code": p.returncode, **json.loads((out / "results.json").read_text())}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="JSON file (or folder) to write")
    ap.add_argument("--exudyn-forces", default="predicted", choices=("compiled", "predicted"))
    args = ap.parse_args(argv)
    rows, loads = {}, {}
    with tempfile.TemporaryDirectory(prefix="bench_gate_described_") as tmp:
        tmp = Path(tmp)
        for described in (False, True):
            label = "described" if described else "adapters"
            loads[label] = [os.getloadavg()[0]]
            res = compare(cases_file(tmp, described, args.exudyn_forces), tmp / label)
            loads[label].append(os.getloadavg()[0])
            rows[label] = {"exit_code": res["exit_code"], "verdict": res["verdict"], "cases": {
                case: {e: {"pass": v[e]["pass"], "text": v[e]["text"],
                           "cpu_s": res["runs"][case][e].get("cpu_time"), "wall_s": res["runs"][case][e].get("wall_time")}
                       for e in PEERS if e in v}
                for case, v in res["verdicts"].items()}}
    ratio = {case: {e: (rows["described"]["cases"][case][e]["cpu_s"] / rows["adapters"]["cases"][case][e]["cpu_s"])
                    for e in PEERS} for case in rows["adapters"]["cases"]}
    out = {"exudyn_forces": args.exudyn_forces, "load_average_before_after": loads, "runs": rows,
           "cpu_ratio_described_over_adapter": ratio,
           "machine": {"cpus": os.cpu_count(), "when": time.strftime("%Y-%m-%d %H:%M:%S")}}
    target = Path(args.out)
    if target.suffix != ".json":
        target = target / "bench_gate_described.json"
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(json.dumps(out, indent=1) + "\n")
    for case, r in ratio.items():
        print(case, {e: (rows["adapters"]["cases"][case][e]["pass"], rows["described"]["cases"][case][e]["pass"],
                         round(r[e], 2)) for e in PEERS})
    return out


if __name__ == "__main__":
    main()
