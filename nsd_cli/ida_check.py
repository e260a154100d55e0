"""An IDA cross-checked where it counts (docs/ida.md): per configuration, the record whose limit
intensity lies closest to the fitted median (in ln IM) is run again at that intensity with its time
series kept, and checked against other models on the same output times:

- with the device: MuJoCo and Exudyn (``comparisons.engines.run_seismic_engine``), differences by
  ``comparisons.seismic.seismic_metrics`` (max |difference| / max over the run of u, device force,
  a_abs; the peaks' relative differences);
- on the supports alone (which MuJoCo and Exudyn do not model): the exact solution of the linear
  oscillator (nsd_cli.ida_exact, eqsig's Nigam-Jennings recursion on the record's own samples).

Each peer runs the record at its step and at the gate's companion step for its method (twice it for
Exudyn, half of it for MuJoCo's Euler: comparisons.estimate.companion_times), its own error estimate
judged by the gate's rule; one that is not converged there runs it once more at the step its runs ask
for (nsd_cli.ida_refine), its first pair's verdict kept beside the refined one.

A limit reached by the rod's length stops the run; the check then runs at the bracket's lower end,
the highest level below the limit, where every model runs the whole record (said in the entry).
Written to DIR/cross_check/<config>/ (seismic.csv, seismic_<engine>.csv) and ida.json's
"cross_check"; the runs are jobs of the IDA's store (resumable).

``--cross-check none|median|all`` (``MODES``): no re-run; the record closest to the median (the
default); or every record that reached the limit (the others under DIR/cross_check/<config>/record_<id>/
and ida.json's "cross_check"["records"]), refused before anything runs when the peers' estimated
steps exceed ``STEPS_MAX``. Each run's wall time is kept with its entry; the cross-check's own time is
returned apart from the IDA's.
"""
from __future__ import annotations

import math
import shutil
import time
import traceback
from functools import partial
from pathlib import Path

from comparisons.seismic import building_metrics, seismic_metrics
from nsd_core.structure.isolation import Structure
from nsd_core.device.params import ParameterError
from nsd_core.device.results import RunResult, read_csv, write_columns
from nsd_core.study.ida import Trace, run_ida_point
from nsd_core.study.store import Store
from nsd_core.study.sweep import run_stored


MODES = ("none", "median", "all")
STEPS_MAX = 20_000_000   # peer steps of --cross-check all: about 2 h at the ~2500 steps per wall s measured
                         # for MuJoCo on the 2-core machine (Exudyn is slower; the in-house re-runs not counted)


def parse_mode(text) -> str:
    if text not in MODES:
        raise ParameterError(f"--cross-check {text!r}: unknown; allowed: {', '.join(MODES)}")
    return text


# Each peer's step on a whole record. MuJoCo Euler: the gate's on its seismic cases (comparisons/cases.toml,
# judged by the per-run rule there) 2e-5 s, 1e-5 s under a building. Exudyn: 1.25e-5 s, the step its own
# runs asked for on the far-field median record (15 at its limit intensity, 16.9 model s): at the gate's
# 1e-4 s its device force differed from the in-house run by 1.4e-2 of its peak (FAIL, not converged; 1.6e-3
# at 2.5e-5 s, 1.1e-3 at 2e-5 s), its refinement asked 1.02e-5 s, capped at 1.25e-5 s, where it passed
# (dF 4.4e-4, estimate 4.4e-4; docs/performance.md): a first pair at 1e-4 s was 57 s of runs spent on
# a FAIL. Other far-field records need finer (their dF against the in-house run, at limit intensity):
# record 4 (14.3 model s, 1.0 m/s^2) 1.8e-3 at 1.25e-5 s, 6.7e-3 at 2.5e-5 s (order 1.9: it asks 8.2e-6 s);
# record 20 (28.5 model s, 0.78 m/s^2) 4.5e-2 at 2.5e-5 s. From 1e-4 s their refinement (at most 8x the
# steps) could not reach a pass; from 1.25e-5 s it can. Each is run at that step and at its companion's (companion_times: 2h for Exudyn, h/2 for
# MuJoCo's Euler, as the gate), so that its own error estimate on this record is measured, not assumed.
PEER_STEPS = {"mujoco": ("timestep", 2e-5, 1e-5), "exudyn": ("step_size", 1.25e-5, 1.25e-5)}
METRIC_TOLERANCE = {"du": "max_du_rel", "dF": "max_dF_device_rel", "da": "peak_a_rel"}


def companion_times(engine: str) -> float:
    """A peer's companion step over its judged step: the gate's for its method with the cross-check's
    settings (comparisons.estimate.companion_times: 2 for Exudyn, 1/2 for MuJoCo's Euler)."""
    from comparisons.estimate import companion_times as gate_companion
    return gate_companion(engine, {})


def pair_cost(engine: str) -> float:
    """A peer's pair (its run and its companion) in steps of its judged run: 1.5 (2h), 3 (h/2)."""
    return 1.0 + 1.0 / companion_times(engine)


def peer_settings(engine: str, building: bool, companion: bool = False, step: float | None = None) -> dict:
    """The settings of a peer's cross-check run: its step on a whole record (``PEER_STEPS``; ``step``:
    a refined one, nsd_cli.ida_refine), times ``companion_times`` for the run that estimates its error."""
    key, h, h_building = PEER_STEPS[engine]
    step = step if step is not None else (h_building if building else h)
    return {key: step * companion_times(engine) if companion else step}


def peer_step(engine: str) -> float:
    """A peer's cross-check step [s] on a seismic run without a building (PEER_STEPS)."""
    return PEER_STEPS[engine][1]


def check_work(mode: str, durations: dict, peers: list[str]) -> dict:
    """The cross-check's estimated peer steps before anything runs: 'median' re-runs at most one record
    (the longest counted), 'all' every record (ParameterError, one line, over STEPS_MAX)."""
    if mode == "none" or not peers:
        return {"mode": mode, "peer_steps": 0, "records": 0}
    n = len(durations) if mode == "all" else 1
    seconds = sum(durations.values()) if mode == "all" else max(durations.values())
    steps = sum(pair_cost(e) * seconds / peer_step(e) for e in peers)   # the run at h and its companion
    if steps > STEPS_MAX:
        raise ParameterError(f"--cross-check all: {n} records x {len(peers)} engines ({', '.join(peers)}) over "
                             f"{seconds:.4g} model s would take about {steps:.3g} peer steps; allowed: at most "
                             f"{STEPS_MAX:.0e} (--cross-check median, fewer --records or --engines semirecursive)")
    return {"mode": mode, "peer_steps": steps, "records": n}


def choose(traces: list[Trace], config: dict, device: bool, store: Store) -> dict | None:
    """The record closest to the median and the level to check it at (None: nothing to check)."""
    median = config.get("median") or (config.get("baker2015") or {}).get("median")
    reached = [r for r in config["records"] if r["limit_im"] is not None]
    if not reached:
        return None
    median = median or reached[0]["limit_im"]
    best = min(reached, key=lambda r: (abs(math.log(r["limit_im"] / median)), r["record"]))
    return pick_for(best, traces, device, store, median)


def pick_for(best: dict, traces: list[Trace], device: bool, store: Store, median: float) -> dict:
    """The level at which to check the record ``best`` (a fragility record entry that reached the limit)."""
    tr = next(t for t in traces if t.record == best["record"] and t.device == device)
    level, note = best["limit_im"], "at the record's limit intensity"
    rec = store.load(tr.point(level).key)
    contact = not device and tr.common["structure"].get("restrainer") is not None
    if rec is None or rec["status"] != "ok" or contact:
        if contact and best["below_im"] is not None:
            return {"record": best["record"], "trace": tr, "level": best["below_im"], "limit_im": best["limit_im"],
                    "median": median, "note": "at the highest level below the limit: the exact linear solution "
                                              "holds while the restrainer is not touched"}
        if best["below_im"] is None:
            return {"record": best["record"], "skipped": "the lowest level run already stopped the run "
                    "(rod reach); no level below the limit to check"}
        level = best["below_im"]
        note = (f"at the highest level below the limit ({level:.6g} m/s^2): at the limit intensity "
                f"({best['limit_im']:.6g} m/s^2) the run stops ({(rec or {}).get('error')})")
    return {"record": best["record"], "trace": tr, "level": level, "limit_im": best["limit_im"],
            "median": median, "note": note}


def run_peer(r, run_engine) -> dict:
    """One peer engine's run of an IDA point (in a worker), its series kept; never raises for the run's
    own failure. The in-house summary (nsd_core.structure.seismic.seismic_summary) needs columns that
    peers do not write (the ground's), so a peer's run keeps its solver statistics only."""
    start = time.perf_counter()
    try:
        from nsd_core.ground.records import fema_record
        from nsd_core.device.params import Params
        motion = fema_record(r.set, r.record, **r.ground)
        result = run_engine(r.engine, Params(**r.params), Structure(**r.structure), motion, duration=r.duration,
                            dt_out=r.dt_out, settings=r.settings or None)
        return {"status": "ok", "error": None, "metrics": {"solver": result.stats},
                "files": {"seismic.csv": result}, "wall_time": time.perf_counter() - start}
    except Exception as e:  # noqa: BLE001 - reported for this engine; the others go on
        return {"status": "failed", "error": " ".join(f"{type(e).__name__}: {e}".split())[:500],
                "metrics": {"reason": "error"}, "traceback": traceback.format_exc(limit=6),
                "wall_time": time.perf_counter() - start}


def cross_check_job(r, run_engine) -> dict:
    """The in-house runs as the IDA's (run_ida_point), the peers' by run_peer."""
    return run_ida_point(r, run_engine) if r.engine == "semirecursive" else run_peer(r, run_engine)


def cross_check(traces: list[Trace], store: Store, frag: dict, peers: list[str], workers: int, scheduler,
                log, run_engine, mode: str = "median") -> tuple[dict, float]:
    """Run the checks (see the module docstring); returns ida.json's "cross_check" and the seconds the
    cross-check's runs took in this call (0 when every run was stored)."""
    if mode == "none":
        return {n: {"skipped": "not asked for (--cross-check none)"} for n in ("device", "nodevice")}, 0.0
    out, picks, others = {}, {}, {"device": [], "nodevice": []}
    for name, device in (("device", True), ("nodevice", False)):
        config = frag["configurations"][name]
        pick = choose(traces, config, device, store)
        picks[name] = pick
        if pick is None:
            out[name] = {"skipped": "no record reached the limit"}
        elif device and not peers:
            out[name] = {"record": pick["record"], "skipped": "no other engine asked for (--engines)"}
            picks[name] = None
        elif "skipped" in pick:
            out[name] = pick
        if mode == "all" and picks[name] is not None:
            others[name] = [pick_for(r, traces, device, store, pick.get("median") or r["limit_im"])
                            for r in config["records"] if r["limit_im"] is not None and r["record"] != pick["record"]]
    chosen = [p for p in [*picks.values(), *others["device"], *others["nodevice"]] if p and "trace" in p]
    jobs = []
    for pick in chosen:   # the peers' runs first, the finest step first: the longest start at once
        tr, level = pick["trace"], pick["level"]
        if tr.device:
            building = tr.common["structure"].get("building") is not None
            jobs += [tr.point(level, keep_series=True, engine=e, settings=peer_settings(e, building, c))
                     for e in sorted(peers, key=peer_step) for c in (False, True)]
        jobs.append(tr.point(level, keep_series=True))
        if tr.device and peers:   # the in-house run's own error: the same point at the converged settings
            jobs.append(_converged(tr, level))
    if not jobs:
        return out, 0.0
    fresh = {j.key for j in jobs if (rec := store.load(j.key)) is None or rec["status"] == "failed"}
    job = partial(cross_check_job, run_engine=run_engine)
    elapsed = run_stored(jobs, store, job, workers, scheduler, True, log,
                         None, f"ida cross-check ({mode}): {len(jobs)} runs (those stored as failed run again)")
    # a peer not converged on its record runs it once more at the step its own runs ask for (ida_refine)
    steps = {id(p): _refinements(p, store, peers, fresh) for p in chosen if p["trace"].device}
    planned = sum(pair_cost(e) * r["duration"] / r["step"] for per in steps.values() for e, r in per.items())
    if planned > STEPS_MAX:   # the refinements' own bound (--cross-check all: several records at up to 8x)
        n = sum(len(per) for per in steps.values())
        out["refinement_skipped"] = (f"{n} engine run(s) not converged at their step were not run again: about "
                                     f"{planned:.3g} peer steps, over {STEPS_MAX:.0e} (--cross-check median refines "
                                     "the median record alone)")
        log(f"ida cross-check ({mode}): {out['refinement_skipped']}")
        steps = {}
    again = [p["trace"].point(p["level"], keep_series=True, engine=e,
                              settings=peer_settings(e, _building(p["trace"]), c, r["step"]))
             for p in chosen for e, r in steps.get(id(p), {}).items() for c in (False, True)]
    if again:
        fresh |= {j.key for j in again if (rec := store.load(j.key)) is None or rec["status"] == "failed"}
        elapsed += run_stored(again, store, job, workers, scheduler, True, log, None,
                              f"ida cross-check ({mode}): {len(again)} runs of the engines not converged at "
                              "their step, at the step their runs ask for")
    for name, pick in picks.items():
        if pick and "trace" in pick:
            out[name] = _entry(pick, store, peers, store.root / "cross_check" / name, fresh, steps.get(id(pick)))
    if mode == "all":
        out["records"] = {name: [_entry(p, store, peers, store.root / "cross_check" / name / f"record_{p['record']}",
                                        fresh, steps.get(id(p))) if "trace" in p else p for p in lst]
                          for name, lst in others.items()}
    return out, elapsed


def _converged(tr: Trace, level: float):
    """The in-house run of a checked point at the gate's converged settings (rtol 1e-10): the re-run at
    the IDA's own settings is judged against it, its difference being that run's own error."""
    import dataclasses
    from comparisons.reference import CONVERGED_SETTINGS
    r = tr.point(level, keep_series=True)
    return dataclasses.replace(r, settings={**r.settings, **CONVERGED_SETTINGS})


def _own_error(tr: Trace, level: float, ref, store: Store) -> dict | None:
    """The IDA's in-house re-run's own error on this record (du, dF, da against the converged run), or
    None when that run is missing or failed."""
    key = _converged(tr, level).key
    rec = store.load(key)
    if rec is None or rec["status"] != "ok":
        return None
    return seismic_metrics(_stored_series(store.folder(key) / "seismic.csv", store.folder(key)), ref)


def _building(tr: Trace) -> bool:
    return tr.common["structure"].get("building") is not None


def _refinements(pick: dict, store: Store, peers: list[str], fresh: set) -> dict:
    """{engine: {"step": the refined step, "asked": what its runs asked for, before the cap, "first": its
    first pair's entry}} of the peers whose first pair on this record says "not converged" (ida_refine)."""
    from comparisons.estimate import nominal_order
    from nsd_cli.ida_refine import asked_step, refined_step
    tr, level = pick["trace"], pick["level"]
    ref_key = tr.point(level, keep_series=True).key
    ref_rec = store.load(ref_key)
    if ref_rec is None or ref_rec["status"] != "ok":
        return {}
    ref = _stored_series(store.folder(ref_key) / "seismic.csv", store.folder(ref_key))
    own = _own_error(tr, level, ref, store)
    out = {}
    for e in peers:
        first, parts = _peer_entry(tr, level, e, store, ref, own, fresh)
        if parts is None:
            continue
        settings = (parts["rec"].get("metrics", {}).get("solver") or {}).get("settings") or {}
        step = settings.get(PEER_STEPS[e][0])
        if step:
            args = (float(step), parts["verdict"], parts["diff"], parts["ref_check"], nominal_order(e, settings),
                    companion_times(e))
            new = refined_step(*args)
            if new is not None:
                out[e] = {"step": new, "asked": asked_step(*args), "duration": float(ref["t"][-1]), "first": first}
    return out


def _entry(pick: dict, store: Store, peers: list[str], folder: Path, fresh: set, refined: dict | None = None) -> dict:
    """One checked record: its runs' series copied into ``folder``, the differences, each run's wall
    time and whether it ran in this call (``run_now``) or was read from the store. A peer refined
    (``refined``: _refinements') is judged on its refined pair; its first pair's entry, judged there, is
    kept as "first"."""
    refined = refined or {}
    tr, level = pick["trace"], pick["level"]
    folder.mkdir(parents=True, exist_ok=True)
    ref_key = tr.point(level, keep_series=True).key
    ref_rec = store.load(ref_key)
    entry = {"record": pick["record"], "level": level, "limit_im": pick["limit_im"], "median": pick["median"],
             "scale": tr.point(level).ground["scale"], "note": pick["note"], "engines": {}}
    if ref_rec is None or ref_rec["status"] != "ok":
        entry["error"] = f"in-house run: {(ref_rec or {}).get('error')}"
        return entry
    _copy(store.folder(ref_key) / "seismic.csv", folder / "seismic.csv")
    ref = _stored_series(folder / "seismic.csv", store.folder(ref_key))
    entry["wall_time"] = {"semirecursive": ref_rec.get("wall_time")}
    entry["run_now"] = {"semirecursive": ref_key in fresh}
    if not tr.device:
        from nsd_cli.ida_exact import exact_supports_alone
        metrics, cols = exact_supports_alone(ref, tr, level)
        if cols is not None:
            write_columns(folder / "exact.csv", cols)
        entry["engines"]["exact"] = metrics
        return entry
    own = _own_error(tr, level, ref, store)
    entry["in_house_error"] = own   # the re-run's own error against the converged in-house run
    conv_key = _converged(tr, level).key
    entry["wall_time"]["converged"] = (store.load(conv_key) or {}).get("wall_time")   # that run's, counted in cost()
    entry["run_now"]["converged"] = conv_key in fresh
    for e in peers:
        r = refined.get(e)
        entry["engines"][e], _ = _peer_entry(tr, level, e, store, ref, own, fresh, r and r["step"], folder)
        if r:
            first = {k: v for k, v in r["first"].items() if k != "building"}
            entry["engines"][e]["first"] = first
            entry["engines"][e]["refined"] = {"from": first["settings"], "to": entry["engines"][e]["settings"],
                                              "asked": r["asked"], "capped": r["asked"] < r["step"]}
    return entry


def _peer_entry(tr: Trace, level: float, e: str, store: Store, ref, own, fresh: set, step: float | None = None,
                folder: Path | None = None) -> tuple[dict, dict | None]:
    """A peer's pair (at ``step``, or its own, and its companion) on a checked point: its entry
    (differences, timing, the gate's verdict) and the parts the refinement reads (None when a run
    failed); ``folder``: the judged run's series copied there."""
    building = _building(tr)
    runs = {}
    for c in (False, True):
        key = tr.point(level, keep_series=True, engine=e, settings=peer_settings(e, building, c, step)).key
        runs[c] = (key, store.load(key))
    (key, rec), (key2, rec2) = runs[False], runs[True]
    timing = {"wall_time": (rec or {}).get("wall_time"), "run_now": key in fresh,
              "check_wall_time": (rec2 or {}).get("wall_time"), "check_run_now": key2 in fresh,
              "settings": peer_settings(e, building, step=step)}
    if rec is None or rec["status"] != "ok" or rec2 is None or rec2["status"] != "ok":
        bad = rec if rec is None or rec["status"] != "ok" else rec2
        return {"status": "failed", "error": (bad or {}).get("error"), **timing}, None
    source = store.folder(key) / "seismic.csv"
    if folder is not None:
        _copy(source, folder / f"seismic_{e}.csv")
        source = folder / f"seismic_{e}.csv"
    peer = _stored_series(source, store.folder(key), e)
    check = _stored_series(store.folder(key2) / "seismic.csv", store.folder(key2), e)
    diff = seismic_metrics(ref, peer)
    verdict = judged(e, diff, seismic_metrics(check, peer), rec, rec2, own)
    out = {**diff, **timing, **verdict}
    if "floor1_x" in ref.columns:   # a building on the slab: its floors and stories too
        out["building"] = building_metrics(ref, peer)
    return out, {"rec": rec, "verdict": verdict, "diff": diff, "ref_check": seismic_metrics(ref, check)}


def judged(engine: str, diff: dict, h_vs_h2: dict, rec: dict, rec2: dict, own: dict | None = None) -> dict:
    """The peer's own error estimate on this record (Richardson from its run and its companion's, ``rec2``,
    at 2h or h/2, whichever their step counts say; ``h_vs_h2``: their difference; the gate's order for
    its method) and the gate's rule on du, dF and da (comparisons/tolerances.toml): consistent
    when the difference from the in-house run is within k (3) x (the estimate + the in-house run's own
    error, ``own``: its difference from the converged in-house run; as the gate adds its reference's),
    accurate when the estimate and the difference are within the tolerance. Without ``own`` the in-house
    run counts as exact: a peer refined below its error then reads as disagreeing."""
    from comparisons.tolerance_file import load_tolerances
    from comparisons.estimate import nominal_order, pair_factor, step_needed
    stats, stats2 = (r.get("metrics", {}).get("solver") or {} for r in (rec, rec2))
    order = nominal_order(engine, stats.get("settings") or {})
    factor, _ = pair_factor(order, stats, stats2, companion_times(engine) > 1.0)
    rule = load_tolerances().rule
    key, step = PEER_STEPS[engine][0], (stats.get("settings") or {}).get(PEER_STEPS[engine][0])
    out, ok, needed = {}, True, []
    for m, name in METRIC_TOLERANCE.items():
        est, tol = h_vs_h2[m] * factor, float(rule.engineering[name])
        consistent, accurate = diff[m] <= rule.k * (est + (own or {}).get(m, 0.0)), max(est, diff[m]) <= tol
        out[m] = {"estimate": est, "tolerance": tol, "consistent": consistent, "accurate": accurate}
        ok = ok and consistent and accurate
        if not accurate and step:
            needed.append(step_needed(float(step), max(est, diff[m]), tol, order))
    verdict = {"estimates": out, "verdict": "PASS" if ok else "FAIL"}
    if needed:   # what its own estimate asks for (as the gate's "not converged at these settings")
        verdict["step_needed"] = {key: min(needed)}
    return verdict


def _stored_series(path: Path, stored: Path, engine: str = "") -> RunResult:
    """A cross-checked run's series; a damaged one (truncated, edited) is one line naming where it is
    stored (exit 2), never a traceback."""
    try:
        return read_csv(path, engine)
    except (ValueError, IndexError, OSError) as e:
        raise ParameterError(f"{stored}: a damaged stored series ({' '.join(str(e).split())[:100]}); delete that "
                             "folder and run nsd ida again to redo it") from None


def _copy(src: Path, dest: Path) -> None:
    tmp = dest.with_name(f".{dest.name}.tmp")
    shutil.copyfile(src, tmp)
    tmp.replace(dest)
