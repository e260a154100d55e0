"""``nsd seismic``: the isolated structure on the device under a ground motion (Table 1, second row)
-> DIR/seismic.csv (time series, header with units) and DIR/summary.json (peaks, residual
displacement, energy balance, working-range events). Exit 4 when |u| reaches the rod's length."""
from __future__ import annotations

import argparse
import math

from nsd_cli.options import (Progress, add_param_arguments, add_solver_arguments, base_params, check_out_dir,
                             solver_settings)
from nsd_core.device.params import ParameterError

HELP = "seismic response of the isolated structure (in-house engine)"

def add_arguments(p: argparse.ArgumentParser) -> None:
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--record", metavar="SET:ID",
                     help="FEMA P695 record: farfield:1..22, nearfield:1..28, nearfield-pulse:1..14, "
                          "nearfield-no-pulse:15..28")
    src.add_argument("--ground", metavar="KIND:K=V,...",
                     help="synthetic input: harmonic:amplitude=A[m/s^2],frequency=f,azimuth=DEG,duration=T or "
                          "pulse:velocity=V[m/s],frequency=fp,gamma=G,phase=DEG,azimuth=DEG (Mavroeidis-Papageorgiou)")
    p.add_argument("--scale", default="1", help="factor on the record's (normalised) acceleration")
    p.add_argument("--window", metavar="T0,T1", help="part of the record, in the record's own seconds")
    p.add_argument("--rotate", default="0", metavar="DEG", help="rotation of the record pair in plan")
    p.add_argument("--time-factor", default=None,
                   help="model seconds per record second (default sqrt(0.1): Froude 1:10 similitude)")
    p.add_argument("--raw", action="store_true", help="the recorded acceleration, not FEMA P695's normalised one")
    p.add_argument("--duration", type=float, default=None,
                   help="model time to run [s] (default: the input's; longer adds free vibration)")
    p.add_argument("--dt-out", type=float, default=1e-3, help="output interval [s]")
    p.add_argument("--no-device", action="store_true", help="the supports alone (the isolation effect's reference)")
    p.add_argument("--engines", default="semirecursive",
                   help="semirecursive (the reference, always first) and any of mujoco, exudyn to cross-check: "
                        "each writes seismic_<engine>.csv; summary.json gets their differences")
    p.add_argument("--structure", action="append", default=[], metavar="NAME=VALUE",
                   help="override the default isolated structure: mass, stiffness, damping, "
                        "radius_of_gyration, support_radius (SI)")
    add_param_arguments(p)
    add_solver_arguments(p)
    p.add_argument("--out", required=True, help="output folder")


def ground_motion(args):
    """The GroundMotion the options describe (ParameterError on anything wrong)."""
    from nsd_core.device import ground
    if args.record is not None:
        set_, sep, rid = args.record.partition(":")
        if not sep or not rid.strip():
            raise ParameterError(f"--record {args.record!r}: expected SET:ID, e.g. nearfield-pulse:1")
        window = None
        if args.window is not None:
            parts = args.window.split(",")
            if len(parts) != 2:
                raise ParameterError(f"--window {args.window!r}: expected T0,T1 (record seconds)")
            window = parts
        tf = ground.SIMILITUDE_TIME_FACTOR if args.time_factor is None else args.time_factor
        return ground.fema_record(set_, rid.strip(), scale=args.scale, time_factor=tf, window=window,
                                  rotate_deg=args.rotate, normalised=not args.raw)
    for name in ("window", "time_factor"):
        if getattr(args, name) is not None:
            raise ParameterError(f"--{name.replace('_', '-')}: applies to --record only")
    from comparisons.seismic import parse_ground
    return parse_ground(args.ground, "--ground")


def run(args) -> int:
    from nsd_core.device.isolation import default_structure
    from nsd_core.device.model import DEFAULT_SOLVER
    from nsd_core.device.params import parse_set
    from nsd_core.device.results import atomic_write_json, versions, write_csv
    from nsd_core.device.seismic import seismic_summary, simulate_seismic
    from comparisons.engines import parse_engine_list, run_seismic_engine
    from comparisons.seismic import seismic_metrics
    params = base_params(args)
    engines = parse_engine_list(args.engines)
    if engines[0] != "semirecursive":
        raise ParameterError(f"--engines {args.engines!r}: semirecursive (the reference) must come first")
    if args.no_device and len(engines) > 1:
        raise ParameterError("--engines: the supports alone (--no-device) run on the in-house engine only")
    motion = ground_motion(args)
    structure = default_structure(params)
    if args.structure:
        structure = structure.replace(**parse_set(args.structure))
    solver = {**DEFAULT_SOLVER, **solver_settings(args)}
    for name in ("duration", "dt_out"):
        v = getattr(args, name)
        if v is not None and not (math.isfinite(v) and v > 0):
            raise ParameterError(f"--{name.replace('_', '-')} = {v}: must be a finite number > 0 (s)")
    out = check_out_dir("--out", args.out)
    result = simulate_seismic(params, structure, motion, duration=args.duration, dt_out=args.dt_out,
                              device=not args.no_device, progress=Progress("nsd seismic"), **solver)
    summary = {"ground": motion.describe(), "structure": structure.to_dict(), "device": not args.no_device,
               **seismic_summary(result), "solver": result.stats, "wall_time": result.stats["wall_time"],
               "versions": versions(), "params": params.describe()}
    others = {}
    for name in engines[1:]:
        other = run_seismic_engine(name, params, structure, motion, duration=args.duration, dt_out=args.dt_out)
        others[name] = other
        summary.setdefault("engines", {})[name] = {**seismic_metrics(result, other),
                                                   "wall_time": other.stats["wall_time"]}
    for name, other in others.items():
        write_csv(out / f"seismic_{name}.csv", other)
    write_csv(out / "seismic.csv", result)
    atomic_write_json(out / "summary.json", summary)
    pd, pa = summary["peak_displacement"], summary["peak_absolute_acceleration"]
    e = summary["energy"]
    print(f"peak |u| = {pd['value'] * 1e3:.3f} mm at t = {pd['t']:.3f} s, peak |a_abs| = {pa['value']:.3f} m/s^2 "
          f"at t = {pa['t']:.3f} s, residual |u| = {summary['residual_displacement']['u'] * 1e3:.3f} mm, "
          f"energy in {e['input']:.4g} J (balance residual {e['relative_residual']:.1e}); "
          f"{result.stats['steps']} steps in {result.stats['wall_time']:.1f} s for {result.stats['model_time']:.2f} s")
    for ev in summary["events"]:
        print(f"  event {ev['kind']}: t = {ev['start']:.4f} s for {ev['duration'] * 1e3:.2f} ms (|u| = {ev['u_start'] * 1e3:.2f} mm)")
    for name, m in summary.get("engines", {}).items():
        print(f"  {name}: max|du|/max|u| = {m['du']:.2e}, max|dF|/max|F| = {m['dF']:.2e}, "
              f"max|da|/max|a| = {m['da']:.2e}, {m['wall_time']:.1f} s")
    if summary["outside_working_range"]:
        print("  WARNING: the ropes went slack: part of this run lies outside the device's working range")
    print(f"wrote {out / 'seismic.csv'} and {out / 'summary.json'}")
    return 0
