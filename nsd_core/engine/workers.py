"""Worker processes that stop when asked: a process pool whose workers leave Ctrl-C to the parent,
send anything they print to stderr, and are terminated (not waited for) when the parent is
interrupted, so that Ctrl-C or SIGTERM stops a run within seconds and leaves no process behind.

A parent that cannot tidy up (SIGKILL, a crash) takes its workers with it too: on Linux
each worker asks the kernel for SIGKILL when its parent ends (``prctl(PR_SET_PDEATHSIG)`` through
ctypes), and everywhere a watchdog thread in each worker ends it within ``WATCH_INTERVAL`` seconds
once its parent's pid is gone (it was re-parented). A later run resumes from what was stored.

Warm workers: ``worker_pool(n, warm=...)`` runs ``warm`` (a picklable callable: the
imports and tiny runs that load or compile every kernel the pool's jobs will use) once in each worker
before its first job, so that no job pays for start-up. What each worker's start cost, the spawn and
imports up to the initializer and the warm-up itself, is reported apart (``pool.startup``): it is
never part of a job's own time."""
from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import os
import queue
import signal
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

from nsd_core.common.errors import ParameterError

PR_SET_PDEATHSIG = 1  # linux/prctl.h
WATCH_INTERVAL = 0.5  # s between the watchdog's looks at the parent
WORKERS_MAX = 256     # local worker processes a command may be asked for (--workers, NSD_WORKERS)
WORKERS_ENV = "NSD_WORKERS"   # a command's local workers when its --workers is not given


def usable_cores() -> int:
    """The cores this process may run on (its affinity: `taskset -c 0` leaves one of a machine's two)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:   # not Linux
        return os.cpu_count() or 1


def default_workers(environ=os.environ) -> int:
    """A command's local worker processes when its --workers is not given: ``NSD_WORKERS`` where set (a
    whole number in [1, WORKERS_MAX]; ParameterError, one line, otherwise), else the usable cores."""
    given = environ.get(WORKERS_ENV, "").strip()
    if not given:
        return usable_cores()
    if not given.isdigit() or not 1 <= int(given) <= WORKERS_MAX:
        raise ParameterError(f"{WORKERS_ENV} = {given!r}: must be a whole number in [1, {WORKERS_MAX}] "
                             "(or unset: the usable cores)")
    return int(given)


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


def _worker_init(parent: int | None = None, warm=None, report=None) -> None:
    entered = time.time()
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
    start, failed = time.perf_counter(), None
    if warm is not None:
        try:
            warm()
        except Exception as e:  # noqa: BLE001 (a job meeting the same failure reports it, with its inputs)
            failed = f"{type(e).__name__}: {e}".splitlines()[0][:300]
    if report is not None:
        report.put({"pid": os.getpid(), "entered": entered, "warm_s": time.perf_counter() - start,
                    "warm_error": failed})
        # a queue's put returns before its feeder thread writes the pipe: flushed now, before the first
        # job, or the parent could read every result and still find no report (seen on a loaded machine)
        report.close()
        report.join_thread()


class Startup:
    """Each worker's start-up as its initializer reported it: ``spawn_s`` from the pool's creation to
    the initializer (process start, interpreter, the imports that unpickling its arguments needs) and
    ``warm_s`` the warm-up; ``ready_s`` their sum, the worker's first job cannot start before it."""

    def __init__(self, queue, created: float):
        self._queue, self._created, self._seen = queue, created, []

    def workers(self) -> list[dict]:
        """One entry per worker that has reported so far (pid, spawn_s, warm_s, ready_s, warm_error)."""
        try:
            while True:
                r = self._queue.get_nowait()
                spawn = r["entered"] - self._created
                self._seen.append({"pid": r["pid"], "spawn_s": spawn, "warm_s": r["warm_s"],
                                   "ready_s": spawn + r["warm_s"], "warm_error": r["warm_error"]})
        except (queue.Empty, OSError, EOFError, ValueError):  # all read, or the pool was ended: keep what came
            pass
        return list(self._seen)

    def summary(self) -> dict | None:
        """The slowest worker's spawn, warm-up and sum, and every worker's entry; None if none reported."""
        seen = self.workers()
        if not seen:
            return None
        return {"workers": len(seen), "spawn_s": max(w["spawn_s"] for w in seen),
                "warm_s": max(w["warm_s"] for w in seen), "ready_s": max(w["ready_s"] for w in seen),
                "per_worker": seen}


@contextlib.contextmanager
def worker_pool(workers: int, warm=None):
    """A spawn-context ProcessPoolExecutor (MuJoCo's callbacks are process-global: one per process)
    that terminates its workers when the body raises (KeyboardInterrupt, SIGTERM, an error).

    ``warm``: a picklable callable (a module-level function or a partial of one) each worker runs once
    before its first job, e.g. ``nsd_core.compilation.warmup.warm_worker``; it must not raise (an error is
    reported in ``pool.startup`` and left to the jobs). ``pool.startup`` (``Startup``) reports each
    worker's start-up apart from the jobs' times."""
    ctx = get_context("spawn")
    # a Queue, not a SimpleQueue: the pool's own result pipe is the one SimpleQueue in a worker
    report, created = ctx.Queue(), time.time()
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_worker_init,
                               initargs=(os.getpid(), warm, report))
    pool.startup = Startup(report, created)
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
