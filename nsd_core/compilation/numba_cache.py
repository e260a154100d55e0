"""Where numba keeps compiled machine code: one folder per version of the source.

numba's on-disk cache checks only the file of the function it compiled, not the functions that
one calls: after an edit to a force law or to an engine kernel, a cached step loop in another file
would go on running the old code. So the cache folder is keyed by a hash of every source file of
``nsd_core`` and ``comparisons`` that compiled code can depend on (``compiled_sources``: the modules
that import numba and what they import, transitively): an edit to any of them starts a fresh folder, an
edit elsewhere keeps the machine code. A NUMBA_CACHE_DIR set by the user is honoured as it is.

numba warns on stderr when it cannot cache a kernel ("Cannot cache compiled function ... as it uses
dynamic globals": every kernel under NUMBA_OPT=0). Such a kernel is compiled again in the next
process, which costs time and changes no number; the warning would break the one-line error promise,
so ``quiet_cache_warnings`` keeps it off the user's stderr (NSD_NUMBA_CACHE_WARNINGS=1 shows it).

numba names the cache's sub-folder of a source file after the hash of its absolute directory: a new
install of the same version elsewhere (another clone, a CI runner's fresh checkout, a venv's
site-packages) would miss every kernel and compile them again. ``relocatable_cache`` names it after the
file's place inside the package instead (``nsd_core/engine`` -> ``nsd_core_engine``): the folder is
already keyed by the content of every source file, so the same version finds the same machine code
wherever it is installed (tests/test_numba_cache.py). A child process (a pool's worker, ``nsd warm``'s
helpers) inherits the folder in NUMBA_CACHE_DIR and the mark NSD_VERSIONED_CACHE that this module chose
it, and names its sub-folders the same way: before the mark, the children took the folder for a user's
own and kept numba's naming, so a parent and its workers never loaded each other's machine code.
"""
from __future__ import annotations

import hashlib
import os
import re
import sys
import warnings
from pathlib import Path

PACKAGES = ("nsd_core", "comparisons")
CHOSEN = "NSD_VERSIONED_CACHE"   # the folder use_versioned_cache chose, for the child processes


def _sources(root: Path) -> dict[str, tuple[Path, bytes]]:
    """module name -> (file, its bytes), every .py file of the packages under ``root``."""
    out = {}
    for pkg in PACKAGES:
        base = root / pkg
        for f in sorted(base.rglob("*.py")) if base.is_dir() else ():
            parts = f.relative_to(root).with_suffix("").parts
            out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = (f, f.read_bytes())
    return out


def source_fingerprint(root: Path, compiled_only: bool = False) -> str:
    """Hash of the names and contents of every .py file of the packages under ``root`` (``compiled_only``:
    of the files numba's machine code can depend on, ``compiled_sources``)."""
    sources = _sources(root)
    keep = compiled_sources(sources) if compiled_only else set(sources)
    h = hashlib.sha256()
    for name, (f, text) in sorted(sources.items(), key=lambda kv: kv[1][0]):
        if name in keep:
            h.update(f.relative_to(root).as_posix().encode())
            h.update(text)
    return h.hexdigest()[:16]


USES_NUMBA = re.compile(rb"^[ \t]*(?:import[ \t]+numba|from[ \t]+numba[ \t.])", re.M)
IMPORT = re.compile(rb"^[ \t]*(?:from[ \t]+([\w.]+)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*)|import[ \t]+([\w., \t]+))", re.M)


def compiled_sources(sources: dict) -> set[str]:
    """The modules numba's machine code can depend on: every module that imports numba (its kernels, and
    the code generators whose output it compiles), and every module of the packages those import, lazily
    too, transitively (a kernel freezes the globals it reads at compile time). An edit anywhere else (the verdict, the command line, the studies, a builder
    that only calls compiled code) leaves the compiled code, and so its cache folder, as they were. A
    package's import is its ``__init__``, whose own imports are followed in turn."""
    def deps(text: bytes) -> set[str]:
        found = set()
        for frm, names, plain in IMPORT.findall(text):
            mods = [m.strip().split(" ")[0] for m in plain.decode().split(",")] if plain else [frm.decode()]
            if frm:
                mods += [f"{frm.decode()}.{n.strip().split(' ')[0]}" for n in names.decode().strip("()").split(",")
                         if n.strip()]
            for m in mods:
                while m and m not in sources:   # a name inside a module: the module
                    m = m.rpartition(".")[0]
                if m:
                    found.add(m)
        return found
    todo = [m for m, (_, text) in sources.items() if USES_NUMBA.search(text)]
    seen = set(todo)
    while todo:
        for d in deps(sources[todo.pop()][1]) - seen:
            seen.add(d)
            todo.append(d)
    return seen


def cache_folder(root: Path, environ=os.environ) -> Path:
    from nsd_core.common.files import cache_root
    return cache_root("numba", environ) / source_fingerprint(root, compiled_only=True)


def use_versioned_cache(environ=os.environ) -> str | None:
    """Point numba's cache at this source version's folder (unless NUMBA_CACHE_DIR is set); the
    folder, or None where the user's own setting stands or no folder can be made."""
    given = environ.get("NUMBA_CACHE_DIR")
    if given:
        if given != environ.get(CHOSEN):
            return None
        # a child process (a pool's worker, a helper) of one that chose this folder: the same naming of
        # its sub-folders, or the two would never find each other's machine code (they did not, before)
        relocatable_cache()
        return given
    try:
        folder = cache_folder(Path(__file__).resolve().parents[2], environ)
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:  # no writable home: numba's default (beside the source) still works
        return None
    environ["NUMBA_CACHE_DIR"] = str(folder)  # child processes compile into the same folder
    environ[CHOSEN] = str(folder)  # ... named as here (not a user's own NUMBA_CACHE_DIR)
    if "numba" in sys.modules:  # numba read its configuration already: tell it too
        from numba.core import config
        config.CACHE_DIR = str(folder)
    relocatable_cache()
    return str(folder)


ROOT = Path(__file__).resolve().parents[2]


def package_subfolder(py_file: str, root: Path = ROOT) -> str | None:
    """The cache sub-folder of a source file of PACKAGES (its folder inside the package, "/" -> "_"),
    None for any other file (numba's own naming then applies)."""
    try:
        rel = Path(py_file).resolve().relative_to(root)
    except ValueError:
        return None
    return "_".join(rel.parent.parts) if rel.parts and rel.parts[0] in PACKAGES else None


def relocatable_cache() -> bool:
    """Put a locator in front of numba's own that names the cache sub-folder of the packages' files
    by their place in the package, not by their absolute path (once per process). Only under the
    versioned folder: a user's own NUMBA_CACHE_DIR keeps numba's naming."""
    from numba.core import caching
    if any(getattr(c, "nsd_relocatable", False) for c in caching.CacheImpl._locator_classes):
        return False

    class PackageLocator(caching.UserProvidedCacheLocator):
        nsd_relocatable = True

        def __init__(self, py_func, py_file):
            super().__init__(py_func, py_file)
            from numba.core import config
            self._cache_path = os.path.join(config.CACHE_DIR, package_subfolder(py_file))

        @classmethod
        def from_function(cls, py_func, py_file):
            return super().from_function(py_func, py_file) if package_subfolder(py_file) else None

    caching.CacheImpl._locator_classes.insert(0, PackageLocator)
    return True


CACHE_WARNING = r"Cannot cache compiled function"


def quiet_cache_warnings(environ=os.environ) -> bool:
    """Ignore numba's cannot-cache warnings in this process (worker processes import nsd_core and
    do the same); True when the filter was installed, False where NSD_NUMBA_CACHE_WARNINGS=1."""
    if environ.get("NSD_NUMBA_CACHE_WARNINGS") == "1":
        return False
    warnings.filterwarnings("ignore", message=CACHE_WARNING)
    return True

