"""A described mechanism's evaluation from Python makes the engine's units ready first: numba files a
call's own compilation apart from a unit's explicit signature, so a first Python-side call before any
unit of the process compiled the velocities and the dynamics again (7 s of the first ``nsd compare
--model`` after ``nsd warm``)."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PROBE = """
from nsd_core.model.load import load_model
from nsd_core.model.semirecursive import start, system_of
from nsd_core.engine.compile_once import DONE
from nsd_core.engine.compiled import DYNAMICS, VELOCITIES
from nsd_core.engine.compiled import reduced_dynamics, velocities_and_predictor
m = load_model("models/fourbar_spring.toml")
system, tree = system_of(m)
_, _, y0, _ = start(m, system, tree)
system.evaluate(system.workspace(), 0.0, y0)
print(DYNAMICS in DONE, VELOCITIES in DONE, len(reduced_dynamics.overloads), len(velocities_and_predictor.overloads))
"""


def test_the_python_side_evaluation_uses_the_units_not_a_call_of_its_own():
    p = subprocess.run([sys.executable, "-c", PROBE], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-2000:]
    assert p.stdout.split() == ["True", "True", "1", "1"], p.stdout
