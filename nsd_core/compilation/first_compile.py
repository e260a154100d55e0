"""A first run's compilation shared with one helper process (a cold cache; docs/compilation.md).

A command's first in-house run of a kind (mode, method, backend, path kind) on a cold cache compiles
the engine's units and the mode's callbacks: ~25 s CPU for a drive cycle, one kernel after another
in one process. The parts are independent enough to be compiled side by side (the evaluation's two
halves, the step loop, the mode's force and motion callbacks: docs/compilation.md), so this process
and one helper share the kind's items out (``compile_once.share_work``: a lock file per item, none
compiled twice). The helper leaves what it compiles in the cache folder and this process loads it;
once this process has every item, the helper has nothing left that it needs and is stopped.

Only the kind's own items: compiling every mode at a first run was measured slower
(nsd_core.compilation.warm_all). Not in a pool's worker (the pool's workers share the work already:
``disable``), not in ``nsd warm`` (it has its own helpers), not in a helper, not on one core, and not
once the kind is marked ready in this version's cache folder (a mark written after its first
successful warm-up; ``nsd warm``'s marks cover every kind), so a warm command starts no process.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from functools import partial
from pathlib import Path

from nsd_core.engine.workers import usable_cores

HELPER = "NSD_FIRST_COMPILE_HELPER"   # set in the helper: it never starts one itself
# the modules whose import compiles a mode's callbacks (njit with their signature: at import)
CALLBACKS = {"drive": "nsd_core.device.compiled", "seismic": "nsd_core.structure.compiled_seismic"}
EVERY_MODE_MARKS = (".compiled-every-mode", ".compiled-in-house")   # nsd warm's (warm_all.MARK, MARK_IN_HOUSE)
_enabled = [True]


def disable() -> None:
    """No helper from this process (a pool worker, ``nsd warm``: they share the work already)."""
    _enabled[0] = False


def _folder() -> Path | None:
    from numba.core import config
    folder = os.environ.get("NUMBA_CACHE_DIR") or config.CACHE_DIR
    return Path(folder) if folder else None


def _mark(key: tuple) -> str:
    return ".ready-" + "-".join("".join(c if c.isalnum() else "_" for c in str(k)) for k in key)


def is_ready(key: tuple) -> bool:
    """Whether this kind's kernels are marked compiled in the cache folder (or every kind is)."""
    folder = _folder()
    return folder is None or any((folder / m).exists() for m in (_mark(key),) + EVERY_MODE_MARKS)


def mark_ready(key: tuple) -> None:
    folder = _folder()
    if folder is not None:
        try:
            (folder / _mark(key)).touch()
        except OSError:   # a read-only cache: the next command checks again, and starts a helper
            pass


def worth_a_helper(key: tuple) -> bool:
    """Share this kind's first compilation with a helper: enabled here, two cores or more, not ready."""
    return _enabled[0] and not os.environ.get(HELPER) and usable_cores() >= 2 and not is_ready(key)


def _import(module: str, block: bool = True) -> None:
    __import__(module)
    if module == CALLBACKS["drive"]:   # and the plate's path series, called from Python for the outputs
        from nsd_core.device.drive import Drive
        Drive(0.001, 100.0).plate([0.0])


def _unit(module: str, name: str, block: bool = False):
    """A unit registered by ``module`` (imported first), made ready as compile_once.compile_now does."""
    from nsd_core.engine.compile_once import compile_now
    __import__(module)
    return compile_now(name, block)


def unit_items() -> list:
    """``share_work`` items of the engine's units (``rk.engine_units``), under the lock names every warm-up
    uses (a first run's, a pool worker's, ``nsd warm``'s), so processes of any of them share the units."""
    from nsd_core.engine.compile_once import compile_now
    from nsd_core.engine.rk import engine_units
    return [(f"warm-unit-{u}", partial(compile_now, u)) for u in engine_units()]


def items(key: tuple, tiny) -> list:
    """The kind's ``share_work`` items: the evaluation's two halves, the mode's callbacks, the
    evaluation, the step loop (the seismic outputs' unit in seismic mode), then ``tiny`` (the kind's
    tiny run, which loads them all). The order is the one that splits a cold drive cycle best
    (docs/compilation.md)."""
    mode = key[0]
    return mode_items((mode,)) + [(f"warm-kind-{mode}", lambda block=True: tiny())]


def mode_items(modes) -> list:
    """``share_work`` items of the engine's units and of each mode's own callbacks (and the seismic
    outputs' unit): the callbacks between the evaluation's halves and the rest of the chain, so that a
    second process compiles them while the first is on the long evaluation and step loop."""
    units = unit_items()
    calls = [(f"first-callbacks-{m}", partial(_import, CALLBACKS[m])) for m in ("drive", "seismic") if m in modes]
    out = units[:2] + calls + units[2:]
    if "seismic" in modes:
        out.append(("warm-unit-seismic_outputs", partial(_unit, CALLBACKS["seismic"], "seismic_outputs")))
    return out


def run_shared(key: tuple, tiny) -> None:
    """Run the kind's items here while one helper process runs them too (share_work), then stop it."""
    from nsd_core.engine.compile_once import share_work
    env = {**os.environ, HELPER: "1"}
    code = f"from nsd_core.compilation.first_compile_helper import helper; helper({json.dumps(json.dumps(list(key)))})"
    helper_process = subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL)
    try:
        share_work(items(key, tiny))
    finally:
        # every item is done here: what the helper still does (loading what it left) is not needed
        helper_process.terminate()
        helper_process.wait()
