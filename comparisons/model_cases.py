"""The cases of a described mechanism (``nsd compare --model FILE [--cases FILE]``): how long to run,
how often to sample, each engine's settings, and an optional reference solution.

A case is a ``[[case]]`` table, in the model file itself or in a separate cases file:

    [[case]]
    name = "andrews_0.03s"
    duration = 0.03            # s
    dt_out = 1e-4              # s: output interval
    mujoco = { timestep = 1e-6 }          # any engine's settings (its builder's default_settings keys)
    exudyn = { step_size = 1e-6 }
    reference = { file = "andrews_reference.csv", source = "...", accuracy = 1e-12 }

A reference file is a CSV whose first column is ``t`` [s] and whose other columns are named outputs of
the model; its times must lie on the case's output grid (0, dt_out, ...) up to ``duration`` (later
rows are ignored). ``accuracy`` is the reference solution's own error, as a fraction of each output's
scale (default 0: exact). ``dt_out`` must divide ``duration`` (within a relative 1e-9): the output grid
is 0, dt_out, ..., duration, never a step silently changed.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from nsd_core.common.files import MAX_REFERENCE_BYTES, input_stream, printable
from nsd_core.device.params import ParameterError
from nsd_core.model.bounds import check_case_count, check_case_work
from nsd_core.model.description import Model
from nsd_core.model.errors import ModelError
from nsd_core.model.load import read_toml
from nsd_core.model.run import output_times

ALL_ENGINES = ("semirecursive", "mujoco", "exudyn", "symbolic")

MAX_OUTPUTS = 1_000_000
DIVIDES = 1e-9   # dt_out must divide the duration within this relative error (the output grid is exact)


@dataclass(frozen=True)
class Reference:
    path: str
    source: str
    accuracy: float
    index: np.ndarray                  # output-grid indices of the reference's times
    columns: dict = field(default_factory=dict)   # output name -> values at those times


@dataclass(frozen=True)
class ModelCase:
    name: str
    duration: float
    dt_out: float
    settings: dict                     # engine -> settings
    reference: Reference | None = None
    refined: tuple = ()                # engines at a step --refine chose

    def times(self) -> np.ndarray:
        return output_times(self.duration, self.dt_out)


def load_model_cases(model: Model, cases_path: str | None, engines) -> list[ModelCase]:
    """The cases of ``cases_path`` (a TOML file of [[case]] tables), or of the model file itself."""
    path = Path(cases_path or model.path)
    raw = read_toml(path, "--cases")
    if cases_path:
        extra = [k for k in raw if k != "case"]
        if extra:
            raise ModelError(f"--cases {path}: {extra[0]!r}: unknown table; a cases file holds [[case]] tables only")
    items = raw.get("case", [])
    if not isinstance(items, list) or not items:
        raise ModelError(f"{path}: no [[case]] table; give at least one (name, duration, dt_out)")
    check_case_count(f"--cases {printable(path)}" if cases_path else printable(path), items)
    cases = [_case(i, t, model, path.parent, engines) for i, t in enumerate(items)]
    names = [c.name for c in cases]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise ModelError(f"case.{sorted(dup)[0]}: the name is used twice")
    return cases


def _case(i: int, t: dict, model: Model, folder: Path, engines) -> ModelCase:
    given = t.get("name") if isinstance(t, dict) else None
    where = (f"case.{given}" if isinstance(given, str) and given and given not in (".", "..")
             and all(c.isalnum() or c in "_-." for c in given) else f"case[{i}]")
    if not isinstance(t, dict):
        raise ModelError(f"{where} = {t!r}: must be a table")
    # every engine's table is allowed (a file names settings for all three; --engines picks which run)
    allowed = {"name", "duration", "dt_out", "reference"} | set(engines) | set(ALL_ENGINES)
    for k in t:
        if k not in allowed:
            raise ModelError(f"{where}.{k}: unknown field; allowed: {', '.join(sorted(allowed))}")
    name = t.get("name")
    if not isinstance(name, str) or not name or not all(c.isalnum() or c in "_-." for c in name) or name in (".", ".."):
        raise ModelError(f"{where}.name = {name!r}: must be a name of letters, digits, '_', '-' or '.' (not '.' or "
                         "'..': it names the case's folder in --out)")
    where = f"case.{name}"
    duration, dt = _positive(f"{where}.duration", t.get("duration")), _positive(f"{where}.dt_out", t.get("dt_out"))
    if dt > duration:
        raise ModelError(f"{where}.dt_out = {dt!r}: must be <= duration ({duration!r} s)")
    if duration / dt > MAX_OUTPUTS:
        raise ModelError(f"{where}.dt_out = {dt!r}: gives more than {MAX_OUTPUTS} output samples")
    check_case_work(where, duration, dt, len(model.outputs), None)
    n = max(1, round(duration / dt))
    if abs(n * dt - duration) > DIVIDES * duration:   # the grid would silently become duration / n
        raise ModelError(f"{where}.dt_out = {dt!r}: must divide the duration ({duration:g} s) into whole intervals "
                         f"(duration / n within a relative {DIVIDES:g}); the nearest is {duration:g}/{n} = "
                         f"{duration / n:.6g} s")
    settings = {}
    for e in engines:
        s = t.get(e, {})
        if not isinstance(s, dict):
            raise ModelError(f"{where}.{e} = {s!r}: must be a table of setting = value")
        settings[e] = dict(s)
    case = ModelCase(name, duration, dt, settings)
    if "reference" in t:
        case = ModelCase(name, duration, dt, settings, _reference(where, t["reference"], model, folder, case.times()))
    return case


def _positive(where: str, v) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
        raise ModelError(f"{where} = {v!r}: must be a number > 0 [s]")
    return float(v)


def _reference(where: str, t, model: Model, folder: Path, grid: np.ndarray) -> Reference:
    if not isinstance(t, dict) or "file" not in t:
        raise ModelError(f"{where}.reference = {t!r}: must be a table with file (and source, accuracy)")
    for k in t:
        if k not in ("file", "source", "accuracy"):
            raise ModelError(f"{where}.reference.{k}: unknown field; allowed: accuracy, file, source")
    path = folder / str(t["file"])
    try:   # through the input guard: a regular file, at most MAX_REFERENCE_BYTES, read within a time bound
        stream = input_stream(path, f"{where}.reference.file", MAX_REFERENCE_BYTES, "a CSV file")
    except ParameterError as e:
        raise ModelError(str(e)) from None
    if not stream.getvalue().strip():
        raise ModelError(f"{where}.reference.file = {t['file']!r}: empty; a CSV with a header (t, then outputs) "
                         "is expected")
    try:
        with warnings.catch_warnings():   # numpy's warnings on a damaged file: the one line below says it
            warnings.simplefilter("ignore")
            data = np.genfromtxt(stream, delimiter=",", names=True)
    except (OSError, ValueError, IndexError) as e:
        raise ModelError(f"{where}.reference.file = {t['file']!r}: cannot read a CSV with a header ({e})") from None
    data = np.atleast_1d(data)
    names = data.dtype.names or ()
    if not names or names[0] != "t":
        raise ModelError(f"{where}.reference.file = {t['file']!r}: the first column must be t [s]")
    outputs = {o.name for o in model.outputs}
    for n in names[1:]:
        if n not in outputs:
            raise ModelError(f"{where}.reference.file: column {n!r} is not an output of the model; "
                             f"allowed: {', '.join(sorted(outputs))}")
    times = data["t"]
    keep = times <= grid[-1] + 1e-9 * max(1.0, grid[-1])
    index = np.rint(times[keep] / (grid[1] - grid[0])).astype(int) if len(grid) > 1 else np.zeros(0, int)
    if not keep.any() or np.any(np.abs(grid[np.clip(index, 0, len(grid) - 1)] - times[keep]) > 1e-9 * max(1.0, grid[-1])):
        raise ModelError(f"{where}.reference.file = {t['file']!r}: its times must lie on the output grid "
                         f"0, {grid[1] - grid[0]:g}, ... {grid[-1]:g} s (and at least one within the duration)")
    for n in names:
        if not np.all(np.isfinite(data[n])):
            raise ModelError(f"{where}.reference.file = {t['file']!r}: column {n!r} holds a value that is not a "
                             "finite number (every value must be one)")
    accuracy = t.get("accuracy", 0.0)
    if isinstance(accuracy, bool) or not isinstance(accuracy, (int, float)) or not 0 <= accuracy < 1:
        raise ModelError(f"{where}.reference.accuracy = {accuracy!r}: must be a number in [0, 1)")
    return Reference(str(path), str(t.get("source", "")), float(accuracy), index,
                     {n: np.asarray(data[n][keep], dtype=float) for n in names[1:]})
