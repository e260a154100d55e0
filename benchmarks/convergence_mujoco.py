"""Convergence study of the MuJoCo engine: discrepancy vs timestep and vs constraint softness.

For each drive case (A x f, ``--cycles`` cycles) the script runs the MuJoCo engine over
- a timestep ladder for each integrator (Euler, RK4; the step actually used divides the output
  interval, see MujocoEngine.run),
- a softness ladder of the loop-closing ``connect``: solref time constant (factor x timestep) and
  solimp impedance d,
and compares each run with a reference on the LAST cycle:
- dF = max|F - F_ref| / max|F_ref|,
- dA = (A - A_ref) / |A_ref|, with the loop area A = closed integral of F du over the last cycle.
Reference: ``nsd_core.device.simulate(params, drive, rtol=1e-10, atol=1e-12)`` (the in-house
semirecursive model) when that module exists, and always the finest MuJoCo run (RK4 at
``--ref-timestep``, Richardson-style: the ladder shows the error shrinking towards it). Both are
recorded; the JSON says which one each metric used.

    PYTHONPATH=. .venv/bin/python benchmarks/convergence_mujoco.py --out results/convergence
    PYTHONPATH=. .venv/bin/python benchmarks/convergence_mujoco.py --out /tmp/conv --quick
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from comparisons.engines.base import EngineError
from comparisons.engines.mujoco_engine import MujocoEngine
from nsd_core.device.drive import Drive
from nsd_core.device.params import Params
from nsd_core.device.results import atomic_write_json

from refcompare import discrepancy as metrics, in_house_reference


def run_one(engine, params, drive, settings):
    try:
        r = engine.run(params, drive, settings)
        return r, None
    except EngineError as exc:
        return None, str(exc)


def study_case(params: Params, drive: Drive, ladders: dict, ref_timestep: float) -> dict:
    eng = MujocoEngine()
    t0 = time.perf_counter()
    fine, err = run_one(eng, params, drive, {"integrator": "RK4", "timestep": ref_timestep})
    if fine is None:
        return {"error": f"reference run failed: {err}"}
    house, house_note = in_house_reference(params, drive)
    case = {"amplitude": drive.amplitude, "frequency": drive.frequency, "cycles": drive.cycles,
            "finest_mujoco": {"settings": {"integrator": "RK4", "timestep": fine.stats["timestep"]},
                              "wall_time": fine.stats["wall_time"], "closure_max": fine.stats["closure_max"]},
            "in_house": house_note if house is None else {"source": house_note},
            "runs": []}
    if house is not None:
        case["in_house"]["finest_mujoco_vs_in_house"] = metrics(fine, house, drive)
    for label, settings in ladders:
        r, err = run_one(eng, params, drive, settings)
        row = {"study": label, "settings": settings}
        if r is None:
            row["error"] = err
        else:
            row.update(timestep=r.stats["timestep"], steps=r.stats["steps"], wall_time=r.stats["wall_time"],
                       closure_max=r.stats["closure_max"], tracking_error=r.stats["tracking_error"],
                       vs_finest_mujoco=metrics(r, fine, drive))
            if house is not None:
                row["vs_in_house"] = metrics(r, house, drive)
        case["runs"].append(row)
        m = row.get("vs_in_house", row.get("vs_finest_mujoco", {}))
        print(f"  {label:9s} {settings}  dF={m.get('dF', float('nan')):.2e}  dA={m.get('dA', float('nan')):+.2e}"
              f"  wall={row.get('wall_time', float('nan')):.1f}s  {row.get('error', '')}", flush=True)
    case["wall_time"] = time.perf_counter() - t0
    return case


def ladders(quick: bool):
    steps = {"Euler": [4e-5, 2e-5, 1e-5] + ([] if quick else [5e-6]),
             "RK4": [5e-5, 2.5e-5] + ([] if quick else [1e-5])}
    out = [("timestep", {"integrator": k, "timestep": h}) for k, hs in steps.items() for h in hs]
    out += [("commit", {"commit_every": k}) for k in ([1, 5] if quick else [1, 5, 20])]
    out += [("solref", {"solref_factor": k}) for k in ([4, 10] if quick else [3, 4, 10, 30])]
    out += [("solimp", {"solimp": [d, d, 0.001, 0.5, 2.0]}) for d in ([0.999, 0.99] if quick else [0.9999, 0.999, 0.99, 0.9])]
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="folder for convergence_mujoco.json")
    ap.add_argument("--amplitudes", type=float, nargs="+", default=[0.015, 0.0255])
    ap.add_argument("--frequencies", type=float, nargs="+", default=[1.0, 10.0])
    ap.add_argument("--cycles", type=int, default=2)
    ap.add_argument("--ref-timestep", type=float, default=5e-6, help="RK4 step of the finest MuJoCo run")
    ap.add_argument("--quick", action="store_true", help="10 Hz only, shorter ladders")
    a = ap.parse_args(argv)
    freqs = [10.0] if a.quick else a.frequencies
    params = Params()
    report = {"engine": "mujoco", "defaults": MujocoEngine.default_settings,
              "metrics": "last cycle: dF = max|F - F_ref|/max|F_ref|, dA = relative loop-area difference",
              "cases": []}
    for f in freqs:
        for amp in a.amplitudes:
            drive = Drive(amp, f, cycles=a.cycles)
            print(f"case A = {amp} m, f = {f} Hz", flush=True)
            report["cases"].append(study_case(params, drive, ladders(a.quick), a.ref_timestep))
            atomic_write_json(Path(a.out) / "convergence_mujoco.json", report)  # partial results survive
    print(f"wrote {Path(a.out) / 'convergence_mujoco.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
