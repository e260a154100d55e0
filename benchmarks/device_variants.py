"""The device as a user varies it, through ``nsd compare --model --refine``: its description written by
``nsd_core.device.describe`` for each path, direction and parameter set below (none of which the gate's
limits or the description's default steps were measured on), every engine, the verdicts as first
judged and after --refine.

    python benchmarks/device_variants.py --out DIR      (DIR/device_variants.json; each variant's folder)

A verdict that says "disagrees" on a correct model is a harness bug (docs/validation.md's campaign);
"not converged" says the case's steps are too coarse for that peer, which --refine's one re-run may not
cure (its cost cap: 8x the steps).
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

# name -> (amplitude [m], frequency [Hz], direction [deg], path, minor axis [m] or None, parameter overrides)
VARIANTS = {
    "circle_A15mm_f10Hz": (0.015, 10.0, 0.0, "circle", None, {}),
    "figure8_A15mm_f10Hz": (0.015, 10.0, 0.0, "figure8", None, {}),
    "ellipse_A20mm_B10mm_f10Hz": (0.02, 10.0, 0.0, "ellipse", 0.01, {}),
    "line_psi30_A20mm_f10Hz": (0.02, 10.0, 30.0, "line", None, {}),
    "line_psi90_A15mm_f10Hz_3wires": (0.015, 10.0, 90.0, "line", None, {"n_wires": 3}),
    "line_psi90_A15mm_f10Hz": (0.015, 10.0, 90.0, "line", None, {}),
    "line_A25.5mm_f10Hz_8wires_k7.5e5": (0.0255, 10.0, 0.0, "line", None, {"n_wires": 8, "rope_stiffness": 7.5e5}),
    "circle_A22mm_f5Hz_6wires": (0.022, 5.0, 0.0, "circle", None, {"n_wires": 6}),
}


def description(amplitude, frequency, direction, path, minor, overrides) -> str:
    import comparisons  # noqa: F401  (registers the device's laws and motions)
    from nsd_core.device.describe import device_description
    from nsd_core.device.drive import Drive
    from nsd_core.device.params import Params, with_overrides
    params = with_overrides(Params(), overrides)
    drive = None if path == "line" else Drive(amplitude, frequency, direction_deg=direction, path=path, minor=minor)
    return device_description(params, amplitude, frequency, direction, drive=drive)


def verdicts(stdout: str, case: str) -> tuple[dict, dict]:
    """engine -> (PASS/FAIL, text) of the first table and of the refined one (the last table)."""
    tables, current = [], None
    for line in stdout.splitlines():
        if line.startswith("model "):
            current = {}
            tables.append(current)
        elif current is not None and line.split()[:1] == [case] and len(line.split()) > 2:
            _, engine, word, *rest = line.split(maxsplit=3)
            current[engine] = {"pass": word == "PASS", "text": rest[0] if rest else ""}
    return (tables[0] if tables else {}), (tables[-1] if tables else {})


def run(name: str, spec: tuple, out: Path) -> dict:
    folder = out / name
    folder.mkdir(parents=True, exist_ok=True)
    model = folder / "model.toml"
    model.write_text(description(*spec))
    start = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "nsd_cli.main", "compare", "--model", str(model), "--refine",
                        "--out", str(folder / "compare")], capture_output=True, text=True, cwd=ROOT)
    wall = time.perf_counter() - start
    result = json.loads((folder / "compare" / "results.json").read_text()) if p.returncode in (0, 1) else {}
    case = next(iter(result.get("cases", {})), "")
    first, last = verdicts(p.stdout, case)
    amplitude, frequency, direction, path, minor, overrides = spec
    return {"name": name, "amplitude_m": amplitude, "frequency_hz": frequency, "direction_deg": direction, "path": path,
            "minor_m": minor, "params": overrides, "exit_code": p.returncode, "wall_s": wall, "case": case,
            "first": first, "refined": last, "refinements": result.get("refined", []),
            "excluded_samples": (result.get("cases", {}).get(case) or {}).get("excluded_samples", {}),
            "stderr": p.stderr[-400:] if p.returncode not in (0, 1) else ""}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--variants", default=",".join(VARIANTS), help="comma-separated names (default: all)")
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for name in a.variants.split(","):
        rows.append(run(name, VARIANTS[name], out))
        r = rows[-1]
        print(f"{name}: exit {r['exit_code']}, {r['wall_s']:.0f} s: "
              + ", ".join(f"{e} {'PASS' if v['pass'] else 'FAIL'}" for e, v in r["refined"].items()), flush=True)
    disagrees = sum("disagrees" in v["text"] for r in rows for t in ("first", "refined") for v in r[t].values())
    (out / "device_variants.json").write_text(json.dumps({"variants": rows, "disagrees": disagrees}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
