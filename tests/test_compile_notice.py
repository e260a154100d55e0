"""The compile notice says what compiles (nsd_core.engine.compile_once): the engine's line once, and at
the first seismic run after a drive run compiled the engine, the seismic mode's own line, not the
engine's again (before: "compiling the in-house engine once" a second time in the same checkout)."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest

from nsd_core.engine import compile_once as co

ENGINE = co.NOTICE.format(seconds=co.NOTICE_SECONDS)
SEISMIC = co.SEISMIC_NOTICE.format(seconds=co.SEISMIC_NOTICE_SECONDS)


def _python(code: str, cache_home, timeout=900) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME")}
    env["XDG_CACHE_HOME"] = str(cache_home)
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env, capture_output=True, text=True,
                          timeout=timeout)


def _notices(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if line.startswith("nsd: compiling")]


def test_parts():
    assert co.notice_part("nsd_core.structure.compiled_seismic") == "seismic"
    assert co.notice_part("nsd_core.ground.motions") == "seismic"
    for module in ("nsd_core.engine.rk", "nsd_core.device.compiled", "nsd_core.device.forces"):
        assert co.notice_part(module) == "engine", module


def test_a_seismic_kernel_compiled_first_gives_the_seismic_line_once(tmp_path):
    p = _python("""
        import numpy as np
        from numba import njit
        import nsd_core.engine.compiled  # installs the listener
        from nsd_core.ground import motions as ground
        f = njit(cache=False)(ground.harmonic_at.py_func)   # a fresh dispatcher of a seismic-mode kernel
        f(0.5, 1.0, 6.0, 1.0)
        g = njit(cache=False)(nsd_core.engine.compiled.copy_into.py_func)   # then an engine kernel: no 2nd line
        g(np.zeros(3), np.ones(3))
    """, tmp_path)
    assert p.returncode == 0, p.stderr
    assert _notices(p.stderr) == [SEISMIC], p.stderr


def test_an_engine_kernel_compiled_first_gives_the_engine_line_once(tmp_path):
    p = _python("""
        import numpy as np
        from numba import njit
        import nsd_core.engine.compiled as C
        from nsd_core.ground import motions as ground
        njit(cache=False)(C.copy_into.py_func)(np.zeros(3), np.ones(3))
        njit(cache=False)(ground.harmonic_at.py_func)(0.5, 1.0, 6.0, 1.0)
    """, tmp_path)
    assert p.returncode == 0, p.stderr
    assert _notices(p.stderr) == [ENGINE], p.stderr


@pytest.mark.slow
def test_a_checkout_s_first_cycle_then_first_building_run(tmp_path):
    """Cold cache: nsd cycle prints the engine's line; the first nsd seismic --building after it
    compiles only the seismic kernels and prints their line (not the engine's again); a second
    seismic run prints nothing."""
    def nsd(*args):
        return _python(f"import sys; from nsd_cli.main import main; sys.exit(main({list(args)!r}))", tmp_path)
    ground = ["--ground", "harmonic:amplitude=1.5,frequency=3,duration=0.05", "--dt-out", "0.005"]
    first = nsd("cycle", "--amplitude", "0.01", "--frequency", "20", "--cycles", "1", "--out", str(tmp_path / "c"))
    assert first.returncode == 0 and _notices(first.stderr) == [ENGINE], first.stderr
    second = nsd("seismic", *ground, "--building", "stories=2", "--out", str(tmp_path / "s"))
    assert second.returncode == 0 and _notices(second.stderr) == [SEISMIC], second.stderr
    third = nsd("seismic", *ground, "--out", str(tmp_path / "s2"))
    assert third.returncode == 0 and _notices(third.stderr) == [], third.stderr
