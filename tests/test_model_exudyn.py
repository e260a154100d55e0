"""The Exudyn builder (comparisons/builders/exudyn.py) against independent solutions: the in-house
builder (minimal coordinates, adaptive, tight tolerances), the test set's reference for Andrews'
mechanism and IFToMM A02, the exact pendulum of IFToMM A01, forces held by hand-derived reactions,
force laws registered only here (one with an internal state), and the device's own description."""
from __future__ import annotations

import csv

import numpy as np
import pytest
from numba import njit

from comparisons.builders import exudyn as exudyn_builder
from comparisons.engines.base import EngineError
from nsd_core.engine.problems.iftomm import pendulum_exact
from nsd_core.model import semirecursive
from nsd_core.model.errors import ModelError
from nsd_core.model.laws import JOINT, LAWS, POINTS, Law, LawParameter, StateSpec, register
from nsd_core.model.load import load_model, parse_model
from tests.conftest import ROOT

TIGHT = {"rtol": 1e-11, "atol": 1e-13}


def test_andrews_within_three_times_its_richardson_estimate():
    """At h = 2.5e-5 s (4 steps per output), each output's distance to the in-house solution is within
    3x Exudyn's own estimate (h and h/2, order 2), and so is the end state to the test set's."""
    model = load_model(ROOT / "models" / "andrews.toml")
    h = 2.5e-5
    coarse = exudyn_builder.simulate(model, 0.03, 1e-4, {"step_size": h})
    fine = exudyn_builder.simulate(model, 0.03, 1e-4, {"step_size": h / 2})
    exact = semirecursive.simulate(model, 0.03, 1e-4, TIGHT)
    with open(ROOT / "models" / "andrews_reference.csv") as f:
        reference = {k: float(v) for k, v in next(csv.DictReader(f)).items()}
    assert coarse.stats["closure_max"] < 1e-9
    for name, y in coarse.outputs.items():
        estimate = np.abs(y - fine.outputs[name]) * 4.0 / 3.0   # the error of y: (y_h - y_h/2) 2^p / (2^p - 1)
        peak = np.max(np.abs(exact.outputs[name]))
        assert np.max(estimate) < 1e-3 * peak, name               # the step is right for the tolerance
        assert np.all(np.abs(y - exact.outputs[name]) <= 3 * estimate + 1e-12 * peak), name
        if name in reference:
            assert abs(y[-1] - reference[name]) <= 3 * estimate[-1] + 1e-9, name


def test_a01_pendulum_follows_the_exact_solution():
    model = load_model(ROOT / "models" / "iftomm_a01_pendulum.toml")
    run = exudyn_builder.simulate(model, 20.0, 0.5, {"step_size": 1e-3})
    exact = pendulum_exact(run.t)
    assert np.max(np.abs(run.outputs["P1_x"] - exact[:, 0])) < 5e-4   # m, of a 1 m link (measured 2.5e-4)
    assert np.max(np.abs(run.outputs["P1_y"] - exact[:, 1])) < 5e-4
    # released at rest at y = 0: kinetic energy = m g (0 - y)
    assert np.max(np.abs(run.outputs["kinetic"] - 9.81 * -exact[:, 1])) < 5e-3


def test_slider_crank_drive_torque_has_the_in_house_sign():
    model = load_model(ROOT / "models" / "slider_crank.toml")
    run = exudyn_builder.simulate(model, 0.1, 0.002, {"step_size": 1e-4})
    exact = semirecursive.simulate(model, 0.1, 0.002, TIGHT)
    torque = exact.outputs["drive_torque"]
    assert np.max(np.abs(torque)) > 5.0                         # N m: the drive works against inertia
    assert np.max(np.abs(run.outputs["drive_torque"] - torque)) < 1e-3 * np.max(np.abs(torque))
    assert run.stats["tracking_error"] < 1e-12 and run.stats["closure_max"] < 1e-12


@njit(cache=False)
def cubic_spring(x, xd, p):
    """T = k3 (L - L0)^3 + c L': a hardening strut (registered by this test only)."""
    return p[0] * (x - p[1]) ** 3 + p[2] * xd


@njit(cache=False)
def cubic_torsion(x, xd, p):
    """Q = -k3 (q - q0)^3: a hardening torsion spring (registered by this test only)."""
    return -p[0] * (x - p[1]) ** 3


@pytest.fixture
def new_laws():
    laws = [Law("test_cubic_spring", POINTS, (LawParameter("k3", "N/m^3", 0.0), LawParameter("free_length", "m", 0.0),
                                              LawParameter("damping", "N s/m", 0.0, default=0.0)),
                cubic_spring, cubic_spring.py_func.__doc__),
            Law("test_cubic_torsion", JOINT, (LawParameter("k3", "N m/rad^3", 0.0), LawParameter("neutral", "rad", -np.inf)),
                cubic_torsion, cubic_torsion.py_func.__doc__)]
    for law in laws:
        register(law)
    yield
    for law in laws:
        LAWS.pop(law.name)


BODY = {"mass": 2.0, "com": [0.1, 0.0, 0.0], "inertia": [0.01, 0.02, 0.03]}


def test_a_law_registered_elsewhere_reaches_exudyn(new_laws):
    """A slider on a cubic strut and a wheel on a cubic torsion spring, started past +pi (the
    connector's turn count), laws unknown to the builder: Exudyn agrees with the in-house builder."""
    raw = {"bodies": [{"name": "slider", "joint": {"type": "prismatic", "axis": [1.0, 0.0, 0.0]}, **BODY},
                      {"name": "wheel", "joint": {"type": "revolute", "position": [0.0, 1.0, 0.0], "axis": [0.0, 0.0, 1.0]}, **BODY}],
           "forces": [{"name": "strut", "law": "test_cubic_spring", "body_a": "ground", "point_a": [-0.5, 0.0, 0.0],
                       "body_b": "slider", "parameters": {"k3": 2.0e4, "free_length": 0.5, "damping": 1.0}},
                      {"name": "torsion", "law": "test_cubic_torsion", "joint": "wheel",
                       "parameters": {"k3": 0.5, "neutral": 3.0}}],
           "initial": {"coordinates": {"slider": 0.1, "wheel": 4.0}},
           "outputs": [{"name": "x", "kind": "coordinate", "joint": "slider"},
                       {"name": "angle", "kind": "coordinate", "joint": "wheel"},
                       {"name": "T", "kind": "force", "element": "strut"},
                       {"name": "Q", "kind": "force", "element": "torsion"},
                       {"name": "v", "kind": "point_velocity", "body": "slider", "component": "x"},
                       {"name": "E", "kind": "energy", "term": "kinetic"}]}
    model = parse_model(raw, "cubic")
    run = exudyn_builder.simulate(model, 1.0, 0.01, {"step_size": 2.5e-4})
    exact = semirecursive.simulate(model, 1.0, 0.01, TIGHT)
    for name, y in exact.outputs.items():
        peak = np.max(np.abs(y))
        assert np.ptp(y) > 0.1 * peak, name                      # every output moves: the laws act
        assert np.max(np.abs(run.outputs[name] - y)) < 2e-3 * peak, name
    assert run.outputs["angle"][0] == pytest.approx(4.0, abs=1e-12)


def test_bad_settings_are_one_line_model_errors():
    model = load_model(ROOT / "models" / "iftomm_a01_pendulum.toml")
    with pytest.raises(ModelError, match=r"exudyn\.stepsize: unknown setting; allowed: step_size, solver"):
        exudyn_builder.simulate(model, 0.1, 0.01, {"stepsize": 1e-3})
    with pytest.raises(ModelError, match=r"exudyn\.spectral_radius = 1\.5: must be < 1"):
        exudyn_builder.simulate(model, 0.1, 0.01, {"spectral_radius": 1.5})
    with pytest.raises(ModelError, match=r"exudyn\.solver = 'rk4': allowed: generalized_alpha, trapezoidal_index2"):
        exudyn_builder.simulate(model, 0.1, 0.01, {"solver": "rk4"})
    with pytest.raises(ModelError, match=r"exudyn\.on_newton_failure = 'retry': allowed: relax, fail$"):
        exudyn_builder.simulate(model, 0.1, 0.01, {"on_newton_failure": "retry"})


def test_bricard_redundant_closure_found_and_solved():
    """IFToMM A04: Exudyn's rank test finds the one redundant equation; the full-pivot LU then runs
    the 5 s case within 1e-4 m of the in-house solution (measured 3e-6 at h = 1e-3 s)."""
    model = load_model(ROOT / "models" / "iftomm_a04_bricard.toml")
    run = exudyn_builder.simulate(model, 5.0, 0.05, {"step_size": 1e-3})
    exact = semirecursive.simulate(model, 5.0, 0.05, TIGHT)
    assert run.stats["redundant_found"] == 1
    for name in ("P3_x", "P3_y", "P3_z"):
        assert np.max(np.abs(run.outputs[name] - exact.outputs[name])) < 1e-4, name
    assert run.stats["closure_max"] < 1e-9


def richardson_check(model, duration, dt_out, h, exact, ordered=None, min_order=1.7):
    """Exudyn at h and h/2 against ``exact`` (the in-house run): per output, the largest error at h is
    within 3x Exudyn's own Richardson estimate (order 2) of it, and the errors of the ``ordered``
    outputs (default all) fall as an order of at least ``min_order`` (a state integrated at first
    order, or a force at a lagged state, falls 2x). Outputs with a stated scale are judged on it (a
    force that is zero up to round-off). Returns {output: (error at h, at h/2, estimate)} over the scale."""
    coarse = exudyn_builder.simulate(model, duration, dt_out, {"step_size": h})
    fine = exudyn_builder.simulate(model, duration, dt_out, {"step_size": h / 2})
    out = {}
    for o in model.outputs:
        y, y2, ref = coarse.outputs[o.name], fine.outputs[o.name], exact.outputs[o.name]
        scale = o.scale or float(np.max(np.abs(ref)))
        err, err2 = np.max(np.abs(y - ref)), np.max(np.abs(y2 - ref))
        estimate = np.max(np.abs(y - y2)) * 4.0 / 3.0
        assert err <= 3.0 * estimate + 1e-12 * scale, (o.name, err / scale, estimate / scale)
        if ordered is None or o.name in ordered:
            assert np.log2(err / err2) > min_order, (o.name, err / scale, err2 / scale)
        out[o.name] = (err / scale, err2 / scale, estimate / scale)
    return out


@njit(cache=False)
def maxwell_tension(x, xd, s, p):
    """T = s: a Maxwell strut's tension is its state (registered by this test only)."""
    return s


@njit(cache=False)
def maxwell_tension_rate(x, xd, s, p):
    """dT/dt = k (L' - T / c): a spring k in series with a dashpot c."""
    return p[0] * (xd - s / p[1])


@njit(cache=False)
def maxwell_joint(x, xd, s, p):
    """Q = s: a Maxwell element on a joint coordinate (registered by this test only)."""
    return s


@njit(cache=False)
def maxwell_joint_rate(x, xd, s, p):
    """dQ/dt = -k (q' + Q / c): it resists the coordinate's motion and relaxes with c / k."""
    return -p[0] * (xd + s / p[1])


@pytest.fixture
def maxwell_laws():
    params = (LawParameter("stiffness", "N/m", 0.0), LawParameter("damping", "N s/m", 0.0),
              LawParameter("initial", "N", -np.inf, default=0.0))
    laws = [Law("test_maxwell_strut", POINTS, params, maxwell_tension, maxwell_tension.py_func.__doc__,
                StateSpec("tension", "N", "initial"), maxwell_tension_rate),
            Law("test_maxwell_joint", JOINT, params, maxwell_joint, maxwell_joint.py_func.__doc__,
                StateSpec("force", "N", "initial"), maxwell_joint_rate)]
    for law in laws:
        register(law)
    yield
    for law in laws:
        LAWS.pop(law.name)


def test_laws_with_a_state_reach_exudyn_at_second_order(maxwell_laws):
    """A block on a translational joint, held along x by a spring and a Maxwell strut (preloaded: its
    state starts at 30 N) and along y by a spring and a Maxwell element on the joint's y slide;
    laws and states unknown to the builder. Every output within 3x Exudyn's Richardson estimate of
    the in-house builder's, falling at second order."""
    raw = {"model": {"gravity": [0.0, 0.0, -9.81]},
           "bodies": [{"name": "block", "joint": {"type": "translational"}, **BODY}],
           "forces": [{"name": "spring_x", "law": "linear_spring_damper", "body_a": "ground", "point_a": [0.5, 0.0, 0.0],
                       "body_b": "block", "point_b": [0.1, 0.0, 0.0], "parameters": {"stiffness": 200.0, "free_length": 0.4}},
                      {"name": "strut", "law": "test_maxwell_strut", "body_a": "ground", "point_a": [-0.5, 0.0, 0.0],
                       "body_b": "block", "point_b": [0.1, 0.0, 0.0],
                       "parameters": {"stiffness": 300.0, "damping": 30.0, "initial": 30.0}},
                      {"name": "spring_y", "law": "joint_spring_damper", "joint": "block", "dof": 1,
                       "parameters": {"stiffness": 150.0}},
                      {"name": "maxwell_y", "law": "test_maxwell_joint", "joint": "block", "dof": 1,
                       "parameters": {"stiffness": 200.0, "damping": 10.0}},
                      {"name": "spring_z", "law": "joint_spring_damper", "joint": "block", "dof": 2,
                       "parameters": {"stiffness": 400.0, "damping": 2.0}}],
           "initial": {"coordinates": {"block": [0.02, 0.05, 0.0]}, "velocities": {"block": [0.0, 0.0, 0.3]}},
           "outputs": [{"name": "x", "kind": "coordinate", "joint": "block", "dof": 0},
                       {"name": "y", "kind": "coordinate", "joint": "block", "dof": 1},
                       {"name": "z", "kind": "coordinate", "joint": "block", "dof": 2},
                       {"name": "T", "kind": "force", "element": "strut"},
                       {"name": "Q", "kind": "force", "element": "maxwell_y"},
                       {"name": "vy", "kind": "point_velocity", "body": "block", "component": "y"}]}
    model = parse_model(raw, "maxwell")
    exact = semirecursive.simulate(model, 1.0, 0.01, TIGHT)
    for name, y in exact.outputs.items():
        assert np.ptp(y) > 0.1 * np.max(np.abs(y)), name        # every output moves: the states act
    assert exact.outputs["T"][0] == 30.0 and abs(exact.outputs["T"][-1]) < 10.0   # the preload relaxes
    errors = richardson_check(model, 1.0, 0.01, 2.5e-3, exact)
    assert max(e[0] for e in errors.values()) < 2e-3, errors


def test_slides_drive_force_has_the_in_house_sign():
    """A slider held on a prismatic joint against a constant +10 N law, and a block held on a
    translational joint against gravity along -x (2 kg, 9.81 m/s^2): the drives hold -10 N and
    +19.62 N (their generalized forces drive the coordinate up), as the in-house builder says."""
    held = {"motion": "constant_speed", "start": 0.0, "speed": 0.0}
    raw = {"model": {"gravity": [-9.81, 0.0, 0.0]},
           "bodies": [{"name": "slider", "joint": {"type": "prismatic", "axis": [0.0, 1.0, 0.0]}, **BODY},
                      {"name": "block", "joint": {"type": "translational", "position": [0.0, 0.0, 1.0]}, **BODY}],
           "forces": [{"name": "push", "law": "constant_force", "joint": "slider", "parameters": {"value": 10.0}}],
           "prescribed": [{"name": "hold_slider", "joint": "slider", **held},
                          {"name": "hold_x", "joint": "block", "dof": 0, **held}],
           "outputs": [{"name": "F_slider", "kind": "drive_force", "element": "hold_slider"},
                       {"name": "F_x", "kind": "drive_force", "element": "hold_x"}]}
    model = parse_model(raw, "held")
    run = exudyn_builder.simulate(model, 0.05, 0.01, {"step_size": 1e-3})
    exact = semirecursive.simulate(model, 0.05, 0.01, TIGHT)
    for name, value in (("F_slider", -10.0), ("F_x", 2.0 * 9.81)):
        assert np.allclose(run.outputs[name], value, atol=1e-6), name
        assert np.allclose(exact.outputs[name], value, atol=1e-6), name


def test_device_description_within_three_times_its_richardson_estimate():
    """models/nsd_drive.toml (translational cap with a prescribed X, Y; prismatic wall; universal rod;
    point closure; ropes, SMA wires and the push spring with their states), 0.1 s at h = 1e-3 and
    5e-4 s: every output against the in-house builder (rtol 1e-10). The drive force's error falls at
    second order; the positions' and the other forces' stay at ~4e-7 of their peaks at both steps (the
    in-house run keeps the ~250 Hz vertical mode's ringing, which generalized-alpha damps at these
    steps), below their estimates."""
    model = load_model(ROOT / "models" / "nsd_drive.toml")
    exact = semirecursive.simulate(model, 0.1, 0.002, {"rtol": 1e-10, "atol": 1e-12})
    errors = richardson_check(model, 0.1, 0.002, 1e-3, exact, ordered=("F_x",))
    assert errors["F_x"][0] < 1e-3, errors


@pytest.mark.slow
def test_device_description_case_at_the_reported_step():
    """The description's case (2 s at 1 Hz) at h = 1e-3 s: the drive force within 1e-3 of its peak
    of the in-house builder's (measured 3.5e-4; 1.4e-3 at 2e-3 s)."""
    model = load_model(ROOT / "models" / "nsd_drive.toml")
    run = exudyn_builder.simulate(model, 2.0, 0.002, {"step_size": 1e-3})
    exact = semirecursive.simulate(model, 2.0, 0.002, {"rtol": 1e-10, "atol": 1e-12})
    peak = np.max(np.abs(exact.outputs["F_x"]))
    assert peak > 500.0
    assert np.max(np.abs(run.outputs["F_x"] - exact.outputs["F_x"])) < 1e-3 * peak
    assert run.stats["closure_max"] < 1e-9 and run.stats["tracking_error"] < 1e-12


@pytest.mark.slow
def test_a02_passes_its_singular_positions_with_a_relaxed_newton():
    """IFToMM A02: at the default Newton tolerance Exudyn's Newton fails at a singular position; the
    builder reruns at the relaxed one and the 5 s case follows the reference within 3x its
    Richardson estimate (h = 1e-3, 5e-4 s)."""
    model = load_model(ROOT / "models" / "iftomm_a02_fourbar.toml")
    with open(ROOT / "models" / "iftomm_a02_reference.csv") as f:
        rows = [r for r in csv.DictReader(f) if float(r["t"]) <= 5.0 + 1e-9]
    coarse = exudyn_builder.simulate(model, 5.0, 0.05, {"step_size": 1e-3})
    fine = exudyn_builder.simulate(model, 5.0, 0.05, {"step_size": 5e-4})
    assert "solver failed" in coarse.stats["newton_relaxed_after"]
    assert coarse.stats["newton_rel_tol"] == exudyn_builder.RELAXED_REL_TOL
    for name in ("B0_x", "B0_y", "B0_vx", "B0_vy"):
        ref = np.array([float(r[name]) for r in rows])
        estimate = np.max(np.abs(coarse.outputs[name] - fine.outputs[name])) * 4.0 / 3.0
        assert np.max(np.abs(coarse.outputs[name] - ref)) <= 3.0 * estimate, name
        assert estimate < 2e-3, name
    with pytest.raises(EngineError, match=r"solver failed in step \d+ of 5000"):
        exudyn_builder.simulate(model, 5.0, 0.05, {"step_size": 1e-3, "on_newton_failure": "fail"})


def test_joint_law_on_a_universal_turn_is_a_one_line_model_error():
    raw = {"bodies": [{"name": "arm", "joint": {"type": "universal"}, **BODY}],
           "forces": [{"name": "k", "law": "joint_spring_damper", "joint": "arm", "dof": 1, "parameters": {"stiffness": 1.0}}],
           "outputs": [{"name": "q", "kind": "coordinate", "joint": "arm"}]}
    with pytest.raises(ModelError, match=r"^forces\.k\.joint = 'arm': the Exudyn builder applies joint laws on slides "
                                         r"and on revolute and planar turns only \(this is a turn of a universal joint\)$"):
        exudyn_builder.simulate(parse_model(raw, "u"), 0.01, 0.01)


def _slide(turn: float, axis) -> dict:
    return {"model": {"gravity": [0.0, 0.0, -9.81]},
            "bodies": [{"name": "arm", "joint": {"type": "revolute", "axis": [0.0, 0.0, 1.0]}, "mass": 1.0,
                        "com": [0.2, 0.0, 0.0], "inertia": [0.01, 0.02, 0.02]},
                       {"name": "slider", "parent": "arm" if turn else "ground",
                        "joint": {"type": "prismatic", "position": [0.1, 0.0, 0.0], "axis": axis},
                        "mass": 0.5, "inertia": [0.001, 0.001, 0.001]}],
            "prescribed": [{"name": "turn", "joint": "arm", "motion": "harmonic", "amplitude": turn or 0.0,
                            "frequency": 1.0},
                           {"name": "slide", "joint": "slider", "motion": "harmonic", "amplitude": 0.05, "frequency": 3.0}],
            "outputs": [{"name": c, "kind": "point", "body": "slider", "component": c} for c in "xyz"]}


def test_a_driven_slide_off_the_z_axis_moves_along_its_own_axis():
    """A slide along (1, 1, 0), driven, on the ground: the slider's point follows the in-house builder.
    Exudyn's joint takes a drive's translation offset in global coordinates once all three of its
    translations are locked (given in the joint frame, the slider moved along the global z)."""
    from comparisons.builders import exudyn as ex
    from nsd_core.model.load import parse_model
    from nsd_core.model.semirecursive import simulate as inhouse
    m = parse_model(_slide(0.0, [1.0, 1.0, 0.0]))
    ref = inhouse(m, 0.5, 0.01, {"rtol": 1e-11, "atol": 1e-13})
    run = ex.simulate(m, 0.5, 0.01, {"step_size": 1e-3})
    assert np.ptp(ref.outputs["x"]) > 0.05 and np.ptp(ref.outputs["y"]) > 0.05
    for c in "xyz":
        assert np.max(np.abs(run.outputs[c] - ref.outputs[c])) < 1e-9, c


def test_a_driven_slide_on_a_moving_parent_is_refused_in_one_line():
    """Exudyn's global offsets would need the parent's rotation at each step's end: refused, one line."""
    from comparisons.builders import exudyn as ex
    from nsd_core.model.load import parse_model
    with pytest.raises(ModelError) as e:
        ex.simulate(parse_model(_slide(0.8, [1.0, 1.0, 0.0])), 0.1, 0.01, {"step_size": 1e-3})
    assert str(e.value).startswith("prescribed.slide: the Exudyn builder drives a slide of slider's prismatic joint on "
                                   "the ground or beside a free slide only") and "\n" not in str(e.value)
