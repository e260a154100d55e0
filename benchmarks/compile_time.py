"""Compilation measured apart from per-run cost: a fresh process's import and first short run
(the code given), once on an empty numba cache and once on the cache that run left behind."""
from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile


def first_run_seconds(code: str, cache_dir: str) -> tuple[float, float]:
    """(wall, CPU) seconds of a fresh process running ``code`` (which prints its own wall time last)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    return float(out.stdout.strip().splitlines()[-1]), cpu


def compile_times(code: str) -> dict:
    with tempfile.TemporaryDirectory() as cache:
        cold, cold_cpu = first_run_seconds(code, cache)
        warm, warm_cpu = first_run_seconds(code, cache)
    return {"cold_cache_first_run_s": cold, "warm_cache_first_run_s": warm, "compile_s": cold - warm,
            "cold_cache_first_run_cpu_s": cold_cpu, "warm_cache_first_run_cpu_s": warm_cpu,
            "compile_cpu_s": cold_cpu - warm_cpu}
