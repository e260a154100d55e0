"""Writing the gate's CSVs: Python's own "%.10g" per value and numpy.loadtxt to read the numbers back
(the harness before 2026-11-30) against nsd_core.device.results.write_columns, which formats in
compiled code and returns the numbers the file reads back (nsd_core.device.decimal_text).

    python benchmarks/bench_csv_text.py --repeats 3 --out DIR

Runs ``nsd compare`` once into DIR/gate (the default cases: every run's table, the references and
companions included), reads its CSVs, then writes each table both ways, alternating, ``--repeats``
times: CPU seconds (this process) of the whole set each way, the median; and whether the two files are
the same bytes and the numbers read back the same bits, table by table.
"""
from __future__ import annotations

import argparse
import io
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from nsd_core.device.decimal_text import TEXT_UNIT  # noqa: E402
from nsd_core.common.files import atomic_write_json, atomic_write_text  # noqa: E402
from nsd_core.device.columns import units_of  # noqa: E402
from nsd_core.device.results import read_csv, write_columns  # noqa: E402
from nsd_core.engine.compile_once import compile_once  # noqa: E402


def python_way(path: Path, columns: dict) -> np.ndarray:
    """The former write: a "%.10g" row format per row, the text written atomically, then read back."""
    header = ",".join(f"{n} [{u}]" for n, u in units_of(columns).items())
    data = np.column_stack(list(columns.values()))
    row_format = ",".join(["%.10g"] * data.shape[1])
    lines = [header] + [row_format % tuple(row) for row in data.astype(float).tolist()]
    atomic_write_text(path, "\n".join(lines) + "\n")
    return np.loadtxt(io.StringIO(path.read_text()), delimiter=",", skiprows=1, ndmin=2)


def compiled_way(path: Path, columns: dict) -> np.ndarray:
    written = write_columns(path, columns)
    return np.column_stack(list(written.values()))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    out = Path(a.out)
    gate = out / "gate"
    subprocess.run([sys.executable, "-m", "nsd_cli.main", "compare", "--out", str(gate)], check=True,
                   stdout=subprocess.DEVNULL)
    tables = [read_csv(p).columns for p in sorted(gate.rglob("*.csv"))]
    compile_once(TEXT_UNIT)   # loaded (or compiled) before the timing: a gate's workers' start-up does it
    scratch = out / "scratch"
    scratch.mkdir(parents=True, exist_ok=True)
    cpu = {"python": [], "compiled": []}
    same_text, same_bits = True, True
    for _ in range(a.repeats):
        for way, fn in (("python", python_way), ("compiled", compiled_way)):
            t0 = time.process_time()
            for i, cols in enumerate(tables):
                fn(scratch / f"{way}{i}.csv", cols)
            cpu[way].append(time.process_time() - t0)
        for i, cols in enumerate(tables):
            same_text &= (scratch / f"python{i}.csv").read_bytes() == (scratch / f"compiled{i}.csv").read_bytes()
            same_bits &= python_way(scratch / "p.csv", cols).tobytes() == compiled_way(scratch / "c.csv", cols).tobytes()
    numbers = sum(len(c) * len(next(iter(c.values()))) for c in tables)
    med = {k: statistics.median(v) for k, v in cpu.items()}
    atomic_write_json(out / "bench_csv_text.json", {
        "tables": len(tables), "rows": sum(len(next(iter(c.values()))) for c in tables), "numbers": numbers,
        "bytes": sum(p.stat().st_size for p in gate.rglob("*.csv")), "repeats": a.repeats,
        "cpu_s": cpu, "median_cpu_s": med, "ratio": med["python"] / med["compiled"],
        "ns_per_number": {k: 1e9 * v / numbers for k, v in med.items()},
        "same_text": bool(same_text), "same_numbers": bool(same_bits)})
    print(json.dumps(med), same_text, same_bits)


if __name__ == "__main__":
    main()
