"""Slider-crank with a crank driven at constant speed: the smallest closed-loop check.

Crank (length r) turns about the ground origin at theta = w t (a prescribed coordinate), the
connecting rod (length l) hangs on the crank pin, the slider moves along X; the loop is cut at
the slider pin (a point cut; its z-row is identically zero and is dropped). Closed form
(any kinematics text, e.g. Norton, Design of Machinery, Sect. 4.13/7.x), s = sqrt(l^2 - r^2 sin^2):
    x   = r cos(theta) + s
    x'  = -r w sin(theta) - r^2 w sin(theta) cos(theta) / s
    x'' = -r w^2 cos(theta) - r^2 w^2 [cos(2 theta) / s + r^2 sin^2(theta) cos^2(theta) / s^3]
No coordinate is left free, so the engine's kinematic steps (Newton for positions, Phi_z for
velocities, the velocity-product term for accelerations) are checked alone at sample times.
"""
from __future__ import annotations

import math
import time

import numpy as np

from nsd_core.engine.mechanism import Cut, mechanism
from nsd_core.engine.semirecursive import SemiRecursiveSystem

X, Z = (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)


def exact(t, r, l, w):
    th = w * np.asarray(t, float)
    s = np.sqrt(l ** 2 - (r * np.sin(th)) ** 2)
    x = r * np.cos(th) + s
    xd = -r * w * np.sin(th) - r ** 2 * w * np.sin(th) * np.cos(th) / s
    xdd = -r * w ** 2 * np.cos(th) - r ** 2 * w ** 2 * (np.cos(2 * th) / s + r ** 2 * (np.sin(th) * np.cos(th)) ** 2 / s ** 3)
    return x, xd, xdd


def solve(r=0.1, l=0.35, w=2 * math.pi * 5, samples=200, periods=2) -> dict:
    bodies = [dict(name="crank", parent=None, joint="R", axis=Z, mass=1.0, com=(r / 2, 0, 0), inertia=(0, 0, 1e-3)),
              dict(name="rod", parent="crank", joint="R", axis=Z, offset=(r, 0, 0), mass=1.0, com=(l / 2, 0, 0),
                   inertia=(0, 0, 1e-2)),
              dict(name="slider", parent=None, joint="P", axis=X, mass=1.0)]
    mech = mechanism(bodies, [Cut("point", "rod", (l, 0, 0), "slider", (0, 0, 0), name="slider pin")])
    motion = lambda t: (np.array([w * t]), np.array([w]), np.array([0.0]))
    forces = lambda t, kin, z, zd, extra: (np.zeros((3, 6)), None, np.zeros(0))
    system = SemiRecursiveSystem(mech, [0], motion, forces)
    system.choose_partition(np.array([0.0, 0.0, r + l]))
    t = np.linspace(0.0, periods * 2 * math.pi / w, samples + 1)
    start = time.perf_counter()
    ws = system.workspace()
    evs = [system.evaluate(ws, ti, np.zeros(0)) for ti in t]
    wall = time.perf_counter() - start
    x = np.array([e.z[2] for e in evs])
    xd = np.array([e.zd[2] for e in evs])
    xdd = np.array([e.zdd[2] for e in evs])
    xe, xde, xdde = exact(t, r, l, w)
    err = {"position": float(np.max(np.abs(x - xe)) / (r + l)),
           "velocity": float(np.max(np.abs(xd - xde)) / (r * w)),
           "acceleration": float(np.max(np.abs(xdd - xdde)) / (r * w ** 2))}
    return {"problem": "slider-crank", "r": r, "l": l, "omega": w, "samples": samples + 1,
            "relative_errors": err, "error": max(err.values()), "closure": float(max(np.max(np.abs(e.Phi)) for e in evs)),
            "drive_torque_final": float(evs[-1].drive_force[0]), "final_state": [x[-1], xd[-1], xdd[-1]],
            "free": int(len(system.partition.free)), "cpu_time": wall, "goal": 1e-10}
