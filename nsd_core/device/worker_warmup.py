"""A pool worker's warm-up (issue 26, item 1): what ``nsd_core.engine.workers.worker_pool(n, warm=...)``
runs once in each worker before its first job, so that the first job costs what the later ones do.

Unpickling ``warm_worker`` in a worker imports the in-house model (the worker's first ~1-2 s); it runs the tiny problem (``nsd_core.device.warmup``) of every
kind the pool's jobs will run (``kind``: mode, method, backend, path kind, as ``warm_and_time`` keys
its runs), reads the FEMA P695 sets' files the jobs will read, and calls the peers' tiny runs it is
given (the study and comparison layers build those: this layer knows only the in-house engine).
"""
from __future__ import annotations

from nsd_core.device import ground
from nsd_core.device.model import DEFAULT_SOLVER, simulate
from nsd_core.device.seismic import simulate_seismic
from nsd_core.device.warmup import PATHS, warm
from nsd_core.engine.rk import compile_engine


def kind(mode: str, settings: dict | None = None, path: str = "line") -> tuple:
    """The warm-up kind (mode, method, backend, path kind) of an in-house run with these solver
    settings (unset ones: the defaults), as ``warm_and_time`` keys it."""
    s = {**DEFAULT_SOLVER, **(settings or {})}
    return (mode, s["method"], s["backend"], path if path in PATHS else "line")


def warm_worker(kinds=(), record_sets=(), calls=()) -> None:
    """A pool worker's warm-up (``worker_pool``'s ``warm``), once per worker before its first job:
    import the in-house model, run each ``kind``'s tiny problem (its kernels loaded from numba's cache
    or compiled), read the files of each FEMA P695 set named in ``record_sets``, and call each of
    ``calls`` (picklable; a peer engine's tiny run, its import and compiled callbacks). A failure is
    left to the job that meets it, with its own inputs."""
    if kinds:
        compile_engine()   # the shared units first, under their locks (nsd_core.engine.compile_once)
    fns = {"drive": simulate, "seismic": simulate_seismic}
    for mode, method, backend, path in kinds:
        warm(mode, fns[mode], method, backend, path)
    for name in record_sets:
        for f in ground.SETS[ground.set_name(name)][0]:
            ground._package_file(f)   # cached per process: the set's HDF5 file read once
    for call in calls:
        try:
            call()
        except Exception:  # noqa: BLE001 (the job reports its own error)
            pass
