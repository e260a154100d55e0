"""The README's first command as a newcomer meets it, for two revisions side by side on one machine.

    python benchmarks/bench_first_command.py --revisions BEFORE,AFTER --out DIR

For each revision: a fresh clone of this repository at that revision, then the README's first command
as that revision's README writes it (a new venv, its ``pip install``, ``nsd compare --convergence --report``) on an
empty cache (``XDG_CACHE_HOME`` a new folder, ``NUMBA_CACHE_DIR`` unset), each phase timed; then the
warm gate (``nsd compare`` again on what the cold run left, ``--warm`` times each). The report's own
share is timed apart: ``nsd report`` on the cold run's folder, after the first command (not part of it). The revisions
alternate phase by phase (cold before, cold after, then warm before, warm after, repeated), so that
both meet the same load; the load average is kept beside every row. Writes DIR/bench_first_command.json.
"""
from __future__ import annotations

import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from nsd_core.device.results import versions
from nsd_core.common.files import atomic_write_json  # noqa: E402

VERDICT = re.compile(r"verdict: (\w+) \(([\d.]+) s\)")


def timed(cmd: list[str], cwd: Path, env: dict) -> dict:
    """Wall and CPU seconds (the command and its children) of one command, with its exit code."""
    load = os.getloadavg()[0]
    before = os.times()
    start = time.perf_counter()
    p = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = os.times()
    cpu = (after.children_user - before.children_user) + (after.children_system - before.children_system)
    m = VERDICT.search(p.stdout)
    return {"cmd": " ".join(cmd), "exit_code": p.returncode, "wall_s": wall, "cpu_s": cpu, "load_before": load,
            "verdict": m.group(1) if m else None, "compare_s": float(m.group(2)) if m else None,
            "tail": (p.stdout + p.stderr)[-400:] if p.returncode else ""}


# what this harness's own shell may set and a newcomer's does not: the package's variables, another venv, and
# PYTHONDONTWRITEBYTECODE (set on this project's sandboxes), under which every process compiles the
# modules it imports again (the project's own ~100 files alone ~0.4 s; the README's install compiles none)
NOT_A_NEWCOMERS = ("NUMBA_CACHE_DIR", "VIRTUAL_ENV", "PYTHONPATH", "NSD_EVALUATOR", "PYTHONDONTWRITEBYTECODE")


def newcomer_env(cache: Path) -> tuple[dict, list[str]]:
    """A newcomer's environment: this one without NOT_A_NEWCOMERS, an empty cache folder, no screen; and
    the names removed that were set (kept with the numbers)."""
    env = {k: v for k, v in os.environ.items() if k not in NOT_A_NEWCOMERS}
    env.update(XDG_CACHE_HOME=str(cache), MPLBACKEND="Agg")
    return env, sorted(k for k in NOT_A_NEWCOMERS if k in os.environ)


def readme_command(tree: Path, runs: str = "nsd compare") -> list[list[str]]:
    """The README's quick-start command in ``tree`` that ``runs`` this ("nsd compare": the first; "pytest":
    the tests), split at '&&' into its argv lists: the venv (run by this Python), the install, the run."""
    readme = (tree / "README.md").read_text(encoding="utf-8")
    line = next(ln for ln in readme.splitlines() if ln.startswith("python3 -m venv") and runs in ln)
    parts = [shlex.split(p) for p in line.split("&&")]
    parts[0][0] = sys.executable
    return parts


def clone(revision: str, where: Path) -> Path:
    subprocess.run(["git", "clone", "-q", str(ROOT), str(where)], check=True)
    subprocess.run(["git", "-C", str(where), "checkout", "-q", revision], check=True)
    return where


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--revisions", required=True, help="BEFORE,AFTER (git revisions)")
    ap.add_argument("--warm", type=int, default=3, help="warm gate runs of each revision (default 3; their median is quoted)")
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    if a.warm < 1:
        print(f"bench_first_command: --warm {a.warm}: must be a whole number >= 1", file=sys.stderr)
        return 2
    revs = a.revisions.split(",")
    work = Path(tempfile.mkdtemp(prefix="first-command-"))
    trees, envs, rows = {}, {}, []
    for r in revs:
        trees[r] = clone(r, work / f"clone-{r}")
        envs[r], removed = newcomer_env(work / f"cache-{r}")
    for r in revs:   # cold: the README's first command, phase by phase
        t = trees[r]
        venv_cmd, pip_cmd, compare_cmd = readme_command(t)
        venv, pip, cmp_ = (timed(c, t, envs[r]) for c in (venv_cmd, pip_cmd, compare_cmd))
        total = venv["wall_s"] + pip["wall_s"] + cmp_["wall_s"]
        rep = timed([".venv/bin/nsd", "report", "--from", "out/compare", "--out", "out/report-again"], t, envs[r])
        rows += [{"revision": r, "phase": "venv", **venv}, {"revision": r, "phase": "install", **pip},
                 {"revision": r, "phase": "first command's nsd compare (cold cache)", **cmp_},
                 {"revision": r, "phase": "first command in all", "wall_s": total, "load_before": venv["load_before"]},
                 {"revision": r, "phase": "its report again (nsd report on its folder)", **rep}]
        print(f"{r}: cold total {total:.1f} s (compare {cmp_['wall_s']:.1f} s, {cmp_['verdict']})", flush=True)
    for k in range(a.warm):   # warm: the gate again on what the cold run left, the revisions alternating
        for r in revs:
            w = timed([".venv/bin/nsd", "compare", "--out", f"out/warm{k}"], trees[r], envs[r])
            rows.append({"revision": r, "phase": "warm nsd compare", **w})
            print(f"{r}: warm {w['wall_s']:.1f} s ({w['verdict']})", flush=True)
    revisions = {r: subprocess.run(["git", "-C", str(trees[r]), "rev-parse", "HEAD"], capture_output=True,
                                   text=True).stdout.strip() for r in revs}
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "bench_first_command.json", {"revisions": revisions, "rows": rows, "cpus": os.cpu_count(),
                                                         "environment_removed": removed, "versions": versions()})
    shutil.rmtree(work, ignore_errors=True)   # two clones with their venvs and caches (~1.5 GB each)
    return 0 if all(r.get("exit_code", 0) == 0 for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
