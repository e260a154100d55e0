"""Generated numba source, compiled once per shape: where it is written, what its name hashes, how it
is loaded (the MuJoCo callback of mujoco_codegen and the Exudyn force functions of exudyn_codegen).

numba's disk cache checks the generated file alone, not the functions it calls into: the file's
name is a hash of its text, of the helper modules it imports, of numba's version and of the source
files of every law it is bound to (and of every numba function those call, transitively), so an edit
anywhere it depends on gives a new file and a fresh compile, never a stale one.
"""
from __future__ import annotations

import hashlib
import importlib.util
import inspect
import os
import sys
import tempfile
from pathlib import Path

import numba

from nsd_core.model import laws as registry

_LOADED: dict[str, object] = {}


def law_set(elements) -> list:
    """The laws a generated module is made for, sorted by name: every registered law defined in a module
    that defines one of ``elements``' laws, and the model layer's own. So the device's drive, its seismic
    models and a mechanism of the model layer's laws share a module (exudyn_codegen, mujoco_codegen)."""
    homes = {registry.__name__} | {_home(f.law) for f in elements}
    return sorted((law for law in registry.LAWS.values() if _home(law) in homes), key=lambda law: law.name)


def _home(law) -> str:
    return getattr(law.force, "py_func", law.force).__module__


def bound_laws(laws) -> dict:
    """The law functions a module generated for ``laws`` (law_set's list) calls, by the names its source
    uses: ``law_<code>`` (Law.force) and ``rate_<code>`` (Law.rate, where the law has a state), the code
    being the law's index in the list."""
    bound = {}
    for i, law in enumerate(laws):
        bound[f"law_{i}"] = law.force
        if law.rate is not None:
            bound[f"rate_{i}"] = law.rate
    return bound


def identity(fn) -> str:
    py = getattr(fn, "py_func", fn)
    return f"{py.__module__}.{py.__qualname__}"


def _dependency_files(fn, seen: set) -> None:
    """The source files of ``fn`` and of every numba function it names, transitively."""
    py = getattr(fn, "py_func", fn)
    if id(py) in seen:
        return
    seen.add(id(py))
    try:
        seen.add(inspect.getsourcefile(py))
    except TypeError:
        return
    for name in py.__code__.co_names:
        g = py.__globals__.get(name)
        if isinstance(g, numba.core.registry.CPUDispatcher):
            _dependency_files(g, seen)
    for cell in py.__closure__ or ():
        if isinstance(cell.cell_contents, numba.core.registry.CPUDispatcher):
            _dependency_files(cell.cell_contents, seen)


def fingerprint(text: str, bound: dict, helpers: tuple) -> str:
    """The hash that names a generated file (see the module's docstring)."""
    h = hashlib.sha256(text.encode())
    h.update(numba.__version__.encode())
    for module in helpers:
        h.update(Path(module.__file__).read_bytes())
    for name, fn in sorted(bound.items()):
        py = getattr(fn, "py_func", fn)
        h.update(f"{name}={identity(fn)}".encode())
        if "<locals>" in py.__qualname__ or py.__closure__:   # not told apart by name: this process only
            h.update(str(id(fn)).encode())
        seen: set = set()
        _dependency_files(fn, seen)
        for path in sorted(p for p in seen if isinstance(p, str)):
            h.update(path.encode())
            h.update(Path(path).read_bytes())
    return h.hexdigest()[:20]


def folder() -> Path:
    """A writable folder for generated source: beside numba's cache, else the user's cache, else tmp."""
    base = numba.core.config.CACHE_DIR or os.environ.get("NUMBA_CACHE_DIR") or ""
    for f in ([Path(base) / "generated"] if base else []) + [
            Path.home() / ".cache" / "nsd-harness" / "generated", Path(tempfile.gettempdir()) / "nsd-generated"]:
        try:
            f.mkdir(parents=True, exist_ok=True)
            return f
        except OSError:
            continue
    raise RuntimeError("no writable folder for generated source")


def load(text: str, bound: dict, helpers: tuple, prefix: str):
    """The module of generated ``text`` with the functions ``bound`` by name, compiled once per shape
    and process, from numba's disk cache when an earlier process compiled it."""
    key = fingerprint(text, bound, helpers)
    if key in _LOADED:
        return _LOADED[key]
    path = folder() / f"{prefix}_{key}.py"
    if not path.exists():   # its name is its content's hash
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(text)
        os.replace(tmp, path)   # atomic: a concurrent process sees the whole file or none
    name = f"nsd_generated_{prefix}_{key}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    module.__dict__.update(bound)   # the law functions, by the names the source calls
    sys.modules[name] = module
    spec.loader.exec_module(module)
    _LOADED[key] = module
    return module
