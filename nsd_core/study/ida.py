"""Incremental dynamic analysis (IDA) over a FEMA P695 record set (docs/ida.md).

Every record is traced twice, with the device and on the supports alone: scaled to intensity levels
chosen by hunt and fill (``nsd_core.study.hunt``) or given, until it reaches the limit state. Each
run is a job of the sweep's store (``nsd_core.study.store``, ``designs/<key>/``), a ``RecordRun`` of
the record-set runs (``nsd_core.study.seismic_set``) keyed by all its inputs, so an IDA that is
stopped resumes: each trace's choices are a pure function of its results, it retraces the same
levels and finds them stored. The runs go to local worker processes or a Dask cluster as the traces
ask for them (a trace waits for its own last run only, so every worker stays busy).

Limit states (``Limit``): ``stroke=VALUE`` peak |u| >= VALUE [m] (|u| the plate's displacement
relative to the base); ``restrainer`` the displacement restrainer engages (its force is positive at
some output time: |u| > u_gap; nsd_core.structure.restrainer, the runs carry it); ``drift=VALUE`` the
peak story drift ratio of a building on the slab (any story, |drift| / story height, -) >= VALUE
(the runs carry the building: nsd_core.structure.building); ``impact=VALUE`` the restrainer's force
>= VALUE [N]. A run that stops because the rod cannot reach (|u| >= l_d) or a wire leaves the SMA
law's validity ends the trace (the device is spent); the rod's reach counts as reaching ``stroke``
and ``restrainer`` (|u| passed them on its way to l_d), and for drift and impact the trace is
"stroke exhausted" (``trace_result``), never counted as reaching them. Every run also says which
of the five limit states of ``nsd_core.study.limit_states`` it reached and when. A solver failure ends
that record's trace undetermined (listed, left out of the fit).
"""
from __future__ import annotations

import math
import sys
import time
from concurrent.futures import FIRST_COMPLETED, wait
from dataclasses import dataclass, field
from functools import partial
from typing import Callable

from nsd_core.device.params import ParameterError
from nsd_core.ground.motions import SCALE_RANGE
from nsd_core.study.hunt import Hunt, next_hunt_level, next_stripe_level
from nsd_core.study.seismic_set import RecordRun, peak_drift_ratio, run_record, set_warmup
from nsd_core.study.store import Store

from nsd_core.study.limit_states import SPENT  # a run stopped by these ends its trace (the device is spent)

LIMITS = ("stroke", "restrainer", "drift", "impact")
VALUES = {  # the limits with a threshold: its upper bound (the lower is 0, excluded) and how to say it
    "stroke": (math.inf, "stroke=VALUE with VALUE > 0 (m)"),
    "drift": (1.0, "drift=VALUE with 0 < VALUE <= 1 (a story drift over the story's height, -)"),
    "impact": (1e9, "impact=VALUE with 0 < VALUE <= 1e9 (the restrainer's force, N)"),
}
# Limits a run stopped by the rod's reach is known to have reached: |u| rose continuously to l_d
# through every displacement below it. Drift and impact force were not observed in it: the trace
# ends there ("stroke exhausted") but is not counted as having reached them (nsd_core.study.limit_states).
PASSED_ON_THE_WAY = ("stroke", "restrainer")


@dataclass(frozen=True)
class Limit:
    """The limit state: kind (stroke, restrainer, drift) and its threshold (stroke: m; drift: -)."""
    kind: str
    value: float | None = None

    def describe(self) -> str:
        if self.kind == "stroke":
            return f"peak |u| >= {self.value:g} m (or the rod's length reached)"
        if self.kind == "drift":
            return (f"peak story drift ratio >= {self.value:g} (any story; a trace the rod's reach ends is stroke "
                    "exhausted, not counted as drift)")
        if self.kind == "impact":
            return (f"the restrainer's force >= {self.value:g} N (a trace the rod's reach ends is stroke exhausted, "
                    "not counted as an impact)")
        return "the displacement restrainer engages, |u| > u_gap (or the rod's length reached)"

    def evaluate(self, rec: dict) -> tuple[bool | None, str]:
        """(reached, why) of a stored run: None when the run cannot tell (a solver failure)."""
        if rec["status"] != "ok":
            reason = (rec.get("metrics") or {}).get("reason", "error")
            if reason in SPENT:
                return True, reason
            return None, f"{reason}: {rec.get('error')}"
        if self.kind == "restrainer":
            engaged = (rec["metrics"].get("peak_restrainer_force") or {}).get("value", 0.0) > 0.0
            return engaged, "restrainer" if engaged else ""
        if self.kind == "impact":
            force = (rec["metrics"].get("peak_restrainer_force") or {}).get("value", 0.0)
            return force >= self.value, "impact" if force >= self.value else ""
        if self.kind == "drift":
            peak = peak_drift_ratio(rec["metrics"])
            if peak is None:
                return None, "the run has no building (drift needs one)"
            return (peak >= self.value), "drift" if peak >= self.value else ""
        peak = rec["metrics"]["peak_displacement"]["value"]
        return (peak >= self.value), "stroke" if peak >= self.value else ""


def parse_limit(text: str) -> Limit:
    """'stroke=0.02', 'restrainer' or 'drift=0.005' -> Limit; ParameterError (one line) otherwise.
    ``drift`` needs a building (the command checks that)."""
    kind, sep, value = str(text).partition("=")
    kind = kind.strip()
    allowed = ("stroke=VALUE (m, 0 < VALUE), restrainer, drift=VALUE (-, 0 < VALUE <= 1; with --building), "
               "impact=VALUE (N, 0 < VALUE <= 1e9)")
    if kind not in LIMITS:
        raise ParameterError(f"--limit {text!r}: unknown limit state; allowed: {allowed}")
    if kind == "restrainer":
        if sep:
            raise ParameterError(f"--limit {text!r}: restrainer takes no value (its gap is the structure's "
                                 "restrainer_gap)")
        return Limit(kind)
    upper, wanted = VALUES[kind]
    try:
        v = float(value) if sep else math.nan
    except ValueError:
        v = math.nan
    if not (math.isfinite(v) and 0 < v <= upper):
        raise ParameterError(f"--limit {text!r}: {kind} needs a value, {wanted}")
    return Limit(kind, v)


@dataclass(frozen=True)
class IdaRun(RecordRun):
    """One run of an IDA: a record-set run, with its time series kept only when asked (the runs
    that are cross-checked): the peaks are what an IDA needs, and whole series of every level
    would fill the disk. ``states``: the limit states' thresholds (LimitStates.to_dict()), whose
    first crossing times the worker finds in the series before dropping them."""
    keep_series: bool = False
    states: dict | None = None


def run_ida_point(r: IdaRun, run_engine: Callable | None = None) -> dict:
    """run_record, without the time series unless the run keeps them (in a worker); with ``states``,
    metrics["crossings"] holds when the run first reached each."""
    out = run_record(r, run_engine, keep_partial=bool(r.states))
    partial = out.pop("partial", None)   # a stopped run's series up to its stop (not stored)
    if r.states and (out["status"] == "ok" or partial is not None):
        from nsd_core.study.limit_states import first_crossings
        series = out["files"]["seismic.csv"] if out["status"] == "ok" else partial
        if len(series["t"]) >= 2:
            out["metrics"]["crossings"] = first_crossings(series, r.states)
    if not r.keep_series:
        out["files"] = {}
    return out


@dataclass
class Trace:
    """One record in one configuration (device on/off), traced upwards in intensity."""
    record: int
    device: bool
    im1: float                     # the record's intensity at scale 1 [m/s^2]
    common: dict                   # IdaRun's fields but record, device, ground's scale
    limit: Limit
    hunt: Hunt | None = None
    levels: list[float] | None = None
    history: list = field(default_factory=list)  # (level, reached, why, key) in the order run
    stopped: str | None = None     # why the trace ended early (a run that could not tell)
    config: str | None = None      # the configuration's name where more than device / no device run (nsd p695)

    @property
    def name(self) -> str:
        if self.config:
            return f"{self.common['set']}_{self.record}_{self.config}"
        return f"{self.common['set']}_{self.record}" + ("" if self.device else "_nodevice")

    def point(self, level: float, keep_series: bool = False, engine: str = "semirecursive",
              settings: dict | None = None) -> IdaRun:
        c = dict(self.common)
        ground = {**c.pop("ground"), "scale": level / self.im1}
        if engine != "semirecursive":
            c["settings"] = dict(settings or {})  # a peer's own (the in-house solver's settings are not its)
        return IdaRun(record=self.record, device=self.device, ground=ground, keep_series=keep_series,
                      engine=engine, **c)

    def next_level(self) -> float | None:
        if self.stopped:
            return None
        hist = [(lv, r) for lv, r, _, _ in self.history]
        level = next_stripe_level(self.levels, hist) if self.levels is not None else next_hunt_level(self.hunt, hist)
        if level is not None and level / self.im1 > SCALE_RANGE[1]:
            return None  # the record would be scaled beyond nsd seismic's --scale bound: censored here
        return level

    def add(self, level: float, rec: dict, key: str) -> None:
        reached, why = self.limit.evaluate(rec)
        self.history.append((level, reached, why, key))
        if reached is None:
            self.stopped = why


def make_traces(set_: str, records: list[int], im1: dict[int, float], common: dict, limit: Limit,
                hunt: Hunt | None, levels: list[float] | None) -> list[Trace]:
    """A trace per record and configuration, the device's first."""
    return [Trace(rid, dev, im1[rid], {**common, "set": set_}, limit, hunt, levels)
            for rid in records for dev in (True, False)]


def _advance(tr: Trace, store: Store, retry_failed: bool, tried: set) -> tuple[IdaRun, float] | None:
    """(run, level): the trace's next run that the store does not hold, feeding it what the store holds."""
    while (level := tr.next_level()) is not None:
        p = tr.point(level)
        rec = store.load(p.key)
        if rec is not None and not _readable(tr.limit, rec):
            rec = None   # a stored run whose metrics the limit cannot read (damaged): run it again
        if rec is None or (retry_failed and rec["status"] == "failed" and p.key not in tried):
            return p, level
        tr.add(level, rec, p.key)
    return None


def _readable(limit: Limit, rec: dict) -> bool:
    try:
        limit.evaluate(rec)
        return True
    except (KeyError, TypeError, ValueError, AttributeError, IndexError):
        return False


class _Local:
    def __init__(self, workers, warm=None):
        from nsd_core.engine.workers import worker_pool
        self.cm = worker_pool(workers, warm=warm)   # warm workers (nsd_core.engine.workers)

    def __enter__(self):
        self.pool = self.cm.__enter__()
        return self

    def __exit__(self, *exc):
        return self.cm.__exit__(*exc)

    def submit(self, job, p):
        return self.pool.submit(job, p)

    @staticmethod
    def wait(futures):
        return wait(futures, return_when=FIRST_COMPLETED).done


class _Dask:
    def __init__(self, address):
        try:
            from distributed import Client, wait as dask_wait
        except ImportError:
            raise ParameterError("--scheduler: needs dask.distributed (pip install 'nsd-harness[dask]')") from None
        self.address, self.dask_wait = address, dask_wait
        self.client = address if hasattr(address, "submit") else Client(address, timeout="20s")

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self.client is not self.address:
            self.client.close()

    def submit(self, job, p):
        return self.client.submit(job, p, key=f"nsd-ida-{p.key}", pure=False)

    def wait(self, futures):
        return self.dask_wait(list(futures), return_when="FIRST_COMPLETED").done


def trace_all(traces: list[Trace], store: Store, workers: int = 1, scheduler=None, retry_failed: bool = False,
              log: Callable[[str], None] | None = None, run_engine: Callable | None = None,
              tally: dict | None = None) -> float:
    """Run every trace to its end, each run stored as it finishes; returns the seconds this took."""
    log = log or (lambda s: print(s, file=sys.stderr, flush=True))
    job = partial(run_ida_point, run_engine=run_engine)
    tally = tally if tally is not None else {}
    tally.update(kept=0, total=0, dir=str(store.root))
    tried: set = set()
    start = time.perf_counter()
    n = 0

    def done(tr, p, level, res):
        nonlocal n
        n += 1
        tried.add(p.key)
        rec = store.save(p, res)
        tally["kept"] += 1
        tally["total"] += 1
        tr.add(level, rec, p.key)
        reached, why = tr.history[-1][1], tr.history[-1][2]
        tail = f"{res['wall_time']:.1f} s" if rec["status"] == "ok" else f"stopped: {rec['error']}"
        log(f"  [{n}] {tr.name} IM {level:.5g} m/s^2 (scale {p.ground['scale']:.5g}): "
            f"{'LIMIT (' + why + ')' if reached else 'below the limit' if reached is False else 'undetermined'}, {tail}")

    first = {id(tr): _advance(tr, store, retry_failed, tried) for tr in traces}
    waiting = sum(p is not None for p in first.values())
    records = len({tr.record for tr in traces})
    log(f"ida: {len(traces)} traces ({records} records x {len(traces) // max(records, 1)} configurations), {waiting} "
        "with runs to do on " + (f"Dask at {scheduler}" if scheduler is not None else f"{workers} local worker(s)"))
    if scheduler is None and (workers <= 1 or waiting <= 1):
        for tr in traces:
            nxt = first[id(tr)]
            while nxt is not None:
                done(tr, *nxt, job(nxt[0]))
                nxt = _advance(tr, store, retry_failed, tried)
        return time.perf_counter() - start
    warm = set_warmup([nxt[0] for nxt in first.values() if nxt is not None], run_engine)
    with (_Dask(scheduler) if scheduler is not None else _Local(min(workers, waiting), warm)) as ex:
        inflight = {ex.submit(job, nxt[0]): (tr, *nxt) for tr in traces if (nxt := first[id(tr)]) is not None}
        while inflight:
            for f in ex.wait(inflight):
                tr, p, level = inflight.pop(f)
                done(tr, p, level, f.result())
                nxt = _advance(tr, store, retry_failed, tried)
                if nxt is not None:
                    inflight[ex.submit(job, nxt[0])] = (tr, *nxt)
    return time.perf_counter() - start


def trace_result(tr: Trace) -> dict:
    """A trace's outcome: the limit intensity (lowest level that reached the limit), the bracket's
    lower end, or the censoring level (highest level run, limit never reached), or undetermined."""
    reached = [lv for lv, r, _, _ in tr.history if r]
    below = [lv for lv, r, _, _ in tr.history if r is False]
    out = {"record": tr.record, "device": tr.device, "runs": len(tr.history), "limit_im": None,
           "below_im": None, "censored_at": None, "undetermined": tr.stopped}
    spent = [lv for lv, r, w, _ in tr.history if r and w in SPENT and not _counts(tr.limit, w)]
    if spent:   # the trace ended with the device spent: stroke exhausted, never counted as this limit
        out["stroke_exhausted_at"] = min(spent)
        reached = [lv for lv in reached if lv < min(spent)]
        below = [lv for lv in below if lv < min(spent)]
    if reached:
        hi = min(reached)
        out["limit_im"] = hi
        out["limit_why"] = next(w for lv, r, w, _ in tr.history if r and lv == hi)
        lower = [lv for lv in below if lv < hi]
        out["below_im"] = max(lower) if lower else None
    elif below and not tr.stopped:
        out["censored_at"] = max(below)
    return out


def _counts(limit: Limit, why: str) -> bool:
    """Whether a run stopped for ``why`` (the device spent) counts as reaching the limit."""
    return why == "rod_reach" and limit.kind in PASSED_ON_THE_WAY

