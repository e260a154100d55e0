"""The NSD on the compiled path: its force and motion callbacks, and one compiled run.

The engine (nsd_core.engine.compiled, nsd_core.engine.rk) knows nothing of the device: it calls ``device_forces``
and ``device_motion`` through function pointers with the device's numbers packed in the model's
``force_params`` / ``motion_params``. The laws themselves are the scalar functions of
nsd_core.device.forces (Eqs. 16-18), the same ones the vectorised numpy laws call.

force_params = [n_ropes, n_wires, k_r, L_r0 (n_ropes), WireLaw (11 fields), SpringLaw (6 fields)]
motion_params = Drive.motion_params (any path: line, circle, ellipse, figure8, a table), evaluated by
the Drive's own ``plate_motion``; the plate's rotation and the base's planar joint are held at zero.
Element order: ropes, wires, then the spring; extra states: wire stresses, then the spring's zeta.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from nsd_core.engine.codegen import evaluator_for
from nsd_core.engine.compiled_model import FORCE_SIG, MOTION_SIG, build_model, make_workspace, split_state
from nsd_core.device.drive import Drive, plate_motion
from nsd_core.device.forces import (bouc_wen_slope_scalar, rope_tension_scalar, sma_slope_scalar, spring_push_scalar,
                                    wire_tension_scalar)
from nsd_core.device.geometry import DeviceGeometry
from nsd_core.engine.rk import Outputs, integrate_kernel, make_outputs, tableau

WIRE_FIELDS, SPRING_FIELDS = 11, 6


@njit(FORCE_SIG, cache=True, _nrt=False)
def device_forces(t, z, zd, P, L, Ld, extra, p, T, gen, rate):
    """Tensions of ropes (Eq. 16), wires (Eq. 17) and the spring (Eq. 18, pushing: T < 0)."""
    nr, nw = int(p[0]), int(p[1])
    k_r = p[2]
    for e in range(nr):
        T[e] = rope_tension_scalar(L[e], p[3 + e], k_r)
    o = 3 + nr
    E, Y, alpha, n, fT, a, Em, eps_t, c, area, L0 = (p[o], p[o + 1], p[o + 2], p[o + 3], p[o + 4], p[o + 5],
                                                   p[o + 6], p[o + 7], p[o + 8], p[o + 9], p[o + 10])
    for k in range(nw):
        e = nr + k
        strain, strain_rate = (L[e] - L0) / L0, Ld[e] / L0
        rate[k] = sma_slope_scalar(strain, strain_rate, extra[k], E, Y, alpha, n, fT, a, Em, eps_t, c) * strain_rate
        T[e] = wire_tension_scalar(extra[k], area)
    o += WIRE_FIELDS
    kse, ksd, beta, gamma, ns, free_length = p[o], p[o + 1], p[o + 2], p[o + 3], p[o + 4], p[o + 5]
    e = nr + nw
    xdot = -Ld[e]  # compression rate
    rate[nw] = bouc_wen_slope_scalar(extra[nw], xdot, ksd, beta, gamma, ns) * xdot
    T[e] = -spring_push_scalar(L[e], extra[nw], kse, free_length)
    return 0


@njit(MOTION_SIG, cache=True, _nrt=False)
def device_motion(t, p, q, qd, qdd):
    """Plate X, Y on the drive's path (plate_motion); plate rotation and the base's planar joint at zero."""
    x, y, xd, yd, xdd, ydd = plate_motion(t, p)
    q[:] = 0.0
    qd[:] = 0.0
    qdd[:] = 0.0
    q[0], q[1] = x, y
    qd[0], qd[1] = xd, yd
    qdd[0], qdd[1] = xdd, ydd
    return 0


def force_params(g: DeviceGeometry) -> np.ndarray:
    return np.concatenate([[g.n_ropes, g.n_wires, g.rope_stiffness], g.rope_natural_length,
                           np.asarray(g.wire, dtype=float), np.asarray(g.spring, dtype=float)])


def motion_params(drive: Drive) -> np.ndarray:
    return drive.motion_params


def compiled_model(system, g: DeviceGeometry, drive: Drive, elements):
    """The immutable compiled model of a device system built by nsd_core.device.device_system."""
    return build_model(system.m, system.partition, system.prescribed,
                       (elements.body_up, elements.pts_up, elements.body_lo, elements.pts_lo),
                       force_params(g), motion_params(drive), n_extra=system.n_extra,
                       newton_tol=system.newton_tol)


def run(model, z0: np.ndarray, y0: np.ndarray, t_eval: np.ndarray, method: str, rtol: float, atol: float,
        max_step: float, max_steps: int, evaluator=None) -> tuple[Outputs, np.ndarray]:
    """One compiled integration; returns the outputs at t_eval and [steps, nfev, status, samples].
    evaluator: an EVAL_FN (nsd_core.engine.compiled_model); default the one generated for the model
    (nsd_core.engine.codegen; NSD_EVALUATOR=generic: the generic one)."""
    evaluator = evaluator or evaluator_for(model)
    ws = make_workspace(model, z0)
    out = make_outputs(len(t_eval), len(y0), len(model.parent), len(model.dependent), len(model.prescribed),
                       len(model.elem_up))
    stats = np.zeros(4, dtype=np.int64)
    settings = np.array([rtol, atol, max_step, 0.0, float(max_steps)])
    integrate_kernel(model, ws, device_forces, device_motion, evaluator, tableau(method),
                     np.ascontiguousarray(y0, float), np.ascontiguousarray(t_eval, float), settings, out, stats)
    return out, stats


__all__ = ["device_forces", "device_motion", "compiled_model", "run", "split_state"]
