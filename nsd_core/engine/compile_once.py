"""Each kernel of the engine compiled once: for its one signature, at its first use, by one process.

The engine's kernels are numba functions whose arguments include compiled callbacks (forces, motion,
the evaluation) typed as function pointers (compiled_model.FORCE_FN, MOTION_FN, EVAL_FN), so one
machine-code version serves every mechanism. ``compile_once`` compiles a kernel for its signature
when it is first needed, not at import (an import, or a bad input's one-line error, never waits for
the compiler), or loads it from numba's on-disk cache (nsd_core.compilation.numba_cache), under a lock file per
kernel in the cache folder: processes started together (a pool's workers) never compile the same
kernel at once; the first takes it, the others compile what is left, or wait and then load it.

The first real compilation in a process prints one line on stderr (``announce_compilation``: numba's
"numba:compile" event fires only when it compiles, never on a load from the cache), so a newcomer on
a cold cache knows why the first run waits. The line names what compiles: the engine, or, when the
engine is already cached (a drive run compiled it), the seismic mode's own kernels at the first
seismic run: a separate compilation, announced in its own words, not the engine's line again.
"""
from __future__ import annotations

import contextlib
import os
import sys

from numba import types


NOTICE = ("nsd: compiling the in-house engine once for this version of the source (about {seconds} s on "
          "2 cores; later runs load it from the cache) ...")
NOTICE_SECONDS = 15  # measured, quiet, cold cache: `nsd cycle` 13.1 s wall (this process and one helper: device.first_compile)
# The seismic mode's own kernels (the ground motions, the structure's and the building's forces) compile
# at the first seismic run; when the engine came from the cache (a drive run compiled it before), that
# run says so in its own words rather than repeating the engine's line.
SEISMIC_NOTICE = ("nsd: compiling the seismic mode's kernels once for this version of the source (about {seconds} s "
                  "on 2 cores; the engine itself is loaded from the cache) ...")
SEISMIC_NOTICE_SECONDS = 10  # measured, cold seismic kernels, warm engine: 6.7 s CPU, 10.9 s wall (`nsd seismic`)
SEISMIC_MODULES = ("nsd_core.structure.compiled_seismic", "nsd_core.ground.motions")
_announced = False


def notice_part(module: str) -> str:
    """"seismic" for a function of the seismic mode's own kernels, else "engine"."""
    return "seismic" if module.startswith(SEISMIC_MODULES) else "engine"


def _notice(stream=None, part: str = "engine") -> None:
    """One line per process, at its first compilation: the engine's (which covers the seismic
    kernels compiled after it in the same process), or the seismic kernels' when they come first."""
    global _announced
    if not _announced:
        _announced = True
        if _first_to_announce(part):
            text = (SEISMIC_NOTICE.format(seconds=SEISMIC_NOTICE_SECONDS) if part == "seismic"
                    else NOTICE.format(seconds=NOTICE_SECONDS))
            print(text, file=stream or sys.stderr, flush=True)


_NOTICE_LOCK: list = []  # the open lock file, held until the process ends


def quiet_notices() -> None:
    """No notice from this process (a caller that prints its own line, as ``nsd warm`` does)."""
    global _announced
    _announced = True


def _first_to_announce(part: str = "engine") -> bool:
    """True unless another live process has printed the notice of this part (a pool's other worker):
    the first keeps a lock file in the cache folder until it ends, so a user sees one line, not one
    per worker."""
    ctx = _locked("notice" if part == "engine" else f"notice-{part}", block=False)
    held = ctx.__enter__()
    if held:
        _NOTICE_LOCK.append(ctx)   # never exited: the lock goes with the process
    return held


def announce_compilation() -> None:
    """Print ``NOTICE`` once in this process when numba starts compiling a function of nsd_core
    (numba's "numba:compile" event fires only on a real compilation, never on a load from the cache)."""
    from numba.core import event

    class Listener(event.Listener):
        def on_start(self, ev):
            func = getattr(ev.data.get("dispatcher"), "py_func", None)
            module = getattr(func, "__module__", "") or ""
            if module.startswith("nsd_core."):
                _notice(part=notice_part(module))

        def on_end(self, ev):
            pass

    if not getattr(announce_compilation, "installed", False):
        announce_compilation.installed = True
        event.register("numba:compile", Listener())


@contextlib.contextmanager
def _locked(name: str, block: bool):
    """An exclusive lock file ``name`` in the cache folder: yields True when held (False when
    ``block`` is False and another process holds it). Without a cache folder or flock: no lock."""
    from numba.core import config
    folder = os.environ.get("NUMBA_CACHE_DIR") or config.CACHE_DIR  # numba reloads its config from it
    try:
        import fcntl
    except ImportError:  # not Unix
        fcntl = None
    if not folder or fcntl is None:
        yield True
        return
    try:
        fd = os.open(os.path.join(folder, f".{name}.lock"), os.O_RDWR | os.O_CREAT, 0o644)
    except OSError:
        yield True
        return
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | (0 if block else fcntl.LOCK_NB))
        except BlockingIOError:
            yield False
            return
        yield True
    finally:
        os.close(fd)  # closing releases the lock


UNITS: dict[str, tuple] = {}  # name -> (((dispatcher, signature), ...), lock name, shared)
NEEDS: dict[str, tuple] = {}  # name -> the units made ready before it (kernels it calls, compiled apart)
DONE: set[str] = set()


def unit(name: str, kernels, lock: str | None = None, shared: bool = True, needs=()) -> str:
    """Register a unit: kernels compiled together, in order (a kernel after the ones it calls, so that
    it links them instead of compiling them again), under the lock ``lock`` (default: the name; units
    that hold the same kernel share one). ``shared``: a process waiting for another unit compiles this
    one meanwhile (every run needs it). ``needs``: units of kernels it calls, made ready first (so two
    processes can compile the parts of a long chain side by side). Returns the name."""
    UNITS[name] = (tuple(kernels), lock or name, shared)
    NEEDS[name] = tuple(needs)
    return name


def _compile_unit(name: str, block: bool) -> bool:
    """Compile (or load) the unit under its lock; False when ``block`` is False and another process
    holds the lock of the unit or of one it needs (it is compiling that now). Without ``block`` this
    never waits and never calls compile_once: a unit whose needs another process holds is put off
    (before, it waited for them through compile_once, whose loop over the shared units came back
    here for the same unit: a RecursionError while another process held a needed unit's lock)."""
    kernels, lock, _ = UNITS[name]
    if any(n not in DONE for n in NEEDS.get(name, ())):
        if block:
            compile_once(*NEEDS[name])   # waits for the others, then loads what they compiled
        elif not all(n in DONE or _compile_unit(n, block=False) for n in NEEDS[name]):
            return False
    with _locked(lock, block) as held:
        if not held:
            return False
        for d, sig in kernels:
            if tuple(sig.args) not in d.overloads:
                d.compile(sig)
            if any(isinstance(a, types.FunctionType) for a in sig.args):
                # closed to other signatures, as njit(signature) is: a call from Python with a compiled
                # function for a function-pointer argument then converts it (no specialisation for it)
                d.disable_compile()
    DONE.add(name)
    return True


def compile_once(*names: str) -> None:
    """Make the units ``names`` ready in this process: compiled, or loaded from the cache. A unit that
    another process is compiling is waited for (then loaded), and meanwhile this process compiles the
    shared units no one has taken: processes started together share the work, none is done twice."""
    needed = [n for n in names if n not in DONE]
    while needed:
        needed = [n for n in needed if not _compile_unit(n, block=False)]
        if needed:  # others are compiling what is needed: do the rest of the work meanwhile
            for other, (_, _, shared) in list(UNITS.items()):
                if shared and other not in DONE and other not in needed:
                    _compile_unit(other, block=False)
            _compile_unit(needed.pop(0), block=True)


def compile_now(name: str, block: bool = False) -> bool:
    """Make the unit ``name`` ready (its needs first) unless another process holds one of their locks:
    then False, and nothing waited for (``block``: wait, as compile_once does)."""
    if block:
        compile_once(name)
        return True
    return all(n in DONE or compile_now(n) for n in NEEDS.get(name, ())) and (
        name in DONE or _compile_unit(name, block=False))


def share_work(items) -> None:
    """Run every ``(lock, fn)`` of ``items`` once in this process, sharing the first runs with processes
    doing the same (a pool's workers warming up). ``fn(block)`` does the item; with ``block`` False it
    may return False, meaning another process is on it (compile_now). An item whose lock another
    process holds, or that returns False, is put off and this process goes on with the next one; it
    waits only when every item left is taken, and then does it on what the other left in the cache."""
    left = list(items)
    while left:
        put_off = []
        for lock, fn in left:
            with _locked(lock, block=False) as held:
                if not (held and fn(False) is not False):
                    put_off.append((lock, fn))
        if put_off and len(put_off) == len(left):
            lock, fn = put_off.pop(0)
            with _locked(lock, block=True):
                fn(True)
        left = put_off


class _CompileClock:
    """Seconds (wall, CPU) this process has spent in numba compilations, outermost ones only: a run
    that compiles something its warm-up did not (another mechanism's generated evaluation, a kernel
    of another kind) moves those seconds from its cost to its compile time (device.warmup)."""
    depth, wall0, cpu0, wall, cpu = 0, 0.0, 0.0, 0.0, 0.0


def _install_clock() -> None:
    import time
    from numba.core import event

    class Listener(event.Listener):
        def on_start(self, ev):
            if _CompileClock.depth == 0:
                _CompileClock.wall0, _CompileClock.cpu0 = time.perf_counter(), time.process_time()
            _CompileClock.depth += 1

        def on_end(self, ev):
            _CompileClock.depth -= 1
            if _CompileClock.depth == 0:
                _CompileClock.wall += time.perf_counter() - _CompileClock.wall0
                _CompileClock.cpu += time.process_time() - _CompileClock.cpu0

    event.register("numba:compile", Listener())


_install_clock()


def compile_seconds() -> tuple[float, float]:
    """(wall, CPU) seconds spent compiling in this process so far (numba's "numba:compile" events;
    a load from the on-disk cache is not a compilation)."""
    return _CompileClock.wall, _CompileClock.cpu

