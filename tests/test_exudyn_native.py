"""Exudyn's compiled per-step force work against the numpy one (real Exudyn, no mocks)."""
from __future__ import annotations

import numpy as np
import pytest

from comparisons.engines.exudyn_engine import ExudynEngine
from nsd_core.device.drive import Drive
from nsd_core.device.params import ParameterError, Params

P = Params()


@pytest.mark.parametrize("path,integrator", [("line", "heun"), ("line", "rk4"), ("circle", "heun")])
def test_compiled_prestep_equals_numpy_prestep(path, integrator):
    """Same laws, same operations: the run whose whole pre-step is one compiled call
    (exudyn_native.pre_step: Exudyn's ODE2 vectors, the plate's path, the Taylor prediction, the loads)
    equals the numpy one (six node outputs, numpy arithmetic, _Elements.step in numpy) bit for bit,
    every column. The ropes go slack and the strains turn, so every branch of the step is taken; the
    circle moves both drive offsets."""
    d = Drive(0.0255 if path == "line" else 0.015, 10.0, cycles=1, samples_per_cycle=200, path=path)
    base = {"step_size": 1e-4, "min_steps_per_cycle": 1, "state_integrator": integrator}
    ref = ExudynEngine().run(P, d, {**base, "force_code": "python"})
    r = ExudynEngine().run(P, d, {**base, "force_code": "compiled"})
    if path == "line":
        assert np.min(ref.stack("rope")) == 0.0 and np.max(ref.stack("rope")) > 100.0
    else:
        assert np.ptp(ref["F_y"]) > 0.5 * np.ptp(ref["F_x"]) > 0.0
    assert ref.columns.keys() == r.columns.keys()
    for col in ref.columns:
        assert np.array_equal(r[col], ref[col]), col


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


def test_compiled_prestep_takes_a_per_rope_stiffness():
    """A modelling error in one rope's stiffness (engines/perturb.py) runs on the compiled pre-step,
    equal to the numpy one, and moves the force (it used to stop the solver in its first step)."""
    d = Drive(0.015, 10.0, cycles=1, samples_per_cycle=100)
    base = {"step_size": 2e-4, "min_steps_per_cycle": 1}
    stiffer = {**base, "perturb": {"what": "rope_stiffness", "index": 0, "by": 0.05}}
    ref = ExudynEngine().run(P, d, {**stiffer, "force_code": "python"})
    r = ExudynEngine().run(P, d, {**stiffer, "force_code": "compiled"})
    for col in ref.columns:
        assert np.array_equal(r[col], ref[col]), col
    nominal = ExudynEngine().run(P, d, base)
    assert np.max(np.abs(r["F"] - nominal["F"])) > 1e-3 * np.max(np.abs(nominal["F"]))
