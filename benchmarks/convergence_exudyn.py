"""Convergence study of the Exudyn engine: discrepancy vs step size, Newton tolerance and model options.

For each drive case (A x f, ``--cycles`` cycles) the Exudyn engine runs
- a step-size ladder with the default settings (the step used divides the output interval),
- a Newton-tolerance ladder (relative / absolute residual tolerance) at the default step,
- option variants at the default step: implicit per-residual user-function forces instead of the
  per-step loads (10 Hz only: ~4x slower), RK4 instead of Heun for the hysteretic states, the
  generalized-alpha spectral radius, a Jacobian update every step, the index-2 trapezoidal solver,
and each run is compared with two references on the LAST cycle:
- dF = max|F - F_ref| / max|F_ref|,
- dA = (A - A_ref) / |A_ref|, with A the loop area, the closed integral of F du over the last cycle.
References: the finest Exudyn run (the default settings at ``--ref-step``; the ladder shows the
error shrinking towards it at second order) and, when ``nsd_core.device.simulate`` exists,
the in-house semirecursive model at rtol = 1e-10, atol = 1e-12. The JSON records both metrics
per run, the step, wall and CPU times and the loop-closure violation.

    PYTHONPATH=. .venv/bin/python benchmarks/convergence_exudyn.py --out results/convergence
    PYTHONPATH=. .venv/bin/python benchmarks/convergence_exudyn.py --out /tmp/conv --quick --frequencies 10
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from comparisons.engines.base import EngineError
from comparisons.engines.exudyn_engine import ExudynEngine
from nsd_core.device.drive import Drive
from nsd_core.device.params import Params
from nsd_core.device.results import atomic_write_json

from refcompare import discrepancy as compare, in_house_reference


def ladders(drive: Drive, default_step: float, ref_step: float, quick: bool) -> list[tuple[str, dict]]:
    steps = [s for s in (8 * ref_step, 4 * ref_step, 2 * ref_step) if not quick or s <= 4 * ref_step]
    out = [("step", {"step_size": s}) for s in sorted(set(steps + [default_step]), reverse=True)]
    tols = [(1e-8, 1e-10), (1e-12, 1e-14)] if quick else [(1e-6, 1e-8), (1e-8, 1e-10), (1e-12, 1e-14)]
    out += [("newton", {"newton_rel_tol": r, "newton_abs_tol": a}) for r, a in tols]
    out += [("options", o) for o in ({"state_integrator": "rk4"}, {"spectral_radius": 0.8},
                                     {"newton_jacobian": "per_step"})]
    if not quick:
        out += [("options", {"solver": "trapezoidal_index2", "drive_offsets": "user_function"})]
    if drive.frequency >= 5.0:  # ~0.6 ms per step: affordable at 10 Hz only
        out += [("options", {"forces": "per_iteration"})]
    return out


def run(engine, params, drive, settings):
    try:
        return engine.run(params, drive, settings), None
    except EngineError as exc:
        return None, str(exc)


def study_case(params: Params, drive: Drive, default_step: float, ref_step: float, quick: bool,
               use_in_house: bool) -> dict:
    eng = ExudynEngine()
    finest, err = run(eng, params, drive, {"step_size": ref_step, "min_steps_per_cycle": 1})
    if finest is None:
        return {"amplitude": drive.amplitude, "frequency": drive.frequency, "error": f"finest run failed: {err}"}
    house, note = in_house_reference(params, drive) if use_in_house else (None, "in-house reference not requested")
    case = {"amplitude": drive.amplitude, "frequency": drive.frequency, "cycles": drive.cycles,
            "default_step": default_step, "in_house": note,
            "finest": {"step_size": finest.stats["step_size"], "wall_time": finest.stats["wall_time"],
                       "cpu_time": finest.stats["cpu_time"], "closure_max": finest.stats["closure_max"]},
            "runs": []}
    if house is not None:
        case["finest"]["vs_in_house"] = compare(finest, house, drive)
    for label, settings in ladders(drive, default_step, ref_step, quick):
        full = {"step_size": default_step, "min_steps_per_cycle": 1, **settings}
        r, err = run(eng, params, drive, full)
        row = {"study": label, "settings": full}
        if r is None:
            row["error"] = err
        else:
            row.update({k: r.stats[k] for k in ("step_size", "steps", "wall_time", "cpu_time", "closure_max",
                                                 "tracking_error", "newton_iterations")})
            row["vs_finest"] = compare(r, finest, drive)
            if house is not None:
                row["vs_in_house"] = compare(r, house, drive)
        case["runs"].append(row)
        m, mh = row.get("vs_finest", {}), row.get("vs_in_house", {})
        print(f"  {label:7s} {settings}  finest: dF={m.get('dF', np.nan):.1e} dA={m.get('dA', np.nan):+.1e}"
              f"  in-house: dF={mh.get('dF', np.nan):.1e} dA={mh.get('dA', np.nan):+.1e}"
              f"  cpu={row.get('cpu_time', np.nan):.1f}s wall={row.get('wall_time', np.nan):.1f}s"
              f" {row.get('error', '')}", flush=True)
    return case


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="folder for convergence_exudyn.json")
    ap.add_argument("--amplitudes", type=float, nargs="+", default=[0.015, 0.0255])
    ap.add_argument("--frequencies", type=float, nargs="+", default=[1.0, 10.0])
    ap.add_argument("--cycles", type=int, default=2)
    ap.add_argument("--ref-step", type=float, nargs=2, default=[6.25e-6, 2.5e-6], metavar=("AT_1HZ", "AT_10HZ"),
                    help="step of the finest Exudyn run below / from 5 Hz")
    ap.add_argument("--no-in-house", action="store_true", help="skip nsd_core.device.simulate")
    ap.add_argument("--quick", action="store_true", help="shorter ladders (combine with --frequencies 10)")
    a = ap.parse_args(argv)
    params = Params()
    defaults = ExudynEngine.default_settings
    report = {"engine": "exudyn", "defaults": defaults, "cases": [],
              "metrics": "last cycle: dF = max|F - F_ref|/max|F_ref|, dA = relative loop-area difference"}
    out = Path(a.out) / "convergence_exudyn.json"
    for f in a.frequencies:
        for amp in a.amplitudes:
            drive = Drive(amp, f, cycles=a.cycles)
            default_step = ExudynEngine.step_used(drive)
            ref_step = a.ref_step[1] if f >= 5.0 else a.ref_step[0]
            print(f"case A = {amp} m, f = {f} Hz (default step {default_step:.3g} s)", flush=True)
            report["cases"].append(study_case(params, drive, default_step, ref_step, a.quick, not a.no_in_house))
            atomic_write_json(out, report)  # partial results survive an interruption
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
