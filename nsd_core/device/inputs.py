"""Reading input files safely, and naming paths on one line. Every file the program reads (a
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

from nsd_core.engine.errors import InputError as ParameterError  # params.py reads through this module

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
    """``os.stat`` of an input file that must be a regular file (ParameterError otherwise)."""
    where = f"{what} {printable(path)}"
    if not str(path).strip():
        raise ParameterError(f"{what} '': name a file")
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise ParameterError(f"{where}: file not found") from None
    except PermissionError:
        raise ParameterError(f"{where}: not readable (permission denied)") from None
    except OSError as e:
        raise ParameterError(f"{where}: cannot be read ({e.strerror or e})") from None
    kind = _kind(st.st_mode)
    if kind is not None or not stat.S_ISREG(st.st_mode):
        raise ParameterError(f"{where}: is {kind or 'not a regular file'}; a regular file is expected")
    return st


def read_input_bytes(path: str | Path, what: str, max_bytes: int, seconds: float = READ_SECONDS) -> bytes:
    """The bytes of a regular input file of at most ``max_bytes``, read within ``seconds``
    (ParameterError otherwise); never blocks on a FIFO."""
    where = f"{what} {printable(path)}"
    deadline = time.monotonic() + seconds
    st = check_regular(path, what)
    if st.st_size > max_bytes:
        raise ParameterError(f"{where}: {st.st_size} bytes; at most {max_bytes} bytes expected")
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
    except PermissionError:
        raise ParameterError(f"{where}: not readable (permission denied)") from None
    except OSError as e:
        raise ParameterError(f"{where}: cannot be read ({e.strerror or e})") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):  # replaced between the stat and the open
            raise ParameterError(f"{where}: is {_kind(st.st_mode) or 'not a regular file'}; a regular file is expected")
        chunks, size = [], 0
        while True:
            chunk = os.read(fd, 1 << 20)
            if not chunk:
                break
            size += len(chunk)
            if size > max_bytes:
                raise ParameterError(f"{where}: more than {max_bytes} bytes; at most {max_bytes} bytes expected")
            chunks.append(chunk)
            if time.monotonic() > deadline:
                raise ParameterError(f"{where}: not read within {seconds:g} s; a local regular file is expected")
        return b"".join(chunks)
    except OSError as e:
        raise ParameterError(f"{where}: cannot be read ({e.strerror or e})") from None
    finally:
        os.close(fd)


def read_input_text(path: str | Path, what: str, max_bytes: int, expected: str = "UTF-8 text") -> str:
    """A regular input file as UTF-8 text (ParameterError naming the path otherwise)."""
    data = read_input_bytes(path, what, max_bytes)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise ParameterError(f"{what} {printable(path)}: not a text file ({expected} expected)") from None


def input_stream(path: str | Path, what: str, max_bytes: int, expected: str = "UTF-8 text") -> io.StringIO:
    """A regular input file's text as a stream (for csv, numpy's loaders): read through the guard above,
    so no parser ever opens the path itself."""
    return io.StringIO(read_input_text(path, what, max_bytes, expected), newline=None)


def read_regular_text(path: str | Path, what: str = "file") -> str:
    """Path.read_text for a file the program wrote itself (results, a store): only a regular file is
    read, so a FIFO or a device planted in a results folder is one line (InputError), never a hang."""
    return read_input_text(path, what, 1 << 32)
