"""Every file the program reads goes through one guard (nsd_core.common.files: regular files only, a
size cap, a time bound): the code is searched for any other way of reading a file, so that the next
reader cannot forget it. Writes and the program's own files (its source, its committed references)
are listed by name below, each with why."""
from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("nsd_core", "comparisons", "nsd_cli", "reports")
RAW = re.compile(r"(?<![\w.])open\(|\.read_text\(|\.read_bytes\(|tomllib\.load\(|np\.loadtxt\(\s*(?!io\.|input_stream)"
                 r"|np\.genfromtxt\(\s*(?!io\.|stream|input_stream)|csv\.(?:Dict)?[rR]eader\(\s*(?!io\.|input_stream)"
                 r"|json\.load\(|np\.load\(|os\.open\(|\.open\(")
# (file, the line's text that may stay, why)
ALLOWED = (
    ("nsd_core/common/files.py", "fd = os.open(path", "the guard itself"),
    ("nsd_cli/outlock.py", "fd = os.open(lock", "the run's own lock file, written"),
    ("nsd_core/engine/compile_once.py", "fd = os.open(os.path.join(folder", "the compile lock, written"),
    ("nsd_core/engine/codegen.py", "path.read_text() != source", "the program's own generated source"),
    ("nsd_core/engine/codegen.py", 'os.fdopen(fd, "w")', "a write"),
    ("nsd_core/device/results.py", 'os.fdopen(fd, "w")', "a write"),
    ("reports/render.py", 'open(merged, "wb")', "a write"),
    ("nsd_core/compilation/numba_cache.py", "(f, f.read_bytes())", "the program's own source files: hashed, and scanned for imports"),
    ("comparisons/builders/generated.py", "Path(module.__file__).read_bytes()", "hash of the program's source"),
    ("comparisons/builders/generated.py", "Path(path).read_bytes()", "hash of the program's source"),
    ("nsd_core/engine/problems/andrews.py", 'open(path or REFERENCES', "the committed Andrews reference"),
    ("nsd_core/engine/problems/andrews.py", "tomllib.load(f)", "the committed Andrews reference"),
    ("nsd_core/structure/design.py", "BASIS.read_text()", "the committed design basis table"),
    ("nsd_cli/compare.py", "DEFAULT_CASES.read_text(", "the committed default cases, for --help"),
    ("comparisons/builders/symbolic_codegen.py", "(here / m).read_bytes()", "hash of the program's source"),
    ("comparisons/builders/symbolic_codegen.py", "meta_file.read_text()", "the program's own code cache"),
    ("nsd_core/ground/record_cache.py", 'with open(path, "rb")', "the program's own record cache (a pickle it wrote)"),
    ("nsd_core/compilation/result_cache.py", 'path.read_text(encoding="utf-8")', "the program's own result cache (JSON it wrote)"),
)


def raw_reads() -> list[str]:
    found = []
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            for n, line in enumerate(path.read_text().splitlines(), 1):
                code = line.split("#", 1)[0]
                if not RAW.search(code) or code.lstrip().startswith(("def ", '"""', "'''")):
                    continue
                if any(rel == f and text in code for f, text, _ in ALLOWED):
                    continue
                found.append(f"{rel}:{n}: {line.strip()}")
    return found


def test_no_read_outside_the_guard():
    found = raw_reads()
    assert not found, "files read without nsd_core.common.files (regular file, size cap, time bound):\n" + \
        "\n".join(found)


def test_the_search_finds_a_raw_read(tmp_path, monkeypatch):
    """The search is not blind: a raw read in a package file is found (a copy of the tree's layout)."""
    pkg = tmp_path / "nsd_core"
    pkg.mkdir()
    (pkg / "x.py").write_text("import numpy as np\n"
                              "a = np.genfromtxt(path, delimiter=',')\n"
                              "b = Path(p).read_text()\n"
                              "c = np.genfromtxt(input_stream(p, 'x', 10))\n")
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    found = raw_reads()
    assert [f.split(":")[1] for f in found] == ["2", "3"], found


@pytest.mark.parametrize("kind", ["fifo", "folder", "big"])
def test_guard_refuses(tmp_path, kind):
    import os

    from nsd_core.common.files import read_input_text
    from nsd_core.common.errors import InputError
    p = tmp_path / "f"
    if kind == "fifo":
        os.mkfifo(p)
    elif kind == "folder":
        p.mkdir()
    else:
        p.write_text("x" * 101)
    with pytest.raises(InputError, match={"fifo": "FIFO", "folder": "folder", "big": "at most 100 bytes"}[kind]):
        read_input_text(p, "--model", 100)


def test_guard_time_bound(tmp_path):
    from nsd_core.common.files import read_input_bytes
    from nsd_core.common.errors import InputError
    p = tmp_path / "f"
    p.write_bytes(b"x" * (3 << 20))   # read in 1 MiB chunks: the bound is looked at after each
    with pytest.raises(InputError, match="not read within"):
        read_input_bytes(p, "--cases", 10 << 20, seconds=-1.0)
