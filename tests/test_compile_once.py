"""The engine compiled once (nsd_core.engine.compile_once): one line on stderr when a process really
compiles it, nothing when it loads a warm cache or stops on a bad input, nothing at import; and
processes started together share the units out instead of compiling the same one at once."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time

import pytest
from numba import njit, types

from nsd_core.engine import compile_once as co

NOTICE_START = co.NOTICE.split("(")[0]


def _python(code: str, cache_home, timeout=900) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME")}
    env["XDG_CACHE_HOME"] = str(cache_home)
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env, capture_output=True, text=True,
                          timeout=timeout)


def test_the_notice_comes_once_for_a_compilation_of_nsd_core_and_never_at_import(tmp_path):
    p = _python("""
        import sys
        from numba import njit
        import nsd_core.engine.compiled as C
        import nsd_core.engine.rk  # the engine's kernels compile at their first use, not at import
        sys.stderr.write("imported\\n")
        sys.stderr.flush()
        njit(lambda x: 2 * x)(3)  # not nsd_core's: no notice
        sys.stderr.write("other code compiled\\n")
        sys.stderr.flush()
        f = njit(cache=False)(C.copy_into.py_func)  # a fresh dispatcher of an engine function
        import numpy as np
        f(np.zeros(3), np.ones(3))
        f(np.zeros((2, 2)), np.ones((2, 2)))  # a second compilation: no second line
    """, tmp_path)
    assert p.returncode == 0, p.stderr
    lines = p.stderr.strip().splitlines()
    assert lines[:2] == ["imported", "other code compiled"], p.stderr
    assert len(lines) == 3 and lines[2].startswith(NOTICE_START), p.stderr


def test_a_bad_input_on_a_cold_cache_is_one_line_and_compiles_nothing(tmp_path):
    p = _python("""
        import sys
        from nsd_cli.main import main
        sys.argv = ["nsd", "cycle", "--amplitude", "0.01", "--frequency", "1", "--set", "bogus=1", "--out", "x"]
        sys.exit(main())
    """, tmp_path, timeout=120)
    assert p.returncode == 2, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "bogus" in lines[0] and NOTICE_START not in p.stderr, p.stderr


@pytest.mark.slow
def test_a_cold_cache_prints_the_notice_a_warm_one_does_not(tmp_path):
    run = """
        from nsd_core.device.drive import Drive
        from nsd_core.device.model import simulate
        from nsd_core.device.params import Params
        r = simulate(Params(), Drive(0.001, 20.0, cycles=1, samples_per_cycle=16))
        print(r["F"][-1])
    """
    cold = _python(run, tmp_path)
    assert cold.returncode == 0, cold.stderr
    assert [line for line in cold.stderr.splitlines() if line.startswith(NOTICE_START)] == \
        [co.NOTICE.format(seconds=co.NOTICE_SECONDS)], cold.stderr
    warm = _python(run, tmp_path)
    assert warm.returncode == 0 and warm.stdout == cold.stdout, warm.stderr
    assert NOTICE_START not in warm.stderr, warm.stderr


def _twice(x):
    return 2.0 * x


def _thrice(x):
    return 3.0 * x


def test_a_unit_another_process_compiles_is_waited_for_and_the_rest_done_meanwhile(tmp_path, monkeypatch):
    """A process holds unit a's lock (it is compiling a) for 2 s: compile_once("a") compiles the free
    unit b first, then waits for a's lock and only then makes a ready."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    sig = types.float64(types.float64)
    a, b = njit(cache=False)(_twice), njit(cache=False)(_thrice)
    monkeypatch.setattr(co, "UNITS", {})
    monkeypatch.setattr(co, "DONE", set())
    co.unit("test_a", ((a, sig),))
    co.unit("test_b", ((b, sig),))
    holder = subprocess.Popen([sys.executable, "-c", textwrap.dedent(f"""
        import fcntl, os, sys, time
        fd = os.open({str(tmp_path / ".test_a.lock")!r}, os.O_RDWR | os.O_CREAT)
        fcntl.flock(fd, fcntl.LOCK_EX)
        print("held", flush=True)
        time.sleep(2.0)
    """)], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        t0 = time.perf_counter()
        seen = {}
        original = co._compile_unit

        def spy(name, block):
            done = original(name, block)
            if done:
                seen[name] = time.perf_counter() - t0
            return done

        monkeypatch.setattr(co, "_compile_unit", spy)
        co.compile_once("test_a")
    finally:
        holder.wait(timeout=30)
    assert list(seen) == ["test_b", "test_a"], seen  # the free unit meanwhile, then the one waited for
    assert seen["test_a"] > 1.0, seen  # after the other process let go of a's lock
    assert a(2.0) == 4.0 and b(2.0) == 6.0 and co.DONE == {"test_a", "test_b"}


def _hold(lock_file, seconds: float) -> subprocess.Popen:
    """Another process holding ``lock_file`` for ``seconds`` (returns once it holds it)."""
    p = subprocess.Popen([sys.executable, "-c", textwrap.dedent(f"""
        import fcntl, os, time
        fd = os.open({str(lock_file)!r}, os.O_RDWR | os.O_CREAT)
        fcntl.flock(fd, fcntl.LOCK_EX)
        print("held", flush=True)
        time.sleep({seconds})
    """)], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "held"
    return p


def test_shared_work_puts_off_an_item_another_process_holds(tmp_path, monkeypatch):
    """A pool's warm-up (share_work): while another process holds item a's lock, items b and c run
    first; a runs last, once the other process has let go (then it only loads what that one left)."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    holder = _hold(tmp_path / ".warm-a.lock", 2.0)
    t0, ran = time.perf_counter(), []
    try:
        co.share_work([(f"warm-{n}", lambda block, n=n: ran.append((n, time.perf_counter() - t0))) for n in "abc"])
    finally:
        holder.wait(timeout=30)
    assert [n for n, _ in ran] == ["b", "c", "a"], ran
    assert ran[0][1] < 1.0 and ran[2][1] > 1.0, ran


def test_the_notice_is_printed_by_one_process_of_those_compiling_together(tmp_path, monkeypatch):
    """Two workers compiling at once on a cold cache: one line for the user, not one per worker."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    holder = _hold(tmp_path / ".notice.lock", 30.0)   # the other worker, which printed it
    try:
        assert co._first_to_announce() is False
    finally:
        holder.kill()
        holder.wait(timeout=30)
    assert co._first_to_announce() is True   # alone: this process prints it


def test_a_unit_is_put_off_while_another_process_compiles_what_it_needs(tmp_path, monkeypatch):
    """compile_now (a warm-up item): unit a needs unit b, which another process is compiling: False,
    nothing waited for and nothing compiled; once b's lock is free, b then a, True."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    sig = types.float64(types.float64)
    a, b = njit(cache=False)(_twice), njit(cache=False)(_thrice)
    monkeypatch.setattr(co, "UNITS", {})
    monkeypatch.setattr(co, "NEEDS", {})
    monkeypatch.setattr(co, "DONE", set())
    co.unit("test_b", ((b, sig),))
    co.unit("test_a", ((a, sig),), needs=("test_b",))
    holder = _hold(tmp_path / ".test_b.lock", 30.0)
    try:
        t0 = time.perf_counter()
        assert co.compile_now("test_a") is False
        assert time.perf_counter() - t0 < 1.0 and co.DONE == set() and not a.overloads and not b.overloads
    finally:
        holder.kill()
        holder.wait(timeout=30)
    assert co.compile_now("test_a") is True and co.DONE == {"test_a", "test_b"}
    assert a(2.0) == 4.0 and b(2.0) == 6.0


def test_a_unit_whose_needs_another_process_holds_is_waited_for_not_recursed_into(tmp_path, monkeypatch):
    """compile_once of a unit whose needed unit another process is compiling (a RecursionError
    in 1.4 s, the loop over the shared units came back to the same unit through its needs): the free
    unit is done meanwhile, then the needed one is waited for and loaded, then the unit itself."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    sig = types.float64(types.float64)
    a, b, c = njit(cache=False)(_twice), njit(cache=False)(_thrice), njit(cache=False)(_twice)
    monkeypatch.setattr(co, "UNITS", {})
    monkeypatch.setattr(co, "NEEDS", {})
    monkeypatch.setattr(co, "DONE", set())
    co.unit("test_b", ((b, sig),))
    co.unit("test_a", ((a, sig),), needs=("test_b",))
    co.unit("test_c", ((c, sig),))
    holder = _hold(tmp_path / ".test_b.lock", 2.0)
    try:
        t0 = time.perf_counter()
        co.compile_once("test_a", "test_c")
        waited = time.perf_counter() - t0
    finally:
        holder.wait(timeout=30)
    assert waited > 1.0 and co.DONE == {"test_a", "test_b", "test_c"}
    assert a(2.0) == 4.0 and b(2.0) == 6.0 and c(1.0) == 2.0


@pytest.mark.slow
def test_a_generic_seismic_run_waits_for_a_compile_lock_another_process_holds(tmp_path):
    """Two real processes on a cold cache: one holds the lock of a unit the evaluation needs; the
    generic seismic run compiles what it can, waits, then runs (exit 0, no traceback)."""
    cache = tmp_path / "numba"
    cache.mkdir()
    holder = _hold(cache / ".dynamics.lock", 8.0)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "NSD_EVALUATOR": "generic"}
    try:
        p = subprocess.run([sys.executable, "-m", "nsd_cli.main", "seismic", "--ground",
                            "harmonic:amplitude=1,frequency=2,duration=0.2", "--out", str(tmp_path / "out")],
                           env=env, capture_output=True, text=True, timeout=900)
    finally:
        holder.wait(timeout=60)
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr[-2000:]
    assert (tmp_path / "out" / "seismic.csv").is_file()
