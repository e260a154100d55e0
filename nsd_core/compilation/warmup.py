"""Compilation kept out of a run's recorded cost (docs/report.md, compile_time).

The in-house engine's kernels are numba functions: the first call in a process compiles them (or
loads them from the on-disk cache), which on a cold cache takes tens of seconds, against ~0.04 s for
a 1 Hz cycle once warm. ``nsd_core.engine.timing.warm_and_time`` wraps ``simulate`` and
``simulate_seismic`` and calls ``warm`` below (installed there when nsd_core is imported): before the
wrapped run's own timer starts, the first call in a process for a (mode, method, backend) runs a
tiny problem of the same kind (a 100 Hz, 1 mm line cycle of 16 samples; 4 ms of a harmonic ground
motion) and records its duration as ``stats["compile_time"]`` (0 once warm); ``stats["cpu_time"]``
is the run's own CPU time (time.process_time), beside its ``wall_time``. Neither start-up nor the
warm-up run is ever part of ``wall_time``/``cpu_time``: those are the integration.

A pool worker does all of this before its first job: nsd_core.compilation.worker_warmup.
"""
from __future__ import annotations

import functools
import time

from nsd_core.engine.timing import install

_WARM: set[tuple] = set()   # (mode, method, backend, path kind) already compiled in this process


# The tiny problems are as short as the bounds allow: what compiles does not depend on their length,
# and each peer's tiny runs are paid in every pool worker at every start (Exudyn's 20 Hz drive cycle
# and 20 ms seismic run cost 0.32 s and 0.59 s warm, against 0.065 s and 0.12 s for these)
TINY_FREQUENCY = 100.0   # Hz, the drive's upper bound
TINY_DURATION = 0.004    # s of ground motion, 4 output intervals of TINY_DT_OUT
TINY_DT_OUT = 1e-3


def tiny_drive(path: str = "line"):
    """The warm-up's drive: a 100 Hz, 1 mm cycle of 16 samples along ``path`` (a path kind of nsd_core.engine.timing.PATHS)."""
    from nsd_core.device.drive import Drive
    minor = 0.0005 if path in ("ellipse", "figure8") else None
    return Drive(0.001, TINY_FREQUENCY, cycles=1, samples_per_cycle=16, path=path, minor=minor)


def tiny_ground():
    """The warm-up's ground motion: 4 ms of a 2 Hz, 0.1 m/s^2 harmonic."""
    from nsd_core.ground.motions import Harmonic
    return Harmonic(0.1, 2.0, duration=TINY_DURATION)


def _tiny_drive_run(fn, method: str, backend: str, path: str) -> None:
    from nsd_core.device.params import Params
    fn(Params(), tiny_drive(path), method=method, backend=backend)


def _tiny_seismic_run(fn, method: str, backend: str, path: str) -> None:
    from nsd_core.structure.isolation import default_structure
    from nsd_core.device.params import Params
    fn(Params(), default_structure(Params()), tiny_ground(), duration=TINY_DURATION, dt_out=TINY_DT_OUT, method=method,
       backend=backend)


TINY = {"drive": _tiny_drive_run, "seismic": _tiny_seismic_run}


def warm(mode: str, fn, method: str, backend: str, path: str = "line") -> float:
    """Run the tiny problem of ``mode`` once per process and (method, backend, path kind); its seconds
    (0 when already warm or when the backend compiles nothing). A failure is left to the real run."""
    key = (mode, method, backend, path)
    if key in _WARM or backend == "numpy":
        return 0.0
    _WARM.add(key)   # before the call: the tiny run goes through the same wrapper
    from nsd_core.compilation import first_compile
    from nsd_core.engine.rk import METHODS
    start = time.perf_counter()
    tiny = functools.partial(TINY[mode], fn, method, backend, path)
    try:
        # a cold cache: the step loop's kernels compiled side by side with one helper process
        if method in METHODS and backend in ("auto", "compiled") and first_compile.worth_a_helper(key):
            first_compile.run_shared(key, tiny)
        else:
            tiny()
        first_compile.mark_ready(key)
    except Exception:  # noqa: BLE001 (the real run reports its own error, with its own inputs)
        pass
    return time.perf_counter() - start


install(warm)   # every run wrapped by warm_and_time (nsd_core.engine.timing) warms up through this
