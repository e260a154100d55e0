"""A run that compiles inside itself (a structure its warm-up did not have) records those seconds as
compilation, not as its cost (its honest cost, kept with the generated evaluations)."""
from __future__ import annotations

import time
from types import SimpleNamespace

from numba import njit

from nsd_core.engine.timing import warm_and_time
from nsd_core.engine.compile_once import compile_seconds


def _fresh_kernel():
    @njit
    def kernel(n):  # a new function object each call: numba compiles it for real
        acc = 0.0
        for i in range(n):
            acc += (i % 7) * 0.5
        return acc
    return kernel


@warm_and_time("drive")
def _run(params, drive, method="DOP853", backend="numpy"):   # numpy: the warm-up runs nothing
    start = time.perf_counter()
    _fresh_kernel()(1000)
    return SimpleNamespace(stats={"wall_time": time.perf_counter() - start})


def test_compilation_inside_a_run_is_moved_to_compile_time():
    before = compile_seconds()
    result = _run(None, None)
    spent_wall = compile_seconds()[0] - before[0]
    assert spent_wall > 0.0   # numba really compiled in the run
    s = result.stats
    assert s["compile_time"] >= spent_wall - 1e-12
    assert s["wall_time"] < spent_wall     # what is left is the run itself, microseconds
    assert s["cpu_time"] < 0.5 * (compile_seconds()[1] - before[1])
