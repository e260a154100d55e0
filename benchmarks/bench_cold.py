"""A newcomer's first commands on an empty cache (docs/performance.md): what each costs, and how many
times the engine is compiled along the way.

    python benchmarks/bench_cold.py --out DIR [--repeats N] [--only cycle,sweep,...] [--label before]

Each entry of COMMANDS runs on its own empty cache folder (``XDG_CACHE_HOME``, ``NUMBA_CACHE_DIR``
unset: numba's kernels, the generated evaluations, matplotlib's font cache), first cold, then warm
on what the cold run left. The ``sequence`` entry runs the README's commands one after another on
ONE empty cache (a drive cycle, a seismic window, the same window under a building), and counts the
"nsd: compiling ..." lines each prints: a version compiled once prints one line in the whole
sequence. Every row keeps the command's wall and CPU seconds (the process and its workers) and the
load average before and after it; the median of the repeats is reported, as is each cold/warm ratio.
"""
from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from nsd_core.device.results import versions
from nsd_core.common.files import atomic_write_json  # noqa: E402

CYCLE = ["cycle", "--amplitude", "0.015", "--frequency", "1"]
SWEEP = ["sweep", "--paper"]
COMPARE = ["compare", "--convergence", "--report"]   # the README's first command
SEISMIC = ["seismic", "--record", "nearfield-pulse:1", "--window", "4.8,6.0", "--scale", "0.4", "--rotate", "20"]
BUILDING = SEISMIC + ["--building", "stories=3"]
COMMANDS = {"cycle": CYCLE, "sweep": SWEEP, "compare": COMPARE}
SEQUENCE = [("cycle", CYCLE), ("seismic", SEISMIC), ("building", BUILDING)]
COLD_ONLY = ("compare", "sequence")   # the README's first command: its cold run is the newcomer's
NOTICE = "nsd: compiling"


def timed(args: list[str], out: Path, cache: Path, root: Path = ROOT) -> dict:
    """One fresh process of ``nsd ARGS --out OUT`` on the cache folder ``cache``, from the source tree
    ``root`` (a snapshot: other edits in a shared working tree would change the cache's key mid-run)."""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(XDG_CACHE_HOME=str(cache), MPLBACKEND="Agg")
    load0 = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "nsd_cli.main", *args, *(["--out", str(out)] if args != ["warm"] else [])],
                       cwd=root, env=env,
                       capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    notices = [ln for ln in p.stderr.splitlines() if ln.startswith(NOTICE)]
    row = {"exit_code": p.returncode, "wall_s": wall, "load_before": load0, "load_after": os.getloadavg()[0],
           "cpu_s": (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime),
           "compile_notices": len(notices)}
    try:   # the gate's own compare time, where the command wrote it
        import json
        row["compare_wall_s"] = json.loads((out / "results.json").read_text()).get("total_wall_time")
    except (OSError, ValueError):
        pass
    if p.returncode not in (0, 1):
        row["error"] = (p.stderr.strip().splitlines() or [""])[-1][:300]
    return row


def record(before: Path, after: Path, commits: tuple[str, str], out: Path, change: str = "") -> None:
    """benchmarks/results/bench_cold.json in benchmarks.measure's record format from two runs of this
    script side by side (before and after a change, each on a `git archive` of its commit): the load is
    the worst either saw, the command the two runs'."""
    import json
    b, a = json.loads(before.read_text()), json.loads(after.read_text())
    worst = lambda k: [round(max(x, y), 2) for x, y in zip(b[k], a[k])]  # noqa: E731
    rec = {"name": "bench_cold", "exit_code": 0,
           "command": f"python benchmarks/bench_cold.py --root <git archive of each commit> --out DIR (before: "
                      f"{commits[0][:12]}, after: {commits[1][:12]}, run one after the other)",
           "measured": {"date_utc": a["date_utc"], "machine": a["machine"], "processor": platform.machine(),
                        "cpus": a["cpus"], "load_average_before": worst("load_average_start"),
                        "load_average_after": worst("load_average_end"),
                        "wall_s": sum(r["wall_s"] for d in (b, a) for runs in d["rows"].values()
                                      for rr in runs.values() for r in rr),
                        "versions": a["versions"], "git_commit": commits[1]},
           "data": {"before": {**b, "commit": commits[0]}, "after": {**a, "commit": commits[1]},
                    **({"change": change} if change else {})}}
    from benchmarks.docs_common import loaded
    rec["measured"]["loaded"] = loaded(rec["measured"])
    atomic_write_json(out, rec)


def main(argv=None) -> int:
    if argv is None and sys.argv[1:2] == ["--record"]:   # --record BEFORE AFTER BEFORE_COMMIT AFTER_COMMIT OUT [CHANGE]
        b, a, cb, ca, out = sys.argv[2:7]
        record(Path(b), Path(a), (cb, ca), Path(out), " ".join(sys.argv[7:]))
        return 0
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="folder for bench_cold.json")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--only", default=",".join([*COMMANDS, "sequence"]), help="entries, comma separated")
    ap.add_argument("--label", default="", help="a name kept with the results (before, after)")
    ap.add_argument("--root", default=str(ROOT), help="the source tree to run (default: this one; e.g. a "
                    "`git archive` of a commit, run by this venv's python from there)")
    ap.add_argument("--warm-first", action="store_true", help="run `nsd warm` on each empty cache first "
                    "(an install step) and time it apart")
    a = ap.parse_args(argv)
    only = a.only.split(",")
    bad = [n for n in only if n not in COMMANDS and n != "sequence"]
    if bad or a.repeats < 1:
        print(f"--only {','.join(bad)}: not one of {', '.join([*COMMANDS, 'sequence'])}" if bad
              else f"--repeats = {a.repeats}: must be >= 1", file=sys.stderr)
        return 2
    rows: dict = {}
    load0 = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        for rep in range(a.repeats):
            for name in only:
                cache = Path(tmp) / f"cache-{name}-{rep}"
                cache.mkdir()
                steps = SEQUENCE if name == "sequence" else [(name, COMMANDS[name])]
                states = ("cold",) if name in COLD_ONLY else ("cold", "warm")
                if a.warm_first:
                    r = timed(["warm"], Path(tmp) / f"out-warm-{name}-{rep}", cache, Path(a.root))
                    rows.setdefault(f"nsd warm (before {name})", {}).setdefault("cold", []).append(r)
                    print(f"nsd warm before {name} #{rep + 1}: exit {r['exit_code']}, {r['wall_s']:.1f} s wall, "
                          f"{r['cpu_s']:.1f} s CPU, load {r['load_before']:.2f}->{r['load_after']:.2f}", flush=True)
                for state in states:
                    for step, args in steps:
                        r = timed(args, Path(tmp) / f"out-{name}-{step}-{state}-{rep}", cache, Path(a.root))
                        rows.setdefault(f"{name}:{step}" if name == "sequence" else name, {}).setdefault(
                            state, []).append(r)
                        print(f"{name} {step} {state} #{rep + 1}: exit {r['exit_code']}, {r['wall_s']:.1f} s wall, "
                              f"{r['cpu_s']:.1f} s CPU, {r['compile_notices']} compile line(s), load "
                              f"{r['load_before']:.2f}->{r['load_after']:.2f}", flush=True)

    def med(vals):
        vals = [v for v in vals if v is not None]
        return statistics.median(vals) if vals else None

    median = {name: {state: {k: med([r.get(k) for r in runs]) for k in ("wall_s", "cpu_s", "compare_wall_s",
                                                                          "compile_notices", "load_before")}
                     for state, runs in per.items()} for name, per in rows.items()}
    for m in median.values():
        if "warm" in m and m["warm"]["wall_s"]:
            m["cold_over_warm"] = m["cold"]["wall_s"] / m["warm"]["wall_s"]
    report = {"label": a.label, "root": a.root, "warm_first": a.warm_first, "repeats": a.repeats, "rows": rows, "median": median,
              "machine": platform.platform(), "cpus": os.cpu_count(), "load_average_start": load0,
              "load_average_end": os.getloadavg(), "versions": versions(),
              "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime())}
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "bench_cold.json", report)
    print(f"wrote {out / 'bench_cold.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
