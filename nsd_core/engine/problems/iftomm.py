"""IFToMM / MBS benchmark library, group A (basic problems), on the generic semirecursive engine.

Source: M. Gonzalez, D. Dopico, U. Lugris, J. Cuadrado, "A benchmarking system for MBS simulation
software: problem standardization and performance measurement", Multibody System Dynamics 16
(2006) 179-190; problem specifications lim.ii.udc.es/mbsbenchmark/dist/A0x/A0x_specification.xml
(now library.iftomm.org). Data used (quoted in references/iftomm_group_a.toml):
  A01 simple pendulum: point mass 1 kg on a massless 1 m link, g = 9.81 in -y, released at rest
      from the horizontal with P1 at x = +1 m; 2000 s; reference = P1's (x, y), 4000 output
      steps, allowed error 1e-3 (high precision), threshold 1e-3.
  A02 N-four-bar (N = 40): 2N+1 uniform 1 m, 1 kg links; cranks start vertical, couplers
      horizontal, x-velocity of B0 = 1 m/s; 20 s; reference = B0's position and velocity, 400
      output steps. All cranks horizontal is a singular position (DOF 1 -> N+1).
  A04 Bricard: five 1 m, 1 kg rods, six revolute joints, 1 DOF although Grubler counts 0 (one
      redundant constraint); gravity -y; reference point P3. See bricard.py.
Reference solutions: the library's data files were not available here, so A01 uses the exact
solution (Jacobi elliptic functions) and A02 the exact reduction of the parallelogram motion to
one angle, J phi'' = C sin(phi), integrated at rtol 1e-13 (independent of the engine).
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import ellipj, ellipk

from nsd_core.engine.mechanism import Cut, mechanism
from nsd_core.engine.semirecursive import SemiRecursiveSystem
from nsd_core.engine.problems.common import library_error, mechanical_energy, run_system

G = 9.81
Z = (0.0, 0.0, 1.0)
NO_MOTION = (lambda t: (np.zeros(0), np.zeros(0), np.zeros(0)))


def no_forces(n):
    def forces(t, kin, z, zd, extra):
        return np.zeros((n, 6)), None, np.zeros(0)
    return forces


# ---------------------------------------------------------------- A01 simple pendulum
def pendulum_exact(t: np.ndarray, L: float = 1.0, g: float = G) -> np.ndarray:
    """P1 (x, y) for release at rest from the horizontal (theta0 = 90 deg from the downward vertical).

    sin(theta/2) = k sn(K - w t, k), k = sin(theta0/2), w = sqrt(g/L), theta measured from -y
    towards +x; then x = L sin(theta) = 2 L k sn dn and y = -L cos(theta) = -L (1 - 2 k^2 sn^2).
    The argument is reduced modulo the period 4K first, so 2000 s keep full accuracy.
    """
    m = math.sin(math.pi / 4) ** 2
    K = float(ellipk(m))
    u = np.mod(K - math.sqrt(g / L) * np.asarray(t, float), 4 * K)
    sn, cn, dn, _ = ellipj(u, m)
    k = math.sqrt(m)
    return np.column_stack([2 * L * k * sn * dn, -L * (1 - 2 * m * sn ** 2)])


def a01(duration=2000.0, outputs=4000, rtol=1e-10, atol=1e-12, method="DOP853") -> dict:
    mech = mechanism([dict(name="pendulum", parent=None, joint="R", axis=Z, mass=1.0, com=(1.0, 0.0, 0.0))],
                     gravity=(0.0, -G, 0.0))
    system = SemiRecursiveSystem(mech, [], NO_MOTION, no_forces(1))
    system.choose_partition(np.zeros(1))
    y0 = system.state(np.zeros(1), np.zeros(1))
    t = np.linspace(0.0, duration, outputs + 1)

    def sample(ev):
        return ev.kin.point(0, (1.0, 0.0, 0.0))[:2], mechanical_energy(system, ev.z, ev.zd)

    run = run_system(system, y0, t, sample, method=method, rtol=rtol, atol=atol)
    P = np.array([s[0] for s in run.samples])
    E = np.array([s[1] for s in run.samples])
    ref = pendulum_exact(t)
    return {"problem": "A01", "duration": duration, "outputs": outputs, "method": method, "rtol": rtol,
            "error": library_error(P, ref), "max_abs_error": float(np.max(np.abs(P - ref))),
            "energy_drift": float(np.max(np.abs(E - E[0]))), "final_P1": P[-1], "reference_final_P1": ref[-1],
            "cpu_time": run.wall_time, "steps": run.steps, "nfev": run.nfev, "goal": 1e-3}


# ---------------------------------------------------------------- A02 N-four-bar
def four_bar_mechanism(N: int):
    """Cranks 0..N hinged on the ground at (i, 0), pointing up; coupler i joins B_{i-1} to B_i.

    Tree: crank_0 -> coupler_1 -> ... is not needed: each coupler hangs on the previous crank's tip
    and is cut at the next crank's tip (a point cut, whose z-row is identically zero)."""
    rod_t = 1.0 / 12.0  # uniform 1 m, 1 kg bar about its centre, transverse axes
    bodies, cuts = [], []
    for i in range(N + 1):
        bodies.append(dict(name=f"crank{i}", parent=None, joint="R", axis=Z, offset=(float(i), 0.0, 0.0),
                           mass=1.0, com=(0.0, 0.5, 0.0), inertia=(rod_t, 0.0, rod_t)))
    for i in range(1, N + 1):
        bodies.append(dict(name=f"coupler{i}", parent=f"crank{i - 1}", joint="R", axis=Z, offset=(0.0, 1.0, 0.0),
                           mass=1.0, com=(0.5, 0.0, 0.0), inertia=(0.0, rod_t, rod_t)))
        cuts.append(Cut("point", f"coupler{i}", (1.0, 0.0, 0.0), f"crank{i}", (0.0, 1.0, 0.0), name=f"B{i}"))
    return mechanism(bodies, cuts, gravity=(0.0, -G, 0.0))


def four_bar_exact(t: np.ndarray, N: int, v0: float = 1.0) -> np.ndarray:
    """B0 (x, y, x', y') of the parallelogram motion: every crank turns by phi (from the vertical,
    clockwise), couplers translate. Energy gives J phi'' = C sin(phi) with
    J = (N+1)/3 + N (cranks about their pivots, couplers translating) and C = g ((N+1)/2 + N)."""
    J = (N + 1) / 3.0 + N
    C = G * ((N + 1) / 2.0 + N)
    sol = solve_ivp(lambda _, s: [s[1], C / J * math.sin(s[0])], (t[0], t[-1]), [0.0, v0], method="DOP853",
                    rtol=1e-13, atol=1e-14, t_eval=t)
    phi, w = sol.y
    return np.column_stack([np.sin(phi), np.cos(phi), np.cos(phi) * w, -np.sin(phi) * w])


def a02(N=40, duration=20.0, outputs=400, rtol=1e-10, atol=1e-12, method="DOP853") -> dict:
    mech = four_bar_mechanism(N)
    system = SemiRecursiveSystem(mech, [], NO_MOTION, no_forces(mech.n), prefer_free=[0])
    z0 = np.zeros(mech.n)
    system.choose_partition(z0)
    zd0 = np.zeros(mech.n)
    zd0[: N + 1] = -1.0  # every crank at -1 rad/s about +Z: B0 moves along +x at 1 m/s
    y0 = system.state(z0, zd0)
    t = np.linspace(0.0, duration, outputs + 1)
    b0 = (0.0, 1.0, 0.0)

    def sample(ev):
        p = ev.kin.point(0, b0)
        v = ev.kin.point_velocity(0, p)
        return np.r_[p[:2], v[:2]], mechanical_energy(system, ev.z, ev.zd), float(np.max(np.abs(ev.Phi)))

    run = run_system(system, y0, t, sample, method=method, rtol=rtol, atol=atol)
    B = np.array([s[0] for s in run.samples])
    E = np.array([s[1] for s in run.samples])
    ref = four_bar_exact(t, N)
    crossings = int(np.sum(np.diff(np.floor(np.arctan2(ref[:, 0], ref[:, 1]) / math.pi + 0.5)) != 0))
    return {"problem": "A02", "N": N, "duration": duration, "outputs": outputs, "method": method, "rtol": rtol,
            "error": library_error(B[:, :2], ref[:, :2]), "velocity_error": library_error(B[:, 2:], ref[:, 2:]),
            "max_abs_error": float(np.max(np.abs(B[:, :2] - ref[:, :2]))),
            "energy_drift": float(np.max(np.abs(E - E[0]))), "closure_max": float(max(s[2] for s in run.samples)),
            "singular_crossings": crossings, "repartitions": run.repartitions, "final_B0": B[-1],
            "reference_final_B0": ref[-1], "cpu_time": run.wall_time, "steps": run.steps, "nfev": run.nfev,
            "goal": 1e-3}
