"""MuJoCo's seismic mode natively (comparisons.engines.mujoco_seismic_native): the same model, laws and
order of operations as the Python callback and loop, so the same time histories to round-off, on the
device alone, with the restrainer engaged and under a building."""
from __future__ import annotations

import numpy as np
import pytest

from comparisons.engines import run_seismic_engine
from nsd_core.device.building import building_from
from nsd_core.device.ground import Harmonic
from nsd_core.device.isolation import default_structure
from nsd_core.device.params import ParameterError, Params
from nsd_core.device.restrainer import with_restrainer


def _structures():
    p = Params()
    st = default_structure(p)
    tight = with_restrainer(st, p, True, {"restrainer_gap": 0.002})   # engaged within the short run
    return {"device": st, "restrainer": tight, "building": st.with_building(building_from(st.mass, {"stories": 3}))}


@pytest.mark.parametrize("name", ["device", "restrainer", "building"])
def test_native_and_python_loops_agree_to_round_off(name):
    st = _structures()[name]
    ground = Harmonic(4.0, 3.0, duration=0.06)
    runs = {loop: run_seismic_engine("mujoco", Params(), st, ground, 0.06, 1e-3,
                                 {"timestep": 2e-5, "step_loop": loop, "model": "adapter"})
            for loop in ("native", "python")}
    a, b = runs["native"].columns, runs["python"].columns
    assert set(a) == set(b)
    for k in a:
        if k in ("closure", "t"):
            continue
        scale = max(np.max(np.abs(b[k])), 1e-12)
        assert np.max(np.abs(a[k] - b[k])) <= 1e-8 * scale, (k, np.max(np.abs(a[k] - b[k])), scale)
    assert np.max(np.abs(a["closure"] - b["closure"])) < 1e-12
    if name == "restrainer":
        assert np.max(b["restrainer_F"]) > 0.0   # engaged: the restrainer's law and rate are exercised
    assert abs(a["E_residual"][-1]) <= abs(a["E_input"]).max() * 1e-2


def test_an_unknown_step_loop_is_one_line_bad_input():
    with pytest.raises(ParameterError, match="step_loop"):
        run_seismic_engine("mujoco", Params(), default_structure(Params()), Harmonic(1.0, 2.0, duration=0.01), 0.01,
                           1e-3, {"step_loop": "fortran", "model": "adapter"})
