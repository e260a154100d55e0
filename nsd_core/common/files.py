"""Reading input files safely, writing output files atomically, and naming paths on one line. Every file the program reads (a
description, a cases, tolerance or parameter file, a reference CSV, a path table, a results folder
given to ``nsd report --from``) is read through this module: tests/test_input_guard.py looks for any
other read in the code.

Only regular files are read as inputs: a FIFO, a character or block device, a socket or a folder
given where a file is expected is bad input (``InputError``, exit 2) naming the path, found by
``os.stat`` before the file is opened, and the file is then opened without blocking
(``O_NONBLOCK``, checked again on the open descriptor), so that a FIFO swapped in between never
makes a command wait for a writer that does not come.

``printable`` escapes control characters (a newline in a file name, an escape sequence) so that
every message stays on one line and cannot rewrite the terminal.
"""
from __future__ import annotations

import io
import os
import stat
import time
from pathlib import Path

import json
import shutil
import tempfile
from typing import Any

import numpy as np

from nsd_core.common.errors import InputError

# What every input file may weigh (bytes): far beyond any real one, small enough to read in seconds.
# A description or a cases file: the largest shipped is 26 kB (81 bodies); 4 MB holds ~20 000 bodies'
# tables, past every bound on a description's size (nsd_core.model.bounds). A reference CSV: its rows
# lie on the output grid (at most 1e6 samples); 100 MB is 1e6 rows of ~100 characters.
MAX_DESCRIPTION_BYTES = 4_000_000
MAX_REFERENCE_BYTES = 100_000_000
READ_SECONDS = 30.0   # a read slower than this (a stalled network file system) is refused, not waited for

KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
         (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def printable(text) -> str:
    """``text`` with every control character (C0, DEL, C1) and every undecodable byte escaped
    (\\n, \\t, \\x1b, \\udcff ...): what a one-line message may show of a name a user chose."""
    out = []
    for ch in str(text):
        o = ord(ch)
        if o < 0x20 or 0x7F <= o < 0xA0 or 0xD800 <= o < 0xE000 or o in (0x2028, 0x2029):
            out.append(ch.encode("unicode_escape", "backslashreplace").decode("ascii")
                       if not 0xD800 <= o < 0xE000 else f"\\udc{o & 0xFF:02x}")
        else:
            out.append(ch)
    return "".join(out)


def _kind(mode: int) -> str | None:
    for test, name in KINDS:
        if test(mode):
            return name
    return None


def check_regular(path: str | Path, what: str) -> os.stat_result:
    """``os.stat`` of an input file that must be a regular file (InputError otherwise)."""
    where = f"{what} {printable(path)}"
    if not str(path).strip():
        raise InputError(f"{what} '': name a file")
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise InputError(f"{where}: file not found") from None
    except PermissionError:
        raise InputError(f"{where}: not readable (permission denied)") from None
    except OSError as e:
        raise InputError(f"{where}: cannot be read ({e.strerror or e})") from None
    kind = _kind(st.st_mode)
    if kind is not None or not stat.S_ISREG(st.st_mode):
        raise InputError(f"{where}: is {kind or 'not a regular file'}; a regular file is expected")
    return st


def read_input_bytes(path: str | Path, what: str, max_bytes: int, seconds: float = READ_SECONDS) -> bytes:
    """The bytes of a regular input file of at most ``max_bytes``, read within ``seconds``
    (InputError otherwise); never blocks on a FIFO."""
    where = f"{what} {printable(path)}"
    deadline = time.monotonic() + seconds
    st = check_regular(path, what)
    if st.st_size > max_bytes:
        raise InputError(f"{where}: {st.st_size} bytes; at most {max_bytes} bytes expected")
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
    except PermissionError:
        raise InputError(f"{where}: not readable (permission denied)") from None
    except OSError as e:
        raise InputError(f"{where}: cannot be read ({e.strerror or e})") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):  # replaced between the stat and the open
            raise InputError(f"{where}: is {_kind(st.st_mode) or 'not a regular file'}; a regular file is expected")
        chunks, size = [], 0
        while True:
            chunk = os.read(fd, 1 << 20)
            if not chunk:
                break
            size += len(chunk)
            if size > max_bytes:
                raise InputError(f"{where}: more than {max_bytes} bytes; at most {max_bytes} bytes expected")
            chunks.append(chunk)
            if time.monotonic() > deadline:
                raise InputError(f"{where}: not read within {seconds:g} s; a local regular file is expected")
        return b"".join(chunks)
    except OSError as e:
        raise InputError(f"{where}: cannot be read ({e.strerror or e})") from None
    finally:
        os.close(fd)


def read_input_text(path: str | Path, what: str, max_bytes: int, expected: str = "UTF-8 text") -> str:
    """A regular input file as UTF-8 text (InputError naming the path otherwise)."""
    data = read_input_bytes(path, what, max_bytes)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{what} {printable(path)}: not a text file ({expected} expected)") from None


def input_stream(path: str | Path, what: str, max_bytes: int, expected: str = "UTF-8 text") -> io.StringIO:
    """A regular input file's text as a stream (for csv, numpy's loaders): read through the guard above,
    so no parser ever opens the path itself."""
    return io.StringIO(read_input_text(path, what, max_bytes, expected), newline=None)


def read_regular_text(path: str | Path, what: str = "file") -> str:
    """Path.read_text for a file the program wrote itself (results, a store): only a regular file is
    read, so a FIFO or a device planted in a results folder is one line (InputError), never a hang."""
    return read_input_text(path, what, 1 << 32)


def check_output_target(path: str | Path, what: str = "output") -> None:
    """An output is written only where nothing is, or over a regular file (or a link to one): a FIFO,
    a device, a socket or a folder there is bad input (InputError, exit 2), never replaced."""
    try:
        st = os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        return
    except OSError:
        return  # (a link loop, no permission: the write itself says so, naming the file)
    if not stat.S_ISREG(st.st_mode):
        raise InputError(f"{what} {printable(path)}: is {_kind(st.st_mode) or 'not a regular file'}; an output is "
                         "written only where no file is or over a regular file")


def atomic_write_text(path: str | Path, text: str) -> None:
    """Write to a temporary file in the same folder, then rename: readers never see half a file.
    A failed write (a full disk) removes the temporary file and raises OSError naming ``path``;
    the file that was there before stays as it was. Only a regular file is replaced
    (check_output_target: a FIFO or a device there is InputError, nothing written)."""
    _atomic_write(path, text, "w")


def atomic_write_bytes(path: str | Path, data: bytes) -> None:
    """``atomic_write_text`` for bytes."""
    _atomic_write(path, data, "wb")


def _atomic_write(path: str | Path, data, mode: str) -> None:
    path = Path(path)
    check_output_target(path)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        with os.fdopen(fd, mode) as f:
            f.write(data)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; a result file gets the usual mode
        os.replace(tmp, path)
    except BaseException as e:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
        if isinstance(e, OSError) and e.filename is None:
            raise OSError(e.errno, e.strerror, str(path)) from None
        raise


def atomic_copy(src: str | Path, dest: str | Path) -> None:
    """Copy a file atomically (temporary file, then rename); a failed copy leaves ``dest`` as it was."""
    dest = Path(dest)
    check_output_target(dest)
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = dest.with_name(f".{dest.name}.tmp")
    try:
        shutil.copyfile(src, tmp)
        tmp.replace(dest)
    except BaseException as e:
        tmp.unlink(missing_ok=True)
        if isinstance(e, OSError) and e.errno is not None:
            raise OSError(e.errno, e.strerror, str(dest)) from None
        raise


def cache_root(kind: str, environ=os.environ) -> Path:
    """The project's cache folder of one kind: ``$XDG_CACHE_HOME/nsd-harness/KIND`` (``~/.cache`` when
    unset): numba's machine code, generated symbolic code, records, kept results."""
    return Path(environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "nsd-harness" / kind


def _umask() -> int:
    mask = os.umask(0o022)  # reading the umask means setting it: put it straight back
    os.umask(mask)
    return mask


def atomic_write_json(path: str | Path, data: Any) -> None:
    atomic_write_text(path, json.dumps(data, indent=2, default=_json_default) + "\n")


def _json_default(o):
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating, np.integer, np.bool_)):
        return o.item()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")
