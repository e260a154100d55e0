"""A per-mechanism evaluation generated from the mechanism's data (docs/engine-codegen.md).

``generated_evaluator(model)`` writes the Python source of one numba function with the evaluator
contract of nsd_core.engine.compiled.evaluate, ``evaluate(t, y, m, w, forces, motion, reactions)``,
for the *structure* of ``model`` (a SystemModel): the parent array, the joint types, which joint-axis
components are exactly 0 or 1, which offsets, centres of mass, inertia entries, cut vectors and
element points are exactly 0, the massless bodies, the cuts' kinds and bodies, the partition into
prescribed / free / dependent coordinates and rows, the elements' bodies. The tree is unrolled body
by body, the structural zeros are left out (a prismatic joint's rotation is its parent's, a massless
body adds nothing, the reduced mass matrix of one free coordinate is a scalar, a zero entry of
Phi_z is never formed), and every number (offsets, axes, masses, inertias, points, parameters) is
read from the model when the function runs: designs that differ only in their numbers share one
compiled function. The arithmetic is the generic kernels' in the same order (codegen_sym), so the
two agree to round-off (tests/test_codegen.py); the generic kernels stay the specification.

The source goes to the numba cache folder (nsd_core.compilation.numba_cache), named by the hash of its text, and
is compiled with an explicit signature and cache=True: a second process loads the machine code from
disk.

Which evaluation a run uses (``evaluator_for``, NSD_EVALUATOR): compiling a structure's generated
evaluation costs 12-25 s CPU on a cold cache, against one compilation of the generic kernels for
every structure; it pays back over a study (thousands of runs of one structure: 3-6x less CPU per
evaluation) but not over the gate's one short run per case and structure. So "auto" (the default)
uses the generated evaluation where it is already compiled (its ``.compiled`` mark beside the
source) and the generic one otherwise; the study commands (sweep, polar, calibration, seismic record
sets, IDA) ask for "generated", which compiles it. The two give the same numbers, bit for bit
(tests/test_codegen.py), so the choice changes only the time.
"""
from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from nsd_core.engine.codegen_main import generate_source
from nsd_core.engine.compile_once import _locked, compile_once
from nsd_core.common.errors import InputError

ENV = "NSD_EVALUATOR"  # "auto" (default), "generated" or "generic": see the module's docstring
KINDS = ("auto", "generated", "generic")
_LOADED: dict[str, object] = {}


def source_folder() -> Path:
    """Where generated sources live: beside numba's cache (keyed by the package's source version)."""
    base = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(tempfile.gettempdir(), "nsd-harness-numba")
    return Path(base) / "generated"


def _write_atomic(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def structure_key(model) -> bytes:
    """Everything generate_source reads from ``model``: its integer arrays, n_extra, and where its
    numbers are exactly 0 (joint axes: or 1). Equal keys, equal sources (a cheap in-process memo)."""
    h = hashlib.sha256()
    for name in model._fields:
        a = np.asarray(getattr(model, name))
        if name in ("force_params", "motion_params"):
            continue
        if name == "settings":
            a = a[2:3]
        elif a.dtype.kind == "f":
            a = (a == 0.0) + 2 * (a == 1.0) if name == "axis" else (a == 0.0)
        h.update(name.encode() + str(a.shape).encode() + np.ascontiguousarray(a).tobytes())
    return h.digest()


_SOURCES: dict[bytes, tuple[str, str]] = {}  # structure key -> (module name, source)


def _generated_source(model) -> tuple[bytes, str, str]:
    """(structure key, module name, source) of ``model``'s generated evaluation (memoized)."""
    skey = structure_key(model)
    if skey not in _SOURCES:
        source = generate_source(model)
        _SOURCES[skey] = (f"nsd_eval_{hashlib.sha256(source.encode()).hexdigest()[:20]}", source)
    return (skey, *_SOURCES[skey])


def is_compiled(model) -> bool:
    """Whether ``model``'s generated evaluation is in this process or compiled on disk (its mark)."""
    skey, name, _ = _generated_source(model)
    return skey in _LOADED or (source_folder() / f"{name}.compiled").exists()


def generated_evaluator(model):
    """The compiled generated evaluation for ``model``'s structure (one per structure and process)."""
    skey, name, source = _generated_source(model)
    if skey in _LOADED:
        return _LOADED[skey]
    path = source_folder() / f"{name}.py"
    path.parent.mkdir(parents=True, exist_ok=True)
    with _locked(name, True):  # processes started together write and compile it once; the others load it
        if not path.exists() or path.read_text() != source:
            _write_atomic(path, source)  # an unchanged file keeps its time stamp, which numba's cache checks
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # before it runs: numba's cache records the module by name, to import it
        spec.loader.exec_module(module)  # njit with a signature: compiled (or loaded) here
        mark = path.with_suffix(".compiled")
        if not mark.exists():
            _write_atomic(mark, "")  # "auto" uses it from now on (numba has written its cache)
    _LOADED[skey] = module.evaluate
    return module.evaluate


def generic_evaluator():
    """nsd_core.engine.compiled.generic_evaluator, compiled (the specification)."""
    from nsd_core.engine.compiled import EVALUATE, generic_evaluator as generic
    compile_once(EVALUATE)
    return generic


def evaluator_kind() -> str:
    """NSD_EVALUATOR checked: "auto" (unset), "generated" or "generic"."""
    kind = os.environ.get(ENV) or "auto"
    if kind not in KINDS:
        raise InputError(f"{ENV} = {kind!r}: allowed 'auto' (the default), 'generated' or 'generic'")
    return kind


def evaluator_for(model, kind: str | None = None):
    """The evaluator a run uses: ``kind`` "auto", "generated" or "generic"; None reads NSD_EVALUATOR.
    "auto": the generated evaluation where it is already compiled, else the generic one."""
    return generic_evaluator() if evaluation_used(model, kind) == "generic" else generated_evaluator(model)


# The largest tree whose evaluation is generated: the unrolled source grows about as the cube of the
# bodies (the seismic device with a building of N stories has 10 + 2N bodies: 0.1 MB of source at 3
# stories, 0.2 MB at 6, 0.8 MB at 12, 37 MB at 50); 12 stories made numba's compilation fail
# (MemoryError under 4 GB, RecursionError after ~140 s). A larger tree runs the generic evaluation,
# which gives the same numbers (a structure-independent compilation), whatever NSD_EVALUATOR says.
GENERATED_MAX_BODIES = 16   # the default building (3 stories) on the device


def evaluation_used(model, kind: str | None = None) -> str:
    """"generated" or "generic": what ``evaluator_for(model, kind)`` runs (also a run's stats)."""
    kind = kind or evaluator_kind()
    if kind not in KINDS:
        raise InputError(f"evaluator = {kind!r}: allowed 'auto', 'generated' or 'generic'")
    if len(model.parent) > GENERATED_MAX_BODIES:
        return "generic"
    return "generic" if kind == "generic" or (kind == "auto" and not is_compiled(model)) else "generated"


@contextlib.contextmanager
def preferring_generated():
    """For a study (many runs of one structure): NSD_EVALUATOR=generated unless the user chose one,
    while the block runs. Set in the environment, so a pool's workers started inside inherit it; put
    back as it was after the block, so a program that runs a study in-process keeps its own choice."""
    before = os.environ.get(ENV)
    os.environ.setdefault(ENV, "generated")
    try:
        yield
    finally:
        if before is None:
            os.environ.pop(ENV, None)
        else:
            os.environ[ENV] = before


def prefer_generated() -> None:
    """For a benchmark script's whole process: NSD_EVALUATOR=generated unless the user chose one
    (call it in ``main()``, never at import: tests/test_import_environment.py)."""
    os.environ.setdefault(ENV, "generated")
