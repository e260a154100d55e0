"""Running a sweep: every design not yet stored, on local cores (ProcessPoolExecutor) or a Dask
cluster (``scheduler``). The parent stores each result as it arrives, so an interrupted sweep
loses at most the designs in flight. A design whose run raises is stored as failed with its
message; an executor breaking down is not stored (that is not the design's fault) and is retried
on the next run.
"""
from __future__ import annotations

import sys
import time
from concurrent.futures import as_completed
from functools import partial
from pathlib import Path
from typing import Any, Callable, Iterator

from nsd_core import __version__
from nsd_core.device.params import ParameterError, Params
from nsd_core.common.files import atomic_copy, atomic_write_json
from nsd_core.engine.workers import worker_pool
from nsd_core.study.designs import PAPER_STUDIES, Design
from nsd_core.study.run import EngineRunner, run_design
from nsd_core.study.store import Store


def _serial(designs: list[Design], job) -> Iterator[tuple[Design, dict]]:
    for d in designs:
        yield d, job(d)


def _local(designs: list[Design], job, workers: int, warm=None, startup: dict | None = None
           ) -> Iterator[tuple[Design, dict]]:
    # spawn, not fork: the parent may hold threads (a Dask client, numba) that fork would copy badly;
    # on Ctrl-C or SIGTERM the workers are terminated, not waited for (nsd_core.engine.workers);
    # ``warm`` runs once per worker before its first job, its cost reported into ``startup``
    with worker_pool(workers, warm=warm) as ex:
        futures = {ex.submit(job, d): d for d in designs}
        for f in as_completed(futures):
            yield futures[f], f.result()
        if startup is not None:
            startup.update(ex.startup.summary() or {})


def _dask(designs: list[Design], job, address, timeout: float = 10.0) -> Iterator[tuple[Design, dict]]:
    try:
        from distributed import Client, as_completed as dask_completed
    except ImportError:
        raise ParameterError("--scheduler: needs dask.distributed (pip install 'nsd-harness[dask]')") from None
    try:
        client = address if hasattr(address, "submit") else Client(address, timeout=f"{timeout}s")
    except (OSError, TimeoutError) as e:  # the address answered the check but not the client
        raise ParameterError(f"--scheduler {address}: no Dask scheduler answered within {timeout:g} s "
                             f"({type(e).__name__})") from None
    try:
        futures = {client.submit(job, d, key=f"nsd-design-{d.key}", pure=False): d for d in designs}
        for f in dask_completed(list(futures)):
            yield futures[f], f.result()
    finally:
        if client is not address:
            client.close()


def run_jobs(pending: list, job, workers: int = 1, scheduler=None, timeout: float = 10.0, warm=None,
             startup: dict | None = None) -> Iterator[tuple]:
    """(item, job(item)) for every item as each finishes: on the Dask cluster at ``scheduler``, on
    ``workers`` local processes, or in this process (one worker or one item). Each item needs a
    ``key``; ``job`` must be picklable (a module-level function or a partial of one). Local workers
    run ``warm`` (picklable) before their first job and report its cost into ``startup``."""
    if not pending:
        return iter(())
    if scheduler is not None:
        return _dask(pending, job, scheduler, timeout)
    if workers > 1 and len(pending) > 1:
        return _local(pending, job, min(workers, len(pending)), warm, startup)
    return _serial(pending, job)


def run_sweep(designs: list[Design], out: str | Path, workers: int = 1, scheduler=None, scheduler_timeout: float = 10.0,
              retry_failed: bool = False, log: Callable[[str], None] | None = None,
              run_engine: EngineRunner | None = None, tally: dict | None = None) -> dict:
    """Run every design not yet stored, store each as it finishes, then write the summaries.

    ``run_engine``: see ``nsd_core.study.run.run_design`` (None: the in-house model only).
    ``tally`` (a dict) is kept up to date with ``kept``, ``total`` and ``dir`` for an interrupt message."""
    job = partial(run_design, run_engine=run_engine)
    log = log or (lambda s: print(s, file=sys.stderr, flush=True))
    store = Store(out)
    store.remove_stale_temps()  # a killed run's half-written files (no worker runs yet)
    n_unique = len({d.key for d in designs})
    elapsed = run_stored(designs, store, job, workers, scheduler, retry_failed, log, tally,
                         f"sweep: {len(designs)} designs ({n_unique} distinct)", scheduler_timeout,
                         sweep_warmup(designs, run_engine))
    return write_summaries(designs, store, elapsed)


def sweep_warmup(designs: list[Design], run_engine: EngineRunner | None = None):
    """A worker's warm-up for these designs: the in-house kernels of each solver setting, and a tiny
    run of each other engine and setting through ``run_engine`` (nsd_core.compilation.worker_warmup)."""
    from nsd_core.compilation.warmup import tiny_drive
    from nsd_core.compilation.worker_warmup import kind, warm_worker
    kinds = sorted({kind("drive", d.settings) for d in designs if d.engine == "semirecursive"})
    peers = {(d.engine, repr(sorted(d.settings.items()))): (d.engine, d.settings) for d in designs
             if d.engine != "semirecursive" and run_engine is not None}
    calls = [partial(run_engine, e, Params(), tiny_drive(), s) for e, s in peers.values()]
    return partial(warm_worker, tuple(kinds), (), tuple(calls))


def run_stored(items: list, store: Store, job: Callable, workers: int, scheduler, retry_failed: bool,
               log: Callable[[str], None], tally: dict | None, heading: str, timeout: float = 10.0,
               warm=None, startup: dict | None = None) -> float:
    """Run each item (anything with ``key`` and ``label``) the store does not hold yet (or holds as
    failed, with ``retry_failed``), store each as it finishes; returns the seconds this took.
    ``tally`` is kept up to date with ``kept``, ``total`` and ``dir`` for an interrupt message.
    ``warm``: each local worker's warm-up before its first job (``nsd_core.engine.workers``); its
    cost is logged and put into ``startup`` (a dict), apart from every job's own time."""
    unique: dict[str, Any] = {}
    for it in items:
        unique.setdefault(it.key, it)
    pending = [it for k, it in unique.items()
               if (rec := store.load(k)) is None or (retry_failed and rec["status"] == "failed")]
    tally = tally if tally is not None else {}
    tally.update(kept=len(unique) - len(pending), total=len(unique), dir=str(store.root))
    log(f"{heading}, {len(unique) - len(pending)} already stored, {len(pending)} to run on "
        + (f"Dask at {scheduler}" if scheduler is not None else f"{workers} local worker(s)"))
    start = time.perf_counter()
    startup = startup if startup is not None else {}
    for n, (it, res) in enumerate(run_jobs(pending, job, workers, scheduler, timeout, warm, startup), 1):
        rec = store.save(it, res)
        tally["kept"] += 1
        tail = f"{res['wall_time']:.1f} s" if rec["status"] == "ok" else f"FAILED: {rec['error']}"
        log(f"  [{n}/{len(pending)}] {it.label} ({it.key}): {tail}")
    if startup:
        log(f"  worker start-up (not in the runs' times): {startup['workers']} worker(s) ready after "
            f"{startup['ready_s']:.1f} s at most (spawn and imports {startup['spawn_s']:.1f} s, warm-up "
            f"{startup['warm_s']:.1f} s)")
    return time.perf_counter() - start


def write_summaries(designs: list[Design], store: Store, elapsed: float) -> dict:
    """Per study: DIR/<study>/summary.json and the steady-cycle CSVs; DIR/sweep.json as index."""
    studies: dict[str, list] = {}
    for d in designs:
        rec = store.load(d.key)
        entry = {"value": d.value, "key": d.key, "engine": d.engine, "status": rec["status"] if rec else "missing",
                 "error": rec["error"] if rec else None, "amplitude": d.amplitude,
                 "amplitude_rule": d.amplitude_rule, "frequency": d.frequency}
        if rec and rec["status"] == "ok":
            m = rec["metrics"]
            for k in ("x_max_quasi_static", "theta_max_deg", "dissipated_energy", "peak_force",
                      "force_at_plus_A", "initial_stiffness", "stiffness_regions", "x_max",
                      "outside_working_range", "events", "wire_elongation_max", "wire_elongation_min"):
                entry[k] = m.get(k)
            entry["run_wall_time"] = rec["wall_time"]
            name = f"{d.study}={d.value:g}" + ("" if d.engine == "semirecursive" else f"@{d.engine}") + ".csv"
            atomic_copy(store.folder(d.key) / "steady.csv", store.root / d.study / name)
            entry["steady_csv"] = f"{d.study}/{name}"
            entry["cycle_csv"] = f"designs/{d.key}/cycle.csv"
        studies.setdefault(d.study, []).append(entry)
    for name, entries in studies.items():
        figs = PAPER_STUDIES.get(name, (None, None))[1]
        atomic_write_json(store.root / name / "summary.json", {
            "study": name, "parameter": name, "paper": figs, "frequency": entries[0]["frequency"],
            "values": [e["value"] for e in entries], "designs": entries,
            "notes": "dissipated_energy = loop area of the steady cycle [J]; theta_max = asin(X_max/l_d) "
                     "from the quasi-static X_max; stiffness in the steady CSV is dF/du [N/m], blank at turning points"})
    index = {"studies": {n: f"{n}/summary.json" for n in studies},
             "designs": len({d.key for d in designs}),
             "ok": sum(e["status"] == "ok" for es in studies.values() for e in es),
             "failed": sorted({e["key"] for es in studies.values() for e in es if e["status"] == "failed"}),
             "missing": sorted({e["key"] for es in studies.values() for e in es if e["status"] == "missing"}),
             "elapsed_this_run_s": elapsed, "version": __version__}
    atomic_write_json(store.root / "sweep.json", index)
    return index
