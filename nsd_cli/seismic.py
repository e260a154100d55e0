"""``nsd seismic``: the isolated structure on the device under a ground motion (Table 1, second row)
-> DIR/seismic.csv (time series, header with units) and DIR/summary.json (peaks, residual
displacement, energy balance, working-range and restrainer events). Exit 4 when |u| reaches the rod's
length: the series up to the event and the summary with the event are still written. ``--restrainer``
and ``--compare-supports``: nsd_cli.seismic_extras (docs/seismic.md).

``--record-set SET [--records 1,3,5-7]``: every record of a FEMA P695 set, each with and without the device
(the isolation effect), resumable and parallel (``nsd_core.study.seismic_set``) -> DIR/set.csv,
DIR/set.json, DIR/records/<set>_<id>[_nodevice]/. A record whose run fails is kept in its row with
its reason and the others still run. Exit 0 every run ran; 3 any run failed in the solver (or
otherwise did not finish), which outranks 4 any run reached the rod's length or left the laws'
validity (the set's numbers are then incomplete in a way the physics explains)."""
from __future__ import annotations

import argparse
import math

from nsd_cli import limits as lim
from nsd_cli import seismic_building, seismic_checks, seismic_extras
from nsd_cli.options import (WORKERS_HELP, Progress, add_param_arguments, add_solver_arguments, base_params, check_finite,
                             check_out_dir, solver_settings, draw_figures)
from nsd_core.device.params import ParameterError

HELP = "seismic response of the isolated structure (in-house engine)"

def add_arguments(p: argparse.ArgumentParser) -> None:
    src = p.add_mutually_exclusive_group()
    src.add_argument("--record", metavar="SET:ID",
                     help="FEMA P695 record: farfield:1..22, nearfield:1..28, nearfield-pulse:1..14, "
                          "nearfield-no-pulse:15..28")
    src.add_argument("--ground", metavar="KIND:K=V,...",
                     help="synthetic input: harmonic:amplitude=A[m/s^2],frequency=f,azimuth=DEG,duration=T or "
                          "pulse:velocity=V[m/s],frequency=fp,gamma=G,phase=DEG,azimuth=DEG (Mavroeidis-Papageorgiou); "
                          "each key once, bounds: " + _ground_bounds())
    src.add_argument("--record-set", metavar="SET",
                     help="every record of a FEMA P695 set (farfield, nearfield, nearfield-pulse, nearfield-no-pulse), "
                          "each with and without the device (see --records)")
    p.add_argument("--scale", default="1", help="factor on the record's (normalised) acceleration, "
                                                 f"in [{lim.SCALE[0]:g}, {lim.SCALE[1]:g}]")
    p.add_argument("--window", metavar="T0,T1", help="part of the record, in the record's own seconds")
    p.add_argument("--rotate", default="0", metavar="DEG", help="rotation of the record pair in plan, "
                                                                  f"in [{lim.ROTATE[0]:g}, {lim.ROTATE[1]:g}]")
    p.add_argument("--time-factor", default=None,
                   help="model seconds per record second (default sqrt(0.1): Froude 1:10 similitude), "
                        f"in [{lim.TIME_FACTOR[0]:g}, {lim.TIME_FACTOR[1]:g}]")
    p.add_argument("--raw", action="store_true", help="the recorded acceleration, not FEMA P695's normalised one")
    p.add_argument("--duration", type=float, default=None,
                   help="model time to run [s] (default: the input's; longer adds free vibration), "
                        f"at most {lim.SEISMIC_DURATION_MAX:g} s (about {lim.SEISMIC_STEPS_PER_SECOND} steps per s)")
    p.add_argument("--dt-out", type=float, default=1e-3,
                   help=f"output interval [s], in [{lim.DT_OUT[0]:g}, {lim.DT_OUT[1]:g}] and <= the duration; "
                        f"duration / dt-out <= {lim.SEISMIC_SAMPLES_MAX:.0e} samples")
    p.add_argument("--no-device", action="store_true", help="the supports alone (the isolation effect's reference)")
    p.add_argument("--engines", default="semirecursive",
                   help="semirecursive (the reference, always first) and any of mujoco, exudyn to cross-check: "
                        "each writes seismic_<engine>.csv; summary.json gets their differences. opensees: with "
                        "--isolator bilinear or friction-pendulum only (building included), judged by the gate's "
                        "rule (its step and half of it)")
    p.add_argument("--structure", action="append", default=[], metavar="NAME=VALUE",
                   help="override the default isolated structure: mass, stiffness, damping, "
                        "radius_of_gyration, support_radius, restrainer_gap, restrainer_stiffness, "
                        "restrainer_exponent, restrainer_damping (SI)")
    seismic_extras.add_arguments(p)
    seismic_extras.add_design_arguments(p)
    seismic_building.add_arguments(p)
    seismic_checks.add_arguments(p)
    p.add_argument("--records", default=None, metavar="1,3,5-7", help="with --record-set: these records only (default all)")
    p.add_argument("--workers", type=int, default=None, help="with --record-set: " + WORKERS_HELP)
    p.add_argument("--scheduler", default=None, help="with --record-set: address of a running Dask scheduler")
    p.add_argument("--scheduler-timeout", type=float, default=None, metavar="S",
                   help=f"with --scheduler: seconds to wait for the connection and for the scheduler's answer, each "
                        f"(default {lim.SCHEDULER_TIMEOUT_DEFAULT:g}, in [{lim.SCHEDULER_TIMEOUT[0]:g}, "
                        f"{lim.SCHEDULER_TIMEOUT[1]:g}])")
    p.add_argument("--retry-failed", action="store_true", help="with --record-set: run records stored as failed again")
    add_param_arguments(p)
    add_solver_arguments(p)
    p.add_argument("--out", required=True, help="output folder (with --record-set: resumable)")


def _ground_bounds() -> str:
    from nsd_core.ground.motions import ground_spec_bounds
    return ground_spec_bounds()


def ground_motion(args):
    """The GroundMotion the options describe (ParameterError on anything wrong)."""
    from nsd_core.ground import records
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
        tf = records.SIMILITUDE_TIME_FACTOR if args.time_factor is None else args.time_factor
        scale = args.scale
        if getattr(args, "design_level", False):
            scale = seismic_extras.design_scale(set_, rid.strip(), args, window)
        return records.fema_record(set_, rid.strip(), scale=scale, time_factor=tf, window=window,
                                   rotate_deg=args.rotate, normalised=not args.raw)
    if getattr(args, "design_level", False):
        raise ParameterError("--design-level: scales a record (--record, --record-set); a synthetic --ground has "
                             "no design level")
    for name in ("window", "time_factor"):
        if getattr(args, name) is not None:
            raise ParameterError(f"--{name.replace('_', '-')}: applies to --record only")
    from comparisons.seismic import parse_ground
    return parse_ground(args.ground, "--ground")


def check_source(args) -> None:
    """Exactly one input: --record, --ground or --record-set. ``--set`` is a parameter override here as
    in every command; a value without '=' (the record set's spelling before --record-set) is pointed there."""
    from nsd_cli.options import reject_record_set_in_set
    reject_record_set_in_set(args.set)
    if not (args.record or args.ground or args.record_set):
        raise ParameterError("input: give exactly one of --record SET:ID, --ground KIND:K=V,... or --record-set SET")


def run(args) -> int:
    """A single run (--record or --ground): seismic.csv, summary.json and the run's PNGs; a set: run_set."""
    check_source(args)
    if args.record_set is not None:
        from nsd_cli.seismic_set import run_set
        return run_set(args)
    for name in ("records", "workers", "scheduler"):
        if getattr(args, name) is not None:
            raise ParameterError(f"--{name}: applies to --record-set only")
    if args.retry_failed:
        raise ParameterError("--retry-failed: applies to --record-set only")
    if args.scheduler_timeout is not None:
        raise ParameterError("--scheduler-timeout: applies to --record-set --scheduler only")
    lim.check_record_flags(args)
    params, engines, baseline, motion, structure, solver = _single_request(args)
    seismic_checks.check_arguments(args, params)
    out = check_out_dir("--out", args.out)
    restoring = seismic_checks.restoring_force(args, params, structure)
    head = {"ground": motion.describe(), "structure": structure.to_dict(), "device": not args.no_device}
    if restoring is not None:
        head["restoring_force"] = restoring
    seismic_checks.print_restoring_force(restoring)
    if args.compare_building:
        if len(engines) > 1:
            raise ParameterError(f"--engines {args.engines!r}: --compare-building runs the in-house engine only")
        return seismic_building.run_compare(args, params, structure, motion, solver, out, head)
    if args.fixed_base:
        solver["fixed_base"] = head["fixed_base"] = True
    if args.compare_supports:
        code = seismic_extras.run_compare(args, params, structure, motion, solver, out, head)
    else:
        code = _single_run(args, params, structure, motion, solver, out, head, engines, baseline)
    draw_figures(out)  # the run's (or the pair's) PNGs into its own folder
    return code


def _single_request(args):
    """A single run's parameters, engines, baseline flag, motion, structure and solver settings, checked in order."""
    from nsd_core.device.model import DEFAULT_SOLVER
    from comparisons.engines import BASELINE_PEERS, parse_engine_list
    params = base_params(args)
    engines = parse_engine_list(args.engines, extra=BASELINE_PEERS)
    if engines[0] != "semirecursive":
        raise ParameterError(f"--engines {args.engines!r}: semirecursive (the reference) must come first")
    baseline = _baseline(args, engines)
    if args.no_device and len(engines) > 1 and not baseline:
        raise ParameterError("--engines: the supports alone (--no-device) run on the in-house engine only")
    seismic_extras.check_compare(args, engines)
    motion = ground_motion(args)
    lim.check_seismic_request(motion.duration if args.duration is None else args.duration, args.dt_out,
                              "" if args.duration is not None else "the input's own duration")
    structure = seismic_building.with_building(args, seismic_extras.isolated_structure(args, params))
    lim.check_building_work(motion.duration if args.duration is None else args.duration,
                            structure.building.stories if structure.building else 0)
    if args.fixed_base and (not args.no_device or args.compare_supports):
        raise ParameterError("--fixed-base: the slab is held to the ground, so the run has no device: add --no-device")
    solver = {**DEFAULT_SOLVER, **solver_settings(args)}
    for name in ("duration", "dt_out"):
        v = getattr(args, name)
        if v is not None and not (math.isfinite(v) and v > 0):
            raise ParameterError(f"--{name.replace('_', '-')} = {v}: must be a finite number > 0 (s)")
    if args.fixed_base and len(engines) > 1:
        raise ParameterError("--engines: the fixed base runs on the in-house engine only")
    return params, engines, baseline, motion, structure, solver


def _single_run(args, params, structure, motion, solver, out, head, engines, baseline) -> int:
    """The in-house run and each peer's, checked, written (seismic*.csv, summary.json) and said; exit 4: DriveError."""
    from nsd_core.device.drive import DriveError
    from nsd_core.device.results import versions, write_csv
    from nsd_core.common.files import atomic_write_json
    from nsd_core.structure.seismic import seismic_summary, simulate_seismic
    from comparisons.engines import BASELINE_PEERS, run_seismic_engine
    from comparisons.seismic import seismic_metrics
    try:
        result = simulate_seismic(params, structure, motion, duration=args.duration, dt_out=args.dt_out,
                                  device=not args.no_device, progress=Progress("nsd seismic"), **solver)
    except DriveError as err:  # exit 4 is still a result: the series up to the event, the event
        seismic_extras.write_stopped(err, out, {**head, "versions": versions(), "params": params.describe()})
        raise
    summary = {**head, **seismic_summary(result), "solver": result.stats, "wall_time": result.stats["wall_time"],
               "versions": versions(), "params": params.describe()}
    seismic_extras.warn(summary)
    others = {}
    for name in engines[1:]:
        if name in BASELINE_PEERS:  # OpenSees's own bearing elements, judged by the gate's rule
            from comparisons.engines.opensees_peer import judged_entry
            other, entry = judged_entry(params, structure, motion, result, args.duration, args.dt_out)
            others[name] = other
            summary.setdefault("engines", {})[name] = entry
            continue
        if baseline:  # the baseline isolator's peers: its description built by each (comparisons/engines/described_isolator.py)
            from comparisons.engines.described_isolator import isolator_metrics as metrics, run_isolator
            other = run_isolator(name, structure, motion, duration=args.duration, dt_out=args.dt_out)
        else:
            metrics = seismic_metrics
            other = run_seismic_engine(name, params, structure, motion, duration=args.duration, dt_out=args.dt_out)
        others[name] = other
        summary.setdefault("engines", {})[name] = {**metrics(result, other), "wall_time": other.stats["wall_time"]}
        if "floor1_x" in result.columns:  # the building's floors and stories (docs/building.md)
            from comparisons.seismic import building_metrics
            summary["engines"][name]["building"] = building_metrics(result, other)
    check_finite({"seismic.csv": result, **{f"seismic_{n}.csv": o for n, o in others.items()},
                  "summary.json": summary}, "nsd seismic")
    for name, other in others.items():
        write_csv(out / f"seismic_{name}.csv", other)
    write_csv(out / "seismic.csv", result)
    atomic_write_json(out / "summary.json", summary)
    _print_single(out, result, summary)
    return 0


def _print_single(out, result, summary) -> None:
    """A single run's lines on stdout: peaks, residual, energy, events, each peer's differences, warnings."""
    pd, pa = summary["peak_displacement"], summary["peak_absolute_acceleration"]
    e = summary["energy"]
    print(f"peak |u| = {pd['value'] * 1e3:.3f} mm at t = {pd['t']:.3f} s, peak |a_abs| = {pa['value']:.3f} m/s^2 "
          f"at t = {pa['t']:.3f} s, residual |u| = {summary['residual_displacement']['u'] * 1e3:.3f} mm, "
          f"energy in {e['input']:.4g} J (balance residual {e['relative_residual']:.1e}); "
          f"{result.stats['steps']} steps in {result.stats['wall_time']:.1f} s for {result.stats['model_time']:.2f} s")
    seismic_building.print_building(summary)
    for ev in summary["events"]:
        print(f"  event {ev['kind']}: t = {ev['start']:.4f} s for {ev['duration'] * 1e3:.2f} ms (|u| = {ev['u_start'] * 1e3:.2f} mm)")
    for name, m in summary.get("engines", {}).items():
        print(f"  {name}: max|du|/max|u| = {m['du']:.2e}, max|dF|/max|F| = {m['dF']:.2e}, "
              f"max|da|/max|a| = {m['da']:.2e}, {m['wall_time']:.1f} s")
        if "verdict" in m:
            print(f"    {name} ({m['element']}, step {m['step']:.3g} s and half of it): {m['verdict']['text']}")
        if "building" in m:
            b = m["building"]
            print(f"    building: floors {b['dfloor']:.2e}, drifts {b['ddrift']:.2e}, floor accelerations "
                  f"{b['dfloor_a']:.2e} (worst floor, max|d - d_ref| / max|d_ref|)")
    seismic_extras.print_restrainer(summary)
    if summary["outside_working_range"]:
        print("  WARNING: the ropes went slack: part of this run lies outside the device's working range")
    print(f"wrote {out / 'seismic.csv'} and {out / 'summary.json'}")


def _baseline(args, engines) -> bool:
    """--isolator: a baseline runs without the device (a single run: as --no-device; --compare-supports and
    --compare-building: their run without the device). True for a bilinear or friction-pendulum single
    run, whose cross-check builds the isolator's description in MuJoCo and Exudyn (comparisons/engines/
    described_isolator.py)."""
    from nsd_core.structure.isolators import KINDS
    kind = seismic_extras.isolator_choice(args)
    if "opensees" in engines and (kind not in KINDS or args.compare_supports or args.compare_building):
        raise ParameterError(f"--engines {args.engines!r}: opensees builds a single run on --isolator bilinear or "
                             f"friction-pendulum only (given --isolator {kind}); it cannot build the "
                             "negative-stiffness device")
    if kind == "device":
        return False
    if args.no_device:
        raise ParameterError(f"--no-device: --isolator {kind} already runs without the device; leave one out")
    if not (args.compare_supports or args.compare_building):
        args.no_device = True
    if kind in KINDS and args.no_device:
        if set(engines[1:]) - {"mujoco", "exudyn", "opensees"}:
            raise ParameterError(f"--engines {args.engines!r}: --isolator {kind} cross-checks in mujoco, exudyn and "
                                 "opensees only")
        if engines[1:] and args.restrainer:
            raise ParameterError(f"--engines {args.engines!r}: the isolator's peers have no restrainer")
        if set(engines[1:]) - {"opensees"} and getattr(args, "building", None):
            raise ParameterError(f"--engines {args.engines!r}: the isolator's described model (mujoco, exudyn) has no "
                                 "building; opensees builds it")
        return True
    return False
