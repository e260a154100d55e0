"""Standard compiled force and motion callbacks for the compiled path (nsd_core.engine.compiled).

Any mechanism runs compiled with these, or with callbacks of its own that have the same signatures
(``FORCE_SIG``, ``MOTION_SIG``): the device supplies its rope, wire and spring laws that way
(nsd_core.device.compiled). Parameters live in the model's ``force_params`` / ``motion_params``.

    no_forces:       nothing applied besides gravity (which is in the mechanism).
    linear_springs:  force_params = [k_1..k_ne, L0_1..L0_ne, gen_1..gen_n]: element tension
                     k (L - L0) and constant generalized joint forces (Andrews' spring and torque).
    no_motion:       no prescribed coordinates.
    uniform_rate:    motion_params = [rate_1..rate_np]: q_i = rate_i t (a crank turned at constant speed).
"""
from __future__ import annotations

from numba import njit

from nsd_core.engine.compiled_model import FORCE_SIG, MOTION_SIG


@njit(FORCE_SIG, cache=True, _nrt=False)
def no_forces(t, z, zd, P, L, Ld, extra, p, T, gen, rate):
    T[:] = 0.0
    return 0


@njit(FORCE_SIG, cache=True, _nrt=False)
def linear_springs(t, z, zd, P, L, Ld, extra, p, T, gen, rate):
    ne = L.shape[0]
    for e in range(ne):
        T[e] = p[e] * (L[e] - p[ne + e])
    for i in range(gen.shape[0]):
        gen[i] = p[2 * ne + i]
    return 0


@njit(MOTION_SIG, cache=True, _nrt=False)
def no_motion(t, p, q, qd, qdd):
    return 0


@njit(MOTION_SIG, cache=True, _nrt=False)
def uniform_rate(t, p, q, qd, qdd):
    for i in range(q.shape[0]):
        q[i] = p[i] * t
        qd[i] = p[i]
        qdd[i] = 0.0
    return 0
