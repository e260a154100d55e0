"""``nsd ida``: incremental dynamic analysis over a FEMA P695 record set, with and without the device,
and the lognormal fragility of a limit state (docs/ida.md).

Each record is scaled to intensity levels (hunt and fill, Vamvatsikos and Cornell 2002, or
``--levels``) until it reaches the limit state; resumable and parallel on the sweep's store
(``nsd_core.study.ida``) -> DIR/ida.csv, DIR/fragility.json, DIR/ida.json, and per configuration the
record closest to the median re-run with MuJoCo and Exudyn (with the device) or against the exact
linear solution (supports alone) under DIR/cross_check/. Exit 0 every trace ended (a limit reached
or the run budget spent); 2 bad input (nothing written); 3 a trace ended undetermined (a solver
failure: listed in fragility.json, the others are kept) or a cross-check run failed.
"""
from __future__ import annotations

import argparse
import dataclasses

from nsd_cli.options import (WORKERS_HELP, add_param_arguments, add_solver_arguments, base_params, check_out_dir,
                             solver_settings, draw_figures)
from nsd_core.common.files import read_regular_text
from nsd_core.device.params import ParameterError

HELP = "incremental dynamic analysis and fragility over a record set, with and without the device"
HUNT_FLAGS = ("start", "step", "max_runs", "resolution")
STROKE_MIN = 1e-6  # m, --limit stroke=VALUE (as a drive's smallest amplitude); the most: the rod's length


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--record-set", default=None, metavar="SET",
                   help="the record set: farfield, nearfield, nearfield-pulse, nearfield-no-pulse")
    p.add_argument("--records", default=None, metavar="1,3,5-7", help="these records of the set only (default all)")
    p.add_argument("--measure", default="sa",
                   help="intensity measure: sa (5%%-damped Sa at the supports-alone period, geometric mean of "
                        "the two components, model time) or pga (geometric mean); m/s^2")
    p.add_argument("--levels", default=None, metavar="L1,L2,...",
                   help="intensity levels [m/s^2] to run upwards, stopping at the first that reaches the limit "
                        "(instead of hunt and fill)")
    p.add_argument("--start", type=float, default=None, help="hunt and fill: first level [m/s^2] (default 0.25)")
    p.add_argument("--step", type=float, default=None,
                   help="hunt and fill: first step up [m/s^2] (default 0.25; each next step 0.5 step longer)")
    p.add_argument("--max-runs", type=int, default=None, help="hunt and fill: runs per record and configuration "
                                                               "(default 6)")
    p.add_argument("--resolution", type=float, default=None,
                   help="hunt and fill: bracket the limit until hi - lo <= resolution hi (default 0.1)")
    p.add_argument("--limit", required=True, metavar="stroke=VALUE|restrainer|drift=VALUE|impact=VALUE",
                   help="limit state that ends each trace: stroke=VALUE peak |u| >= VALUE m; restrainer: the "
                        "displacement restrainer engages (runs with it); drift=VALUE the peak story drift ratio of the "
                        "building >= VALUE (needs --building); impact=VALUE the restrainer's force >= VALUE N (runs "
                        "with it); the rod's reach ends every trace, counted as reached for stroke and restrainer, as "
                        "'stroke exhausted' (not reached) for drift and impact")
    p.add_argument("--limit-states", default=None, metavar="NAME=VALUE,...",
                   help="thresholds of the limit states reported apart (limit_states.json/.csv/.png): capacity=m "
                        "(isolator displacement capacity; default the device's working range X_max), drift=- "
                        "(default --limit's drift, else 0.015; with --building), floor_acceleration=m/s^2 (default 9.80665), impact=N "
                        "(restrainer force; default 0, any engagement; with --restrainer)")
    p.add_argument("--building", action="append", default=[], metavar="NAME=VALUE",
                   help="a shear building on the slab, as nsd seismic --building (docs/building.md); "
                        "--building stories=3 gives the default building")
    p.add_argument("--restrainer", action="store_true",
                   help="run with the displacement restrainer (always with --limit restrainer); its constants by "
                        "--structure restrainer_gap=, restrainer_stiffness=, restrainer_exponent=, restrainer_damping=")
    p.add_argument("--structure", action="append", default=[], metavar="NAME=VALUE",
                   help="override the default isolated structure: mass, stiffness, damping, "
                        "radius_of_gyration, support_radius, restrainer_* (SI)")
    p.add_argument("--engines", default="semirecursive,mujoco,exudyn",
                   help="semirecursive first, then the engines that re-run the median record with the device "
                        "(default both; 'semirecursive' alone skips them)")
    p.add_argument("--cross-check", default="median", metavar="none|median|all",
                   help="re-run records at their limit intensity in the other engines of --engines (with the device) "
                        "and against the exact linear solution (supports alone): none; median (default) the record "
                        "closest to the fitted median; all every record that reached the limit (refused when the "
                        "other engines' estimated steps exceed a bound); each re-run is printed with its time")
    p.add_argument("--workers", type=int, default=None, help=WORKERS_HELP)
    p.add_argument("--scheduler", default=None, help="address of a running Dask scheduler")
    p.add_argument("--retry-failed", action="store_true", help="run levels stored as failed again")
    add_param_arguments(p)
    add_solver_arguments(p)
    from nsd_cli.seismic_extras import add_design_arguments  # --isolator, --resize, --design-level (docs/design.md)
    add_design_arguments(p)
    p.add_argument("--out", required=True, help="output folder (resumable)")


def _options(args):
    """Everything the command line says, checked (ParameterError, one line) before anything runs."""
    from nsd_core.ground.records import SETS, set_name
    from nsd_core.study.hunt import Hunt, parse_levels
    from nsd_core.study.ida import parse_limit
    from nsd_core.study.intensity import MEASURES
    from nsd_core.study.seismic_set import parse_records
    from nsd_cli.options import reject_record_set_in_set
    reject_record_set_in_set(args.set)
    if args.record_set is None:
        raise ParameterError(f"--record-set: give the record set; allowed: {', '.join(SETS)}")
    set_ = set_name(args.record_set)
    records = parse_records(args.records, set_)
    if args.measure not in MEASURES:
        raise ParameterError(f"--measure {args.measure!r}: unknown; allowed: {', '.join(MEASURES)}")
    limit = parse_limit(args.limit)
    given = [f"--{n.replace('_', '-')}" for n in HUNT_FLAGS if getattr(args, n) is not None]
    if args.levels is not None:
        if given:
            raise ParameterError(f"{given[0]}: a hunt-and-fill option; --levels gives the levels instead")
        return set_, records, limit, None, parse_levels(args.levels)
    defaults = Hunt()
    hunt = Hunt(**{n: getattr(args, n) if getattr(args, n) is not None else getattr(defaults, n) for n in HUNT_FLAGS})
    return set_, records, limit, hunt, None


def run(args) -> int:
    from comparisons.engines import parse_engine_list, run_seismic_engine
    from comparisons.harness import code_fingerprint
    from nsd_cli.limits import check_ida_scales, check_ida_work
    from nsd_cli.options import resolved_workers
    from nsd_cli.sweep import check_scheduler
    from nsd_core.ground.records import SIMILITUDE_TIME_FACTOR, fema_record
    from nsd_cli.seismic_building import with_building
    from nsd_cli.seismic_extras import isolated_structure
    from nsd_core.device.model import DEFAULT_SOLVER
    from nsd_core.study.ida import make_traces, trace_all
    from nsd_core.study.ida_outputs import write_ida
    from nsd_core.study.intensity import record_intensity
    from nsd_core.study.store import Store
    from nsd_cli.ida_check import check_work, parse_mode
    set_, records, limit, hunt, levels = _options(args)
    mode = parse_mode(args.cross_check)
    engines = parse_engine_list(args.engines)
    if engines[0] != "semirecursive":
        raise ParameterError(f"--engines {args.engines!r}: semirecursive (the reference) must come first")
    workers = resolved_workers(args.workers)
    params = base_params(args)
    args.restrainer = args.restrainer or limit.kind in ("restrainer", "impact")
    structure = with_building(args, isolated_structure(args, params))
    if limit.kind == "stroke" and not STROKE_MIN <= limit.value <= params.rod_length:
        raise ParameterError(f"--limit {args.limit!r}: stroke must be in [{STROKE_MIN:g}, {params.rod_length:g}] m "
                             "(at least 1 um; at the rod's length every run stops, which counts as reached)")
    if limit.kind == "drift" and structure.building is None:
        raise ParameterError(f"--limit {args.limit!r}: drift needs a building on the slab (--building stories=N)")
    from nsd_cli.ida_states import parse_limit_states
    states = parse_limit_states(args.limit_states, params, structure, limit=limit)
    solver = {**DEFAULT_SOLVER, **solver_settings(args)}
    check_scheduler(args.scheduler)
    ground = {"scale": 1.0, "time_factor": SIMILITUDE_TIME_FACTOR, "window": None, "rotate_deg": 0.0,
              "normalised": True}
    period = structure.first_period   # the supports alone (and the building on them, if any)
    motions = {rid: fema_record(set_, rid, **ground) for rid in records}
    flag = "--levels" if levels is not None else "--max-runs"
    check_ida_work({r: motions[r].duration for r in records}, len(levels or []) or hunt.max_runs, flag,
                   structure.building.stories if structure.building else 0)
    work = check_work(mode, {r: motions[r].duration for r in records}, engines[1:])
    im = {rid: record_intensity(motions[rid], args.measure, period) for rid in records}
    check_ida_scales({r: im[r]["value"] for r in records}, levels or [hunt.start], flag if levels else "--start",
                     args.measure)
    out = check_out_dir("--out", args.out)
    numbers = {k: v for k, v in structure.to_dict().items() if k != "provenance"}
    common = dict(ground=ground, params=params.to_dict(), structure=numbers, duration=None, dt_out=1e-3,
                  settings=solver, code=code_fingerprint(), states=states.to_dict())
    traces = make_traces(set_, records, {r: im[r]["value"] for r in records}, common, limit, hunt, levels)
    store = Store(out)
    store.remove_stale_temps()  # a killed run's half-written files (no worker runs yet)
    elapsed = trace_all(traces, store, workers=workers, scheduler=args.scheduler, retry_failed=args.retry_failed,
                        run_engine=run_seismic_engine, tally=args.tally)
    measure = {k: v for k, v in im[records[0]].items() if k not in ("value", "components")}
    index = {"set": set_, "records": records, "measure": measure, "limit": limit.describe(),
             "limit_option": args.limit, "hunt": None if hunt is None else dataclasses.asdict(hunt), "levels": levels,
             "intensity_at_scale_1": {str(r): im[r] for r in records}, "structure": structure.to_dict(),
             "ground": ground, "code": common["code"], "elapsed_this_run_s": elapsed,
             "notes": "im in m/s^2, model time scale (records x time_factor); scale = im / intensity_at_scale_1; "
                      "a trace's limit intensity is the lowest level at which it reached the limit"}
    index = write_ida(traces, store, index)
    bad = _cross_check(traces, store, engines, workers, args, index, run_seismic_engine, work)
    _print(index, out)
    from nsd_core.study.limit_state_outputs import summary_lines
    if (out / "limit_states.json").exists():
        import json
        print("limit states apart (limit_states.json, .csv, .png):")
        print("\n".join(summary_lines(json.loads(read_regular_text(out / "limit_states.json", "limit_states.json")))))
    draw_figures(out)  # the study's PNGs into its own folder
    undetermined = [t["name"] for t in index["traces"] if t["undetermined"]]
    return 3 if undetermined or bad else 0


def _cross_check(traces, store, engines, workers, args, index, runner, work: dict) -> bool:
    """The records re-run as --cross-check says (nsd_cli.ida_check); ida.json gets "cross_check", its
    mode and estimate, and the times of the IDA's runs and of the cross-check apart."""
    import json
    import sys
    from nsd_cli.ida_check import cross_check
    from nsd_cli.ida_check_text import cost, entries
    from nsd_core.common.files import atomic_write_json
    frag = json.loads(read_regular_text(store.root / "fragility.json", "fragility.json"))
    if work["peer_steps"]:
        print(f"ida cross-check ({work['mode']}): up to {work['records']} record(s) in {', '.join(engines[1:])}, "
              f"about {work['peer_steps']:.3g} steps of theirs", file=sys.stderr, flush=True)
    check, elapsed = cross_check(traces, store, frag, engines[1:], workers, args.scheduler,
                                 lambda s: print(s, file=sys.stderr, flush=True), runner, work["mode"])
    index["cross_check"] = check
    index["cross_check_mode"] = work["mode"]
    index["cross_check_estimate"] = work
    index["cross_check_cost"] = cost(check)
    index["elapsed_cross_check_s"] = elapsed
    index["elapsed_total_s"] = index["elapsed_this_run_s"] + elapsed
    atomic_write_json(store.root / "ida.json", index)
    found = [c for _, c in entries(check)]
    return any(e.get("status") == "failed" for c in found for e in c.get("engines", {}).values()) or \
        any("error" in c for c in found)


def _print(index: dict, out) -> None:
    for t in index["traces"]:
        tail = (f"limit at IM {t['limit_im']:.4g} m/s^2 ({t['limit_why']})" if t["limit_im"] is not None else
                f"never reached up to {t['censored_at']:.4g} m/s^2" if t["censored_at"] is not None else
                f"undetermined: {t['undetermined']}" if t["undetermined"] else "never observed")
        if t.get("stroke_exhausted_at") is not None:
            tail += f"; stroke exhausted (the rod's reach) at {t['stroke_exhausted_at']:.4g} m/s^2, not counted"
        print(f"  {t['name']}: {t['runs']} runs, {tail}")
    for name, f in index["fragility"].items():
        fit = ("median %.4g m/s^2, dispersion %.3f" % (f["median"], f["dispersion"]) if f["median"] is not None
               else "no fit")
        print(f"{name}: {fit} ({f['n_reached']} reached, {f['n_censored']} censored)")
    from nsd_cli.ida_check_text import describe_entry, entries
    for name, c in entries(index.get("cross_check", {})):
        print(describe_entry(name, c))
    spent = index.get("cross_check_cost") or {}
    runs = sum(v["runs"] for v in spent.values())
    per = ", ".join(f"{e} {v['runs']} in {v['wall_s']:.1f} s" for e, v in spent.items())
    check = (f"cross-check ({index.get('cross_check_mode')}) {runs} runs in {index['elapsed_cross_check_s']:.1f} s"
             + (f" ({per})" if per else ""))
    print(f"{index['runs']} IDA runs in {index['elapsed_this_run_s']:.1f} s + {check} = "
          f"{index['elapsed_total_s']:.1f} s in all; wrote {out / 'ida.csv'}, {out / 'fragility.json'}, "
          f"{out / 'ida.json'}")

