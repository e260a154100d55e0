"""The Exudyn builder (comparisons/builders/exudyn.py) on the description features of the seismic mode:
a ground-acceleration excitation, per-direction points elements, planar_translation joints and a
line element whose points coincide (a stop at rest). Real Exudyn runs against closed forms and the
in-house builder."""
from __future__ import annotations

import tomllib

import numpy as np

from comparisons.builders import exudyn as exudyn_builder
from nsd_core.model import semirecursive
from nsd_core.model.load import load_model, parse_model
from tests.conftest import ROOT
from tests.test_model_exudyn import richardson_check

MASS, K, C = 2.0, 800.0, 4.0          # kg, N/m, N s/m
A, F = 2.0, 3.0                       # the ground's acceleration amplitude [m/s^2] and frequency [Hz]
AZIMUTH = np.radians(30.0)
X0 = 0.5                              # m: the x spring's neutral offset (p_b's x on the ground)

# one body sliding in the ground plane (planar_translation): along x a per-direction spring between
# points that are neither at the body's centre nor level (only the x offset enters), along y a joint
# law; the ground accelerates A sin(2 pi F t) at 30 degrees in plan
SDOF = f'''
[model]
name = "sdof_excited"
gravity = [0.0, 0.0, -9.81]
[excitation]
type = "ground_acceleration"
ground = "harmonic:amplitude={A},frequency={F},azimuth=30,duration=10"
[[bodies]]
name = "m"
joint = {{ type = "planar_translation", position = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}
mass = {MASS}
inertia = [0.1, 0.1, 0.1]
[[forces]]
name = "sx"
law = "linear_spring_damper"
body_a = "m"
point_a = [0.0, 0.0, 0.3]
body_b = "ground"
point_b = [{X0}, 0.2, 0.0]
direction = [1.0, 0.0, 0.0]
parameters = {{ stiffness = {K}, damping = {C}, free_length = 0.0 }}
[[forces]]
name = "sy"
law = "joint_spring_damper"
joint = "m"
dof = 1
parameters = {{ stiffness = {K}, damping = {C} }}
[[outputs]]
name = "x"
kind = "coordinate"
joint = "m"
dof = 0
[[outputs]]
name = "y"
kind = "coordinate"
joint = "m"
dof = 1
[[outputs]]
name = "sx_tension"
kind = "force"
element = "sx"
'''


def forced_response(t, a, x0):
    """x(t) of m x'' + c x' + k x = -m a sin(w t), x(0) = x0, x'(0) = 0 (closed form: the steady
    response as a complex amplitude, plus the damped free vibration that meets the initial state)."""
    w, wn2, cm = 2.0 * np.pi * F, K / MASS, C / MASS
    Z = -a / (wn2 - w * w + 1j * w * cm)
    xp = np.imag(Z * np.exp(1j * w * t))
    s, wd = cm / 2.0, np.sqrt(wn2 - cm * cm / 4.0)
    c1 = x0 - np.imag(Z)
    c2 = (-np.imag(1j * w * Z) + s * c1) / wd
    return xp + np.exp(-s * t) * (c1 * np.cos(wd * t) + c2 * np.sin(wd * t))


def test_excitation_and_direction_element_follow_the_closed_form_at_second_order():
    """x: the direction element, x = (p_a - p_b) . e_x = q_x - X0, pulls the body back to X0 (its
    tension acts as -T e on a); y: a joint law on the planar_translation's v. Each coordinate is a
    forced damped oscillator under -m a_g(t); the errors fall 4x per halving (the excitation applied
    at the step's end, where generalized-alpha solves the equations of motion)."""
    model = parse_model(tomllib.loads(SDOF))
    errors = []
    for h in (2e-3, 1e-3, 5e-4):
        run = exudyn_builder.simulate(model, 2.0, 0.01, {"step_size": h})
        x = X0 + forced_response(run.t, A * np.cos(AZIMUTH), -X0)
        y = forced_response(run.t, A * np.sin(AZIMUTH), 0.0)
        assert run.outputs["sx_tension"][0] == K * (0.0 - X0)   # N: x = (p_a - p_b) . e at rest, not the distance
        errors.append((np.max(np.abs(run.outputs["x"] - x)), np.max(np.abs(run.outputs["y"] - y))))
    errors = np.array(errors)
    assert np.max(np.abs(x - X0)) > 0.4 and np.max(np.abs(y)) > 0.01        # m: the response is there
    assert np.all(errors[-1] < 1e-4), errors                                # m
    assert np.all(np.log2(errors[1:-1] / errors[2:]) > 1.8), errors         # measured 2.00, 2.00


def test_zero_length_stop_is_finite_and_acts_past_its_gap():
    """A hunt_crossley_stop between the body's centre and the ground's, coinciding at rest: no force
    and no NaN at zero length; once the ground's motion carries the body past the gap it holds it,
    as the in-house builder does."""
    stop = '''
[[forces]]
name = "stop"
law = "hunt_crossley_stop"
body_a = "m"
body_b = "ground"
parameters = { gap = 0.02, stiffness = 1e6, exponent = 1.5, damping = 0.5 }
[[outputs]]
name = "stop_force"
kind = "force"
element = "stop"
scale = 100.0
'''
    model = parse_model(tomllib.loads(SDOF.replace("point_b = [0.5, 0.2, 0.0]", "point_b = [0.0, 0.2, 0.0]") + stop))
    run = exudyn_builder.simulate(model, 1.0, 0.01, {"step_size": 5e-4})
    exact = semirecursive.simulate(model, 1.0, 0.01, {"rtol": 1e-11, "atol": 1e-13})
    assert all(np.all(np.isfinite(v)) for v in run.outputs.values())
    force = run.outputs["stop_force"]
    assert force[0] == 0.0
    assert np.max(force) > 1.0                                               # N: it engages
    assert np.max(np.hypot(run.outputs["x"], run.outputs["y"])) < 0.03      # m: held near the gap
    for name in ("x", "y"):
        assert np.max(np.abs(run.outputs[name] - exact.outputs[name])) < 1e-3 * np.max(np.abs(exact.outputs[name]))


def test_seismic_description_within_three_times_its_richardson_estimate():
    """models/nsd_seismic.toml (planar plate, the device on it, harmonic ground), 0.4 s at h = 1e-3
    and 5e-4 s against the in-house builder: every output within 3x Exudyn's own estimate; the
    plate's motion converges at second order (the device's internal forces sit at ~1e-4 of their
    peaks at both steps: the in-house run keeps the ~250 Hz vertical mode's ringing, which
    generalized-alpha damps), and every estimate is within the 1e-3 tolerance."""
    model = load_model(ROOT / "models" / "nsd_seismic.toml")
    exact = semirecursive.simulate(model, 0.4, 0.002, {"rtol": 1e-11, "atol": 1e-13})
    errors = richardson_check(model, 0.4, 0.002, 1e-3, exact, ordered=("u_x", "u_y", "support_x"))
    assert all(e[2] < 1e-3 for e in errors.values()), errors


def test_compiled_forces_are_the_connectors_equations():
    """forces = "compiled" (one object, compiled kernels) and "connectors" (one connector per element)
    solve the same discrete equations: on the seismic description (planar joint laws incl. a turn,
    line elements with states) and the excited oscillator (a direction element, a planar_translation
    law) they agree far inside Exudyn's own error estimate (measured ~1e-13 of the peaks)."""
    for model, duration, dt_out in ((load_model(ROOT / "models" / "nsd_seismic.toml"), 0.2, 0.002),
                                    (parse_model(tomllib.loads(SDOF)), 1.0, 0.01)):
        a = exudyn_builder.simulate(model, duration, dt_out, {"step_size": 1e-3, "forces": "connectors"})
        b = exudyn_builder.simulate(model, duration, dt_out, {"step_size": 1e-3, "forces": "compiled"})
        for o in model.outputs:
            scale = o.scale or float(np.max(np.abs(a.outputs[o.name])))
            assert np.max(np.abs(a.outputs[o.name] - b.outputs[o.name])) < 1e-9 * scale, o.name
