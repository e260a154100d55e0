"""IFToMM / MBS benchmark A04: Bricard's mechanism, on the generic semirecursive engine.

Library description (lim.ii.udc.es/mbsbenchmark, A04): five rods of 1 m and 1 kg, six revolute
joints, gravity 9.81 in -y; Grubler's count gives 0 DOF but the joint axes make it a 1-DOF
overconstrained linkage (one redundant constraint); accuracy = mechanical-energy drift and the
trajectory of point P3. The library's specification text and reference data file were not
readable here; the geometry below is the one of the public OpenSim port of the library problems
(RehabEngGroup/MBSbenchmarksInOpenSim, src/A04-BricardsMechanism/createModel.cpp: square 0.1 m
cross-section, P3 = the joint between rods 2 and 3, start at rest):
    joints at O(0,0,0) axis Y, (1,0,0) axis Z, P3 (1,-1,0) axis X, (1,-1,1) axis Y,
    (0,-1,1) axis Z, and (0,0,1) axis X back to the ground.
Five joints form the tree; the sixth is a cut revolute joint (point + 2 perpendicularity rows):
5 loop equations in 5 coordinates whose Jacobian has rank 4 everywhere, so the full-pivot
elimination leaves one equation out and one coordinate free. As there is no reference file, the
check is energy conservation plus model independence: cutting the loop at another joint (P3)
gives another tree and must give the same motion of P3.
"""
from __future__ import annotations

import numpy as np

from nsd_core.engine.mechanism import mechanism, revolute_cut
from nsd_core.engine.semirecursive import SemiRecursiveSystem
from nsd_core.engine.problems.common import mechanical_energy, run_system

G = 9.81
X, Y, Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
SECTION = 0.1
# the closed chain: joint points (global, at the initial configuration) and axes, in loop order
POINTS = np.array([(0, 0, 0), (1, 0, 0), (1, -1, 0), (1, -1, 1), (0, -1, 1), (0, 0, 1)], dtype=float)
AXES = [Y, Z, X, Y, Z, X]
P3 = 2  # index of P3 in POINTS


def rod_inertia(direction) -> np.ndarray:
    """1 kg, 1 m rod of square 0.1 m section about its centre, long axis along ``direction``."""
    a = np.asarray(direction, float)
    a = a / np.linalg.norm(a)
    transverse = (1.0 + SECTION ** 2) / 12.0
    axial = SECTION ** 2 / 6.0
    return transverse * (np.eye(3) - np.outer(a, a)) + axial * np.outer(a, a)


def bricard_mechanism(cut_joint: int = 5):
    """Rods k = 0..4 join POINTS[k] -> POINTS[k+1]; the ground is the sixth link POINTS[5] -> POINTS[0].

    The tree opens the loop at joint ``cut_joint`` (5: the last joint to the ground; 2: at P3, two
    branches from the ground). All body frames are parallel to the global axes at z = 0."""
    rods = list(range(5))
    # joint j connects link j-1 (ground for j = 0 or 6 mod 6) and rod j (rod 5 = ground)
    def branch(first_joint, step):
        out, j = [], first_joint
        while True:
            rod = j if step > 0 else j - 1
            if rod < 0 or rod > 4 or j == cut_joint:
                return out
            out.append((j, rod))
            j += step
    # from the ground through joint 0 forwards, and through joint 5 backwards
    bodies, origin = [], {}
    for chain in (branch(0, +1), branch(5, -1)):
        parent = None
        for j, rod in chain:
            p = POINTS[j]
            offset = p - (origin[parent] if parent is not None else 0.0)
            far = POINTS[rod + 1] if rod == j else POINTS[rod]
            bodies.append(dict(name=f"rod{rod}", parent=parent, joint="R", axis=AXES[j], offset=tuple(offset),
                               mass=1.0, com=tuple((POINTS[rod] + POINTS[rod + 1]) / 2 - p),
                               inertia=rod_inertia(far - p)))
            origin[f"rod{rod}"] = p
            parent = f"rod{rod}"
    names = {b["name"] for b in bodies}
    assert names == {f"rod{r}" for r in rods}
    # the cut joint: between rod (cut_joint - 1) and rod cut_joint (ground at either end)
    pc = POINTS[cut_joint % 6]
    a_name = f"rod{cut_joint - 1}" if cut_joint >= 1 else "ground"
    b_name = f"rod{cut_joint}" if cut_joint <= 4 else "ground"
    loc = {n: (pc - origin[n]) if n != "ground" else pc for n in (a_name, b_name)}
    cuts = revolute_cut(a_name, tuple(loc[a_name]), AXES[cut_joint], b_name, tuple(loc[b_name]), AXES[cut_joint],
                        name="cut revolute")
    return mechanism(bodies, cuts, gravity=(0.0, -G, 0.0)), origin


def a04(duration=20.0, outputs=400, rtol=1e-10, atol=1e-12, method="DOP853", cut_joint: int = 5) -> dict:
    mech, origin = bricard_mechanism(cut_joint)
    forces = lambda t, kin, z, zd, extra: (np.zeros((mech.n, 6)), None, np.zeros(0))  # gravity is in mech
    system = SemiRecursiveSystem(mech, [], lambda t: (np.zeros(0), np.zeros(0), np.zeros(0)), forces)
    z0 = np.zeros(mech.n)
    P = system.choose_partition(z0)
    y0 = system.state(z0, np.zeros(mech.n))
    # P3 is the origin of rod 2 when the tree reaches it through joint 2, else the far end of rod 1
    host = mech.names.index("rod2") if "rod2" in origin and np.allclose(origin["rod2"], POINTS[P3]) \
        else mech.names.index("rod1")
    local = POINTS[P3] - origin[mech.names[host]]
    t = np.linspace(0.0, duration, outputs + 1)

    def sample(ev):
        return ev.kin.point(host, local), mechanical_energy(system, ev.z, ev.zd), float(np.max(np.abs(ev.Phi)))

    run = run_system(system, y0, t, sample, method=method, rtol=rtol, atol=atol)
    p3 = np.array([s[0] for s in run.samples])
    E = np.array([s[1] for s in run.samples])
    return {"problem": "A04", "duration": duration, "outputs": outputs, "method": method, "rtol": rtol,
            "cut_joint": cut_joint, "constraint_rows": mech.n_constraints, "independent_rows": int(len(P.rows)),
            "free": int(len(P.free)), "energy_drift": float(np.max(np.abs(E - E[0]))),
            "closure_max": float(max(s[2] for s in run.samples)), "p3": p3, "final_P3": p3[-1],
            "p3_range": float(np.max(np.ptp(p3, axis=0))), "cpu_time": run.wall_time, "steps": run.steps,
            "nfev": run.nfev, "repartitions": run.repartitions}
