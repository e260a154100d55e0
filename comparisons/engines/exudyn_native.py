"""Exudyn's per-step force work compiled (numba): _Elements.step of exudyn_engine in one call.

At the 1e-4 aim Exudyn spends about two thirds of its time in the Python pre-step function, most of
it in ``_Elements.step`` (numpy over 4 ropes and 4 wires: ~50 us a step). This is the same
computation on the shared scalar laws of ``nsd_core.device.forces`` (rope_tension_scalar,
wire_tension_scalar, spring_push_scalar and the strain integrators advance_*_scalar, the one
implementation each array law is built from): commit the hysteretic states at the converged
configuration, predict them at the end of the next step, and return the loads there.

``pre_step`` is the whole pre-step of a drive run in one call: from Exudyn's ODE2 vectors (three
fetches instead of six node outputs), the plate's position at the end of the step, the second-order
Taylor prediction and ``step``. The arithmetic is the numpy form's, operation for operation (position
= reference + coordinate, as Exudyn's node output; p + h v + ((h/2) h) a), so the loads are the same
numbers bit for bit (tests/test_exudyn_prestep.py).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from nsd_core.device.drive import plate_motion
from nsd_core.device.forces import (advance_spring_zeta_scalar, advance_wire_stress_scalar, rope_tension_scalar,
                             spring_push_scalar, wire_tension_scalar)


@njit(cache=True)
def _wire_length(off, j, cx, cy, cz, wz):
    vx, vy, vz = off[j, 0] + cx, off[j, 1] + cy, off[j, 2] + (cz - wz)
    return vx, vy, vz, np.sqrt(vx * vx + vy * vy + vz * vz)


@njit(cache=True)
def _advance_wire(e0, e1, s, w, order):
    return advance_wire_stress_scalar(e0, e1, s, w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7], w[8], 1, order)


@njit(cache=True)
def step(cap, wz, cap_p, wall_p, eps, sigma, x, zeta, rope_off, rope_l0, rope_k, wire_off, wire, spring, order,
         out):
    """One pre-step: as _Elements.step. ``eps``, ``sigma`` (committed, per wire) are updated in place;
    returns the committed (x_s, zeta) and writes the loads at the predicted state into
    out[0:3] (cap) and out[3:6] (wall)."""
    nw, nr = len(eps), len(rope_l0)
    L0w, area = wire[10], wire[9]
    fwx = fwy = fwz = 0.0
    for j in range(nw):
        L_n = _wire_length(wire_off, j, cap[0], cap[1], cap[2], wz)[3]
        vx, vy, vz, L = _wire_length(wire_off, j, cap_p[0], cap_p[1], cap_p[2], wall_p)
        eps_n, eps_p = (L_n - L0w) / L0w, (L - L0w) / L0w
        sig_n = _advance_wire(eps[j], eps_n, sigma[j], wire, order)
        if (eps_p - eps_n) * (eps_n - eps[j]) <= 0.0:   # the strain turns (or rests) at eps_n
            sig_p = _advance_wire(eps_n, eps_p, sig_n, wire, order)
        else:
            sig_p = _advance_wire(eps[j], eps_p, sigma[j], wire, order)
        eps[j], sigma[j] = eps_n, sig_n
        t = wire_tension_scalar(sig_p, area) / L
        fwx += t * vx
        fwy += t * vy
        fwz += t * vz
    ksd, beta, gamma, n = spring[1], spring[2], spring[3], spring[4]
    x_n, x_p = spring[5] - wz, spring[5] - wall_p
    zeta_n = advance_spring_zeta_scalar(x, x_n, zeta, ksd, beta, gamma, n, 1, order)
    if (x_p - x_n) * (x_n - x) <= 0.0:
        zeta_p = advance_spring_zeta_scalar(x_n, x_p, zeta_n, ksd, beta, gamma, n, 1, order)
    else:
        zeta_p = advance_spring_zeta_scalar(x, x_p, zeta, ksd, beta, gamma, n, 1, order)
    frx = fry = frz = 0.0
    for i in range(nr):
        rx, ry, rz = rope_off[i, 0] + cap_p[0], rope_off[i, 1] + cap_p[1], rope_off[i, 2] + cap_p[2]
        rl = np.sqrt(rx * rx + ry * ry + rz * rz)
        t = rope_tension_scalar(rl, rope_l0[i], rope_k[i]) / rl
        frx += t * rx
        fry += t * ry
        frz += t * rz
    out[0], out[1], out[2] = -frx - fwx, -fry - fwy, -frz - fwz
    out[3], out[4] = fwx, fwy
    out[5] = fwz + spring_push_scalar(wall_p, zeta_p, spring[0], spring[5])
    return x_n, zeta_n


@njit(cache=True)
def pre_step(q, q_t, q_tt, at, ref, h, t, path, eps, sigma, xz, rope_off, rope_l0, rope_k, wire_off, wire, spring,
             order, work, out):
    """One pre-step of a drive run (exudyn_engine, forces = per_step): ``q``, ``q_t``, ``q_tt`` are
    Exudyn's ODE2 coordinates and their rates at the converged state (the start of the step), ``at``
    the first ODE2 index of the cap's node and of the wall's, ``ref`` the cap's reference position and
    the wall's reference height, ``t`` the end of the step, ``path`` the drive's packed path.
    Commits the states (``eps``, ``sigma`` in place, ``xz`` = [x_s, zeta]), writes the loads at the
    predicted end of the step into out[0:6] (as ``step``) and the plate's x, y at ``t`` into
    out[6:8]; ``work`` (6) holds the cap's position and its prediction."""
    m = plate_motion(t, path)
    c, w = at[0], at[1]
    hh = 0.5 * h * h
    for i in range(3):
        work[i] = ref[i] + q[c + i]
    work[3], work[4] = m[0], m[1]   # the horizontal end-of-step position is prescribed: exact
    work[5] = (work[2] + h * q_t[c + 2]) + hh * q_tt[c + 2]
    wz = ref[3] + q[w + 2]
    wall_p = (wz + h * q_t[w + 2]) + hh * q_tt[w + 2]
    xz[0], xz[1] = step(work[0:3], wz, work[3:6], wall_p, eps, sigma, xz[0], xz[1], rope_off, rope_l0, rope_k,
                        wire_off, wire, spring, order, out)
    out[6], out[7] = m[0], m[1]


class PreStep:
    """Exudyn's pre-step function of a drive run (exudyn_engine, forces = per_step, drive offsets set
    in the pre-step) as one compiled call a step: ``pre_step`` from the ODE2 vectors, then the two
    loads, a sample at output steps (``record(k)``) and the two drive offsets. ``el`` is the run's
    exudyn_engine._Elements (its committed states are updated in place); ``ref`` the cap's reference
    position and the wall's reference height; ``counter`` the run's step count ([n], advanced here, as
    the Python pre-step does). Call ``assembled()`` after mbs.Assemble()."""

    def __init__(self, mbs, el, nodes, ref, h, path, loads, drives, per_out, record, counter):
        self.mbs, self.el, self.nodes, self.h, self.path = mbs, el, nodes, float(h), path
        self.ref = np.array(ref, dtype=float)
        self.loads, self.drives, self.per_out, self.record, self.counter = loads, drives, per_out, record, counter
        self.at, self.work, self.out = np.zeros(2, dtype=np.int64), np.zeros(6), np.zeros(8)
        self.sd = mbs.systemData
        # own float arrays for the states the compiled call updates in place
        el.eps, el.sigma = np.array(el.eps, dtype=float), np.array(el.sigma, dtype=float)
        self.xz = np.array([el.x, el.zeta], dtype=float)

    def assembled(self) -> None:
        """The nodes' first ODE2 indices (known once the system is assembled)."""
        self.at[:] = [self.mbs.GetNodeODE2Index(n) for n in self.nodes]

    def __call__(self, mbs_, t):
        """t is the END of the step (Exudyn's convention); the state is the converged one at t - h."""
        n, el, sd, out = self.counter[0], self.el, self.sd, self.out
        self.counter[0] += 1
        ro, rl0, rk, wo, wire, spring = el.consts
        pre_step(sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t(), sd.GetODE2Coordinates_tt(), self.at, self.ref,
                 self.h, t, self.path, el.eps, el.sigma, self.xz, ro, rl0, rk, wo, wire, spring, el.order, self.work,
                 out)
        el.x, el.zeta = self.xz[0], self.xz[1]
        set_load = mbs_.SetLoadParameter
        set_load(self.loads[0], "loadVector", out[0:3])
        set_load(self.loads[1], "loadVector", out[3:6])
        if n % self.per_out == 0:
            self.record(n // self.per_out)
        mbs_.SetObjectParameter(self.drives[0], "offset", out[6])
        mbs_.SetObjectParameter(self.drives[1], "offset", out[7])
        return True
