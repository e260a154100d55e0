"""The generic semirecursive engine on mechanisms with known answers."""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from nsd_core.device.model import BODY, device_mechanism
from nsd_core.engine.dynamics import kinetic_energy, potential_energy_gravity
from nsd_core.device.geometry import device_geometry
from nsd_core.engine.integrate import integrate
from nsd_core.engine.mechanism import Cut, mechanism
from nsd_core.device.params import Params
from nsd_core.engine.semirecursive import SemiRecursiveSystem

G = 9.81


def no_motion(t):
    return np.zeros(0), np.zeros(0), np.zeros(0)


def no_forces(m):
    return lambda t, k, z, zd, e: (np.zeros((m.n, 6)), None, np.zeros(0))


def run(system, z0, t_end, n_out=51, **kw):
    system.choose_partition(z0)
    z0 = system.assemble(system.workspace(), 0.0, z0[system.partition.free]).copy()
    system.choose_partition(z0)
    ws = system.workspace()
    energies, closures, states = [], [], []

    def out(t, y):
        ev = system.evaluate(ws, t, y)
        energies.append(kinetic_energy(system.m, ev.kin) + potential_energy_gravity(system.m, ev.kin))
        closures.append(np.max(np.abs(ev.Phi)) if len(ev.Phi) else 0.0)
        states.append(ev.z.copy())

    integrate(system, ws, system.state(z0, np.zeros(system.m.n)), np.linspace(0, t_end, n_out), **kw, outputs=out)
    return np.array(energies), np.array(closures), np.array(states)


def test_pendulum_matches_its_ode():
    L = 0.7
    m = mechanism([dict(name="bob", parent=None, joint="R", axis=(0, 0, 1), mass=2.0, com=(L, 0, 0))],
                  gravity=(0, -G, 0))
    s = SemiRecursiveSystem(m, [], no_motion, no_forces(m))
    E, _, z = run(s, np.array([0.3]), 2.0, rtol=1e-11, atol=1e-12)
    ref = solve_ivp(lambda t, y: [y[1], -G / L * math.cos(y[0])], (0, 2), [0.3, 0], rtol=1e-12, atol=1e-12,
                    t_eval=np.linspace(0, 2, 51))
    np.testing.assert_allclose(z[:, 0], ref.y[0], atol=1e-8)
    assert np.ptp(E) < 1e-8 * 2.0 * G * L


def four_bar():
    a, b, c, d = 1.0, 2.0, 2.0, 2.0
    bodies = [dict(name="crank", parent=None, joint="R", axis=(0, 0, 1), mass=1, com=(a / 2, 0, 0), inertia=(0, 0, a * a / 12)),
              dict(name="coupler", parent="crank", joint="R", axis=(0, 0, 1), offset=(a, 0, 0), mass=1,
                   com=(b / 2, 0, 0), inertia=(0, 0, b * b / 12)),
              dict(name="rocker", parent=None, joint="R", axis=(0, 0, 1), offset=(d, 0, 0), mass=1,
                   com=(c / 2, 0, 0), inertia=(0, 0, c * c / 12))]
    return mechanism(bodies, [Cut("point", "coupler", (b, 0, 0), "rocker", (c, 0, 0))], gravity=(0, -G, 0))


def test_four_bar_conserves_energy_and_closes_the_loop():
    m = four_bar()
    s = SemiRecursiveSystem(m, [], no_motion, no_forces(m))
    E, C, _ = run(s, np.array([math.pi / 2, -1.3, 1.8]), 3.0, rtol=1e-10, atol=1e-12)
    assert np.ptp(E) < 1e-6 * np.max(np.abs(E))
    assert C.max() < 1e-13  # dependent coordinates re-solved by Newton: drift stays at round-off


def test_planar_loop_drops_the_redundant_equation():
    m = four_bar()
    s = SemiRecursiveSystem(m, [], no_motion, no_forces(m))
    P = s.choose_partition(np.array([1.8054, -1.3, 1.8145]))
    assert len(P.rows) == 2 and 2 not in P.rows  # the z-row of a planar loop is identically zero
    assert len(P.free) == 1 and len(P.dependent) == 2


def test_path_matrix_is_derived_from_the_parent_array():
    m = device_mechanism(device_geometry(Params()))
    T = m.path_matrix()
    for i in range(m.n):
        for j in range(m.n):
            on_path = j == i or j in m.ancestors(m.parent[i]) if m.parent[i] >= 0 else j == i
            assert T[i, j] == int(on_path)
    assert T[BODY["rod"], BODY["wall"]] == 1 and T[BODY["rod"], BODY["cap"]] == 0
    assert T.sum() == 4 * 5 / 2 + 6 * 7 / 2  # two chains of 4 and 6 joints


def test_prescribed_coordinate_reaction_is_the_drive_force():
    """A driven slider on a spring: the drive force is m x'' + k x exactly."""
    mass, k = 3.0, 50.0
    m = mechanism([dict(name="slider", parent=None, joint="P", axis=(1, 0, 0), mass=mass)])

    def motion(t):
        return np.array([0.1 * math.sin(5 * t)]), np.array([0.5 * math.cos(5 * t)]), np.array([-2.5 * math.sin(5 * t)])

    def forces(t, kin, z, zd, e):
        W = np.zeros((1, 6))
        W[0, 0] = -k * z[0]
        return W, None, np.zeros(0)

    s = SemiRecursiveSystem(m, [0], motion, forces)
    s.choose_partition(np.zeros(1))
    for t in (0.1, 0.7, 1.3):
        ev = s.evaluate(s.workspace(), t, np.zeros(0))
        x, _, xdd = motion(t)
        assert ev.drive_force[0] == pytest.approx(mass * xdd[0] + k * x[0], rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("A", [0.015, 0.0255])
def test_compiled_fast_path_equals_the_numpy_specification(A):
    """nsd_core.engine.compiled runs the numpy steps of rhs_parts compiled; both must give the same numbers."""
    from nsd_core.device.model import device_system, rest_coordinates
    from nsd_core.device.drive import Drive
    d = Drive(A, 10.0)
    s, g = device_system(Params(), d)
    z0 = rest_coordinates(g)
    ws = s.workspace()
    y = s.state(s.assemble(ws, 0.0, z0[s.partition.free]).copy(), np.zeros(len(z0)), np.r_[np.zeros(g.n_wires), g.spring_zeta0])
    y[1] = -0.05  # a vertical velocity, so that velocity terms matter
    for t in (0.003, 0.011, 0.02):
        s.fast = True
        a = s.evaluate(ws, t, y)
        s.fast = False
        b = s.evaluate(ws, t, y)
        for name in ("z", "zd", "zdd", "lam", "drive_force", "extra_rate"):
            np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-9,
                                       atol=1e-9 * max(1.0, np.max(np.abs(getattr(b, name)))), err_msg=name)


def test_velocity_terms_obey_lagranges_equations_and_constraint_rates():
    """On the device tree at a random state: the recursive velocity terms equal
    -(M' z' - 1/2 d(z'^T M z')/dz) by finite differences, and c equals (d Phi_z/dt) z'."""
    import dataclasses
    from nsd_core.engine.closure import closure
    from nsd_core.engine.dynamics import tree_equations
    from nsd_core.engine.kinematics import positions, velocities
    from nsd_core.device.model import rest_coordinates
    g = device_geometry(Params())
    m = dataclasses.replace(device_mechanism(g), gravity=np.zeros(3))
    rng = np.random.default_rng(7)
    z = rest_coordinates(g) + rng.normal(0, 0.02, m.n)
    zd = rng.normal(0, 1, m.n)
    h = 1e-6
    zero = np.zeros((m.n, 6))

    def mass(q):
        return tree_equations(m, positions(m, q), zero)[0]

    k = velocities(m, positions(m, z), zd)
    _, Q = tree_equations(m, k, zero)
    Mdot = (mass(z + h * zd) - mass(z - h * zd)) / (2 * h)
    grad = np.array([(zd @ mass(z + h * e) @ zd - zd @ mass(z - h * e) @ zd) / (2 * h) for e in np.eye(m.n)])
    np.testing.assert_allclose(Q, -(Mdot @ zd - 0.5 * grad), atol=1e-7 * np.max(np.abs(Q)))
    _, _, c = closure(m, k, with_rates=True)
    Jp = closure(m, positions(m, z + h * zd))[1]
    Jm = closure(m, positions(m, z - h * zd))[1]
    np.testing.assert_allclose(c, (Jp - Jm) / (2 * h) @ zd, rtol=1e-6, atol=1e-10)
