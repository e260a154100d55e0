"""docs/performance.md's first-command table, from benchmarks/results/bench_first_command.json
(benchmarks/bench_first_command.py: the README's first command, two revisions side by side)."""
from __future__ import annotations

import statistics


def first_command(load, provenance, table, g, plain) -> str:
    rec = load("bench_first_command")
    d = rec["data"]
    revs = list(d["revisions"])
    rows = []
    for r in d["rows"]:
        rows.append([f"`{r['revision']}` ({d['revisions'][r['revision']][:7]})", r["phase"], plain(r["wall_s"]),
                     plain(r["cpu_s"]) if r.get("cpu_s") is not None else "-",
                     plain(r["compare_s"]) if r.get("compare_s") is not None else "-",
                     r.get("verdict") or "-", plain(r["load_before"], 2)])
    by = {}
    for r in d["rows"]:
        by.setdefault((r["revision"], r["phase"]), []).append(r["wall_s"])
    lines = []
    for phase in ("first command in all", "first command's nsd compare (cold cache)", "warm nsd compare"):
        a, b = by.get((revs[0], phase)), by.get((revs[-1], phase))
        if a and b:
            many = len(a) > 1 or len(b) > 1
            a, b = statistics.median(a), statistics.median(b)
            which = f"{phase} (median of each revision's runs)" if many else phase
            lines.append(f"{which}: **{plain(a)} s** before, **{plain(b)} s** after (ratio {g(b / a)})")
    return (provenance(rec) + "\n\n" + "; ".join(lines) + ".\n\n"
            + table(["revision", "phase", "wall s", "CPU s (children)", "compare s (its own line)", "verdict",
                     "load before"], rows))
