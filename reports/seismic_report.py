"""The seismic report from an ``nsd seismic`` folder: a single run (summary.json, seismic.csv and
seismic_<engine>.csv) or a set run (set.json, records/<set>_<id>[_nodevice]/), and the seismic
cases of an ``nsd compare`` folder (``seismic/<case>__<engine>.csv``). Everything is read and
checked before anything is written (ParameterError, one line)."""
from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Callable

from nsd_core.device.params import ParameterError
from nsd_core.common.files import read_regular_text
from nsd_core.device.results import read_csv

from reports import building_pages as bp
from reports import seismic_compare as sc
from reports import seismic_pages as sp
from reports.warnings_page import collect, warnings_pages

NEEDED = ("t", "x", "y", "ax_abs", "ay_abs", "device_Fx", "device_Fy")


def is_seismic(folder) -> bool:
    """An nsd seismic folder (not an nsd compare one)."""
    root = Path(folder)
    return not (root / "results.json").is_file() and ((root / "set.json").is_file()
                                                     or (root / "seismic.csv").is_file() or sc.is_compare(root))


def _runs(folder: Path, ref_name: str = "seismic.csv") -> dict:
    runs = {}
    for path in [folder / ref_name, *sorted(folder.glob("seismic_*.csv"))]:
        eng = "semirecursive" if path.name == ref_name else path.stem[len("seismic_"):]
        try:
            r = read_csv(path, eng)
        except (OSError, ValueError, IndexError) as e:
            raise ParameterError(f"{path}: not a readable seismic CSV ({' '.join(str(e).split())[:120]})") from None
        missing = [c for c in NEEDED if c not in r.columns]
        if missing:
            raise ParameterError(f"{path}: malformed (no column {missing[0]!r})")
        runs[eng] = r
    return runs


def _run_pages(label: str, runs: dict, cost: dict | None = None, ground: dict | None = None,
               nodevice=None) -> list[tuple[str, Callable]]:
    """cost: engine -> warm wall seconds per model second, shown on the response page where known;
    ground: the ground motion's description; nodevice: the supports-alone run, overlaid where it exists."""
    stem = label.replace(":", "_").replace(" ", "_")
    out = [(f"response_{stem}", lambda: sp.response_figure(f"Seismic response: {label}", runs, cost, ground, nodevice)),
           (f"loops_{stem}", lambda: sp.loops_figure(f"Device loops during the record: {label}", runs))]
    if any("E_input" in r.columns for r in runs.values()):
        out.append((f"energy_{stem}", lambda: sp.energy_figure(f"Energy balance: {label}", runs)))
    if all("floor1_x" in r.columns for r in runs.values()):  # a building (reports.building_pages)
        out.append((f"floors_{stem}", lambda: bp.floors_figure(f"The building's floors per engine: {label}", runs)))
    return out


def _summary(folder: Path) -> dict:
    """A run's summary.json ({} when there is none); one that is there but is no regular file or no JSON
    object is one line, exit 2 (a FIFO or a damaged file is not silently left out)."""
    path = folder / "summary.json"
    if not os.path.lexists(path):
        return {}
    try:
        s = json.loads(read_regular_text(path, str(path)))
    except json.JSONDecodeError as e:
        raise ParameterError(f"{path}: not readable JSON ({' '.join(str(e).split())[:100]})") from None
    except ValueError as e:   # InputError: a FIFO, a device, not text
        raise ParameterError(str(e)) from None
    if not isinstance(s, dict):
        raise ParameterError(f"{path}: malformed (expected a JSON object)")
    return s


def _cost(summary: dict) -> dict | None:
    solver = summary.get("solver") if isinstance(summary.get("solver"), dict) else {}
    if isinstance(solver.get("wall_time"), (int, float)) and solver.get("model_time"):
        return {"semirecursive": solver["wall_time"] / solver["model_time"]}
    return None


def seismic_plan(folder) -> tuple[list[tuple[str, Callable]], str]:
    """(file stem, figure function) per page and the footer's title for an nsd seismic folder."""
    root = Path(folder)
    if (root / "set.json").is_file():
        try:
            index = json.loads(read_regular_text(root / "set.json"))
            rows = index["rows"]
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise ParameterError(f"{root / 'set.json'}: malformed ({' '.join(str(e).split())[:100]})") from None
        for row in rows:   # each record's warm cost, from its own summary (compilation timed apart)
            solver = _summary(root / "records" / f"{row['set']}_{row['id']}").get("solver") or {}
            if isinstance(solver.get("wall_time"), (int, float)) and solver.get("model_time"):
                cpu = solver.get("cpu_time")
                row["cost"] = (f"{solver['wall_time'] / solver['model_time']:.3g} / "
                               + (f"{cpu / solver['model_time']:.3g}" if isinstance(cpu, (int, float)) else "n/a"))
        entries = index.get("entries") if isinstance(index.get("entries"), list) else []
        plan = [("set_table", lambda: sp.set_table_figure(index))]
        plan += warnings_pages(f"record set {index.get('set')}", collect(
            (f"record {e.get('set')}:{e.get('id')}: ", e) for e in entries if isinstance(e, dict)), "set.json")
        for row in rows:
            folder = root / "records" / f"{row['set']}_{row['id']}"
            if row.get("status") == "ok" and (folder / "seismic.csv").is_file():
                runs = _runs(folder)
                summ = _summary(folder)
                alone = folder.parent / (folder.name + "_nodevice") / "seismic.csv"
                nodevice = _runs(alone.parent)["semirecursive"] if alone.is_file() else None
                plan += _run_pages(f"{row['set']}:{row['id']}", runs, _cost(summ), summ.get("ground"), nodevice)
        return plan, f"NSD seismic report  |  record set {index.get('set')}"
    if bp.is_building_compare(root):  # nsd seismic --compare-building (reports.building_pages)
        plan, footer = bp.compare_plan(root, _runs)
        return warnings_pages("the building fixed-base and isolated", collect(
            (f"{c}: ", _summary(root / c)) for c in bp.CONFIGS), "each configuration's summary.json") + plan, footer
    if sc.is_compare(root):  # nsd seismic --compare-supports (reports.seismic_compare)
        plan, footer = sc.compare_plan(root, _runs)
        return warnings_pages("with and without the device", collect(
            (f"{sc.RUNS[c][0]}: ", _summary(root / c)) for c in sc.RUNS), "device/ and supports/summary.json") + plan, \
            footer
    runs = _runs(root)
    summary = _summary(root)
    ground = summary.get("ground") if isinstance(summary.get("ground"), dict) else {}
    label = f"{ground['set']}:{ground['record']}" if "record" in ground else str(ground.get("kind", "run"))
    if summary.get("device") is False:
        label += " (supports alone)"
    pages = _run_pages(label, runs, _cost(summary), ground)
    if isinstance(summary.get("stopped"), dict):  # exit 4: the series up to the event, the event marked
        pages = [(stem, sc.with_stop_mark(draw, summary["stopped"])) for stem, draw in pages]
    return warnings_pages(label, collect([("", summary)])) + pages, f"NSD seismic report  |  {label}"


def compare_seismic_pages(root) -> list[tuple[str, Callable]]:
    """Pages for the seismic cases of an nsd compare folder (<root>/seismic/<case>__<engine>.csv)."""
    folder = Path(root) / "seismic"
    cases: dict[str, dict] = {}
    for path in sorted(folder.glob("*__*.csv")):
        case, _, eng = path.stem.partition("__")
        try:
            r = read_csv(path, eng)
        except (OSError, ValueError, IndexError):
            continue  # an optional extra: a file that cannot be read is left out, the validation stays
        if all(c in r.columns for c in NEEDED):
            cases.setdefault(case, {})[eng] = r
    try:
        results = json.loads(read_regular_text(Path(root) / "results.json"))
        recorded = results.get("runs", {})
        grounds = {c["name"]: c.get("ground") for c in results.get("seismic_cases", []) if isinstance(c, dict)}
    except (OSError, ValueError, AttributeError, KeyError, TypeError):
        recorded, grounds = {}, {}
    plan = []
    for case, runs in cases.items():
        runs = dict(sorted(runs.items(), key=lambda kv: kv[0] != "semirecursive"))
        entries = recorded.get(case, {}) if isinstance(recorded, dict) else {}
        cost = {e: v["wall_time_per_model_second"] for e, v in entries.items()
                if isinstance(v, dict) and isinstance(v.get("wall_time_per_model_second"), (int, float))}
        plan += _run_pages(f"seismic case {case}", runs, cost or None, grounds.get(case))
    return plan
