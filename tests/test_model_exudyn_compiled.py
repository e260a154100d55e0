"""The Exudyn builder's compiled force paths (comparisons/builders/exudyn_compiled.py and
exudyn_codegen.py): the generated module per set of laws and its cache key, its Jacobian against a
central difference, the "compiled" path against the "connectors" reference on the device's drive
description, and the "predicted" path (forces once a step at the predicted end) against the in-house
builder at second order."""
from __future__ import annotations

import numpy as np

from comparisons.builders import exudyn as exudyn_builder
from comparisons.builders import exudyn_codegen, generated
from comparisons.builders.exudyn import Build, check_settings
from nsd_core.model import semirecursive
from nsd_core.model.load import load_model
from tests.conftest import ROOT


def _build(path: str, h: float = 1e-3) -> Build:
    model = load_model(ROOT / "models" / path)
    return Build(model, check_settings({"step_size": h}, model), h)


def test_generated_module_is_keyed_by_its_laws_not_the_model():
    """The generated module names laws and nothing of the model: the device's drive, its seismic model
    and its building (other bodies, elements and counts) share one module, and a parameter or step
    change is data. The file's name is the hash of its source and of the law sources it calls; a
    description whose laws come from another module (the isolators' plane law) gets another."""
    a, b = _build("nsd_drive.toml").compiled, _build("nsd_drive.toml", 5e-4).compiled
    assert a.gen is b.gen
    assert a.F[a.F.size - 1] == 1e-3 and b.F[b.F.size - 1] == 5e-4   # the step is data, not code
    laws = generated.law_set(a.elements)
    assert {"rope", "sma_wire", "push_spring", "hunt_crossley_stop", "linear_spring_damper",
            "joint_spring_damper"} <= {law.name for law in laws}
    text, bound = exudyn_codegen.source(laws)
    key = exudyn_codegen.fingerprint(text, bound)
    assert (generated.folder() / f"exudyn_forces_{key}.py").read_text() == text
    assert exudyn_codegen.fingerprint(text + "\n", bound) != key
    seismic, building = _build("nsd_seismic.toml").compiled, _build("nsd_building.toml").compiled
    assert seismic.gen is a.gen and building.gen is a.gen
    assert len(building.elements) != len(a.elements) != len(seismic.elements)
    mechanism = _build("fourbar_spring.toml").compiled   # the model layer's laws alone: a smaller module
    assert {law.name for law in generated.law_set(mechanism.elements)} < {law.name for law in laws}
    assert mechanism.gen is not a.gen


def test_compiled_jacobian_is_the_force_functions_derivative():
    """jacobian(q, q') = -(fq df/dq + fv df/dq') of ``evaluate``, against a central difference, at a
    displaced state of the seismic description (points elements with states, joint laws, a turn)."""
    cf = _build("nsd_seismic.toml").compiled
    rng = np.random.default_rng(1)
    n = 7 * len(cf.bodies)
    q, v = 1e-3 * rng.standard_normal(n), 1e-2 * rng.standard_normal(n)
    J = cf.gen.jacobian(q, v, cf.F, cf.I, cf.W.copy(), 2.0, 0.5, np.zeros((n, n)))
    f = lambda q_, v_: cf.gen.evaluate(q_, v_, cf.F, cf.I, cf.W.copy(), np.zeros(n)).copy()  # noqa: E731
    ref = np.zeros((n, n))
    for i in range(n):
        d = 1e-6 * max(1e-2, abs(q[i]))
        e = np.zeros(n)
        e[i] = d
        ref[:, i] -= 2.0 * (f(q + e, v) - f(q - e, v)) / (2 * d)
        d = 1e-6 * max(1e-2, abs(v[i]))
        e[i] = d
        ref[:, i] -= 0.5 * (f(q, v + e) - f(q, v - e)) / (2 * d)
    assert np.max(np.abs(J - ref)) < 1e-5 * np.max(np.abs(ref))


def test_compiled_forces_agree_with_the_connectors_on_the_drive():
    """forces = "compiled" and "connectors" solve the same equations on models/nsd_drive.toml (cap,
    wall, rod; ropes, SMA wires with their states, the push spring): every output within 1e-8 of its
    peak (Newton's tolerance; their Jacobians differ), far inside Exudyn's estimate (~1e-4)."""
    model = load_model(ROOT / "models" / "nsd_drive.toml")
    a = exudyn_builder.simulate(model, 0.2, 0.002, {"step_size": 1e-3, "forces": "connectors"})
    b = exudyn_builder.simulate(model, 0.2, 0.002, {"step_size": 1e-3, "forces": "compiled"})
    for o in model.outputs:
        scale = o.scale or float(np.max(np.abs(a.outputs[o.name])))
        assert np.max(np.abs(a.outputs[o.name] - b.outputs[o.name])) < 1e-8 * scale, o.name


def test_predicted_forces_within_their_estimate_at_second_order():
    """forces = "predicted" on models/nsd_drive.toml, 0.1 s at h = 2.5e-4 and 1.25e-4 s (the gate's
    1 Hz step; explicit in the forces, it is not stable at 1e-3 s, where the ~250 Hz mode has
    omega h = 1.6): every output within 3x its own Richardson estimate of the in-house builder's
    (rtol 1e-10), the drive force's error falling at second order, and within 1e-5 of the implicit
    "compiled" path's peak at h."""
    model = load_model(ROOT / "models" / "nsd_drive.toml")
    exact = semirecursive.simulate(model, 0.1, 0.002, {"rtol": 1e-10, "atol": 1e-12})
    h = 2.5e-4
    coarse = exudyn_builder.simulate(model, 0.1, 0.002, {"step_size": h, "forces": "predicted"})
    fine = exudyn_builder.simulate(model, 0.1, 0.002, {"step_size": h / 2, "forces": "predicted"})
    implicit = exudyn_builder.simulate(model, 0.1, 0.002, {"step_size": h})
    for o in model.outputs:
        y, y2, ref = coarse.outputs[o.name], fine.outputs[o.name], exact.outputs[o.name]
        scale = o.scale or float(np.max(np.abs(ref)))
        err, err2 = np.max(np.abs(y - ref)), np.max(np.abs(y2 - ref))
        estimate = np.max(np.abs(y - y2)) * 4.0 / 3.0
        assert err <= 3.0 * estimate + 1e-12 * scale, (o.name, err / scale, estimate / scale)
        assert estimate < 1e-3 * scale, o.name
        # measured 3.4e-6 (F_x); a law's state is the integral of its rate along each path's own motion, so
        # the two schemes' difference accumulates: spring_zeta 1.1e-5 of its peak after 0.1 s (both within
        # 3x their own estimates of the in-house reference, checked above)
        close = 2e-5 if o.kind == "state" else 1e-5
        assert np.max(np.abs(y - implicit.outputs[o.name])) < close * scale, o.name
        if o.name == "F_x":
            assert np.log2(err / err2) > 1.7, (err / scale, err2 / scale)
