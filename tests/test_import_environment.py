"""Importing a module leaves the environment alone: a benchmark module that set NSD_EVALUATOR=generated
at import (tests/test_benchmarks_speed.py imports one) made every later run of the test process and of
its subprocesses compile a generated evaluation for each new structure (a two-story building's
three-configuration compare: 52 s instead of 4.6 s on a warm cache)."""
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# the package's own choice of numba's cache folder, passed to its child processes (docs/compilation.md)
CHOSEN_BY_THE_PACKAGE = {"NUMBA_CACHE_DIR", "NSD_VERSIONED_CACHE"}

PROBE = """
import importlib, json, os, pathlib, sys
sys.path[:0] = [{root!r}, {root!r} + "/benchmarks"]
before = dict(os.environ)
changed = {{}}
for name in {modules!r}:
    importlib.import_module(name)
    now = dict(os.environ)
    diff = sorted(k for k in set(now) | set(before) if now.get(k) != before.get(k) and k not in {chosen!r})
    if diff:
        changed[name] = diff
    before = now
print(json.dumps(changed))
"""


def test_importing_the_packages_and_the_benchmarks_changes_no_environment_variable():
    modules = ["nsd_core", "comparisons.harness", "nsd_cli.main", "reports"]
    modules += ["benchmarks." + p.stem for p in sorted((ROOT / "benchmarks").glob("*.py")) if p.stem != "__init__"]
    env = {k: v for k, v in os.environ.items() if k != "NSD_EVALUATOR"}
    env["MPLBACKEND"] = "Agg"
    code = PROBE.format(root=str(ROOT), modules=modules, chosen=CHOSEN_BY_THE_PACKAGE)
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300, cwd=ROOT)
    assert p.returncode == 0, p.stderr[-2000:]
    assert json.loads(p.stdout.strip().splitlines()[-1]) == {}
