"""Worker processes that stop when asked: a process pool whose workers leave Ctrl-C to the parent,
send anything they print to stderr, and are terminated (not waited for) when the parent is
interrupted, so that Ctrl-C or SIGTERM stops a run within seconds and leaves no process behind.

A parent that cannot tidy up (SIGKILL, a crash) takes its workers with it too (issue 22): on Linux
each worker asks the kernel for SIGKILL when its parent ends (``prctl(PR_SET_PDEATHSIG)`` through
ctypes), and everywhere a watchdog thread in each worker ends it within ``WATCH_INTERVAL`` seconds
once its parent's pid is gone (it was re-parented). A later run resumes from what was stored."""
from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import os
import signal
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

PR_SET_PDEATHSIG = 1  # linux/prctl.h
WATCH_INTERVAL = 0.5  # s between the watchdog's looks at the parent


def die_with_parent(parent: int) -> None:
    """End this process when ``parent`` ends: the kernel's parent-death signal where there is one
    (Linux), and a watchdog thread that polls the parent's pid (any Unix; also covers a parent that
    died before the signal was armed)."""
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    except (OSError, AttributeError):
        pass  # not Linux: the watchdog alone
    if os.getppid() != parent:  # the parent was gone before the signal was armed
        os._exit(1)

    def watch():
        while True:
            time.sleep(WATCH_INTERVAL)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=watch, name="nsd-parent-watchdog", daemon=True).start()


def _worker_init(parent: int | None = None) -> None:
    if parent is not None:
        die_with_parent(parent)
    # Ctrl-C reaches the whole process group: the parent alone decides what to keep and stops us
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # a parent that was stopped closes the pipes: a worker writing to one then ends quietly, the Unix
    # way, instead of printing a BrokenPipeError traceback into the parent's one-line message
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    # a worker's stdout would land in the middle of the parent's table (Exudyn's allocation warnings)
    os.dup2(2, 1)
    # nothing here renders; left on, MuJoCo's import loads glfw, which starts a Python subprocess to
    # probe its library: a grandchild that stop() does not reach, and that prints a BrokenPipeError
    # traceback when its worker is ended in the middle of the probe
    os.environ.setdefault("MUJOCO_GL", "disable")


@contextlib.contextmanager
def worker_pool(workers: int):
    """A spawn-context ProcessPoolExecutor (MuJoCo's callbacks are process-global: one per process)
    that terminates its workers when the body raises (KeyboardInterrupt, SIGTERM, an error)."""
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn"), initializer=_worker_init,
                               initargs=(os.getpid(),))
    try:
        yield pool
    except BaseException:
        stop(pool)
        raise
    pool.shutdown(wait=True)


def stop(pool: ProcessPoolExecutor, grace: float = 3.0) -> None:
    """Cancel what is queued and end the running workers now (SIGTERM, then SIGKILL after ``grace``),
    then see the pool's manager thread out. Leave the cancelling to this: a future cancelled by the
    caller but still in the pool's books makes Python 3.11's broken-pool path raise in that thread."""
    procs = list((getattr(pool, "_processes", None) or {}).values())
    manager = getattr(pool, "_executor_manager_thread", None)
    results = getattr(pool, "_result_queue", None)
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=grace)
        if p.is_alive():
            p.kill()
            p.join(timeout=grace)
    # A result over 64 KiB (a run's time series) goes down the result pipe in several writes: a worker
    # ended in the middle of one leaves the manager thread waiting for the rest for ever, and the
    # interpreter joins that thread on exit (a hang after "interrupted"). With the workers gone, ours is
    # the last write end: closing it gives that thread end-of-file, and it winds the pool up as broken.
    if results is not None:
        results._writer.close()
    if manager is not None and manager.is_alive():
        manager.join(timeout=grace)  # gone before exit, which would otherwise race it for the wakeup pipe


@contextlib.contextmanager
def stdout_to_stderr():
    """Send file descriptor 1 to stderr for the duration (engines' C++ code prints on stdout)."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        os.dup2(2, 1)
        yield
    finally:
        try:
            sys.stdout.flush()
        except (OSError, ValueError):
            pass
        os.dup2(saved, 1)
        os.close(saved)
