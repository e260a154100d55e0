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
import time
from dataclasses import asdict
from pathlib import Path


from nsd_core import __version__
from nsd_core.device.results import atomic_write_json, write_columns, write_csv
from nsd_core.study.designs import Design


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
            write_columns(folder / "steady.csv", out["steady"])
            rec["files"] = {"cycle": "cycle.csv", "steady": "steady.csv"}
        else:
            rec["traceback"] = out.get("traceback")
        atomic_write_json(folder / "result.json", rec)  # last: marks the design finished
        return rec
