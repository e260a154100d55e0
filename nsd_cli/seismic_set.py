"""``nsd seismic --record-set SET``: every record of a FEMA P695 set, each with and without the device,
resumable and parallel (nsd_core.study.seismic_set); the flags and exit codes are nsd_cli.seismic's."""
from __future__ import annotations

import math
import sys

from nsd_cli import limits as lim
from nsd_cli import seismic_building, seismic_checks, seismic_extras
from nsd_cli.options import base_params, check_out_dir, solver_settings, draw_figures
from nsd_core.device.params import ParameterError


def run_set(args) -> int:
    """--record-set: the record set, with and without the device (see the module docstring for exit codes)."""
    from comparisons.engines import run_seismic_engine
    from comparisons.seismic import seismic_metrics
    from nsd_cli.sweep import check_scheduler, scheduler_timeout
    from nsd_core.study.seismic_set import run_set as run_record_set
    set_, records, engines, workers = _set_request(args)
    runs, params, structure = _set_runs(args, set_, records, engines)
    timeout = scheduler_timeout(args)
    check_scheduler(args.scheduler, timeout)
    seismic_checks.check_arguments(args, params)
    out = check_out_dir("--out", args.out)
    restoring = seismic_checks.restoring_force(args, params, structure)
    seismic_checks.print_restoring_force(restoring)
    index = run_record_set(runs, out, workers=workers, scheduler=args.scheduler, scheduler_timeout=timeout,
                           retry_failed=args.retry_failed, run_engine=run_seismic_engine,
                           compare=seismic_metrics, tally=args.tally)
    if restoring is not None:   # the set's isolation level, as a single run's summary.json has it
        import json
        from nsd_core.common.files import atomic_write_json, read_regular_text
        atomic_write_json(out / "set.json", {**json.loads(read_regular_text(out / "set.json", "set.json")),
                                             "restoring_force": restoring})
    c = index["counts"]
    for row in index["rows"]:
        ratio = ("" if row.get("peak_u_ratio") is None else
                 f", peak |u| {row['peak_u'] * 1e3:.2f} / {row['peak_u_nodevice'] * 1e3:.2f} mm (ratio "
                 f"{row['peak_u_ratio']:.3f}), peak |a_abs| ratio {row['peak_a_abs_ratio']:.3f}")
        status = row["status"] + (" (outside the working range)" if row.get("outside_working_range") == "yes" else "")
        print(f"  {row['set']}:{row['id']} {row['earthquake']}: {status}{ratio}"
              + (f" [{row['reason']}]" if row["reason"] else ""))
    for e in index.get("entries", []):   # each run's warnings (nsd_core.structure.seismic_warnings), as a single run's
        for w in e.get("warnings", []):
            print(f"nsd seismic: warning: {e['set']}:{e['id']} {w}", file=sys.stderr)
    print(f"{len(index['rows'])} records: " + ", ".join(f"{c[k]} {k}" for k in c if k == "ok" or c[k])
          + f"; {index['elapsed_this_run_s']:.1f} s; wrote {out / 'set.csv'} and {out / 'set.json'}")
    draw_figures(out)  # the set's PNGs into its own folder
    if c["solver_failure"] or c["error"] or c["missing"]:
        return 3
    return 4 if c["rod_reach"] or c["outside_validity"] else 0


def _set_request(args):
    """A record set's name, records, engines and local workers, checked; the flags a set cannot take refused."""
    from comparisons.engines import BASELINE_PEERS, parse_engine_list
    from nsd_cli.options import resolved_workers
    from nsd_core.ground.records import set_name
    from nsd_core.study.seismic_set import parse_records
    set_ = set_name(args.record_set)
    records = parse_records(args.records, set_)
    lim.check_record_flags(args)
    if args.no_device:
        raise ParameterError("--no-device: --record-set runs every record both with and without the device "
                             "(the run without it on --isolator's baseline)")
    if args.compare_supports:
        raise ParameterError("--compare-supports: --record-set runs every record both with and without the device already")
    if args.fixed_base or args.compare_building:
        flag = "--fixed-base" if args.fixed_base else "--compare-building"
        raise ParameterError(f"{flag}: --record-set runs every record with and without the device (a building: "
                             "--building)")
    engines = parse_engine_list(args.engines, extra=BASELINE_PEERS)
    if set(engines) & set(BASELINE_PEERS):
        raise ParameterError(f"--engines {args.engines!r}: a record set's cross-check runs mujoco and exudyn; opensees "
                             "runs one record: nsd seismic --record SET:ID --isolator bilinear|friction-pendulum "
                             "--engines semirecursive,opensees")
    if engines[0] != "semirecursive":
        raise ParameterError(f"--engines {args.engines!r}: semirecursive (the reference) must come first")
    workers = resolved_workers(args.workers)
    return set_, records, engines, workers


def _set_runs(args, set_, records, engines):
    """The set's runs (each record with and without the device), each one's work checked; their params and structure."""
    from comparisons.harness import code_fingerprint
    from nsd_core.ground.records import SIMILITUDE_TIME_FACTOR, fema_record
    from nsd_core.device.model import DEFAULT_SOLVER
    from nsd_core.study.seismic_set import record_runs
    tf = SIMILITUDE_TIME_FACTOR if args.time_factor is None else args.time_factor
    window = _window(args.window)
    fema_record(set_, records[0], scale=args.scale, time_factor=tf, window=window, rotate_deg=args.rotate,
                normalised=not args.raw)  # checks scale, time factor, rotation (one line each)
    ground = {"scale": float(args.scale), "time_factor": float(tf), "window": window,
              "rotate_deg": float(args.rotate), "normalised": not args.raw}
    params = base_params(args)
    structure = seismic_building.with_building(args, seismic_extras.isolated_structure(args, params))
    numbers = {k: v for k, v in structure.to_dict().items() if k != "provenance"}
    solver = {**DEFAULT_SOLVER, **solver_settings(args)}
    for name in ("duration", "dt_out"):
        v = getattr(args, name)
        if v is not None and not (math.isfinite(v) and v > 0):
            raise ParameterError(f"--{name.replace('_', '-')} = {v}: must be a finite number > 0 (s)")
    if seismic_extras.isolator_choice(args) not in ("device", "linear") and engines[1:]:
        raise ParameterError(f"--engines {args.engines!r}: a record set's cross-check runs the device and the supports; "
                             f"the {args.isolator} baseline's peer: nsd seismic --record SET:ID --isolator "
                             f"{args.isolator} --engines semirecursive,mujoco,exudyn")
    if args.design_level:   # each record at its own scale: Sa(T_D) = the design spectrum's (docs/design.md)
        runs = []
        for rec in records:
            own = {**ground, "scale": seismic_extras.design_scale(set_, rec, args, window)}
            runs += record_runs(set_, [rec], own, params.to_dict(), numbers, args.duration, args.dt_out, solver,
                                code_fingerprint(), peers=tuple(engines[1:]))
    else:
        runs = record_runs(set_, records, ground, params.to_dict(), numbers, args.duration, args.dt_out, solver,
                           code_fingerprint(), peers=tuple(engines[1:]))  # every record's window checked here
    stories = structure.building.stories if structure.building else 0
    for r in runs:
        own = fema_record(r.set, r.record, **r.ground).duration if args.duration is None else args.duration
        if args.duration is None:
            lim.check_seismic_request(own, args.dt_out, f"record {r.set}:{r.record}'s own duration")
        lim.check_building_work(own, stories, f"record {r.set}:{r.record}")
    return runs, params, structure


def _window(text: str | None) -> list[float] | None:
    if text is None:
        return None
    parts = text.split(",")
    try:
        if len(parts) != 2:
            raise ValueError
        return [float(parts[0]), float(parts[1])]
    except ValueError:
        raise ParameterError(f"--window {text!r}: expected T0,T1 (two numbers, record seconds)") from None
