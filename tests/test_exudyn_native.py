"""Exudyn's compiled per-step force work against the numpy one (real Exudyn, no mocks)."""
from __future__ import annotations

import numpy as np
import pytest

from comparisons.engines.exudyn_engine import ExudynEngine
from nsd_core.device.drive import Drive
from nsd_core.device.params import ParameterError, Params

P = Params()


@pytest.mark.parametrize("integrator", ["heun", "rk4"])
def test_compiled_step_equals_numpy_step(integrator):
    """Same laws, same operations: the run with the compiled pre-step loads equals the numpy one (the
    ropes go slack and the strains turn, so every branch of the step is taken)."""
    d = Drive(0.0255, 10.0, cycles=1, samples_per_cycle=200)
    base = {"step_size": 1e-4, "min_steps_per_cycle": 1, "state_integrator": integrator}
    ref = ExudynEngine().run(P, d, {**base, "force_code": "python"})
    r = ExudynEngine().run(P, d, {**base, "force_code": "compiled"})
    assert np.min(ref.stack("rope")) == 0.0 and np.max(ref.stack("rope")) > 100.0
    for col in ("F", "cap_z", "wall_z", "spring_zeta", "wire0_stress", "wire2_stress"):
        scale = np.max(np.abs(ref[col]))
        assert np.max(np.abs(r[col] - ref[col])) <= 1e-12 * scale, col


def test_linear_solvers_agree_and_bad_names_are_refused():
    d = Drive(0.015, 10.0, cycles=1, samples_per_cycle=100)
    base = {"step_size": 2e-4, "min_steps_per_cycle": 1}
    a = ExudynEngine().run(P, d, {**base, "linear_solver": "exudyn_dense"})
    b = ExudynEngine().run(P, d, {**base, "linear_solver": "eigen_dense"})
    assert np.max(np.abs(a["F"] - b["F"])) < 1e-7 * np.max(np.abs(a["F"]))
    with pytest.raises(ParameterError, match="exudyn.linear_solver"):
        ExudynEngine().run(P, d, {"linear_solver": "lapack"})
    with pytest.raises(ParameterError, match="exudyn.force_code"):
        ExudynEngine().run(P, d, {"force_code": "c++"})
