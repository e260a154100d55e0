"""Andrews' squeezing mechanism on the generic semirecursive engine.

Source: E. Hairer, G. Wanner, Solving Ordinary Differential Equations II, 2nd ed., Springer 1996,
Section VII.7; data, initial values and reference solution from the Test Set for IVP Solvers
(F. Mazzia, C. Magherini, Univ. of Bari, problem "andrews", file andrews.f: parameter block,
init and andsoln), kept with their source in references/andrews_reference.toml.

The test set writes the equations of motion by hand in 7 angles (beta, Theta, gamma, Phi, delta,
Omega, epsilon) and 6 loop equations g(q) = 0. Here the same machine is only *data*: seven planar
bodies with revolute joints about Z, arranged as a tree read off the test set's mass matrix and
constraint functions:
    O -> K1 (beta) -> K2 (Theta, relative)      crank and coupler, E at distance d on K2
    B -> K3 (gamma)                              E at distance ss, spring point D on K3
    A -> K5 (delta) -> K4 (Phi, relative)       joint at zt on K5, E at distance e on K4
    A -> K7 (epsilon) -> K6 (Omega, relative)   joint at u on K7, E at distance zf on K6
and three point cuts that make K3, K4 and K6 meet K2 at E (the test set's g1..g6). Each planar
point cut also yields a z-row that is identically zero; the full-pivot elimination drops it.
The motor torque mom acts on joint beta, the spring c0 runs from D on K3 to C on the ground.
Gravity is not modelled in the test set. Angle coordinates are the test set's y(1..7).
"""
from __future__ import annotations

import tomllib

import numpy as np

from nsd_core.engine.elements import AxialElements
from nsd_core.engine.mechanism import Cut, Mechanism, mechanism
from nsd_core.engine.semirecursive import SemiRecursiveSystem
from nsd_core.engine.problems.common import REFERENCES, Run, digits, run_system

Z = (0.0, 0.0, 1.0)
# engine body order (parents first) and where each sits in the test set's y(1..7)
BODIES = ["beta", "Theta", "gamma", "delta", "Phi", "epsilon", "Omega"]
TESTSET_ORDER = ["beta", "Theta", "gamma", "Phi", "delta", "Omega", "epsilon"]
TO_TESTSET = [BODIES.index(n) for n in TESTSET_ORDER]


def load_reference(path=None) -> dict:
    with open(path or REFERENCES / "andrews_reference.toml", "rb") as f:
        return tomllib.load(f)


def andrews_mechanism(p: dict) -> Mechanism:
    """The seven bodies as data (parameters by the test set's names: m1, i1, rr, ra, ...)."""
    def inertia(i):
        return (0.0, 0.0, i)  # planar motion about Z: only I_zz enters
    bodies = [
        dict(name="beta", parent=None, joint="R", axis=Z, mass=p["m1"], com=(p["ra"], 0, 0), inertia=inertia(p["i1"])),
        dict(name="Theta", parent="beta", joint="R", axis=Z, offset=(p["rr"], 0, 0), mass=p["m2"],
             com=(-p["da"], 0, 0), inertia=inertia(p["i2"])),
        dict(name="gamma", parent=None, joint="R", axis=Z, offset=(p["xb"], p["yb"], 0), mass=p["m3"],
             com=(p["sa"], p["sb"], 0), inertia=inertia(p["i3"])),
        dict(name="delta", parent=None, joint="R", axis=Z, offset=(p["xa"], p["ya"], 0), mass=p["m5"],
             com=(p["ta"], p["tb"], 0), inertia=inertia(p["i5"])),
        dict(name="Phi", parent="delta", joint="R", axis=Z, offset=(p["zt"], 0, 0), mass=p["m4"],
             com=(0, -(p["e"] - p["ea"]), 0), inertia=inertia(p["i4"])),
        dict(name="epsilon", parent=None, joint="R", axis=Z, offset=(p["xa"], p["ya"], 0), mass=p["m7"],
             com=(p["ua"], p["ub"], 0), inertia=inertia(p["i7"])),
        dict(name="Omega", parent="epsilon", joint="R", axis=Z, offset=(0, -p["u"], 0), mass=p["m6"],
             com=(p["zf"] - p["fa"], 0, 0), inertia=inertia(p["i6"])),
    ]
    E2 = (-p["d"], 0.0, 0.0)  # point E on K2
    cuts = [Cut("point", "Theta", E2, "gamma", (0.0, -p["ss"], 0.0), name="E: K2-K3"),
            Cut("point", "Theta", E2, "Phi", (0.0, -p["e"], 0.0), name="E: K2-K4"),
            Cut("point", "Theta", E2, "Omega", (p["zf"], 0.0, 0.0), name="E: K2-K6")]
    return mechanism(bodies, cuts)


class AndrewsForces:
    """Driving torque mom on joint beta, and the spring c0 (free length l0) from D on K3 to C."""

    def __init__(self, p: dict, n: int):
        self.mom, self.c0, self.l0, self.n = p["mom"], p["c0"], p["l0"], n
        self.spring = AxialElements([BODIES.index("gamma")], [(p["sd"], -p["sc"], 0.0)], [-1],
                                    [(p["xc"], p["yc"], 0.0)], n)

    def __call__(self, t, kin, z, zd, extra):
        L, _ = self.spring.state(kin)
        gen = np.zeros(self.n)
        gen[0] = self.mom
        return self.spring.wrench(self.c0 * (L - self.l0)), gen, np.zeros(0)


def andrews_system(ref: dict | None = None) -> tuple[SemiRecursiveSystem, np.ndarray]:
    """The system with beta free (as in the test set's drive), and the consistent initial state."""
    ref = ref or load_reference()
    p = ref["parameters"]
    mech = andrews_mechanism(p)
    sysm = SemiRecursiveSystem(mech, [], lambda t: (np.zeros(0), np.zeros(0), np.zeros(0)),
                               AndrewsForces(p, mech.n), prefer_free=[0])
    z0 = np.zeros(mech.n)
    z0[TO_TESTSET] = ref["initial"]["angles"]
    sysm.choose_partition(z0)
    z0 = sysm.assemble(sysm.workspace(), 0.0, z0[sysm.partition.free]).copy()
    return sysm, sysm.state(z0, np.zeros(mech.n))


def solve(rtol=1e-12, atol=1e-14, method="DOP853", ref: dict | None = None) -> dict:
    """Integrate 0 -> 0.03 s and compare the seven angles with the test set's reference."""
    ref = ref or load_reference()
    system, y0 = andrews_system(ref)
    t1 = ref["reference"]["t"]

    def sample(ev):
        return ev.z[TO_TESTSET].copy(), ev.zd[TO_TESTSET].copy(), float(np.max(np.abs(ev.Phi)))

    run: Run = run_system(system, y0, np.array([0.0, t1]), sample, method=method, rtol=rtol, atol=atol)
    q, qd, closure = run.samples[-1]
    qref = np.array(ref["reference"]["angles"])
    qdref = np.array(ref["reference"]["velocities"])
    d = digits(q, qref)
    return {"t": t1, "method": method, "rtol": rtol, "atol": atol, "angles": q, "velocities": qd,
            "digits": dict(zip(TESTSET_ORDER, d)), "min_digits": float(d.min()),
            "velocity_digits": float(digits(qd, qdref).min()), "closure": closure,
            "wall_time": run.wall_time, "steps": run.steps, "nfev": run.nfev, "repartitions": run.repartitions}


def work_precision(tolerances=(1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12), method="DOP853",
                   repeats: int = 1) -> list[dict]:
    """Correct digits (min over the angles) against wall time over a range of tolerances."""
    ref = load_reference()
    rows = []
    for tol in tolerances:
        runs = [solve(rtol=tol, atol=tol * 1e-2, method=method, ref=ref) for _ in range(repeats)]
        r = runs[-1]
        rows.append({"rtol": tol, "atol": tol * 1e-2, "method": method, "min_digits": r["min_digits"],
                     "digits": r["digits"], "wall_time": float(np.median([x["wall_time"] for x in runs])),
                     "steps": r["steps"], "nfev": r["nfev"]})
    return rows
