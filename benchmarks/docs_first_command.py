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
    for phase in ("first command in all", "first command's nsd compare (cold cache)", "warm nsd compare",
                  "its report again (nsd report on its folder)"):
        a, b = by.get((revs[0], phase)), by.get((revs[-1], phase))
        if a and b:
            many = len(a) > 1 or len(b) > 1
            a, b = statistics.median(a), statistics.median(b)
            which = f"{phase} (median of each revision's runs)" if many else phase
            lines.append(f"{which}: **{plain(a)} s** before, **{plain(b)} s** after (ratio {g(b / a)})")
    return (provenance(rec) + "\n\n" + "; ".join(lines) + ".\n\n"
            + table(["revision", "phase", "wall s", "CPU s (children)", "compare s (its own line)", "verdict",
                     "load before"], rows))


def _min_s(seconds: float) -> str:
    m, s = divmod(round(seconds), 60)
    return f"{m}:{s:02d}"


def test_command(load, provenance, table, g, plain) -> str:
    """docs/performance.md's test-command table, from benchmarks/results/bench_test_command.json
    (benchmarks/bench_test_command.py: the README's test command in fresh clones on empty caches)."""
    rec = load("bench_test_command")
    d = rec["data"]
    rows = [[str(r["repeat"] + 1), f"`{r['commit'][:7]}`", r["summary"] or f"exit {r['exit_code']}",
             plain(r["install_wall_s"]), f"{plain(r['pytest_wall_s'])} ({_min_s(r['pytest_wall_s'])})",
             plain(r["pytest_cpu_s"] / 60), f"{plain(r['total_wall_s'])} ({_min_s(r['total_wall_s'])})",
             plain(r["load_before"], 2)] for r in d["rows"]]
    s, first = d["summary"], d["rows"][0]
    text = (f"Median of {len(d['rows'])}: pytest **{plain(s['pytest_wall_s_median'])} s "
            f"({_min_s(s['pytest_wall_s_median'])})**, install and pytest **{plain(s['total_wall_s_median'])} s "
            f"({_min_s(s['total_wall_s_median'])})**, pytest's CPU {plain(s['pytest_cpu_s_median'] / 60)} min. "
            f"Collected in the first clone: {first.get('collected_default')} tests in the default run, "
            f"{first.get('collected_slow')} in the slow mark (`pytest -m slow`, run apart by .ci/run).")
    return (provenance(rec) + "\n\n" + text + "\n\n"
            + table(["repeat", "commit", "pytest's summary", "install s", "pytest wall s (min:s)",
                     "pytest CPU min (with its workers)", "install + pytest s (min:s)", "load before"], rows))


def model_first(load, provenance, table, g, plain) -> str:
    """docs/performance.md's table of a user's first ``nsd compare --model`` (benchmarks/bench_model_first.py)."""
    rec = load("bench_model_first")
    d = rec["data"]
    rows = [[r["phase"], r["model"] or "-", plain(r["wall_s"]), plain(r["cpu_s"]), str(r["compile_notices"]),
             {0: "PASS", 1: "FAIL"}.get(r["exit_code"], f"exit {r['exit_code']}"), plain(r["load_before"], 2)]
            for r in d["rows"]]
    new = {r["model"]: r["wall_s"] for r in d["rows"] if r["phase"].startswith("package compiled")}
    warm = {r["model"]: r["wall_s"] for r in d["rows"] if r["phase"].startswith("again")}
    extra = ", ".join(f"{m} {new[m] - warm[m]:+.1f} s" for m in new if m in warm)
    text = (f"The first time against again, per description, on the package `nsd warm` compiled: {extra} "
            "(what the first run compiles, its compile notices in the table; a difference under ~0.5 s is the "
            "machine's noise).") if extra else ""
    return (provenance(rec) + "\n\n" + text + "\n\n"
            + table(["phase", "description", "wall s", "CPU s (with its workers)", "compile notices", "verdict",
                     "load before"], rows))


def report_drawing(load, provenance, table, g, plain) -> str:
    """docs/performance.md's table of ``nsd report`` under two matplotlib versions (benchmarks/bench_report.py)."""
    rec = load("bench_report")
    d = rec["data"]
    rows = [[str(r["repeat"] + 1), r["matplotlib"], str(r["pages"]), plain(r["wall_s"]), plain(r["cpu_s"]),
             plain(r["report_s"]) if r.get("report_s") is not None else f"exit {r['exit_code']}",
             plain(r["load_before"], 2)] for r in d["rows"]]
    by: dict[str, list[float]] = {}
    for r in d["rows"]:
        if r.get("report_s") is not None:
            by.setdefault(r["matplotlib"], []).append(r["report_s"])
    med = {v: statistics.median(t) for v, t in by.items()}
    text = "; ".join(f"matplotlib {v}: **{plain(m)} s** (median of {len(by[v])})" for v, m in med.items())
    if len(med) == 2:
        (va, a), (vb, b) = med.items()
        text += f"; ratio {vb} / {va}: {g(b / a)}"
    return (provenance(rec) + "\n\n" + f"The report's own line (drawing, start-up excluded): {text}.\n\n"
            + table(["repeat", "matplotlib", "pages", "wall s", "CPU s (with its second process)",
                     "report s (its own line)", "load before"], rows))
