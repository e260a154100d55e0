"""A pool worker's warm-up: what ``nsd_core.engine.workers.worker_pool(n, warm=...)``
runs once in each worker before its first job, so that the first job costs what the later ones do.

Unpickling ``warm_worker`` in a worker imports the in-house model (the worker's first ~1-2 s); it runs the tiny problem (``nsd_core.compilation.warmup``) of every
kind the pool's jobs will run (``kind``: mode, method, backend, path kind, as ``warm_and_time`` keys
its runs), reads the FEMA P695 sets' files the jobs will read, and calls the peers' tiny runs it is
given (the study and comparison layers build those: this layer knows only the in-house engine).
"""
from __future__ import annotations

from functools import partial

from nsd_core.compilation import first_compile
from nsd_core.ground import records
from nsd_core.device.model import DEFAULT_SOLVER, simulate
from nsd_core.structure.seismic import simulate_seismic
from nsd_core.compilation.warmup import warm
from nsd_core.engine.timing import PATHS
from nsd_core.engine.compile_once import share_work


def kind(mode: str, settings: dict | None = None, path: str = "line") -> tuple:
    """The warm-up kind (mode, method, backend, path kind) of an in-house run with these solver
    settings (unset ones: the defaults), as ``warm_and_time`` keys it."""
    s = {**DEFAULT_SOLVER, **(settings or {})}
    return (mode, s["method"], s["backend"], path if path in PATHS else "line")


def warm_worker(kinds=(), record_sets=(), calls=()) -> None:
    """A pool worker's warm-up (``worker_pool``'s ``warm``), once per worker before its first job:
    import the in-house model, make its shared kernels ready (``engine_units``), call each
    of ``calls`` (picklable; a peer engine's tiny run, its import and compiled callbacks), run each
    ``kind``'s tiny problem (its kernels loaded from numba's cache or compiled), and read the files
    of each FEMA P695 set named in ``record_sets``. On a cold cache the workers share the compiling
    (``share_work``): while one compiles an item the others take the next ones instead of waiting,
    so two workers are ready in about half the time one would take. A failure is left to the job
    that meets it, with its own inputs."""
    first_compile.disable()   # the pool's workers share the compiling: no helper of their own
    items = []
    if kinds:   # the units, and each compiled mode's callbacks as items of their own, not inside its
        # tiny run: one worker takes them while another is on the evaluation and step loop
        from nsd_core.engine.rk import METHODS
        items += first_compile.mode_items({k[0] for k in kinds if k[1] in METHODS and k[2] in ("auto", "compiled")})
    # one lock per peer engine and one per in-house mode: the runs under one lock compile the same
    # kernels (MuJoCo's step loop for a line and a circle), so two workers never take two of them at once
    items += [(f"warm-call-{_name(call)}", partial(_quietly, call)) for call in calls]
    fns = {"drive": simulate, "seismic": simulate_seismic}
    items += [(f"warm-kind-{k[0]}", partial(_quietly, partial(warm, k[0], fns[k[0]], *k[1:]))) for k in kinds]
    share_work(items)
    for name in record_sets:
        for f in records.SETS[records.set_name(name)][0]:
            records._package_file(f)   # cached per process: the set's HDF5 file read once


def _name(call) -> str:
    """A warm-up call's lock name: the engine it runs (its first argument, a name), file-safe."""
    engine = next((a for a in getattr(call, "args", ()) if isinstance(a, str)), "call")
    return "".join(c if c.isalnum() or c in "._-" else "_" for c in engine)[:40]


def _quietly(call, block: bool = True) -> None:
    """``call()`` as a share_work item (it always runs: ``block`` is not needed)."""
    try:
        call()
    except Exception:  # noqa: BLE001 (the job reports its own error)
        pass
