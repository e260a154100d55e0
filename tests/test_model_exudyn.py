"""The Exudyn builder (comparisons/builders/exudyn.py) against independent solutions: the in-house
builder (minimal coordinates, adaptive, tight tolerances), the test set's reference for Andrews'
mechanism, the exact pendulum of IFToMM A01, and a force law registered only here."""
from __future__ import annotations

import csv

import numpy as np
import pytest
from numba import njit

from comparisons.builders import exudyn as exudyn_builder
from nsd_core.engine.problems.iftomm import pendulum_exact
from nsd_core.model import semirecursive
from nsd_core.model.errors import ModelError
from nsd_core.model.laws import JOINT, LAWS, POINTS, Law, LawParameter, register
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
