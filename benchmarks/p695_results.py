"""benchmarks/results/p695.json: a whole `nsd p695` run (and a device variant's, and the three engines on
the variant's governing record) kept for docs/p695.md's generated tables (benchmarks/docs_p695.py).

    python -m benchmarks.p695_results --run DIR --log FILE [--command TEXT] [--variant DIR
                                      --variant-log FILE --variant-command TEXT] [--cross-check DIR ...]

A whole evaluation takes tens of minutes on the 2-core machine, so it is run by hand (from a snapshot
of the commit, `git archive`, so that other edits in a shared working tree do not change the store's
keys mid-run) with its output and a log: the log's first line ``start <UTC> load <1 5 15 ...> commit
<sha>`` and last line ``exit <code> end <UTC> load <...>`` (written around the command) give the date,
the load before and after, the wall time and the commit; this script adds the machine and the
versions, as benchmarks/measure.py does for the measurements it runs itself.
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import platform
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
DROP = ("structures",)   # every number of the structures is in design.md / the params listing


def _log(path: Path) -> dict:
    """start / end times, loads, exit code and commit from the log's first and last lines."""
    lines = [ln for ln in Path(path).read_text().splitlines() if ln.strip()]
    start = re.match(r"start (\S+) load (\S+) (\S+) (\S+).*?(?:commit (\w+))?$", lines[0])
    end = re.match(r"exit (\d+) end (\S+) load (\S+) (\S+) (\S+)", lines[-1])
    if not (start and end):
        raise SystemExit(f"{path}: needs 'start <UTC> load <l1 l5 l15> ... commit <sha>' first and "
                         "'exit <code> end <UTC> load <l1 l5 l15>' last")
    t0, t1 = (dt.datetime.strptime(s, "%Y-%m-%dT%H:%M:%SZ") for s in (start[1], end[2]))
    command = next((ln for ln in lines if ln.startswith("command ")), "command nsd p695")[8:]
    return {"date_utc": t1.strftime("%Y-%m-%d %H:%M"), "wall_s": (t1 - t0).total_seconds(),
            "load_average_before": [float(x) for x in start.group(2, 3, 4)],
            "load_average_after": [float(x) for x in end.group(3, 4, 5)], "exit_code": int(end[1]),
            "git_commit": start[5] or "", "command": command}


def _run(folder: Path) -> dict:
    res = json.loads((Path(folder) / "p695.json").read_text())
    return {k: v for k, v in res.items() if k not in DROP}


def _runs(folder: Path) -> int:
    return json.loads((Path(folder) / "ida.json").read_text())["runs"]


def _check(folder: Path) -> dict:
    """A run at a found capacity: per configuration, its Ŝ_CT, bracket, ACMR and verdicts."""
    res = json.loads((Path(folder) / "p695.json").read_text())
    keep = ("S_CT", "S_CT_bracket", "S_CT_interval", "mu_T", "SSF", "ACMR", "ACMR10", "ACMR20", "pass_ACMR20",
            "pass_ACMR10", "verdict_over_bracket", "collapse_modes")
    wp = {n: {t: {k: e[t].get(k) for k in ("found", "capacity", "S_CT", "ACMR", "how", "n_extrapolated")}
              for t in ("ACMR20", "ACMR10")} for n, e in (res.get("what_passes") or {}).get("configurations", {}).items()}
    return {"capacity": res["limit_states"]["capacity"], "runs": _runs(Path(folder)),
            "configurations": {n: {k: c[k] for k in keep} for n, c in res["configurations"].items()},
            "what_passes": wp}


def _cross_check(folder: Path) -> dict:
    """An `nsd seismic --engines ...` run: the record, scale, peaks and each peer's differences."""
    s = json.loads((Path(folder) / "summary.json").read_text())
    keep = ("du", "dF", "da", "wall_time", "settings", "dt")
    return {"ground": s.get("ground"), "peak_displacement": s["peak_displacement"],
            "peak_device_force": s.get("peak_device_force"), "in_house_wall_time": s.get("wall_time"),
            "engines": {n: {k: m[k] for k in keep if k in m} for n, m in (s.get("engines") or {}).items()},
            "folder": Path(folder).name}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--run", required=True)
    ap.add_argument("--log", required=True)
    ap.add_argument("--variant")
    ap.add_argument("--variant-log")
    ap.add_argument("--cross-check", action="append", default=[])
    ap.add_argument("--ida-check", help="an nsd ida --cross-check median run of the governing record at one level "
                                        "(the gate's rule: each peer at its step and half of it)")
    ap.add_argument("--ida-check-log")
    ap.add_argument("--check", action="append", default=[],
                    help="an nsd p695 run at a capacity what-passes found (--isolators X --capacity C): kept as run")
    ap.add_argument("--note", default="")
    ap.add_argument("--command", help="the command as a user types it (default: the log's 'command ...' line)")
    ap.add_argument("--variant-command")
    a = ap.parse_args(argv)
    from nsd_core.device.results import versions
    from nsd_core.common.files import atomic_write_json
    from benchmarks.docs_common import loaded
    log = _log(Path(a.log))
    measured = {k: log[k] for k in ("date_utc", "wall_s", "load_average_before", "load_average_after", "git_commit")}
    measured.update(machine=platform.platform(), processor=platform.machine(), cpus=os.cpu_count() or 1,
                    versions=versions(), how="run by hand from a snapshot of the commit (git archive), output kept")
    measured["loaded"] = loaded(measured)
    data = {"evaluation": _run(Path(a.run)), "ida_runs": _runs(Path(a.run)), "note": a.note}
    if a.variant:
        vlog = _log(Path(a.variant_log)) if a.variant_log else {}
        data["variant"] = {"evaluation": _run(Path(a.variant)), "ida_runs": _runs(Path(a.variant)), "command": a.variant_command or vlog.get("command"),
                           "wall_s": vlog.get("wall_s"), "exit_code": vlog.get("exit_code"),
                           "load_average_before": vlog.get("load_average_before"),
                           "git_commit": vlog.get("git_commit")}
    data["cross_check"] = [_cross_check(Path(f)) for f in a.cross_check]
    data["capacity_checks"] = [_check(Path(f)) for f in a.check]
    if a.ida_check:
        ida = json.loads((Path(a.ida_check) / "ida.json").read_text())
        ilog = _log(Path(a.ida_check_log)) if a.ida_check_log else {}
        data["gate_rule_check"] = {"command": ilog.get("command"), "wall_s": ilog.get("wall_s"),
                                   "exit_code": ilog.get("exit_code"),
                                   "device": (ida.get("cross_check") or {}).get("device")}
    rec = {"name": "p695", "command": a.command or log["command"], "exit_code": log["exit_code"], "measured": measured,
           "data": data}
    RESULTS.mkdir(parents=True, exist_ok=True)
    atomic_write_json(RESULTS / "p695.json", rec)
    print(f"wrote {RESULTS / 'p695.json'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
