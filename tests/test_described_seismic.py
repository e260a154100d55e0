"""The peers' seismic mode built from the device's description (comparisons/engines/described_seismic.py)
against the in-house engine: real MuJoCo and Exudyn on short record windows."""
from __future__ import annotations

import numpy as np
import pytest

from comparisons.engines import run_seismic_engine
from comparisons.engines.base import EngineError
from comparisons.engines.described_seismic import DescribedSeismic, ground_table
from comparisons.seismic import gate_metrics, own_seismic_metrics
from nsd_core.structure.describe_seismic import structure_for
from nsd_core.ground.motions import parse_ground_spec
from nsd_core.ground.records import fema_record
from nsd_core.device.params import ParameterError, Params
from nsd_core.structure.seismic import simulate_seismic

STEPS = {"mujoco": {"timestep": 2e-5}, "exudyn": {"step_size": 1e-4}}   # the gate's seismic cases' steps


@pytest.fixture(scope="module")
def pulse():
    """The gate's first seismic window, shortened: record seconds 4.8-5.1 (0.095 model s)."""
    return fema_record("nearfield-pulse", 1, scale=0.4, window=(4.8, 5.1), rotate_deg=20)


@pytest.mark.parametrize("engine", ["mujoco", "exudyn"])
def test_columns_and_units_are_the_in_house_ones(engine):
    """A 2-story building with the restrainer: every column the gate reads (floors, drifts, story shears,
    restrainer, the energy balance) in the in-house run's unit, and near its values."""
    p = Params()
    st = structure_for(p, 2, True)
    ground = fema_record("farfield", 1, window=(3.0, 3.05))
    a = simulate_seismic(p, st, ground, dt_out=1e-3, rtol=1e-10, atol=1e-13)
    d = run_seismic_engine(engine, p, st, ground, None, 1e-3, STEPS[engine])
    assert d.stats["model"] == "described" and np.array_equal(d["t"], a["t"])
    for c in ("x", "y", "floor2_x", "drift1_y", "story_shear1_x", "device_Fx", "base_shear_y", "restrainer_F",
              "E_input", "E_device", "E_building_stored"):
        assert d.units[c] == a.units[c], c
        # an energy against the energy put in (the device's own is ~1e-5 J here, 1e-3 of E_input)
        scale = float(np.max(np.abs(a["E_input" if c.startswith("E_") else c])))
        assert np.max(np.abs(d[c] - a[c])) <= 2e-2 * scale, c


@pytest.fixture(scope="module")
def reference(pulse):
    return simulate_seismic(Params(), structure_for(Params()), pulse, dt_out=1e-3, rtol=1e-10, atol=1e-13)


@pytest.mark.parametrize("engine, bounds", [
    # measured on this window (peak |u| 2.5 mm): MuJoCo Euler 2e-5 s du 2.9e-4, dF 1.1e-3, peak u 2.9e-4,
    # peak a 1.1e-4 (its adapter's to 3 digits); Exudyn 1e-4 s 2.4e-6, 6.9e-6, 1.6e-7, 1.8e-7 (its adapter's
    # 2.4e-6, 6.2e-6, 2.0e-7, 1.1e-6). Bounds: ~3x those (the cap's mass left out of Newton's law: dF 1e-3).
    # The energy balance (of max E_input): own residual MuJoCo 3.6e-4, Exudyn 1.0e-6; E_input against the
    # in-house one 4.1e-5, 7.0e-6
    ("mujoco", {"max_du_rel": 1e-3, "max_dF_device_rel": 3.5e-3, "peak_u_rel": 1e-3, "peak_a_rel": 4e-4,
                "energy_residual_rel": 1.2e-3, "dE_input": 1.5e-4}),
    ("exudyn", {"max_du_rel": 8e-6, "max_dF_device_rel": 2e-5, "peak_u_rel": 1e-6, "peak_a_rel": 1e-6,
                "energy_residual_rel": 3e-6, "dE_input": 2e-5}),
])
def test_described_agrees_with_the_in_house_engine(engine, bounds, pulse, reference):
    """The gate's seismic metrics of the described run against the in-house engine at rtol 1e-10: the
    device force from Newton's law on the plate and cap (the module's docstring) included."""
    d = run_seismic_engine(engine, Params(), structure_for(Params()), pulse, None, 1e-3, STEPS[engine])
    m = {**gate_metrics(reference, d), **own_seismic_metrics(d),
         "dE_input": float(np.max(np.abs(d["E_input"] - reference["E_input"])) / np.max(np.abs(reference["E_input"])))}
    for k, bound in bounds.items():
        assert m[k] <= bound, (k, m[k])
    for c in ("cap_z", "wall_z"):   # the device's heights, m (measured: 6e-8 MuJoCo, 5e-11 Exudyn)
        assert np.max(np.abs(d[c] - reference[c])) < 2e-7, c


def test_device_force_is_the_in_house_sign(pulse, reference):
    """device_F is the force the plate applies to the device: with the supports' its sum is the base
    shear, and it points as the in-house engine's (not its negative)."""
    p = Params()
    d = DescribedSeismic("exudyn").run_seismic(p, structure_for(p), pulse, None, 1e-3, STEPS["exudyn"])
    assert np.allclose(d["base_shear_x"], d["support_Fx"] + d["device_Fx"], rtol=0, atol=1e-9)
    F, F_ref = d["device_Fx"], reference["device_Fx"]
    assert float(np.dot(F, F_ref)) > 0.99 * float(np.dot(F_ref, F_ref))


def test_ground_is_written_exactly(pulse):
    """A record becomes [excitation].record, a closed form its text; each parses to the same block."""
    assert ground_table(pulse) == {"set": "nearfield-pulse", "id": 1, "scale": 0.4,
                                   "time_factor": pulse.meta["time_factor"], "window": [4.8, 5.1], "rotate": 20.0}
    for text in ("harmonic:amplitude=0.3,frequency=2,azimuth=30,duration=0.01",
                 "pulse:velocity=0.1,frequency=2,gamma=2.5,phase=10,azimuth=-40"):
        assert parse_ground_spec(ground_table(parse_ground_spec(text))).block().tolist() == \
            parse_ground_spec(text).block().tolist()


@pytest.mark.parametrize("engine, value", [("mujoco", "describd"), ("exudyn", 3), ("mujoco", "adapter")])
def test_bad_model_is_one_line(engine, value, pulse):
    with pytest.raises(ParameterError) as e:
        run_seismic_engine(engine, Params(), structure_for(Params()), pulse, 0.01, 1e-3, {"model": value})
    msg = str(e.value)
    assert "\n" not in msg and f"{engine}.model = {value!r}" in msg and "allowed: described" in msg


def test_ground_an_excitation_cannot_write_is_refused():
    raw = fema_record("nearfield-pulse", 1, window=(4.8, 4.9), normalised=False)
    with pytest.raises(EngineError, match="normalised"):
        DescribedSeismic("mujoco").run_seismic(Params(), structure_for(Params()), raw, None, 1e-3, STEPS["mujoco"])


@pytest.mark.parametrize("perturb", [{"what": "cap_mass", "by": 0.05}, {"what": "isolated_mass", "by": 0.02},
                                     {"what": "rod_length", "by": 5e-4}])
def test_an_injected_modelling_error_reaches_the_described_seismic_model(pulse, perturb):
    """The gate's detection power injects an error into one peer's model: the described seismic model
    carries it (the device's geometry, the isolated mass): it moves the plate or the device force. Where the
    error is a parameter of the case (a longer rod, a heavier structure), MuJoCo's perturbed run is its run
    with that parameter changed, to round-off. (A heavier cap is not: the injected error leaves the rest
    state computed with the nominal cap, a model inconsistent with itself as a slip would be.)"""
    import dataclasses
    p, st = Params(), structure_for(Params())
    what, by = perturb["what"], perturb["by"]
    p2 = p.replace(rod_length=p.rod_length + by) if what == "rod_length" else p
    st2 = dataclasses.replace(st, mass=st.mass * (1 + by)) if what == "isolated_mass" else st
    nominal, moved = (run_seismic_engine("mujoco", p, st, pulse, None, 1e-3, {**STEPS["mujoco"], **extra})
                      for extra in ({}, {"perturb": perturb}))
    changed = run_seismic_engine("mujoco", p2, st2, pulse, None, 1e-3, STEPS["mujoco"])
    visible = []
    for cols in (("x", "y"), ("device_Fx", "device_Fy")):
        peak = np.max(np.hypot(*(nominal[c] for c in cols)))
        shift = np.max(np.hypot(*(moved[c] - nominal[c] for c in cols)))
        if what != "cap_mass":
            assert np.max(np.hypot(*(moved[c] - changed[c] for c in cols))) < 1e-9 * peak, cols
        visible.append(shift > 1e-4 * peak)
    assert any(visible)   # the error shows at all (a 5 % heavier cap barely moves the plate, but its force)
