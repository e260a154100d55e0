"""The time series every engine returns: the same columns, units and signs (written atomically through nsd_core.common.files).

Sign convention (docs/model.md, "Drive and outputs"): F is the horizontal force the drive applies to
the cap along psi, F = m_c u'' - (rod + ropes + wires on the cap) . e_psi. Each part column is the
part's contribution to F, i.e. minus its force on the cap along psi, so that
F_device = F_rod + F_ropes + F_wires and F = m_c u'' + F_device.
For any path in the plane (nsd-model.md, "Two-dimensional drive paths"): x, y are the plate's
position, F_x, F_y the drive's force vector on the cap, F_tangent and F_radial its projections on
the path's unit tangent and on the unit vector from the centre (nsd_core.outputs.path_directions);
F and its parts stay the projections on e_psi.
"""
from __future__ import annotations

import importlib.metadata as md
import platform
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from nsd_core.device.decimal_text import table_text
from nsd_core.common.files import atomic_write_bytes
from nsd_core.device.columns import units_of

BASE_COLUMNS = ("t", "u", "F", "F_device", "F_rod", "F_ropes", "F_wires", "spring_push", "spring_zeta", "cap_z",
                "wall_z", "closure", "x", "y", "F_x", "F_y", "F_tangent", "F_radial")


def column_units(n_ropes: int, n_wires: int) -> dict[str, str]:
    """Ordered column names with units (nsd_core.device.columns) for a device with n_ropes ropes and
    n_wires wires."""
    names = list(BASE_COLUMNS)
    for i in range(n_ropes):
        names += [f"rope{i}_tension", f"rope{i}_F"]
    for j in range(n_wires):
        names += [f"wire{j}_tension", f"wire{j}_F", f"wire{j}_strain", f"wire{j}_stress"]
    return units_of(names)


@dataclass
class RunResult:
    """One engine's run of one drive: columns (name -> array) and what it took. ``frequency`` [Hz] is
    the drive's (set by every engine's drive run; None for a seismic run or a result read from CSV)."""
    engine: str
    columns: dict[str, np.ndarray]
    units: dict[str, str]
    stats: dict[str, Any] = field(default_factory=dict)
    frequency: float | None = None

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def steady(self, frequency: float | None = None) -> "RunResult":
        """The steady (last) cycle as a result of its own: every column on t >= t_end - 1/f, both end
        points included so that the loop closes (the cycle ``nsd compare`` and the summary use).
        ``frequency`` [Hz] is needed only for a result that does not carry its drive's."""
        f = self.frequency if frequency is None else frequency
        if f is None:
            raise ValueError("steady(): this result has no drive frequency (a seismic run, or read from CSV); "
                             "pass frequency=f [Hz]")
        mask = last_cycle(self["t"], f)
        return RunResult(self.engine, {n: c[mask] for n, c in self.columns.items()}, dict(self.units),
                         dict(self.stats), f)

    def stack(self, prefix: str) -> np.ndarray:
        """All per-element columns of one kind, e.g. stack('rope') -> (n_t, n_ropes) tensions."""
        names = [n for n in self.columns if n.startswith(prefix) and n.endswith("_tension")]
        return np.column_stack([self.columns[n] for n in names]) if names else np.zeros((len(self["t"]), 0))


def first_nonfinite(data, where: str = "") -> str | None:
    """Where the first NaN or inf in ``data`` (dicts, lists, numbers, arrays, RunResults) lies, as
    'field[index] = value (N non-finite values)'; None when every number is finite. Any non-finite
    output is a solver failure (exit 3), never a result."""
    if isinstance(data, RunResult):
        data = data.columns
    if isinstance(data, dict):
        items = data.items()
    elif isinstance(data, (list, tuple)):
        items = ((f"[{i}]", v) for i, v in enumerate(data))
    elif isinstance(data, np.ndarray) and data.dtype.kind in "fc":
        bad = ~np.isfinite(data)
        if not bad.any():
            return None
        k = int(np.flatnonzero(bad.ravel())[0])
        return f"{where}[{k}] = {data.ravel()[k]} ({int(bad.sum())} non-finite values)"
    elif isinstance(data, (float, np.floating)):
        return None if np.isfinite(data) else f"{where} = {data}"
    else:
        return None
    for k, v in items:
        name = k if str(k).startswith("[") else (f"{where}.{k}" if where else str(k))
        found = first_nonfinite(v, f"{where}{k}" if str(k).startswith("[") else name)
        if found:
            return found
    return None


def last_cycle(t: np.ndarray, frequency: float) -> np.ndarray:
    """Boolean mask of the last full cycle of period 1/frequency (both end points included)."""
    return t >= t[-1] - 1.0 / frequency - 1e-9 / frequency


def write_columns(path: str | Path, columns: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Numeric columns {name: values} as CSV with "name [unit]" headers, every unit from the one table
    (nsd_core.device.columns; a column it does not know is a KeyError), atomically; each value written
    as ``"%.10g" % v`` (nsd_core.device.decimal_text, compiled). Returns the columns as the file reads
    back (``read_csv``'s numbers, bit for bit), so a caller need not read it again."""
    header = ",".join(f"{n} [{u}]" for n, u in units_of(columns).items())
    data = np.column_stack(list(columns.values()))
    body, read = table_text(data)
    atomic_write_bytes(path, header.encode() + b"\n" + body)
    return {n: read[:, i] for i, n in enumerate(columns)}


def write_csv(path: str | Path, result: RunResult) -> RunResult:
    """A run's time series, every column with its unit; returns it as ``read_csv`` reads it back
    (the engine and units of ``result``, no stats)."""
    return RunResult(result.engine, write_columns(path, {n: result.columns[n] for n in result.units}),
                     dict(result.units))


def read_csv(path: str | Path, engine: str = "") -> RunResult:
    import io

    from nsd_core.common.files import read_regular_text
    text = read_regular_text(path, "CSV")  # a FIFO or a device in a results folder: one line, never a hang
    header = text.split("\n", 1)[0].strip().split(",")
    names, units = [], {}
    for h in header:
        name, _, unit = h.partition(" [")
        names.append(name)
        units[name] = unit.rstrip("]")
    import warnings
    with warnings.catch_warnings():   # an empty table is said below, in one line, not warned about
        warnings.simplefilter("ignore")
        data = np.loadtxt(io.StringIO(text), delimiter=",", skiprows=1, ndmin=2)
    if data.shape[0] == 0 or data.shape[1] != len(names):
        raise ValueError(f"{len(names)} columns named, {data.shape[1]} read in {data.shape[0]} rows")
    return RunResult(engine, {n: data[:, i] for i, n in enumerate(names)}, units)


def versions() -> dict[str, str]:
    """Python and package versions, recorded with every result."""
    out = {"python": platform.python_version()}
    for pkg in ("nsd-harness", "numpy", "scipy", "numba", "mujoco", "exudyn", "matplotlib"):
        try:
            out[pkg] = md.version(pkg)
        except md.PackageNotFoundError:
            pass
    return out
