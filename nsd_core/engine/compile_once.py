"""Each kernel of the engine compiled once: for its one signature, at its first use, by one process.

The engine's kernels are numba functions whose arguments include compiled callbacks (forces, motion,
the evaluation) typed as function pointers (compiled_model.FORCE_FN, MOTION_FN, EVAL_FN), so one
machine-code version serves every mechanism. ``compile_once`` compiles a kernel for its signature
when it is first needed, not at import (an import, or a bad input's one-line error, never waits for
the compiler), or loads it from numba's on-disk cache (nsd_core.numba_cache), under a lock file per
kernel in the cache folder: processes started together (a pool's workers) never compile the same
kernel at once; the first takes it, the others compile what is left, or wait and then load it.

The first real compilation in a process prints one line on stderr (``announce_compilation``: numba's
"numba:compile" event fires only when it compiles, never on a load from the cache), so a newcomer on
a cold cache knows why the first run waits.
"""
from __future__ import annotations

import contextlib
import os
import sys


NOTICE = ("nsd: compiling the in-house engine once for this version of the source (about {seconds} s on "
          "2 cores; later runs load it from the cache) ...")
NOTICE_SECONDS = 60  # measured, cold cache, one process: the first drive run's compilation
_announced = False


def _notice(stream=None) -> None:
    global _announced
    if not _announced:
        _announced = True
        print(NOTICE.format(seconds=NOTICE_SECONDS), file=stream or sys.stderr, flush=True)


def announce_compilation() -> None:
    """Print ``NOTICE`` once in this process when numba starts compiling a function of nsd_core
    (numba's "numba:compile" event fires only on a real compilation, never on a load from the cache)."""
    from numba.core import event

    class Listener(event.Listener):
        def on_start(self, ev):
            func = getattr(ev.data.get("dispatcher"), "py_func", None)
            if getattr(func, "__module__", "").startswith("nsd_core."):
                _notice()

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
    folder = config.CACHE_DIR or os.environ.get("NUMBA_CACHE_DIR")
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


def _ready(dispatcher, sig) -> bool:
    return tuple(sig.args) in dispatcher.overloads


def compile_once(kernels) -> None:
    """Compile each (dispatcher, signature) of ``kernels`` in this process (or load it from the
    cache), each under its own lock: a kernel another process is compiling is left for later and
    waited for (then loaded) only when nothing else is left. Then each dispatcher is closed to other
    signatures, as ``njit(signature)`` would (a call from Python with a compiled function for a
    function-pointer argument then converts it, instead of compiling a specialisation for it)."""
    pending = [(d, s) for d, s in kernels if not _ready(d, s)]
    while pending:
        left = []
        for d, s in pending:
            name = f"{d.py_func.__module__}.{d.py_func.__qualname__}"
            with _locked(name, block=False) as held:
                if held:
                    d.compile(s)
                else:
                    left.append((d, s))
        if left:  # all taken by others: wait for the first, then go round again
            d, s = left[0]
            with _locked(f"{d.py_func.__module__}.{d.py_func.__qualname__}", block=True):
                d.compile(s)
            left = left[1:]
        pending = left
    for d, _ in kernels:
        d.disable_compile()
