"""``nsd p695``: a FEMA P695 evaluation of the isolated structure, with the device and on each
baseline, on the far-field set (docs/p695.md; the methodology in nsd_core/study/p695.py).

An IDA (nsd ida's machinery, resumable, parallel) scales the whole normalised set together until
each record reaches the collapse surrogate; then per configuration Ŝ_CT (with a bootstrap interval
over records), S_MT, CMR, mu_T, SSF, beta_TOT, ACMR and pass/fail against ACMR10% and ACMR20%
-> DIR/p695.json, DIR/p695.png, and the IDA's files (ida.csv, fragility.json, ida.json,
limit_states.*). Exit 0 done; 2 bad input (nothing written); 3 a trace ended undetermined.
"""
from __future__ import annotations

import argparse
import os

from nsd_cli.options import WORKERS_HELP, add_param_arguments, add_solver_arguments, base_params, check_out_dir, solver_settings
from nsd_core.device.params import ParameterError

HELP = "FEMA P695 evaluation (CMR, SSF, beta_TOT, ACMR) on the far-field set, with and without the device"
G_RECORDS = 9.80665   # m/s^2: the records and the package's spectra are in g of this value
COLLAPSE = "capacity | drift=VALUE | impact=VALUE"
# Hunt and fill for Ŝ_CT (docs/p695.md): each record's collapse bracketed to 5 % of its level (Ŝ_CT read
# at the bracket's geometric midpoint is then within 2.5 %); 10 runs cover the hunt (3-5 runs to the
# collapse levels of the design basis, 0.5-2 m/s^2) and the 3-4 halvings from its last step; no fill.
P695_HUNT = {"resolution": 0.05, "max_runs": 10, "fill": False}


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--records", default=None, metavar="1,3,5-7", help="these far-field records only (default all 22)")
    p.add_argument("--collapse", default="capacity", metavar=COLLAPSE,
                   help="the collapse surrogate: capacity (default) the isolator displacement capacity exhausted, peak "
                        "|u| >= --capacity; drift=VALUE a story drift ratio (with --building); impact=VALUE a "
                        "restrainer force in N (runs with the restrainer); the rod's reach is collapse in every one "
                        "(the device spent), counted apart")
    p.add_argument("--capacity", type=float, default=None,
                   help="isolator displacement capacity [m] (default: the device's working range X_max)")
    p.add_argument("--isolators", default="device,linear,bilinear,friction-pendulum", metavar="LIST",
                   help="the configurations evaluated: device (the device on the supports), and the baselines linear "
                        "(the supports alone), bilinear (lead-rubber), friction-pendulum, sized for the design "
                        "displacement (docs/design.md); default all four")
    p.add_argument("--sdc", default="basis", help="the design level of S_MT: basis (default: the project's design "
                                                  "basis, MCE_R = 1.5 x its ASCE 7-16 spectrum; SSF for SDC dmin), or "
                                                  "a FEMA P695 category dmax, dmin, cmax, cmin, bmax, bmin")
    p.add_argument("--quality", default=None, metavar="DR=B,TD=C,MDL=B",
                   help="quality ratings A-D of design requirements, test data and modelling (default DR=B,TD=C,MDL=B)")
    p.add_argument("--duration", type=float, default=None, help="model seconds of each record (default whole records)")
    p.add_argument("--start", type=float, default=None, help="hunt and fill: first level [m/s^2] (default 0.25)")
    p.add_argument("--step", type=float, default=None, help="hunt and fill: first step [m/s^2] (default 0.25)")
    p.add_argument("--max-runs", type=int, default=None,
                   help=f"runs per record and configuration (default {P695_HUNT['max_runs']}; a record whose "
                        "bracket is not within --resolution when they are spent is listed as out of budget)")
    p.add_argument("--resolution", type=float, default=None,
                   help=f"bracket each record's collapse until hi - lo <= resolution hi (default "
                        f"{P695_HUNT['resolution']:g})")
    p.add_argument("--fill", action="store_true",
                   help="after the bracket, fill the IDA curve below collapse with the runs left (default off: "
                        "S_CT needs the brackets only)")
    p.add_argument("--bootstrap", type=int, default=2000, help="bootstrap resamples of the median (default 2000)")
    p.add_argument("--seed", type=int, default=None, help="the bootstrap's seed (default fixed: same numbers)")
    p.add_argument("--building", action="append", default=[], metavar="NAME=VALUE",
                   help="a shear building on the slab, as nsd seismic --building")
    p.add_argument("--restrainer", action="store_true", help="run with the displacement restrainer")
    p.add_argument("--structure", action="append", default=[], metavar="NAME=VALUE",
                   help="override the default isolated structure (as nsd ida)")
    p.add_argument("--workers", type=int, default=None, help=WORKERS_HELP)
    add_param_arguments(p)
    add_solver_arguments(p)
    p.add_argument("--out", required=True, help="output folder (resumable)")


def _collapse_limit(text: str, capacity: float):
    from nsd_core.study.ida import Limit, parse_limit
    if text.strip() == "capacity":
        return Limit("stroke", capacity)
    if text.split("=")[0].strip() in ("drift", "impact"):
        try:   # nsd ida's --limit parser: its message names the option typed here
            return parse_limit(text)
        except ParameterError as e:
            said = str(e)
            raise ParameterError("--collapse" + said[len("--limit"):] if said.startswith("--limit ") else said) from None
    raise ParameterError(f"--collapse {text!r}: unknown surrogate; allowed: {COLLAPSE}")


def _no_repeat(option: str, text: str | None) -> None:
    """A NAME=VALUE list names each NAME once (a repeated one is refused, not the last kept)."""
    names = [item.partition("=")[0].strip().upper() for item in (text or "").split(",") if item.strip()]
    for n in names:
        if names.count(n) > 1:
            raise ParameterError(f"{option} {text!r}: {n} is given {names.count(n)} times; give each once")


def _isolators(text: str) -> list[str]:
    from nsd_core.structure.isolators import CHOICES
    names = [n.strip() for n in str(text).split(",") if n.strip()]
    bad = [n for n in names if n not in CHOICES]
    if not names or bad or len(set(names)) != len(names):
        raise ParameterError(f"--isolators {text!r}: allowed: a list of distinct {', '.join(CHOICES)}")
    return names


def _numbers(structure) -> dict:
    """A structure's numbers as a run takes them (its provenance is not an input)."""
    d = structure.to_dict()
    d.pop("provenance", None)
    if isinstance(d.get("isolator"), dict):
        d["isolator"].pop("provenance", None)
    return d


def _what_passes(traces, store, params, structures, states, limit, level, ratings) -> dict:
    """The displacement capacity at which each configuration passes (nsd_core.study.p695_capacity),
    with the capacity surrogate only (a drift or impact collapse has no capacity to move)."""
    from functools import lru_cache
    from nsd_core.study import p695, p695_capacity
    if limit.kind != "stroke":
        return {"note": f"with --collapse {limit.kind} the collapse does not depend on a displacement capacity"}

    def mu_of(device, st):
        return lru_cache(maxsize=None)(lambda c: p695.pushover(params, st, c, device=device)["mu_T"])
    pushovers = {name: (dev, mu_of(dev, st)) for name, (dev, st) in structures.items()}
    return p695_capacity.what_passes(p695_capacity.curves(traces, store), states.capacity, pushovers, level, ratings,
                                     params.rod_length)


def _request(args):
    """The records, design category, quality ratings, local workers, configurations and hunt, checked in turn."""
    from nsd_cli.options import reject_record_set_in_set, resolved_workers, whole
    from nsd_core.study import p695
    from nsd_core.study.hunt import Hunt
    from nsd_core.study.seismic_set import parse_records
    reject_record_set_in_set(args.set)
    records = parse_records(args.records, "farfield")
    sdc = p695.check_sdc(args.sdc)
    _no_repeat("--quality", args.quality)
    ratings = p695.parse_ratings(args.quality)
    whole("--bootstrap", args.bootstrap, 100, 100000)
    if args.seed is not None:
        whole("--seed", args.seed, 0, 2 ** 32 - 1)
    workers = resolved_workers(args.workers)
    if args.duration is not None and not (0.1 <= args.duration <= 1000.0):
        raise ParameterError(f"--duration = {args.duration!r}: allowed: model seconds in [0.1, 1000]")
    configs = _isolators(args.isolators)
    hunt_given = {n: getattr(args, n) for n in ("start", "step", "max_runs", "resolution") if getattr(args, n) is not None}
    hunt = Hunt(**{**P695_HUNT, **hunt_given, "fill": bool(args.fill)})
    return records, sdc, ratings, workers, configs, hunt


def _structure_and_collapse(args):
    """The parameters, the structure at its design level, the collapse surrogate and its limit states."""
    from nsd_cli.ida_states import parse_limit_states
    from nsd_cli.seismic_building import with_building
    from nsd_cli.seismic_extras import isolated_structure
    params = base_params(args)
    args.restrainer = args.restrainer or args.collapse.strip().startswith("impact")
    # the isolation level as designed: its supplemental damping (docs/design.md), every device alike
    args.design_level, args.isolator, args.resize = True, "device", False
    structure = with_building(args, isolated_structure(args, params))
    cap = None if args.capacity is None else f"capacity={args.capacity!r}"
    limit = _collapse_limit(args.collapse, 1.0)   # checked before the states (a capacity comes from them)
    states = parse_limit_states(cap, params, structure, option="--capacity" if cap else "--limit-states", limit=limit)
    limit = _collapse_limit(args.collapse, states.capacity)
    if limit.kind == "drift" and structure.building is None:
        raise ParameterError(f"--collapse {args.collapse!r}: drift needs a building on the slab (--building stories=N)")
    return params, structure, cap, states, limit


def _set_sa(args, records, structure, hunt, period):
    """The set's common ground settings and S_NRT (median Sa(T) of the records' components); the work checked."""
    import numpy as np
    from nsd_cli.limits import check_ida_work
    from nsd_core.ground.records import SIMILITUDE_TIME_FACTOR, fema_record
    from nsd_core.study.intensity import component_sa
    ground = {"scale": 1.0, "time_factor": SIMILITUDE_TIME_FACTOR, "window": None, "rotate_deg": 0.0,
              "normalised": True}
    motions = {rid: fema_record("farfield", rid, **ground) for rid in records}
    durations = {r: min(m.duration, args.duration or m.duration) for r, m in motions.items()}
    check_ida_work(durations, hunt.max_runs, "--max-runs", structure.building.stories if structure.building else 0)
    # the set's median Sa at T (every component of the chosen records): a level is this x the common scale
    s_nrt = float(np.median([component_sa(c.t, c.a, period) for m in motions.values() for c in m.comp]))
    return ground, s_nrt


def run(args) -> int:
    """The evaluation: the request checked, every trace run (resumable, parallel), p695.json and its lines said."""
    from comparisons.engines import run_seismic_engine
    from comparisons.harness import code_fingerprint
    from nsd_core.ground.records import SIMILITUDE_TIME_FACTOR
    from nsd_core.device.model import DEFAULT_SOLVER
    from nsd_core.study import p695
    from nsd_core.structure.isolators import sized
    from nsd_core.study.ida import Trace, trace_all
    from nsd_core.study.ida_outputs import write_ida
    from nsd_core.study.p695_outputs import evaluation, print_lines, write_p695
    from nsd_core.study.store import Store
    records, sdc, ratings, workers, configs, hunt = _request(args)
    params, structure, cap, states, limit = _structure_and_collapse(args)
    solver = {**DEFAULT_SOLVER, **solver_settings(args)}
    period = structure.first_period
    level = p695.design_level(sdc, period, SIMILITUDE_TIME_FACTOR, G_RECORDS)
    ground, s_nrt = _set_sa(args, records, structure, hunt, period)
    out = check_out_dir("--out", args.out)
    if cap is None:   # a device without a working range: the capacity falls back to the rod's length, said
        from nsd_cli.ida_states import default_capacity
        value, source = default_capacity(params, structure)
        if "rod" in source:
            print(f"nsd p695: note: collapse capacity {value:g} m = {source}; give --capacity to choose another")
    common = dict(ground=ground, params=params.to_dict(), duration=args.duration, dt_out=1e-3, settings=solver,
                  code=code_fingerprint(), states=states.to_dict(), set="farfield")
    structures = {name: (name == "device", structure if name in ("device", "linear") else
                         structure.with_isolator(sized(name, structure.mass))) for name in configs}
    traces = [Trace(rid, dev, s_nrt, {**common, "structure": _numbers(st)}, limit, hunt, None, config=name)
              for rid in records for name, (dev, st) in structures.items()]
    store = Store(out)
    store.remove_stale_temps()
    elapsed = trace_all(traces, store, workers=workers, run_engine=run_seismic_engine, tally=args.tally)
    measure = {"measure": "sa_set_median", "period": period, "S_NRT": s_nrt, "unit": "m/s^2",
               "definition": "median Sa(T) (5 %) of the normalised set's components x the common scale"}
    index = {"set": "farfield", "records": records, "measure": measure, "limit": limit.describe(),
             "limit_option": args.collapse, "hunt": hunt.__dict__, "levels": None, "structure": structure.to_dict(),
             "ground": ground, "code": common["code"], "elapsed_this_run_s": elapsed}
    index = write_ida(traces, store, index)
    from nsd_core.study.p695_capacity import curves
    result = evaluation(traces, params, structures, states, limit, level, s_nrt, ratings, args.bootstrap,
                        args.seed if args.seed is not None else p695.SEED, records, elapsed, os.getloadavg(),
                        curves=curves(traces, store))
    result["what_passes"] = _what_passes(traces, store, params, structures, states, limit, level, ratings)
    write_p695(result, out)
    print("\n".join(print_lines(result)))
    if result["what_passes"].get("configurations"):
        from nsd_core.study.p695_capacity import lines
        print("\n".join(lines(result["what_passes"])))
    print(f"wrote {out / 'p695.json'}, {out / 'p695.png'}, {out / 'limit_states.json'}, {out / 'ida.csv'}")
    return 3 if any(t["undetermined"] for t in index["traces"]) else 0
