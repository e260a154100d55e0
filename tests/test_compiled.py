"""The compiled path equals the numpy specification, and its step loop is scipy's, step for step."""
import numpy as np
import pytest
from scipy.integrate import DOP853, RK45

from nsd_core.device.compiled import compiled_model, device_forces, device_motion
from nsd_core.device.drive import Drive
from nsd_core.device.model import device_system, rest_coordinates, simulate
from nsd_core.device.params import Params
from nsd_core.engine.callbacks import linear_springs, no_forces, no_motion
from nsd_core.engine.compiled import generic_evaluator
from nsd_core.engine.compiled_model import build_model, make_workspace, split_state
from nsd_core.engine.dynamics import tree_kernel, tree_product
from nsd_core.engine.mechanism import mechanism
from nsd_core.engine.problems.andrews import andrews_system, load_reference
from nsd_core.engine.semirecursive import SemiRecursiveSystem
from nsd_core.engine.rk import integrate_kernel, make_outputs, rhs_entry, tableau


def device_case(t=0.137):
    """The device mid-cycle: moving, wires and spring off their rest states."""
    drive = Drive(0.02, 1.0)
    system, g = device_system(Params(), drive)
    z0 = rest_coordinates(g)
    z = system.assemble(system.workspace(), 0.0, z0[system.partition.free]).copy()
    extra = np.concatenate([np.array([3e7, -1e7, 5e6, 0.0])[:g.n_wires], [0.9 * g.spring_zeta0]])
    y = system.state(z, np.zeros(len(z0)), extra)
    y[1] = 0.013  # the free coordinate's velocity
    model = compiled_model(system, g, drive, system.forces.elements)
    return system, model, z, y, t


def numpy_rhs(system, t, y):
    system.fast = False
    try:
        return system.rhs(system.workspace(), t, y)
    finally:
        system.fast = True


def test_device_rhs_compiled_equals_the_numpy_specification():
    system, model, z, y, t = device_case()
    ws = make_workspace(model, z)
    dydt = np.zeros(len(y))
    assert rhs_entry(t, y, model, ws, device_forces, device_motion, generic_evaluator, dydt) == 0
    ref = numpy_rhs(system, t, y)
    assert np.all(ref[2:] != 0.0)  # the hysteretic states really move
    np.testing.assert_allclose(dydt, ref, rtol=1e-9, atol=1e-9 * np.max(np.abs(ref)))
    ev = system.evaluate(system.workspace(), t, y)
    np.testing.assert_allclose(ws.tau, ev.drive_force, rtol=1e-9, atol=1e-9 * np.max(np.abs(ev.drive_force)))


def andrews_model():
    ref = load_reference()
    system, y0 = andrews_system(ref)
    p, sp = ref["parameters"], system.forces.spring
    gen = np.zeros(system.m.n)
    gen[0] = p["mom"]
    params = np.concatenate([[p["c0"]], [p["l0"]], gen])
    model = build_model(system.m, system.partition, system.prescribed, (sp.body_up, sp.pts_up, sp.body_lo, sp.pts_lo),
                        params, (), n_extra=0, newton_tol=system.newton_tol)
    z0 = system.assemble(system.workspace(), 0.0, split_state(y0, len(system.partition.free)).free_positions).copy()
    return system, model, z0, y0


def test_andrews_rhs_compiled_equals_the_numpy_specification():
    system, model, z0, y0 = andrews_model()
    y = y0.copy()
    y[1] = 50.0  # beta' (rad/s)
    ws = make_workspace(model, z0)
    dydt = np.zeros(len(y))
    assert rhs_entry(0.0, y, model, ws, linear_springs, no_motion, generic_evaluator, dydt) == 0
    ref = numpy_rhs(system, 0.0, y)
    np.testing.assert_allclose(dydt, ref, rtol=1e-9, atol=1e-9 * np.max(np.abs(ref)))


@pytest.mark.parametrize("case", ["device", "andrews"])
def test_tree_product_is_the_assembled_mass_matrix_times_a_vector(case):
    """Eq. 12 uses M only in products, computed by one O(n) recursion each (tree_product); they equal
    M v - Q and M v with M, Q assembled by Eqs. 7-8 (tree_kernel), for random v."""
    if case == "device":
        _, model, z, y, t = device_case()
        forces, motion = device_forces, device_motion
    else:
        _, model, z, y = andrews_model()
        y, t, forces, motion = y.copy(), 0.0, linear_springs, no_motion
        y[1] = 50.0
    ws = make_workspace(model, z)
    # fills the body terms
    assert rhs_entry(t, y, model, ws, forces, motion, generic_evaluator, np.zeros(len(y))) == 0
    n = len(model.parent)
    M, Q = np.zeros((n, n)), np.zeros(n)
    tree_kernel(model.parent, ws.B, ws.vp, ws.Mb.copy(), ws.Qb.copy(), M, Q, np.zeros(6))
    Q += ws.gen
    assert np.linalg.matrix_rank(M) > 1 and np.any(Q != 0.0)
    rng = np.random.default_rng(7)
    acc, F, out = np.zeros((n, 6)), np.zeros((n, 6)), np.zeros(n)
    for _ in range(5):
        v = rng.normal(size=n)
        tree_product(model.parent, ws.B, ws.vp, ws.Mb, ws.Qb, ws.gen, v, True, acc, F, out)
        np.testing.assert_allclose(out, M @ v - Q, rtol=1e-12, atol=1e-12 * np.max(np.abs(M @ v - Q)))
        tree_product(model.parent, ws.B, ws.vp, ws.Mb, ws.Qb, ws.gen, v, False, acc, F, out)
        np.testing.assert_allclose(out, M @ v, rtol=1e-12, atol=1e-12 * np.max(np.abs(M @ v)))


def double_pendulum():
    """A tree without loops: the right-hand side is a pure function of (t, y), no Newton warm start."""
    bodies = [dict(name="upper", parent=None, joint="R", axis=(0, 0, 1), mass=1.0, com=(0.5, 0, 0),
                   inertia=(0, 0, 0.02)),
              dict(name="lower", parent="upper", joint="R", axis=(0, 0, 1), offset=(1.0, 0, 0), mass=0.7,
                   com=(0.4, 0, 0), inertia=(0, 0, 0.01))]
    mech = mechanism(bodies, gravity=(0, -9.81, 0))
    system = SemiRecursiveSystem(mech, [], lambda t: (np.zeros(0),) * 3,
                                 lambda t, k, z, zd, e: (np.zeros((2, 6)), None, np.zeros(0)))
    z0 = np.array([0.3, 1.1])
    system.choose_partition(z0)
    model = build_model(mech, system.partition, system.prescribed)
    return model, z0, system.state(z0, np.zeros(2))


@pytest.mark.parametrize("method, scipy_solver", [("DOP853", DOP853), ("RK45", RK45)])
def test_compiled_step_loop_is_scipys_step_for_step(method, scipy_solver):
    """A chaotic double pendulum over 3 s: the same accepted steps as scipy's solver on the same
    compiled right-hand side, and the same end state. Not bit for bit: the stage sums are added in
    another order than numpy's dot, and the error estimate (a sum with heavy cancellation) turns
    that round-off into ~1e-11 relative changes of the step sizes, which a chaotic motion grows."""
    model, z0, y0 = double_pendulum()
    t1, rtol, atol = 3.0, 1e-8, 1e-10
    ws = make_workspace(model, z0)
    out = make_outputs(2, len(y0), len(model.parent), 0, 0, 0, keep_steps=100000)
    stats = np.zeros(4, dtype=np.int64)
    assert integrate_kernel(model, ws, no_forces, no_motion, generic_evaluator, tableau(method), y0.copy(),
                            np.array([0.0, t1]), np.array([rtol, atol, np.inf, 0.0, 1e9]), out, stats) == 0
    ws2 = make_workspace(model, z0)

    def fun(t, y):
        dydt = np.zeros(len(y))
        assert rhs_entry(t, np.ascontiguousarray(y), model, ws2, no_forces, no_motion, generic_evaluator,
                         dydt) == 0
        return dydt

    solver = scipy_solver(fun, 0.0, y0.copy(), t1, rtol=rtol, atol=atol)
    times = []
    while solver.status == "running":
        solver.step()
        times.append(solver.t)
    assert stats[0] == len(times) > 50
    np.testing.assert_allclose(out.step_t[:stats[0]], times, rtol=1e-7)
    np.testing.assert_allclose(out.y[-1], solver.y, rtol=1e-6, atol=1e-8)


def test_device_cycle_compiled_equals_numpy_backend():
    """A whole 10 Hz cycle (two drives of 0.1 s): drive force and states agree far inside the 1e-4 aim."""
    d = Drive(0.015, 10.0, cycles=1, samples_per_cycle=200)
    p = Params()
    a = simulate(p, d, backend="compiled", rtol=1e-9)
    b = simulate(p, d, backend="numpy", rtol=1e-9)
    for col in ("F", "cap_z", "wall_z", "spring_zeta"):
        np.testing.assert_allclose(a[col], b[col], rtol=0, atol=1e-6 * np.max(np.abs(b[col])))
    assert a.stats["backend"] == "compiled" and b.stats["backend"] == "numpy"


def test_split_state_names_the_parts():
    y = np.arange(7.0)
    parts = split_state(y, 2)
    assert list(parts.free_positions) == [0, 1] and list(parts.free_velocities) == [2, 3]
    assert list(parts.extra) == [4, 5, 6]
    assert split_state(np.vstack([y, y]), 2).extra.shape == (2, 3)


def table_file(tmp_path):
    """A (t, x, y) table that starts at rest at the centre and wanders over the plane for 0.2 s."""
    t = np.linspace(0.0, 0.2, 41)
    x = 0.012 * np.sin(5 * np.pi * t) ** 2
    y = 0.008 * np.sin(10 * np.pi * t) * np.sin(5 * np.pi * t)
    f = tmp_path / "path.csv"
    f.write_text("t,x,y\n" + "\n".join(f"{a:.17g},{b:.17g},{c:.17g}" for a, b, c in zip(t, x, y)) + "\n")
    return str(f)


def test_table_motion_is_scipys_spline(tmp_path):
    """plate_motion's piecewise cubic equals scipy's CubicSpline (value and two derivatives), also on
    the knots and beyond the last one; the compiled callback hands the same numbers to the engine."""
    from scipy.interpolate import CubicSpline
    from nsd_core.device.drive import plate_motion
    d = Drive(0.0, 10.0, cycles=2, path=table_file(tmp_path))
    a = np.loadtxt(d.path, delimiter=",", skiprows=1)
    spline = CubicSpline(a[:, 0], a[:, 1:], bc_type="clamped")
    t = np.concatenate([np.linspace(-0.01, 0.21, 2201), a[:, 0]])
    got = np.array([plate_motion(tk, d.motion_params) for tk in t])
    want = np.column_stack([spline(t), spline(t, 1), spline(t, 2)])
    assert np.max(np.abs(got - want) / np.max(np.abs(want), axis=0)) < 1e-12  # per column, of its largest value
    q, qd, qdd = np.zeros(6), np.zeros(6), np.zeros(6)
    assert device_motion(0.1234, d.motion_params, q, qd, qdd) == 0
    np.testing.assert_array_equal(np.r_[q[:2], qd[:2], qdd[:2]], np.array(d.plate_at(0.1234))[[0, 1, 2, 3, 4, 5]])
    assert np.all(q[2:] == 0.0) and np.all(qdd[2:] == 0.0)


@pytest.mark.parametrize("path, extra", [("circle", {}), ("ellipse", {"minor": 0.006}),
                                         ("figure8", {}), ("table", {})])
def test_compiled_paths_equal_the_scipy_path(path, extra, tmp_path):
    """Every path other than a line on the compiled backend (its motion callback is the Drive's own
    plate_motion) against the scipy-driven SemiRecursiveSystem: one 10 Hz cycle (the circle's is its
    spiral out), force vector and states within 1e-6 of their largest values at rtol 1e-9."""
    if path == "table":
        d = Drive(0.0, 10.0, cycles=2, samples_per_cycle=100, path=table_file(tmp_path))
    else:
        d = Drive(0.015, 10.0, 30.0, cycles=1, samples_per_cycle=200, path=path, **extra)
    p = Params()
    a = simulate(p, d, backend="compiled", rtol=1e-9)
    b = simulate(p, d, backend="scipy", rtol=1e-9)
    assert a.stats["backend"] == "compiled" and b.stats["backend"] == "scipy"
    assert simulate(p, d, rtol=1e-9).stats["backend"] == "compiled"  # the default takes it
    assert np.max(np.abs(b["F_y"])) > 0.05 * np.max(np.abs(b["F_x"]))  # really off the line
    for col in ("F_x", "F_y", "cap_z", "wall_z", "spring_zeta", "wire0_stress"):
        np.testing.assert_allclose(a[col], b[col], rtol=0, atol=1e-6 * np.max(np.abs(b[col])))


@pytest.mark.parametrize("method", ["DOP853", "RK45"])
def test_the_step_loops_tableau_type_is_each_pairs(method):
    """rk.TABLEAU_TYPE is written from the arrays' dimensions (no scipy at import): it must be the type of
    each pair's tableau, or the step loop's explicit signature would not accept it."""
    from numba import typeof
    from nsd_core.engine.rk import TABLEAU_TYPE
    assert typeof(tableau(method)) == TABLEAU_TYPE
