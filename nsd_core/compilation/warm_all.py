"""``nsd warm``: every mode compiled once per version of the source, on every core, with one line
(docs/compilation.md).

Without it each command compiles what it uses at its first use (nsd_core.engine.compile_once: the
first ``nsd cycle`` the drive mode, a first seismic run the seismic kernels with a line of its own, the
gate's workers the peers' callbacks). ``ensure_all`` compiles the in-house engine for every mode: its
units and a tiny run of every drive path, of the seismic mode, with the restrainer and under a
building; with ``peers`` (``nsd warm``) the peers' tiny runs too (``PROVIDERS``: the layer that knows
the peers names them). It is an explicit step (``nsd warm``: an install step, or a CI runner's first
step, ``.ci/run``), after which no command of this version on the device compiles anything (a
described mechanism, ``nsd compare --model``, still compiles MuJoCo's generated callback, Exudyn's
forces for a law module it did not meet and a law kernel the device never calls at its first run:
docs/compilation.md).

It is not run automatically at a command's first run. That was tried and measured
(docs/performance.md, "A newcomer's first commands"): the first ``nsd cycle`` on a cold cache went
from 27.9 to 38.7 s wall (28 to 65 s CPU) and the README's first compare from 79 to 139 s. Most of
that doubled CPU was the child processes' cache naming, fixed since (nsd_core.compilation.numba_cache: the helpers'
machine code went where the first process never looked); a first run now shares only its own kind's
items with one helper (nsd_core.compilation.first_compile).

The work runs in this process and one helper per further core it may use (its affinity), sharing the
items out (``compile_once.share_work``: no two processes compile the same item at once), prints one line, and
leaves a mark in the cache folder: a later ``nsd warm`` of the same version, or of a new install of it
(the folder is keyed by the source's content and named independently of where it is installed,
nsd_core.compilation.numba_cache), finds the mark and compiles nothing. A second ``nsd warm`` started while one
compiles waits for it, then loads.

This module sits in the device layer (it runs the device's tiny problems); the generic engine
(nsd_core.engine) knows nothing of it.
"""
from __future__ import annotations

import importlib
import os
import subprocess
import sys
import time
from functools import partial
from pathlib import Path

from nsd_core.compilation import first_compile
from nsd_core.engine import compile_once as co

# the in-house engine's modes and the peers' callbacks (``nsd warm``); the in-house modes alone
# (``ensure_all(peers=False)``): first_compile reads them too (every kind ready)
MARK, MARK_IN_HOUSE = first_compile.EVERY_MODE_MARKS
LOCK = "warm-all"
HELPER = "NSD_WARM_HELPER"
# tiny runs of the layers above, as "module:function" returning a list of callables (the gate's
# peers); an import failure (a peer not installed) leaves them to their first use
PROVIDERS = ("comparisons.warmup:every_mode_calls",)
NOTICE = ("nsd: compiling the in-house engine{peers} once for this version of the source, every mode, on "
          "{processes} processes (about {seconds} s on 2 cores; later commands and new installs of this version "
          "load it from the cache) ...")
PEERS = " and the peers' callbacks"
# measured, 2 cores, load ~9 (benchmarks/results/bench_cold.json): the in-house modes ~50 s CPU, with the
# peers' callbacks ~95 s CPU; over two processes on a quiet machine about half of that in wall seconds
NOTICE_SECONDS = {False: 25, True: 50}
_STATE: dict = {}   # kind (peers or not) -> done in this process


def cache_dir() -> str | None:
    from numba.core import config
    return os.environ.get("NUMBA_CACHE_DIR") or config.CACHE_DIR or None


def complete(peers: bool = False) -> bool:
    """Whether the in-house modes (and with ``peers`` the peers' callbacks) of this version are compiled
    in the cache folder (their mark; every mode's mark covers the in-house one)."""
    folder = cache_dir()
    marks = (MARK,) if peers else (MARK, MARK_IN_HOUSE)
    return bool(folder) and any((Path(folder) / m).exists() for m in marks)


def ensure_all(peers: bool = False, stream=None) -> float:
    """Compile the in-house engine's every mode (with ``peers``: and the peers' callbacks) once for this
    version unless done (the mark), being done by another process (then wait for it) or running in a
    helper. Returns the seconds this process spent on it (0 when
    there was nothing to do). Once per process and kind."""
    if _STATE.get(peers) or os.environ.get(HELPER):
        return 0.0
    _STATE[peers] = True
    if complete(peers):
        return 0.0
    t0 = time.perf_counter()
    with co._locked(LOCK, block=False) as held:
        if held:
            if not complete(peers):
                _warm_here(peers, stream or sys.stderr)
            return time.perf_counter() - t0
    with co._locked(LOCK, block=True):   # another process compiles: load what it leaves
        pass
    return time.perf_counter() - t0


def _warm_here(peers: bool, stream) -> None:
    co.quiet_notices()   # this line is the only one: the units' own notices would repeat it
    first_compile.disable()   # its own helpers share every mode: the runs start none
    t0 = time.perf_counter()
    n = max(0, first_compile.usable_cores() - 1)   # the cores this process may use (taskset: fewer)
    print(NOTICE.format(peers=PEERS if peers else "", processes=n + 1, seconds=NOTICE_SECONDS[peers]), end="",
          file=stream, flush=True)
    env = {**os.environ, HELPER: "1"}
    code = f"from nsd_core.compilation.warm_all import helper; helper({peers})"
    helpers = [subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL) for _ in range(n)]
    try:
        co.share_work(items(peers))
    finally:
        for h in helpers:
            h.wait()
    folder = cache_dir()
    if folder:
        for mark in (MARK, MARK_IN_HOUSE) if peers else (MARK_IN_HOUSE,):
            (Path(folder) / mark).write_text(f"{time.perf_counter() - t0:.1f} s\n")
    print(f" done in {time.perf_counter() - t0:.0f} s", file=stream, flush=True)


def helper(peers: bool = False) -> None:
    """A helper process: the same items, shared out with the process that started it."""
    co.quiet_notices()
    first_compile.disable()
    co.share_work(items(peers))


def _tiny_structure_run(structure: str) -> None:
    """A tiny seismic run with the restrainer or a 3-story building (their own force kernels)."""
    from nsd_core.structure.isolation import default_structure
    from nsd_core.device.params import Params
    from nsd_core.structure.seismic import simulate_seismic
    from nsd_core.compilation.warmup import TINY_DT_OUT, TINY_DURATION, tiny_ground
    p = Params()
    st = default_structure(p)
    if structure == "restrainer":
        from nsd_core.structure.restrainer import with_restrainer
        st = with_restrainer(st, p, True, {})
    else:
        from nsd_core.structure.building import building_from
        st = st.with_building(building_from(st.mass, {"stories": 3}))
    simulate_seismic(p, st, tiny_ground(), duration=TINY_DURATION, dt_out=TINY_DT_OUT)


def _quietly(fn, block: bool = True) -> None:
    try:
        fn()
    except Exception:  # noqa: BLE001 (a failure is left to the run that meets it, with its own inputs)
        pass


def items(peers: bool = True) -> list:
    """``share_work`` items: the engine's units, then a tiny run of every mode, then (``peers``) the
    peers' tiny runs (``peers=False``: the in-house modes alone)."""
    from nsd_core.device.model import DEFAULT_SOLVER, simulate
    from nsd_core.structure.seismic import simulate_seismic
    from nsd_core.compilation.warmup import warm
    from nsd_core.engine.timing import PATHS
    from nsd_core.device.decimal_text import TEXT_UNIT   # the CSVs' numbers, written by every command
    out = first_compile.unit_items() + [(f"warm-unit-{TEXT_UNIT}", partial(co.compile_now, TEXT_UNIT))]
    m, b = DEFAULT_SOLVER["method"], DEFAULT_SOLVER["backend"]
    # one lock per mode and per peer: the runs under one lock compile the same kernels (every drive
    # path the drive's), so two processes never compile them side by side; the modes go on meanwhile
    out += [("warm-all-drive", partial(_quietly, partial(warm, "drive", simulate, m, b, p))) for p in PATHS]
    out.append(("warm-all-seismic", partial(_quietly, partial(warm, "seismic", simulate_seismic, m, b, "line"))))
    out += [("warm-all-seismic", partial(_quietly, partial(_tiny_structure_run, s))) for s in ("restrainer", "building")]
    from nsd_core.compilation.worker_warmup import _name
    for name in PROVIDERS if peers else ():
        module, fn = name.split(":")
        try:
            calls = getattr(importlib.import_module(module), fn)()
        except Exception:  # noqa: BLE001 (a peer not installed: compiled at its first use, if ever)
            calls = []
        out += [(f"warm-all-call-{_name(c)}", partial(_quietly, c)) for c in calls]
    return out
