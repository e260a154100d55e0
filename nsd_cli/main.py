"""The ``nsd`` command: the top layer. Exit codes: 0 ok, 1 a tolerance failed (compare) or a
benchmark missed its goal, 2 bad input, 3 solver or engine failure, 4 a drive the mechanism cannot
follow or a state outside the force laws' validity.

One module per subcommand in this package, each with ``HELP``, ``add_arguments(parser)`` and
``run(args) -> int``; the options several share are defined once in ``nsd_cli.options``.
"""
from __future__ import annotations

import argparse
import contextlib
import errno
import importlib
import importlib.util
import os
import signal
import sys
import threading

from nsd_core.device.drive import DriveError
from nsd_core.common.files import printable
from nsd_core.common.errors import InputError, SolverError

DESCRIPTION = """Cross-validation harness for a negative-stiffness seismic isolation device: an in-house
two-step semirecursive multibody model checked against MuJoCo and Exudyn models that call the
same force laws (Dai et al. 2024)."""
EPILOG = """exit codes: 0 ok; 1 a tolerance exceeded (compare) or a benchmark goal missed;
2 bad input (one line naming the field, the value and what is allowed; nothing written);
3 a solver or engine failed (including "exceeded N steps", and any NaN or inf in an output);
4 a drive the mechanism cannot follow; a full disk is exit 1 with one line naming the file (what was
kept stays valid); a second run into a folder another run is writing is exit 2 naming its pid;
130 / 143 interrupted by Ctrl-C / SIGTERM (finished cases are kept; a re-run resumes them).
docs/limits.md lists every bound. Run `nsd COMMAND --help` for each command's options."""

# writing failed for want of room (or the medium): exit 1, one line naming the file
DISK_ERRNOS = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS, errno.EIO}

SUBCOMMANDS = ("cycle", "seismic", "compare", "report", "sweep", "tables", "calibrate", "benchmark", "polar", "params",
               "ida", "p695", "warm")
# many runs of one structure: worth compiling its generated evaluation (nsd_core.engine.codegen). Not
# `sweep`: its designs change the structure (n_ropes, n_wires: 14 structures in --paper) and each runs
# ~0.1 s, so compiling a generated evaluation per structure (12-25 s CPU each) cost it ~100 s on a cold
# cache to save a few; it uses those already compiled ("auto")
STUDIES = ("tables", "calibrate", "polar", "ida", "p695")


class OneLineParser(argparse.ArgumentParser):
    """Bad options get one line on stderr (naming the option, the value and what is allowed) and exit 2,
    like every other bad input; ``nsd CMD --help`` shows the usage."""

    def error(self, message: str):
        from nsd_core.common.files import printable
        self.exit(2, f"{self.prog}: error: {printable(message)} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="nsd", description=DESCRIPTION,
                           epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True, parser_class=OneLineParser)
    for name in SUBCOMMANDS:
        mod = importlib.import_module(f"nsd_cli.{name}")
        p = sub.add_parser(name, help=mod.HELP, description=(mod.__doc__ or mod.HELP).strip())
        mod.add_arguments(p)
        p.set_defaults(handler=mod.run)
    return parser


class Interrupted(BaseException):
    """SIGINT or SIGTERM arrived: stop, keep what is finished, say so in one line."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


# An interrupt must stop the run however it is busy. Raised inside numba's or llvmlite's compiler (a
# run compiling its evaluation), the exception is swallowed by their callbacks and the compiler goes
# on (or hangs): there it is deferred and asked for again every RETRY s until the compiler returns;
# after DEADLINE s without the run having ended, the process says its one line, releases its lock and
# exits (its workers end with it: PR_SET_PDEATHSIG).
RETRY, DEADLINE = 0.05, 5.0


def _package_dirs(*names: str) -> tuple[str, ...]:
    """The installed folders of these packages (found without importing them), each ending in os.sep.
    Matched by folder, not by a name in the path: the project's generated modules live under a cache
    folder called ``numba`` too, and an interrupt there must not be deferred."""
    dirs = []
    for name in names:
        spec = importlib.util.find_spec(name)
        for d in (spec.submodule_search_locations or []) if spec is not None else []:
            dirs += [os.path.join(d, ""), os.path.join(os.path.realpath(d), "")]
    return tuple(dirs)


COMPILER = _package_dirs("numba", "llvmlite")
_state: dict = {}   # "signum", "tally", "done": an interrupt in progress
_SAY = threading.Lock()


def _say_once(line: str) -> None:
    """The interrupt's one line, said once whichever of the main thread and the watchdog comes first."""
    with _SAY:
        if _state.get("said"):
            return
        _state["said"] = True
        sys.stderr.write(line + "\n")
        sys.stderr.flush()


def _in_compiler(frame) -> bool:
    while frame is not None:
        if frame.f_code.co_filename.startswith(COMPILER):
            return True
        frame = frame.f_back
    return False


def _watchdog(signum: int) -> None:
    """Ask the main thread again while it is inside the compiler; end the process at DEADLINE."""
    import _thread
    import time
    end = time.monotonic() + DEADLINE
    while not _state.get("done") and time.monotonic() < end:
        time.sleep(RETRY)
        if _state.get("deferred") and not _state.get("done"):
            _thread.interrupt_main(signum)
    if _state.get("done"):
        return
    t = _state.get("tally") or {}
    where = (f"; {t['kept']} of {t['total']} cases kept in {printable(t['dir'])}" if "total" in t else "; nothing kept")
    try:
        _say_once(f"nsd: interrupted{where}")
        from nsd_cli.outlock import release_all
        release_all()
    finally:
        os._exit(128 + int(signum))


def _raise_interrupted(signum, frame):
    if "signum" not in _state:
        _state["signum"] = signum
        threading.Thread(target=_watchdog, args=(signum,), daemon=True, name="nsd-interrupt").start()
    if _in_compiler(frame):   # raised there it would be swallowed: asked again when the compiler returns
        _state["deferred"] = True
        return
    _state["deferred"] = False
    raise Interrupted(_state["signum"])


def _handle_signals():
    """Ctrl-C and SIGTERM raise Interrupted in the main thread (returns the handlers to restore)."""
    if threading.current_thread() is not threading.main_thread():
        return {}
    _state.clear()
    saved = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        saved[sig] = signal.signal(sig, _raise_interrupted)
    return saved


def main(argv: list[str] | None = None) -> int:
    for stream in (sys.stdout, sys.stderr):  # a name with bytes that are not UTF-8 prints escaped, not a traceback
        if hasattr(stream, "reconfigure"):
            try:
                stream.reconfigure(errors="backslashreplace")
            except (ValueError, OSError):
                pass
    parser = build_parser()
    args = parser.parse_args(argv)
    args.tally = {}  # subcommands that keep results as they go fill in kept / total / dir
    saved = _handle_signals()
    _state["tally"] = args.tally
    try:
        from nsd_core.engine.codegen import evaluator_kind, preferring_generated
        evaluator_kind()  # a bad NSD_EVALUATOR: one line, exit 2, before any work
        from nsd_cli.options import figures_wanted
        figures_wanted()  # a bad NSD_FIGURES: the same
        study = args.command in STUDIES or getattr(args, "record_set", None)
        with preferring_generated() if study else contextlib.nullcontext():
            return int(args.handler(args) or 0)
    except InputError as e:
        print(f"nsd: error: {printable(e)}", file=sys.stderr)
        return 2
    except DriveError as e:
        print(f"nsd: error: {printable(e)}", file=sys.stderr)
        return 4
    except SolverError as e:
        print(f"nsd: solver failure: {printable(e)}", file=sys.stderr)
        return 3
    except (ZeroDivisionError, OverflowError, FloatingPointError) as e:  # arithmetic that failed inside a run
        print(f"nsd: solver failure: {type(e).__name__}: {printable(e)} (the state left the range the "
              "model's arithmetic holds)", file=sys.stderr)
        return 3
    except OSError as e:
        if e.errno not in DISK_ERRNOS:
            raise
        t = args.tally
        kept = f"; {t['kept']} of {t['total']} cases kept in {printable(t['dir'])}" if "total" in t else ""
        print(f"nsd: error: cannot write {printable(e.filename or 'the output')}: {e.strerror or e}{kept} "
              "(files written before are intact)", file=sys.stderr)
        return 1
    except (Interrupted, KeyboardInterrupt) as e:
        signum = e.signum if isinstance(e, Interrupted) else signal.SIGINT
        for sig in saved:  # a second Ctrl-C while we tidy up must not print a traceback
            signal.signal(sig, signal.SIG_IGN)
        t = args.tally
        where = (f"; {t['kept']} of {t['total']} cases kept in {printable(t['dir'])}" if "total" in t
                 else "; nothing kept")
        _say_once(f"nsd: interrupted{where}")
        # an interrupt inside numba's compiler (a run compiling its mechanism's evaluation) leaves
        # llvmlite objects half-built, whose finalizers print "Exception ignored ... Traceback" at exit:
        # the process is ending, and that noise must not follow the one line
        sys.unraisablehook = lambda unraisable: None
        return 128 + int(signum)
    finally:
        from nsd_cli.outlock import release_all
        release_all()
        _state["done"] = True
        for sig, handler in saved.items():
            signal.signal(sig, handler)


if __name__ == "__main__":
    sys.exit(main())
