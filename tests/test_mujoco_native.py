"""MuJoCo's compiled passive callback and native step loop against the Python callback (real MuJoCo)."""
from __future__ import annotations

import mujoco
import numpy as np
import pytest

from comparisons.engines import mujoco_native as native
from comparisons.engines.mujoco_engine import MujocoEngine, _Device, build_mjcf
from nsd_core.device.drive import Drive
from nsd_core.device.geometry import device_geometry
from nsd_core.device.params import ParameterError, Params

P = Params()
G = device_geometry(P)


def _device_pair(predict: bool):
    """A model with userdata, the Python _Device on it and the same states packed for the C callback."""
    d = Drive(0.0255, 10.0, cycles=1, samples_per_cycle=200)
    s = dict(MujocoEngine.default_settings)
    model = mujoco.MjModel.from_xml_string(build_mjcf(G, d, s, 1e-5, native.userdata_size(G.n_ropes, G.n_wires)))
    data = mujoco.MjData(model)
    dev = _Device(G, d, data, predict=predict, substeps=2)
    return model, data, dev


def _pack(data, dev):
    native.pack_userdata(data.userdata, G, (1.0, 0.0), dev.sigma, dev.zeta, dev.eps_c, dev.x_c, dev.predict,
                         dev.substeps)


@pytest.mark.parametrize("predict", [False, True])
def test_c_callback_forces_equal_the_python_callback(predict):
    """Through mj_forward, at random configurations and committed states (slack and taut elements,
    both strain directions), the C callback adds the same generalized forces as _Device.passive."""
    model, data, dev = _device_pair(predict)
    rng = np.random.default_rng(1)
    cb = native.passive_callback()
    previous = mujoco.get_mjcb_passive()
    try:
        for _ in range(25):
            dev.sigma = rng.uniform(-2e8, 6e8, G.n_wires)
            dev.zeta = float(rng.uniform(-300.0, 300.0))
            dev.eps_c, dev.x_c = dev.strains(rng.normal(0.0, [0.01, 0.002, 0.002, 0.002]))
            dev._slopes()
            _pack(data, dev)
            data.qpos[:4] = rng.normal(0.0, [0.02, 0.002, 0.003, 0.003])
            mujoco.set_mjcb_passive(dev.passive)
            mujoco.mj_forward(model, data)
            ref = data.qfrc_passive.copy()
            mujoco.set_mjcb_passive(cb.ctypes)
            mujoco.mj_forward(model, data)
            # same laws, same operations; only the order of the element sums may differ (numpy's dot)
            np.testing.assert_allclose(data.qfrc_passive, ref, rtol=0, atol=1e-13 * np.max(np.abs(ref)))
            assert np.max(np.abs(ref[:4])) > 100.0   # the elements did act
    finally:
        mujoco.set_mjcb_passive(previous)


def test_compiled_commit_equals_python_commit():
    """The hysteretic states advanced in compiled code equal _Device.commit's, step after step (to
    round-off: the array form runs the same law as a vectorised loop, whose tanh/pow may differ in
    the last bit)."""
    model, data, dev = _device_pair(True)
    _pack(data, dev)
    ud = data.userdata
    t = np.linspace(0.0, 0.1, 400)
    for k, tk in enumerate(t):   # a swing with reversals, through slack and taut wires
        data.qpos[:4] = [0.025 * np.sin(60 * tk), 0.0, 1e-3 * np.sin(90 * tk), 1e-3 * np.cos(70 * tk)]
        dev.commit()
        native.commit(data.qpos, ud)
        np.testing.assert_allclose(ud[native.sigma_slice(ud)], dev.sigma, rtol=1e-13, atol=1e-3)
        assert ud[native.ZETA] == pytest.approx(dev.zeta, rel=1e-13, abs=1e-9)
        assert ud[native.Z_UP] == pytest.approx(dev.z_up, rel=1e-13)
        assert ud[native.Z_DN] == pytest.approx(dev.z_dn, rel=1e-13)
    assert np.max(dev.sigma) > 1e8   # the wires were loaded


@pytest.mark.parametrize("integrator,timestep", [("Euler", 2e-5), ("RK4", 5e-5)])
def test_native_run_equals_python_run(integrator, timestep):
    """A whole run: the native loop with the C callback gives the Python loop's drive force, states and
    positions (bit for bit on this machine; within 1e-12 of the peak allowed for the sums' order)."""
    d = Drive(0.0255, 10.0, cycles=1, samples_per_cycle=200)
    base = {"integrator": integrator, "timestep": timestep}
    ref = MujocoEngine().run(P, d, {**base, "passive": "python", "step_loop": "python"})
    for mode in ({"passive": "compiled", "step_loop": "python"}, {"passive": "compiled", "step_loop": "native"}):
        r = MujocoEngine().run(P, d, {**base, **mode})
        for col in ("F", "cap_z", "wall_z", "spring_zeta", "wire0_stress"):
            scale = np.max(np.abs(ref[col]))
            assert np.max(np.abs(r[col] - ref[col])) <= 1e-12 * scale, (mode, col)
        assert r.stats["tracking_error"] == pytest.approx(ref.stats["tracking_error"], rel=1e-9, abs=1e-15)
    assert mujoco.get_mjcb_passive() is None


def test_bad_loop_settings_are_refused():
    d = Drive(0.001, 50.0, cycles=1, samples_per_cycle=100)
    with pytest.raises(ParameterError, match="mujoco.passive"):
        MujocoEngine().run(P, d, {"passive": "fortran"})
    with pytest.raises(ParameterError, match="needs passive = compiled"):
        MujocoEngine().run(P, d, {"passive": "python", "step_loop": "native"})


def test_native_run_takes_a_per_rope_stiffness():
    """A modelling error in one rope's stiffness (engines/perturb.py) runs in the C callback (each rope's
    stiffness in mjData.userdata), as the Python callback does it: measured 2.9e-12 of the peak apart
    (Euler, 10 000 steps of sums in another order; the nominal run is within 1e-12, the test above),
    while the error itself moves the force by ~6e-3 of the peak. It used to raise in pack_userdata."""
    d = Drive(0.0255, 10.0, cycles=1, samples_per_cycle=200)
    stiffer = {"integrator": "Euler", "timestep": 2e-5, "perturb": {"what": "rope_stiffness", "index": 0, "by": 0.05}}
    ref = MujocoEngine().run(P, d, {**stiffer, "passive": "python", "step_loop": "python"})
    r = MujocoEngine().run(P, d, stiffer)
    scale = np.max(np.abs(ref["F"]))
    assert np.max(np.abs(r["F"] - ref["F"])) <= 1e-11 * scale
    nominal = MujocoEngine().run(P, d, {"integrator": "Euler", "timestep": 2e-5})
    assert np.max(np.abs(r["F"] - nominal["F"])) > 1e-3 * scale
