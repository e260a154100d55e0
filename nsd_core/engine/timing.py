"""A run's recorded cost without its compilation: ``warm_and_time(mode)`` wraps a run function (the
device's drive, the structure's seismic run) so that compilation is never part of its ``wall_time``
or ``cpu_time`` (docs/report.md, compile_time).

Before the wrapped run's own clock starts, the warm-up installed here runs a tiny problem of the same
kind once per process (nsd_core.compilation.warmup installs it when nsd_core is imported: the
layers above the engine register their warm-up, the engine knows none of them); what the run itself
compiles beyond that (a structure the tiny run does not have) is measured by the engine's compile
accounting and moved out of its wall and CPU time into ``compile_time``.
"""
from __future__ import annotations

import functools
import inspect
import time

from nsd_core.engine.compile_once import compile_seconds

PATHS = ("line", "circle", "ellipse", "figure8")   # the path kinds with compiled callbacks of their own
_WARM_UP = [lambda mode, fn, method, backend, path: 0.0]   # warm(mode, fn, method, backend, path) -> s


def install(warm) -> None:
    """The warm-up every wrapped run calls first: ``warm(mode, fn, method, backend, path) -> seconds``."""
    _WARM_UP[0] = warm


def warm_and_time(mode: str):
    """Decorator: warm the compiled kernels first (``compile_time``), then time the run's CPU."""
    def wrap(fn):
        sig = inspect.signature(fn)

        @functools.wraps(fn)
        def run(*args, **kwargs):
            bound = sig.bind(*args, **kwargs)
            bound.apply_defaults()
            drive = bound.arguments.get("drive")
            path = drive.path if drive is not None and drive.path in PATHS else "line"   # a table: a line
            # what this run uses, at its first use (every mode at once is `nsd warm`'s: an explicit
            # step, nsd_core.compilation.warm_all; automatic, it made a first drive cycle slower, measured)
            compile_time = _WARM_UP[0](mode, fn, bound.arguments["method"], bound.arguments["backend"], path)
            c0, (cw0, cc0) = time.process_time(), compile_seconds()
            result = fn(*args, **kwargs)
            cpu = time.process_time() - c0
            # what the run itself compiled (a structure the tiny run does not have: a building, other
            # wires) is compilation too: moved out of its wall and CPU time
            cw, cc = (a - b for a, b in zip(compile_seconds(), (cw0, cc0)))
            result.stats["cpu_time"] = max(cpu - cc, 0.0)
            if cw > 0.0 and "wall_time" in result.stats:
                result.stats["wall_time"] = max(result.stats["wall_time"] - cw, 0.0)
            result.stats["compile_time"] = compile_time + cw
            return result
        return run
    return wrap

