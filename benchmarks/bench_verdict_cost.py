"""What the per-run verdict costs: the gate (``nsd compare`` on the default cases) on a warm cache,
the current code against an earlier revision with fixed limits, in one run, interleaved.

    python benchmarks/bench_verdict_cost.py --baseline REV --repeats 2 --out DIR

The baseline revision is checked out into a temporary git worktree and run by the same Python (its
own source first on the path: ``python -m nsd_cli.main`` from its folder). Each side first runs once
to fill its own compile cache (not timed), then the two alternate ``repeats`` times, each into a fresh
output folder (no kept runs). Kept per run: the command's wall and CPU seconds, the compare's own wall
seconds (``total_wall_time``), the verdict and the number of runs; then the medians and their ratio.
The extra runs of the current code (each fixed-step peer at h/2 on every case, the converged
reference's rtol 1e-11 check) are summed by kind from its results.json, so the table says where the
extra time goes.
"""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.bench_start import timed_nsd  # noqa: E402
from nsd_core.device.results import versions
from nsd_core.common.files import atomic_write_json  # noqa: E402


def run_once(cwd: Path, out: Path) -> dict:
    load0 = os.getloadavg()
    row, res = timed_nsd(["compare"], out, {**os.environ, "MPLBACKEND": "Agg"}, cwd)
    row["load_before"] = round(load0[0], 2)
    if res is None:
        return row
    cpu: dict[str, float] = {}
    for per in list(res["runs"].values()) + list(res.get("reference_runs", {}).values()):
        for label, r in per.items():
            kind = ("peer at 2h" if label.endswith("_2h") else "converged check (rtol 1e-11)"
                    if label == "converged_check" else "converged reference" if label == "converged"
                    else "order check (h/4)" if label.endswith("_h4") else label)
            cpu[kind] = cpu.get(kind, 0.0) + float(r.get("cpu_time") or 0.0)
    row.update(verdict=res.get("verdict"), compare_wall_s=res.get("total_wall_time"),
               runs=sum(len(per) for per in res["runs"].values()) + sum(len(per) for per in
                                                                         res.get("reference_runs", {}).values()),
               run_cpu_s_by_kind=cpu, rule=(res.get("rule") or {}).get("name", "limits"))
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", required=True, help="git revision with the fixed-limit gate")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        old = Path(tmp) / "baseline"
        subprocess.run(["git", "worktree", "add", "--detach", str(old), a.baseline], cwd=ROOT, check=True,
                       capture_output=True)
        try:
            sides = {"baseline": old, "current": ROOT}
            for name, cwd in sides.items():   # fill each side's compile cache: not timed
                run_once(cwd, Path(tmp) / f"fill_{name}")
            rows = {name: [] for name in sides}
            for k in range(a.repeats):
                for name, cwd in sides.items():
                    rows[name].append(run_once(cwd, Path(tmp) / f"{name}_{k}"))
                    print(f"{name} {k}: {rows[name][-1].get('compare_wall_s')}", file=sys.stderr)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(old)], cwd=ROOT, capture_output=True)
    med = {n: statistics.median(r["compare_wall_s"] for r in rs if r.get("compare_wall_s")) for n, rs in rows.items()}
    rec = {"baseline": a.baseline, "repeats": a.repeats, "rows": rows, "median_compare_wall_s": med,
           "ratio": med["current"] / med["baseline"], "machine": platform.platform(), "cpus": os.cpu_count(),
           "versions": versions()}
    atomic_write_json(out / "bench_verdict_cost.json", rec)
    print(f"warm gate: baseline {med['baseline']:.1f} s, current {med['current']:.1f} s, ratio {rec['ratio']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
