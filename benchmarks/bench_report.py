"""The validation report's drawing time under two matplotlib versions, side by side on one machine.

    python benchmarks/bench_report.py --matplotlib 3.11.2,3.10.9 --repeats 3 --out DIR [--from FOLDER]

The folder reported on is the default gate's (``nsd compare --convergence``, run once here unless
``--from`` names one). For each matplotlib version: a new venv with this checkout installed from
constraints.txt, that version of matplotlib in place of the pinned one. Then ``nsd report`` on the same
folder, the versions alternating run by run so that both meet the same load; wall and CPU seconds of
the command (its forked second process included), the report's own line (the drawing, start-up
excluded) and the load average before each run. Writes DIR/bench_report.json.
"""
from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from nsd_core.common.files import atomic_write_json  # noqa: E402
from nsd_core.device.results import versions  # noqa: E402

OWN_LINE = re.compile(r"\((\d+) pages, ([\d.]+) s\)")


def venv_with(matplotlib: str, where: Path) -> Path:
    """A venv at ``where`` with this checkout installed from constraints.txt, matplotlib at ``matplotlib``."""
    pins = [("matplotlib==" + matplotlib) if line.split("#")[0].strip().startswith("matplotlib==") else line
            for line in (ROOT / "constraints.txt").read_text().splitlines()]
    constraints = where.with_suffix(".constraints.txt")
    constraints.write_text("\n".join(pins) + "\n")
    subprocess.run([sys.executable, "-m", "venv", str(where)], check=True)
    subprocess.run([str(where / "bin" / "pip"), "install", "-q", "-c", str(constraints), "-e", str(ROOT)],
                   check=True, capture_output=True)
    return where / "bin" / "python"


def timed_report(python: Path, folder: Path, out: Path) -> dict:
    """Wall and CPU seconds (the command and its children) of one ``nsd report``, and its own line."""
    shutil.rmtree(out, ignore_errors=True)
    load = os.getloadavg()[0]
    before, start = os.times(), time.perf_counter()
    p = subprocess.run([str(python), "-m", "nsd_cli.main", "report", "--from", str(folder), "--out", str(out)],
                       capture_output=True, text=True, env={**os.environ, "MPLBACKEND": "Agg"})
    wall, after = time.perf_counter() - start, os.times()
    m = OWN_LINE.search(p.stdout)
    return {"exit_code": p.returncode, "wall_s": wall, "load_before": load,
            "cpu_s": (after.children_user - before.children_user) + (after.children_system - before.children_system),
            "pages": int(m.group(1)) if m else None, "report_s": float(m.group(2)) if m else None,
            "tail": (p.stdout + p.stderr)[-400:] if p.returncode else ""}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--matplotlib", required=True, help="V1,V2,...: matplotlib versions to draw with")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--from", dest="source", help="a results folder (default: a fresh nsd compare --convergence)")
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    wanted = a.matplotlib.split(",")
    bad = None
    if a.repeats < 1:
        bad = f"--repeats {a.repeats}: must be a whole number >= 1"
    elif not all(re.fullmatch(r"\d+(\.\d+)*", v) for v in wanted):
        bad = f"--matplotlib {a.matplotlib!r}: expected versions such as 3.11.2,3.10.9"
    elif a.source is not None and not Path(a.source).is_dir():
        bad = f"--from {a.source!r}: not a folder"
    if bad:
        print(f"bench_report: {bad}", file=sys.stderr)
        return 2
    work = Path(tempfile.mkdtemp(prefix="bench-report-"))
    try:
        folder = Path(a.source) if a.source else work / "gate"
        if not a.source:
            subprocess.run([sys.executable, "-m", "nsd_cli.main", "compare", "--convergence", "--out", str(folder)],
                           capture_output=True, check=False)
        try:
            pythons = {v: venv_with(v, work / f"venv-{v}") for v in wanted}
        except subprocess.CalledProcessError as e:
            print(f"bench_report: --matplotlib {a.matplotlib!r}: a venv could not be made "
                  f"({' '.join(map(str, e.cmd))[-120:]} exited {e.returncode}); nothing written", file=sys.stderr)
            return 2
        found = {v: subprocess.run([str(py), "-c", "import matplotlib; print(matplotlib.__version__)"],
                                   capture_output=True, text=True).stdout.strip() for v, py in pythons.items()}
        rows = []
        for k in range(a.repeats):
            for v, py in pythons.items():
                r = timed_report(py, folder, work / f"report-{v}")
                rows.append({"matplotlib": found[v], "repeat": k, **r})
                print(f"matplotlib {found[v]}: {r['wall_s']:.1f} s wall, {r['cpu_s']:.1f} s CPU "
                      f"(its own line {r['report_s']} s)", flush=True)
        out = Path(a.out)
        out.mkdir(parents=True, exist_ok=True)
        atomic_write_json(out / "bench_report.json", {"rows": rows, "cpus": os.cpu_count(), "versions": versions(),
                                                      "folder": "given" if a.source else "nsd compare --convergence"})
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0 if all(r["exit_code"] == 0 for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
