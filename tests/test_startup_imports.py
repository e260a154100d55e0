"""What a command imports before it runs anything: scipy's integrators (~1 s of every command's start
on a 2-core machine) only where a scipy solver or a step loop's tableau is made."""
import subprocess
import sys

import pytest

LATER = ("scipy.integrate", "scipy.optimize", "matplotlib", "sympy")


@pytest.mark.parametrize("modules", [
    "nsd_cli.main, nsd_cli.compare, nsd_cli.cycle, nsd_cli.seismic",
    "comparisons.harness, comparisons.engines.peers, nsd_core.device.model, nsd_core.structure.seismic",
])
def test_a_commands_modules_import_no_integrator_optimizer_or_plotting(modules):
    code = (f"import sys\nimport {modules}\nfrom comparisons.engines import get_engine\n"
            "for e in ('semirecursive', 'mujoco', 'exudyn'):\n    get_engine(e)\n"
            f"print(sorted(m for m in {LATER!r} if m in sys.modules))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr[-2000:]
    assert p.stdout.strip() == "[]", p.stdout
