"""Options and checks that several subcommands share, defined once."""
from __future__ import annotations

import argparse
import errno
import math
import os
import stat
import sys
import tempfile
import time
from pathlib import Path

from nsd_core.common.files import printable
from nsd_core.device.params import ParameterError, Params, load_params, parse_set
from nsd_core.engine.workers import WORKERS_MAX, default_workers


class Progress:
    """A progress bar on stderr, shown only once a run has taken more than ``after`` seconds."""

    def __init__(self, label: str, after: float = 2.0, stream=sys.stderr):
        self.label, self.after, self.stream = label, after, stream
        self.start = time.perf_counter()
        self.last = -1

    def __call__(self, fraction: float) -> None:
        if time.perf_counter() - self.start < self.after:
            return
        pct = int(100 * min(max(fraction, 0.0), 1.0))
        tty = self.stream.isatty()
        if pct == self.last or (not tty and pct % 10):
            return
        self.last = pct
        bar = "#" * (pct // 4) + "." * (25 - pct // 4)
        end = "\r" if tty and pct < 100 else "\n"
        self.stream.write(f"{self.label} [{bar}] {pct:3d}%{end}")
        self.stream.flush()


FIGURES_ENV = "NSD_FIGURES"


def figures_wanted(environ=os.environ) -> bool:
    """Whether a study command draws its PNGs into its folder: ``NSD_FIGURES`` = 1 (or unset, or empty)
    draws them, 0 leaves them to ``nsd report --from FOLDER`` (the numbers are written either way);
    ParameterError, one line, for anything else."""
    given = environ.get(FIGURES_ENV, "").strip()
    if given not in ("", "0", "1"):
        raise ParameterError(f"{FIGURES_ENV} = {given!r}: must be 1 (draw each study's PNGs into its folder) or 0 "
                             "(numbers only; nsd report --from FOLDER draws them later)")
    return given != "0"


def draw_figures(out) -> list[str]:
    """A study command's PNGs into its folder ``out``, unless NSD_FIGURES = 0 (said in one line)."""
    if not figures_wanted():
        print(f"figures: none drawn ({FIGURES_ENV}=0; nsd report --from {printable(out)} draws them)")
        return []
    from reports.build import draw_study
    return draw_study(out)


def add_param_arguments(p: argparse.ArgumentParser, what: str = "parameter overrides") -> None:
    """--params FILE and --set NAME=VALUE (repeatable): the device's parameters."""
    p.add_argument("--params", help=f"TOML file of {what}")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="override one parameter (every name, unit and bound: nsd params)")


def reject_record_set_in_set(values: list[str]) -> None:
    """``--set`` is a parameter override (NAME=VALUE) in every command; a value without '=' (the record
    set's old spelling) is pointed to --record-set in one line."""
    for v in values:
        if "=" not in v:
            raise ParameterError(f"--set {v!r}: expected NAME=VALUE (a parameter override); a record set is "
                                 f"--record-set {v}")


def base_params(args) -> Params:
    """The parameter set that --params and --set describe (checked: exit 2 on bad input)."""
    return load_params(args.params, parse_set(args.set))


def add_solver_arguments(p: argparse.ArgumentParser) -> None:
    """The in-house engine's integrator settings (None: the engine's default)."""
    p.add_argument("--method", default=None, help="semirecursive integrator: RK45, DOP853 (default), RK23, Radau, LSODA")
    p.add_argument("--rtol", type=float, default=None, help="relative tolerance")
    p.add_argument("--atol", type=float, default=None, help="absolute tolerance")
    p.add_argument("--max-step", type=float, default=None, help="largest step [s]")


def solver_settings(args) -> dict:
    """The solver options given on the command line, checked by the in-house engine's own settings
    check (types, ranges, the step-size floor, the method), by setting name."""
    given = {k: getattr(args, k) for k in ("method", "rtol", "atol", "max_step") if getattr(args, k) is not None}
    if not given:
        return given  # nothing to check (and the engines' imports stay out of a refusal's start-up)
    from comparisons.engines.base import check_settings
    from comparisons.engines.semirecursive_engine import SemirecursiveEngine
    try:
        check_settings(SemirecursiveEngine, given, "semirecursive")
    except ParameterError as e:  # name the option the user typed
        for k in given:
            if str(e).startswith(f"semirecursive.{k} "):
                raise ParameterError(f"--{k.replace('_', '-')}" + str(e)[len(f"semirecursive.{k}"):]) from None
        raise
    return given


def whole(name: str, v, low: int, high: int) -> None:
    """None passes; otherwise a whole number in [low, high]."""
    if v is not None and not low <= v <= high:
        raise ParameterError(f"{name} = {v}: must be a whole number in [{low}, {high}]")


def resolved_workers(given: int | None) -> int:
    """--workers as given (a whole number in [1, WORKERS_MAX]) or, not given, the default: NSD_WORKERS,
    else the cores this process may use (nsd_core.engine.workers.default_workers); ParameterError, one
    line, for a bad value of either."""
    whole("--workers", given, 1, WORKERS_MAX)
    return default_workers() if given is None else given


WORKERS_HELP = f"local processes, in [1, {WORKERS_MAX}] (default: $NSD_WORKERS, else the cores this process may use)"


# bytes (Linux): longer names are refused before anything is made; PATH_MAX keeps room for what a
# command writes inside --out (designs/<key>/result.json, a temporary file's prefix and suffix)
NAME_MAX, PATH_MAX, TMP_AFFIX = 255, 4096 - 256, 16


def _path_error(option: str, value: str, path: Path, e: OSError) -> ParameterError:
    """One line for an OSError met while resolving an output path."""
    shown = f"{option} {printable(value)}"
    if e.errno == errno.ELOOP:
        return ParameterError(f"{shown}: {printable(path)} is a symbolic link loop")
    if e.errno == errno.ENAMETOOLONG:
        return ParameterError(f"{shown}: name too long (at most {NAME_MAX} bytes a name, {PATH_MAX} in all)")
    if e.errno == errno.ENOTDIR:
        return ParameterError(f"{shown}: a part of it is a file, not a folder")
    if e.errno in (errno.EACCES, errno.EPERM):
        return ParameterError(f"{shown}: {printable(path)} is not accessible (permission denied)")
    return ParameterError(f"{shown}: {printable(path)} cannot be used ({e.strerror or e})")


def _nearest_existing(option: str, value: str, path: Path) -> Path:
    """The deepest existing folder on the way to ``path``; every part checked once: a symbolic link
    loop, a dangling link, a name too long, a file where a folder is needed are bad input."""
    raw = os.fsencode(str(path.absolute()))
    if len(raw) >= PATH_MAX or any(len(part) > NAME_MAX for part in raw.split(b"/")):
        raise ParameterError(f"{option} {printable(value)}: name too long (at most {NAME_MAX} bytes a name, "
                             f"{PATH_MAX} in all)")
    p = path.absolute()
    while True:
        try:
            st = os.stat(p)
        except FileNotFoundError:
            try:
                os.lstat(p)
            except FileNotFoundError:
                if p == p.parent:
                    raise ParameterError(f"{option} {printable(value)}: no folder on the way exists") from None
                p = p.parent
                continue
            except OSError as e:
                raise _path_error(option, value, p, e) from None
            raise ParameterError(f"{option} {printable(value)}: {printable(p)} is a symbolic link to nothing") from None
        except OSError as e:
            raise _path_error(option, value, p, e) from None
        if not stat.S_ISDIR(st.st_mode):
            raise ParameterError(f"{option} {printable(value)}: {printable(p)} "
                                 + ("exists and is not a folder" if p == path.absolute() else "is a file, not a folder"))
        return p


def _writable_folder(option: str, value: str, folder: Path) -> None:
    """The folder exists or can be made, and a file can be created in it (probed, then removed)."""
    base = _nearest_existing(option, value, folder)
    if not os.access(base, os.W_OK | os.X_OK):
        raise ParameterError(f"{option} {printable(value)}: {printable(base)} is not writable")
    try:
        with tempfile.TemporaryFile(dir=base):
            pass
    except OSError as e:
        raise ParameterError(f"{option} {printable(value)}: {printable(base)} is not writable "
                             f"({e.strerror or e})") from None


SCAN_MAX = 20_000  # entries of an existing --out folder looked at (a resumed study holds a few thousand)


OUT_RULE = "outputs are written only over regular files (remove it or choose another folder)"


def no_special_files(option: str, value: str, folder: Path, rule: str = OUT_RULE) -> None:
    """An existing folder holds no FIFO, device or socket: for --out, where a command would write (outputs
    replace regular files only, nsd_core.device.results.check_output_target); for nsd report --from,
    what it reads (a FIFO would block). Refused before any work, so that nothing is written. Folders
    inside are looked into (not through links), up to SCAN_MAX entries."""
    from nsd_core.common.files import _kind
    todo, seen = [folder], 0
    while todo and seen < SCAN_MAX:
        try:
            entries = list(os.scandir(todo.pop()))
        except OSError:
            continue
        for e in entries:
            seen += 1
            try:
                if e.is_dir(follow_symlinks=False):
                    todo.append(Path(e.path))
                    continue
                mode = os.stat(e.path).st_mode
            except OSError:
                continue   # a dangling link: the write replaces it
            if not stat.S_ISREG(mode) and not stat.S_ISDIR(mode):
                raise ParameterError(f"{option} {printable(value)}: {printable(e.path)} is {_kind(mode)}; {rule}")


def check_out_dir(option: str, value: str | None, lock: bool = True) -> Path | None:
    """--out must name a folder (existing or to be made) that can be written, checked before any
    computation so that a run never fails at the end for want of a place to put its results; then
    the folder is locked for this run (nsd_cli.outlock: a second run into it is exit 2)."""
    if value is None:
        return None
    if not value.strip():
        raise ParameterError(f"{option} '': name an output folder")
    path = Path(value)
    _writable_folder(option, value, path)
    no_special_files(option, value, path)
    if lock:
        from nsd_cli.outlock import acquire
        try:
            acquire(path, option, value)
        except ParameterError:
            raise
        except OSError as e:
            raise _path_error(option, value, path, e) from None
    return path


def check_out_file(option: str, value: str | None) -> Path | None:
    """An output file (--junit): not a folder, in a folder that can be written."""
    if value is None:
        return None
    path = Path(value)
    if not value.strip() or value.endswith(("/", os.sep)) or os.path.isdir(value):
        raise ParameterError(f"{option} {printable(repr(value))}: must name a file, not a folder")
    if len(os.fsencode(path.name)) > NAME_MAX - TMP_AFFIX:
        raise ParameterError(f"{option} {printable(value)}: name too long (at most {NAME_MAX - TMP_AFFIX} bytes for "
                             "a file name)")
    _writable_folder(option, value, path.parent)
    from nsd_core.common.files import check_output_target
    check_output_target(path, option)  # a FIFO or a device there is refused, never replaced
    return path


def check_finite(data, what: str) -> None:
    """Any NaN or inf in an output is a solver failure (exit 3), never exit 0: raises SolverError
    naming the first field that holds one (nsd_core.device.results.first_nonfinite); nothing is written."""
    from nsd_core.device.results import first_nonfinite
    from nsd_core.common.errors import SolverError
    bad = first_nonfinite(data)
    if bad:
        raise SolverError(f"{what}: a non-finite output, {bad}; nothing written")


def positive(name: str, v, whole: bool = False) -> None:
    """None passes; otherwise a finite number > 0 (a whole number >= 1 when ``whole``)."""
    if v is None:
        return
    if not math.isfinite(v) or v <= 0 or (whole and v != int(v)):
        raise ParameterError(f"{name} = {v}: must be a {'whole number >= 1' if whole else 'finite number > 0'}")


def parse_numbers(option: str, text: str | None, context: str = "") -> list[float]:
    """Comma-separated finite numbers."""
    if not text:
        raise ParameterError(f"{option}: required{context} (comma-separated numbers)")
    out = []
    for item in text.split(","):
        try:
            v = float(item)
        except ValueError:
            raise ParameterError(f"{option} {item.strip()!r}: not a number (comma-separated numbers expected)") from None
        if not math.isfinite(v):
            raise ParameterError(f"{option} {item.strip()!r}: must be finite")
        out.append(v)
    return out


def parse_engines(text: str, check_available: bool = False) -> list[str]:
    """Comma-separated engine names from the one registry (comparisons.engines), each once."""
    from comparisons.engines import get_engine, parse_engine_list
    names = parse_engine_list(text)
    if check_available:
        for e in names:
            try:
                get_engine(e)
            except Exception as exc:  # noqa: BLE001 - any import failure means not usable here
                raise ParameterError(f"--engines {e}: not available ({type(exc).__name__}: {exc})".splitlines()[0]) from None
    return names
