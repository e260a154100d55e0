"""The README's test command as a newcomer meets it: fresh clones on empty caches, repeated.

    python benchmarks/bench_test_command.py --repeats 3 [--revision REV] --out DIR

Each repeat, one after another: a fresh clone of this repository at REV (default HEAD, resolved to its
commit once at the start), a new venv,
the install as that revision's README writes it (``pip install ... -e '.[test]'``), then ``python -m pytest -q`` (the README's command:
pyproject's addopts leave the slow mark out and spread the rest over every core), on an empty cache
folder (``XDG_CACHE_HOME`` a new folder, ``NUMBA_CACHE_DIR`` unset): the cold cache is included; in a
newcomer's environment (bench_first_command.newcomer_env: what this shell sets and a new Debian shell
does not, PYTHONDONTWRITEBYTECODE among it, removed and named in each row). Kept
per repeat: the wall and CPU seconds (the command and its children) of the install and of pytest,
pytest's own summary line and counts, the load average before. Also kept, from the first clone: how
many tests the default run and the slow mark collect (no test lost: each is in one or the other).
Writes DIR/bench_test_command.json; exit 1 when a repeat's pytest did not pass.
"""
from __future__ import annotations

import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.bench_first_command import clone, newcomer_env, readme_command, timed  # noqa: E402
from nsd_core.common.files import atomic_write_json  # noqa: E402
from nsd_core.device.results import versions  # noqa: E402

SUMMARY = re.compile(r"^=*\s*(\d+ (?:passed|failed|errors?|skipped)\b.*?) in ([\d.]+)s", re.M)
COUNT = re.compile(r"(\d+) (passed|failed|skipped|xfailed|xpassed|errors?|deselected)")


def counts(line: str) -> dict:
    """pytest's summary line as {kind: number}."""
    return {kind.rstrip("s") if kind.startswith("error") else kind: int(n) for n, kind in COUNT.findall(line)}


def collected(tree: Path, env: dict, mark: str) -> int:
    """How many tests ``pytest -m MARK`` selects (collection only, one process)."""
    p = subprocess.run([".venv/bin/python", "-m", "pytest", "--collect-only", "-q", "-n", "0", "-m", mark],
                       cwd=tree, env=env, capture_output=True, text=True)
    m = re.search(r"(\d+)(?:/\d+)? tests? (?:collected|selected)", p.stdout)
    return int(m.group(1)) if m else -1


def pytest_timed(tree: Path, env: dict) -> dict:
    """The README's pytest command: wall and CPU seconds (with its workers), exit code, summary line."""
    load = os.getloadavg()[0]
    before, start = os.times(), time.perf_counter()
    p = subprocess.run([".venv/bin/python", "-m", "pytest", "-q", "-p", "no:cacheprovider"], cwd=tree, env=env,
                       capture_output=True, text=True)
    wall, after = time.perf_counter() - start, os.times()
    cpu = (after.children_user - before.children_user) + (after.children_system - before.children_system)
    found = SUMMARY.findall(p.stdout)
    line = found[-1][0] if found else ""
    return {"pytest_wall_s": wall, "pytest_cpu_s": cpu, "exit_code": p.returncode, "load_before": load,
            "summary": line, "pytest_own_s": float(found[-1][1]) if found else None, "counts": counts(line),
            "tail": "" if p.returncode == 0 else (p.stdout + p.stderr)[-1500:]}


def one_repeat(revision: str, work: Path, k: int) -> dict:
    """A fresh clone, install and test run; the clone and its cache are removed after."""
    tree = clone(revision, work / f"clone-{k}")
    env, removed = newcomer_env(work / f"cache-{k}")
    venv_cmd, pip_cmd, _ = readme_command(tree, "pytest")   # the install as that revision's README writes it
    venv, pip = timed(venv_cmd, tree, env), timed(pip_cmd, tree, env)
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=tree, capture_output=True, text=True).stdout.strip()
    row = {"repeat": k, "commit": commit, "environment_removed": removed,
           "install_wall_s": venv["wall_s"] + pip["wall_s"], "install_cpu_s": venv["cpu_s"] + pip["cpu_s"],
           **pytest_timed(tree, env)}
    row["exit_code"] = row["exit_code"] or venv["exit_code"] or pip["exit_code"]
    row["total_wall_s"] = row["install_wall_s"] + row["pytest_wall_s"]
    if k == 0:
        row["collected_default"] = collected(tree, env, "not slow")
        row["collected_slow"] = collected(tree, env, "slow")
    shutil.rmtree(tree, ignore_errors=True)
    shutil.rmtree(work / f"cache-{k}", ignore_errors=True)
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="fresh clones, one after another (default 3)")
    ap.add_argument("--revision", default="HEAD", help="the git revision to test (default HEAD)")
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    if a.repeats < 1:
        print(f"bench_test_command: --repeats {a.repeats}: must be a whole number >= 1", file=sys.stderr)
        return 2
    p = subprocess.run(["git", "rev-parse", "--verify", a.revision + "^{commit}"], cwd=ROOT, capture_output=True,
                       text=True)
    if p.returncode:
        print(f"bench_test_command: --revision {a.revision!r}: not a commit of this repository", file=sys.stderr)
        return 2
    commit = p.stdout.strip()   # resolved once: commits made while it runs are not measured
    work = Path(tempfile.mkdtemp(prefix="test-command-"))
    rows = []
    for k in range(a.repeats):
        row = one_repeat(commit, work, k)
        rows.append(row)
        print(f"repeat {k}: pytest {row['pytest_wall_s']:.1f} s wall, {row['pytest_cpu_s']:.1f} s CPU, "
              f"{row['summary'] or 'no summary'}, exit {row['exit_code']}", flush=True)
    summary = {"pytest_wall_s_median": statistics.median(r["pytest_wall_s"] for r in rows),
               "total_wall_s_median": statistics.median(r["total_wall_s"] for r in rows),
               "pytest_cpu_s_median": statistics.median(r["pytest_cpu_s"] for r in rows)}
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "bench_test_command.json", {"revision": a.revision, "rows": rows, "summary": summary,
                                                        "cpus": os.cpu_count(), "versions": versions()})
    shutil.rmtree(work, ignore_errors=True)
    return 0 if all(r["exit_code"] == 0 for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
