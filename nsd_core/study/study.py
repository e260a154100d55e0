"""Parametric sweeps: the paper's Section 4.3 (Figures 8-20; Tables 5 and 6 give X_max).

A *design* is one full parameter set with one drive, one engine and its solver settings. Its key
is a SHA-256 of exactly those (canonical JSON), so the nominal device, which every one of the
seven studies contains, runs once, and a resumed sweep recognises finished work.

Store layout under DIR (every file written atomically; ``result.json`` is written last, so its
presence marks a design as finished, ok or failed):

    designs/<key>/result.json   status ("ok" | "failed"), error, design, metrics
    designs/<key>/cycle.csv     the run's full time series (RunResult columns, units in the header)
    designs/<key>/steady.csv    the steady (last) cycle: u, F, tangent stiffness, wire elongations
    <study>/summary.json        per study: one entry per value (metrics + file names)
    <study>/<param>=<value>.csv copy of that design's steady.csv
    sweep.json                  the index: studies, designs, status, timing

Designs run on local cores (ProcessPoolExecutor) or on a Dask cluster (``scheduler``); the parent
stores each result as it arrives, so an interrupted sweep loses at most the designs in flight.
A design whose run raises is stored as failed with its message; an executor breaking down is not
stored (that is not the design's fault) and is retried on the next run.
"""
from __future__ import annotations

import hashlib
import json
import math
import shutil
import sys
import time
import traceback
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field
from multiprocessing import get_context
from pathlib import Path
from typing import Callable, Iterator

import numpy as np

from nsd_core import __version__
from nsd_core.device.params import ParameterError, Params, with_overrides
from nsd_core.device.results import RunResult, atomic_write_json, atomic_write_text, write_csv

# Section 4.3 (paper-data.toml [parametric]): f = 10 Hz, A = 0.024 m, drive along +X.
PAPER_FREQUENCY, PAPER_AMPLITUDE = 10.0, 0.024
PAPER_STUDIES = {
    "rod_length": ([0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09, 0.10], "Figure 8, Table 5"),
    "n_ropes": ([3, 4, 5, 6, 7, 8, 9], "Figure 9"),
    "rope_stiffness": ([3.0e5, 5.0e5, 7.0e5, 9.0e5], "Figure 10"),
    "precompression_force": ([2400.0, 2600.0, 2800.0, 3000.0, 3200.0, 3400.0, 3600.0, 3800.0],
                             "Figure 11, Table 6"),
    "wire_diameter": ([0.0012, 0.0016, 0.0020, 0.0024], "Figures 12-13"),
    "n_wires": ([3, 4, 5, 6, 7, 8, 9, 10], "Figures 14-16"),
    "wire_inclination_deg": ([0.0, 3.2, 6.4, 9.6, 12.8, 16.0, 19.2, 22.4], "Figures 17-20"),
}
WORKING_RANGE_FRACTION = 0.95  # A = min(0.024, 0.95 X_max): stay inside each design's range (Figure 8)
ENGINE_MODULES = {"mujoco": "comparisons.engines.mujoco_engine", "exudyn": "comparisons.engines.exudyn_engine"}
ENGINES = ("semirecursive", *ENGINE_MODULES)


@dataclass(frozen=True)
class Design:
    study: str                 # the swept parameter (the study's name)
    value: float               # its value in this design
    params: dict               # the full parameter set (Params.to_dict())
    amplitude: float
    amplitude_rule: str
    frequency: float
    direction_deg: float = 0.0
    cycles: int = 2
    samples_per_cycle: int = 500
    engine: str = "semirecursive"
    settings: dict = field(default_factory=dict)

    @property
    def key(self) -> str:
        """Hash of what determines the run (not the study it is listed under)."""
        ident = {"params": self.params, "amplitude": self.amplitude, "frequency": self.frequency,
                 "direction_deg": self.direction_deg, "cycles": self.cycles,
                 "samples_per_cycle": self.samples_per_cycle, "engine": self.engine, "settings": self.settings}
        return hashlib.sha256(json.dumps(ident, sort_keys=True).encode()).hexdigest()[:20]

    @property
    def label(self) -> str:
        return f"{self.study}={self.value:g}" + ("" if self.engine == "semirecursive" else f"@{self.engine}")


def _engine(name: str):
    """An engine instance, imported lazily: the comparisons registry if present, else ``Engine``."""
    import importlib
    try:
        from comparisons.engines import get_engine
    except ImportError:
        return importlib.import_module(ENGINE_MODULES[name]).Engine()
    return get_engine(name)


def check_engines(names: list[str]) -> None:
    """Unknown or unavailable engines are bad input (exit 2), found before anything runs."""
    for n in names:
        if n not in ENGINES:
            raise ParameterError(f"--engines {n}: unknown engine; allowed: {', '.join(ENGINES)}")
        if n in ENGINE_MODULES:
            try:
                _engine(n)
            except Exception as e:  # noqa: BLE001 - any import failure means not usable here
                raise ParameterError(f"--engines {n}: not available ({type(e).__name__}: {e})".splitlines()[0]) from None


def make_designs(param: str, values: list[float], base: Params | None = None, amplitude: float | None = None,
                 frequency: float = PAPER_FREQUENCY, engines: tuple[str, ...] = ("semirecursive",),
                 settings: dict | None = None, cycles: int = 2, samples_per_cycle: int = 500,
                 direction_deg: float = 0.0) -> list[Design]:
    """One design per value (and engine). amplitude None: min(0.024, 0.95 X_max) per design."""
    from nsd_core.device.model import DEFAULT_SOLVER
    from nsd_core.study.tables import SlackPointError, x_max_at_slack
    base = base or Params()
    if not values:
        raise ParameterError(f"--values for {param}: give at least one value")
    out = []
    for v in values:
        p = with_overrides(base, {param: v})
        if amplitude is None:
            try:
                xm = x_max_at_slack(p, direction_deg)
            except SlackPointError:
                xm = math.inf
            a = min(PAPER_AMPLITUDE, WORKING_RANGE_FRACTION * xm)
            rule = "0.024 m" if a == PAPER_AMPLITUDE else f"0.95 * X_max = 0.95 * {xm:.6f} m (0.024 m exceeds X_max)"
        else:
            a, rule = amplitude, "fixed (--amplitude)"
        for eng in engines:
            s = dict(DEFAULT_SOLVER, **(settings or {})) if eng == "semirecursive" else {}
            out.append(Design(param, float(v), p.to_dict(), float(a), rule, float(frequency), direction_deg,
                              cycles, samples_per_cycle, eng, s))
    return out


def paper_designs(**kw) -> list[Design]:
    """All seven studies of Section 4.3 at f = 10 Hz (A per the working-range rule)."""
    return [d for name, (vals, _) in PAPER_STUDIES.items() for d in make_designs(name, vals, **kw)]


# ---------------------------------------------------------------- one design (runs in a worker)
def steady_table(result: RunResult, d: Design, wire_length: float) -> dict[str, tuple[str, np.ndarray]]:
    """The last cycle: u, F, tangent stiffness dF/du (Figures 8-17 B), wire elongations (15, 18)."""
    from nsd_core.device.cycle import steady_cycle
    m = steady_cycle(result, d.frequency)
    t = result["t"][m]
    w = 2 * math.pi * d.frequency
    udot = d.amplitude * w * np.cos(w * t)
    # dF/du = (dF/dt)/(du/dt): undefined at the turning points, where du/dt vanishes
    k = np.gradient(result["F"][m], t) / np.where(np.abs(udot) > 0.05 * d.amplitude * w, udot, np.nan)
    cols = {"t": ("s", t), "u": ("m", result["u"][m]), "F": ("N", result["F"][m]),
            "F_device": ("N", result["F_device"][m]), "stiffness": ("N/m", k),
            "F_rod": ("N", result["F_rod"][m]), "F_ropes": ("N", result["F_ropes"][m]),
            "F_wires": ("N", result["F_wires"][m]), "spring_push": ("N", result["spring_push"][m])}
    for j in range(int(d.params["n_wires"])):
        cols[f"wire{j}_elongation"] = ("m", result[f"wire{j}_strain"][m] * wire_length)
    return cols


def run_design(d: Design) -> dict:
    """Run one design and analyse it; never raises for the design's own failure (status failed)."""
    start = time.perf_counter()
    try:
        from nsd_core.device.cycle import analyse
        from nsd_core.device.drive import Drive
        from nsd_core.device.geometry import device_geometry
        from nsd_core.study.tables import SlackPointError, x_max_at_slack
        p = Params(**d.params)
        drive = Drive(d.amplitude, d.frequency, d.direction_deg, d.cycles, d.samples_per_cycle)
        if d.engine == "semirecursive":
            from nsd_core.device.model import simulate
            result = simulate(p, drive, **d.settings)
        else:
            result = _engine(d.engine).run(p, drive, d.settings or None)
        summary = analyse(result, d.amplitude, d.frequency)
        try:
            xq = x_max_at_slack(p, d.direction_deg)
            theta = math.degrees(math.asin(xq / p.rod_length))
        except SlackPointError:
            xq = theta = None
        steady = steady_table(result, d, device_geometry(p).wire.natural_length)
        elong = [steady[n][1] for n in steady if n.endswith("_elongation")]
        metrics = {**summary, "dissipated_energy": summary["loop_area"], "x_max_quasi_static": xq,
                   "theta_max_deg": theta,
                   "wire_elongation_max": [float(np.max(e)) for e in elong],
                   "wire_elongation_min": [float(np.min(e)) for e in elong],
                   "solver": {k: v for k, v in result.stats.items() if isinstance(v, (int, float, str))}}
        return {"status": "ok", "error": None, "metrics": metrics, "result": result, "steady": steady,
                "wall_time": time.perf_counter() - start}
    except Exception as e:  # noqa: BLE001 - the design failed; record it and let the sweep go on
        msg = f"{type(e).__name__}: {e}".splitlines()[0]
        return {"status": "failed", "error": msg, "traceback": traceback.format_exc(limit=6),
                "metrics": None, "wall_time": time.perf_counter() - start}


# ---------------------------------------------------------------- store
class Store:
    """Finished designs under DIR/designs/<key>/ (see the module docstring)."""

    def __init__(self, root: str | Path):
        self.root = Path(root)

    def folder(self, key: str) -> Path:
        return self.root / "designs" / key

    def load(self, key: str) -> dict | None:
        try:
            return json.loads((self.folder(key) / "result.json").read_text())
        except FileNotFoundError:
            return None

    def save(self, d: Design, out: dict) -> dict:
        folder = self.folder(d.key)
        rec = {"key": d.key, "status": out["status"], "error": out["error"], "design": asdict(d),
               "metrics": out["metrics"], "wall_time": out["wall_time"], "version": __version__,
               "stored_at": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
        if out["status"] == "ok":
            write_csv(folder / "cycle.csv", out["result"])
            _write_table(folder / "steady.csv", out["steady"])
            rec["files"] = {"cycle": "cycle.csv", "steady": "steady.csv"}
        else:
            rec["traceback"] = out.get("traceback")
        atomic_write_json(folder / "result.json", rec)  # last: marks the design finished
        return rec


def _write_table(path: Path, cols: dict[str, tuple[str, np.ndarray]]) -> None:
    header = ",".join(f"{n} [{u}]" for n, (u, _) in cols.items())
    data = np.column_stack([v for _, v in cols.values()])
    atomic_write_text(path, "\n".join([header] + [",".join(f"{x:.10g}" for x in row) for row in data]) + "\n")


# ---------------------------------------------------------------- executors
def _serial(designs: list[Design]) -> Iterator[tuple[Design, dict]]:
    for d in designs:
        yield d, run_design(d)


def _local(designs: list[Design], workers: int) -> Iterator[tuple[Design, dict]]:
    # spawn, not fork: the parent may hold threads (a Dask client, numba) that fork would copy badly
    with ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn")) as ex:
        futures = {ex.submit(run_design, d): d for d in designs}
        try:
            for f in as_completed(futures):
                yield futures[f], f.result()
        finally:
            for f in futures:
                f.cancel()


def _dask(designs: list[Design], address) -> Iterator[tuple[Design, dict]]:
    try:
        from distributed import Client, as_completed as dask_completed
    except ImportError:
        raise ParameterError("--scheduler: needs dask.distributed (pip install 'nsd-harness[dask]')") from None
    client = address if hasattr(address, "submit") else Client(address, timeout="20s")
    try:
        futures = {client.submit(run_design, d, key=f"nsd-design-{d.key}", pure=False): d for d in designs}
        for f in dask_completed(list(futures)):
            yield futures[f], f.result()
    finally:
        if client is not address:
            client.close()


# ---------------------------------------------------------------- the sweep
def run_sweep(designs: list[Design], out: str | Path, workers: int = 1, scheduler=None,
              retry_failed: bool = False, log: Callable[[str], None] | None = None) -> dict:
    """Run every design not yet stored, store each as it finishes, then write the summaries."""
    log = log or (lambda s: print(s, file=sys.stderr, flush=True))
    store = Store(out)
    unique: dict[str, Design] = {}
    for d in designs:
        unique.setdefault(d.key, d)
    pending = []
    for k, d in unique.items():
        rec = store.load(k)
        if rec is None or (retry_failed and rec["status"] == "failed"):
            pending.append(d)
    log(f"sweep: {len(designs)} designs ({len(unique)} distinct), {len(unique) - len(pending)} already "
        f"stored, {len(pending)} to run on "
        + (f"Dask at {scheduler}" if scheduler is not None else f"{workers} local worker(s)"))
    start = time.perf_counter()
    if not pending:
        runner = iter(())
    elif scheduler is not None:
        runner = _dask(pending, scheduler)
    elif workers > 1 and len(pending) > 1:
        runner = _local(pending, min(workers, len(pending)))
    else:
        runner = _serial(pending)
    for n, (d, res) in enumerate(runner, 1):
        rec = store.save(d, res)
        tail = f"{res['wall_time']:.1f} s" if rec["status"] == "ok" else f"FAILED: {rec['error']}"
        log(f"  [{n}/{len(pending)}] {d.label} ({d.key}): {tail}")
    elapsed = time.perf_counter() - start
    return write_summaries(designs, store, elapsed)


def write_summaries(designs: list[Design], store: Store, elapsed: float) -> dict:
    """Per study: DIR/<study>/summary.json and the steady-cycle CSVs; DIR/sweep.json as index."""
    studies: dict[str, list] = {}
    for d in designs:
        rec = store.load(d.key)
        entry = {"value": d.value, "key": d.key, "engine": d.engine, "status": rec["status"] if rec else "missing",
                 "error": rec["error"] if rec else None, "amplitude": d.amplitude,
                 "amplitude_rule": d.amplitude_rule, "frequency": d.frequency}
        if rec and rec["status"] == "ok":
            m = rec["metrics"]
            for k in ("x_max_quasi_static", "theta_max_deg", "dissipated_energy", "peak_force",
                      "force_at_plus_A", "initial_stiffness", "stiffness_regions", "x_max",
                      "outside_working_range", "events", "wire_elongation_max", "wire_elongation_min"):
                entry[k] = m.get(k)
            entry["run_wall_time"] = rec["wall_time"]
            name = f"{d.study}={d.value:g}" + ("" if d.engine == "semirecursive" else f"@{d.engine}") + ".csv"
            dest = store.root / d.study / name
            dest.parent.mkdir(parents=True, exist_ok=True)
            tmp = dest.with_name(f".{dest.name}.tmp")
            shutil.copyfile(store.folder(d.key) / "steady.csv", tmp)
            tmp.replace(dest)
            entry["steady_csv"] = f"{d.study}/{name}"
            entry["cycle_csv"] = f"designs/{d.key}/cycle.csv"
        studies.setdefault(d.study, []).append(entry)
    for name, entries in studies.items():
        figs = PAPER_STUDIES.get(name, (None, None))[1]
        atomic_write_json(store.root / name / "summary.json", {
            "study": name, "parameter": name, "paper": figs, "frequency": entries[0]["frequency"],
            "values": [e["value"] for e in entries], "designs": entries,
            "notes": "dissipated_energy = loop area of the steady cycle [J]; theta_max = asin(X_max/l_d) "
                     "from the quasi-static X_max; stiffness in the steady CSV is dF/du [N/m], blank at turning points"})
    index = {"studies": {n: f"{n}/summary.json" for n in studies},
             "designs": len({d.key for d in designs}),
             "ok": sum(e["status"] == "ok" for es in studies.values() for e in es),
             "failed": sorted({e["key"] for es in studies.values() for e in es if e["status"] == "failed"}),
             "missing": sorted({e["key"] for es in studies.values() for e in es if e["status"] == "missing"}),
             "elapsed_this_run_s": elapsed, "version": __version__}
    atomic_write_json(store.root / "sweep.json", index)
    return index


# ---------------------------------------------------------------- quasi-static cycles (cheap checks)
def quasi_static_cycle(params: Params, amplitude: float, points_per_cycle: int = 80, cycles: int = 2,
                       substeps: int = 6) -> dict[str, np.ndarray]:
    """The last of ``cycles`` quasi-static cycles, u = A sin(2 pi s) (the hysteresis is carried).

    Returns the quasi-static path's arrays plus 's' (cycle phase, 0..1) and 'stiffness' on the
    loading quarter (u from 0 to A), used by the qualitative checks of Figures 7-20.
    """
    from nsd_core.device.quasistatic import quasi_static_path
    s = np.linspace(0.0, cycles, cycles * points_per_cycle + 1)
    out = quasi_static_path(params, amplitude * np.sin(2 * np.pi * s), substeps=substeps)
    m = s >= cycles - 1 - 1e-12
    cyc = {k: v[m] for k, v in out.items()}
    cyc["s"] = s[m] - (cycles - 1)
    q = cyc["s"] <= 0.25 + 1e-12
    cyc["loading_u"], cyc["loading_stiffness"] = cyc["u"][q], np.gradient(cyc["F_device"][q], cyc["u"][q])
    return cyc
