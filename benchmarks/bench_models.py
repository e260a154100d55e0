"""Every mechanism description under models/ through ``nsd compare --model`` in every engine: the
verdicts, each engine's largest difference over its bound and error over its tolerance, and each
run's wall time. Kept in benchmarks/results/bench_models.json; docs/validation.md's table is made
from it (python -m benchmarks.docs).

    python -m benchmarks.measure bench_models
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODELS = ("andrews", "iftomm_a01_pendulum", "iftomm_a02_fourbar", "iftomm_a04_bricard", "slider_crank",
          "fourbar_spring", "nsd_drive", "nsd_seismic", "nsd_building")


def summarise(results: dict) -> dict:
    out = {"model": results["model"], "passed": results["passed"], "cases": {}}
    for case, c in results["cases"].items():
        rows = [r for r in results["rows"] if r["case"] == case]
        engines = {}
        for e, v in c["verdicts"].items():
            mine = [r for r in rows if r["engine"] == e]
            ratios = [r["value"] / r["bound"] for r in mine if r.get("bound")]
            errors = [max(r["estimate"] or 0.0, r["value"]) / r["tolerance"] for r in mine
                      if r.get("bound") and r.get("consistent") is not False]
            engines[e] = {"pass": v["pass"], "text": v.get("text", ""),
                          "worst_ratio": max(ratios) if ratios else None,
                          "worst_error": max(errors) if errors else None,
                          "wall_time": c["runs"].get(e, {}).get("wall_time"),
                          "steps": c["runs"].get(e, {}).get("steps"),
                          "settings": {k: v for k, v in c["runs"].get(e, {}).items()
                                       if k in ("timestep", "step_size", "rtol", "integrator", "solver")}}
        out["cases"][case] = {"duration": c["duration"], "reference": (c.get("reference") or {}).get("source"),
                              "engines": engines}
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser()
    p.add_argument("--out", required=True)
    p.add_argument("--models", default=",".join(MODELS))
    a = p.parse_args(argv)
    res = {}
    for name in a.models.split(","):
        with tempfile.TemporaryDirectory() as tmp:
            start = time.perf_counter()
            proc = subprocess.run([sys.executable, "-m", "nsd_cli.main", "compare", "--model",
                                   str(ROOT / "models" / f"{name}.toml"), "--out", tmp], capture_output=True, text=True)
            wall = time.perf_counter() - start
            try:
                data = json.loads((Path(tmp) / "results.json").read_text())
            except OSError:
                res[name] = {"exit_code": proc.returncode, "error": proc.stderr.strip().splitlines()[-1:]}
                continue
            res[name] = {**summarise(data), "exit_code": proc.returncode, "command_wall_time": wall}
        print(name, res[name].get("passed"), f"{wall:.1f} s", flush=True)
    Path(a.out).mkdir(parents=True, exist_ok=True)
    (Path(a.out) / "bench_models.json").write_text(json.dumps(res, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
