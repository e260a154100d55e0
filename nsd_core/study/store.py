"""The sweep's store: finished designs on disk, resumable.

Layout under DIR (every file written atomically; ``result.json`` is written last, so its
presence marks a design as finished, ok or failed):

    designs/<key>/result.json   status ("ok" | "failed"), error, design, metrics
    designs/<key>/cycle.csv     the run's full time series (RunResult columns, units in the header)
    designs/<key>/steady.csv    the steady (last) cycle: u, F, tangent stiffness, wire elongations
    <study>/summary.json        per study: one entry per value (metrics + file names)
    <study>/<param>=<value>.csv copy of that design's steady.csv
    sweep.json                  the index: studies, designs, status, timing
"""
from __future__ import annotations

import json
import os
import time
from dataclasses import asdict
from pathlib import Path


from nsd_core import __version__
from nsd_core.common.files import read_input_bytes
from nsd_core.device.results import RunResult, write_columns, write_csv
from nsd_core.common.files import atomic_write_json
from nsd_core.study.designs import Design


class Store:
    """Finished designs under DIR/designs/<key>/ (see the module docstring)."""

    def __init__(self, root: str | Path):
        self.root = Path(root)

    def folder(self, key: str) -> Path:
        return self.root / "designs" / key

    def remove_stale_temps(self) -> int:
        """Delete the temporary files of atomic writes that a killed run left in its design folders
        (a worker ended by its parent's SIGKILL mid-write). Call it from the parent before any worker
        starts, while it holds the output folder's lock, so no live writer owns one. Returns the count."""
        n = 0
        for tmp in self.root.glob("designs/*/.*.tmp"):
            if tmp.is_file() and not tmp.is_symlink():
                tmp.unlink()
                n += 1
        return n

    def load(self, key: str) -> dict | None:
        """The stored result of job ``key``; None when there is none or it is damaged (not JSON, not an
        object, a field missing or of the wrong type: a half-copied or edited folder), so the job runs
        again and its result.json is written anew. A FIFO or device there is bad input (InputError)."""
        path = self.folder(key) / "result.json"
        if not os.path.lexists(path):
            return None
        data = read_input_bytes(path, "stored result", 1 << 32)   # a FIFO or a device: InputError
        try:
            rec = json.loads(data.decode("utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError, RecursionError):
            return None
        if not _intact(rec):
            return None
        for name in (rec.get("files") or {}).values() if rec["status"] == "ok" else ():
            f = self.folder(key) / str(name)
            if not (f.is_file() and not f.is_symlink()) or Path(name).name != name:
                return None   # a series it names is gone (or not a plain file there): run it again
        return rec

    def save(self, d: Design, out: dict) -> dict:
        """Store one finished job (a Design or any frozen dataclass with ``key``): its files, then result.json."""
        folder = self.folder(d.key)
        rec = {"key": d.key, "status": out["status"], "error": out["error"], "design": asdict(d),
               "metrics": out["metrics"], "wall_time": out["wall_time"], "version": __version__,
               "stored_at": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
        if out["status"] == "ok":
            # a sweep's design: its run and steady cycle; other jobs (a record of a seismic set) name
            # their own files, {file name: RunResult or {column: values} (units from nsd_core.device.columns)}, possibly none
            files = out["files"] if "files" in out else {"cycle.csv": out["result"], "steady.csv": out["steady"]}
            for name, data in files.items():
                (write_csv if isinstance(data, RunResult) else write_columns)(folder / name, data)
            rec["files"] = {Path(name).stem: name for name in files}
        else:
            rec["traceback"] = out.get("traceback")
        atomic_write_json(folder / "result.json", rec)  # last: marks the design finished
        return rec


def _intact(rec) -> bool:
    """A stored result as ``save`` writes it: status ok or failed, design and metrics objects, an error."""
    return (isinstance(rec, dict) and rec.get("status") in ("ok", "failed") and isinstance(rec.get("design"), dict)
            and (isinstance(rec.get("metrics"), dict) or (rec["status"] == "failed" and rec.get("metrics") is None))
            and "error" in rec
            and (rec["status"] == "failed" or isinstance(rec.get("files", {}), dict)))
