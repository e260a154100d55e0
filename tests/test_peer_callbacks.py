"""The peers' Python callbacks made cheaper (issue 26) compute the same numbers bit for bit: the
row-wise cross product, the geometry kept for the last pose, the array laws through their plain
ufunc. Real MuJoCo and Exudyn modules; the whole runs are compared in test_exudyn_native.py (drive)
and by the gate (seismic)."""
from __future__ import annotations

import numpy as np

from comparisons.engines.exudyn_seismic import _cross, _Elements
from comparisons.engines.mujoco_seismic import _Forces
from nsd_core.device.forces import (advance_wire_stress, advance_wire_stress_scalar, rope_tension, rope_tension_scalar,
                                    spring_push, spring_push_scalar)
from nsd_core.device.geometry import device_geometry
from nsd_core.device.isolation import Structure
from nsd_core.device.params import Params

G = device_geometry(Params())
RNG = np.random.default_rng(7)
STRUCTURE = Structure(mass=3743.80, radius_of_gyration=0.40825, stiffness=147799.2, damping=2352.30,
                      support_radius=0.5)


def test_rowwise_cross_is_numpy_cross_bit_for_bit():
    a, b = RNG.normal(size=(8, 3)) * 0.1, RNG.normal(size=(8, 3)) * 1e3
    assert np.array_equal(_cross(a, b), np.cross(a, b))
    assert np.array_equal(_cross(a, b).sum(0), np.cross(a, b).sum(0))


def _poses(n):
    return [(np.array([*RNG.normal(size=2) * 0.01, G.cap_rest_z + RNG.normal() * 1e-3]), RNG.normal() * 0.01,
             G.wall_rest_z + RNG.normal() * 1e-3) for _ in range(n)]


def test_exudyn_geometry_kept_for_the_last_pose_only():
    """Alternating poses (as a step asks: converged, predicted, converged ...) give what a fresh
    element set computes for each; the same pose twice gives the kept arrays."""
    el = _Elements(G)
    poses = _poses(4)
    for cap, th, wz in poses + poses[::-1] + poses:
        fresh = _Elements(G).geometry(cap, th, wz)
        got = el.geometry(cap, th, wz)
        assert all(np.array_equal(x, y) for x, y in zip(got, fresh))
        assert el.geometry(cap.copy(), th, wz) is got
    cap, th, wz = poses[0]
    assert el.geometry(cap, th + 1e-12, wz)[1] is not got[1]


def test_mujoco_geometry_kept_for_the_last_configuration_only():
    forces = _Forces(G, STRUCTURE, 1)
    qs = [RNG.normal(size=5) * 1e-3 for _ in range(4)]
    for q in qs + qs[::-1]:
        fresh = _Forces(G, STRUCTURE, 1).geometry(q)
        got = forces.geometry(q)
        assert all(np.array_equal(np.asarray(x), np.asarray(y)) for x, y in zip(got, fresh))
        assert forces.geometry(q.copy()) is got
    moved = qs[0].copy()
    moved[4] += 1e-12
    assert forces.geometry(moved)[3] != forces.geometry(qs[0])[3]


def test_array_laws_equal_the_scalar_laws():
    L = G.rope_natural_length + RNG.normal(size=(4,)) * 1e-3
    assert np.array_equal(rope_tension(L, G.rope_natural_length, G.rope_stiffness),
                          [rope_tension_scalar(x, l0, G.rope_stiffness) for x, l0 in zip(L, G.rope_natural_length)])
    wz = G.wall_rest_z + 1e-3
    assert spring_push(wz, 0.0, 12.5, G.spring)[0] == spring_push_scalar(wz, 12.5, G.spring.kse, G.spring.free_length)
    w = G.wire
    e0, e1, s = RNG.normal(size=4) * 1e-3, RNG.normal(size=4) * 1e-3, RNG.normal(size=4) * 1e7
    arr = advance_wire_stress(e0, e1, s, w, substeps=2, order=2)
    one = [advance_wire_stress_scalar(a, b, c, w.E, w.Y, w.alpha, w.n, w.fT, w.a, w.Em, w.eps_t, w.c, 2, 2)
           for a, b, c in zip(e0, e1, s)]
    assert np.array_equal(arr, one)
