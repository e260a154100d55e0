"""The seismic mode on the compiled path: its force and motion callbacks, and the per-sample outputs.

The same mechanism and partition as nsd_core.structure.seismic (``seismic_mechanism``, Table 1 second
row); the generic compiled engine (nsd_core.engine.compiled, rk) integrates it with these callbacks:
    seismic_motion: the base's planar joint follows the ground, (x_g, y_g, 0), from the ground's
        one implementation (nsd_core.ground.motions.ground_values) on the model's motion_params;
    seismic_forces: the device's elements (nsd_core.device.compiled.device_forces: the shared laws),
        the supports as generalised forces on the plate's X, Y and rotation, and the rates of the
        three energy states: E_input' = -a_g . P_rel with P_rel = P - m_total v_g (P: the
        mechanism's linear momentum, which the engine passes), E_device' = sum T L' (the power the
        elements absorb; they have no end on the ground, so it is frame-free) and
        E_supports_dissipated' = c_b |u'|^2 + c_b r_b^2 theta'^2; with the displacement restrainer
        (nsd_core.device.forces.restrainer_force_scalar, the shared law) its force on the plate and
        E_restrainer' = F delta'. It stops the run with ROD_REACH where |u| >= l_d (RodReachError, exit 4).

force_params = [header (HEADER fields), device block (nsd_core.device.compiled.force_params), ground block]
header: has_device, n_device_params, n_device_extra, ground offset, plate_x, plate_y, plate, base_x,
        base_y, base, cap, wall (indices; -1 without the device), k_b, c_b, k_b r_b^2, c_b r_b^2,
        rod_length, total mass, has_restrainer, u_gap, k_c, n_c, alpha_c, building offset
        (the building's block, nsd_core.structure.building_tree.building_block, after the ground's; its
        story and floor-slab dampers' power is the fifth energy state, E_building_dissipated'),
        isolator offset (-1: none; else a baseline isolator's law constants, Isolator.block(), after the
        building's: its state z is extra[0:2] of a run without the device, its work joins the supports')
motion_params = the ground block (GroundMotion.block()); a fixed-base run prescribes the plate too
(six prescribed coordinates: the slab follows the ground).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, types

from nsd_core.structure.building_tree import building_block
from nsd_core.device.compiled import device_forces, force_params as device_force_params
from nsd_core.device.forces import restrainer_force_scalar
from nsd_core.ground.motions import ground_values
from nsd_core.structure.isolator_laws import hysteretic_force_scalar
from nsd_core.engine.codegen import evaluator_for
from nsd_core.engine.compiled import EVALUATE, copy_into, derivatives, generic_evaluator
from nsd_core.engine.compiled_model import (EVAL_FN, FORCE_FN, FORCE_SIG, MODEL_TYPE, MOTION_FN, MOTION_SIG,
                                            WORK_TYPE, build_model, make_workspace)
from nsd_core.engine.compile_once import compile_once, unit
from nsd_core.engine.rk import STEP_LOOP, integrate_kernel, make_outputs, tableau

HEADER = 25
CHUNK = 1.0  # s of model time per compiled call: progress and Ctrl-C are seen between calls
STEPS_PER_SECOND = 100_000  # accepted steps per model second beyond which a run is a runaway
ROD_REACH = 10  # the force callback's failure code: |u| >= l_d
# columns of sample_outputs' table, in order
COLUMNS = ("x_g", "y_g", "vx_g", "vy_g", "ax_g", "ay_g", "x", "y", "theta", "vx", "vy", "theta_rate", "ax_abs",
           "ay_abs", "device_Fx", "device_Fy", "cap_z", "wall_z", "closure", "kinetic", "height")


@njit(cache=True, _nrt=False)
def building_forces(z, zd, p, o, gen):
    """The building's joint forces on floors and slab (nsd_core.structure.building, per direction:
    story S_i = k_i drift_i + c_i drift_i' on floor i, -S_i on floor i-1; b_i (d_i' - d_0') between
    floor i and the slab); returns the power they dissipate."""
    n = int(p[o])
    if n == 0:
        return 0.0
    sx, sy = int(p[o + 1]), int(p[o + 2])
    power = 0.0
    for a in range(2):
        lower = sx if a == 0 else sy
        slab = lower
        for i in range(n):
            r = o + 3 + 5 * i
            j = int(p[r + a])
            k, c, b = p[r + 2], p[r + 3], p[r + 4]
            dv = zd[j] - zd[lower]
            S = k * (z[j] - z[lower]) + c * dv
            gen[j] -= S
            gen[lower] += S
            rel = zd[j] - zd[slab]
            gen[j] -= b * rel
            gen[slab] += b * rel
            power += c * dv * dv + b * rel * rel
            lower = j
    return power


@njit(FORCE_SIG, cache=True, _nrt=False)
def seismic_forces(t, z, zd, P, L, Ld, extra, p, T, gen, rate):
    has_dev, n_dev, nx_dev, og = p[0] != 0.0, int(p[1]), int(p[2]), int(p[3])
    px, py, pl, bx, by, bs = int(p[4]), int(p[5]), int(p[6]), int(p[7]), int(p[8]), int(p[9])
    k, c, kt, ct, reach, m_total = p[12], p[13], p[14], p[15], p[16], p[17]
    ux, uy = z[px] - z[bx], z[py] - z[by]
    vx, vy = zd[px] - zd[bx], zd[py] - zd[by]
    th, thd = z[pl] - z[bs], zd[pl] - zd[bs]
    absorbed = 0.0
    if has_dev:
        if math.hypot(ux, uy) >= reach:
            return ROD_REACH
        code = device_forces(t, z, zd, P, L, Ld, extra, p[HEADER:HEADER + n_dev], T, gen, rate)
        if code != 0:
            return code
        for e in range(L.shape[0]):
            absorbed += T[e] * Ld[e]  # tension T > 0 resists lengthening: the elements absorb T L'
    gen[px] = -k * ux - c * vx
    gen[py] = -k * uy - c * vy
    gen[pl] = -kt * th - ct * thd
    _, _, vgx, vgy, agx, agy = ground_values(t, p, og)
    rate[nx_dev] = -(agx * (P[0] - m_total * vgx) + agy * (P[1] - m_total * vgy))
    rate[nx_dev + 1] = absorbed
    rate[nx_dev + 2] = c * (vx * vx + vy * vy) + ct * thd * thd
    rate[nx_dev + 3] = 0.0
    rate[nx_dev + 4] = building_forces(z, zd, p, int(p[23]), gen)
    oi = int(p[24])
    if oi >= 0:  # a baseline isolator (nsd_core.structure.isolator_laws, the shared law)
        fx, fy, rate[0], rate[1], power = hysteretic_force_scalar(vx, vy, extra[0], extra[1], p[oi], p[oi + 1],
                                                                  p[oi + 2], p[oi + 3], p[oi + 4])
        gen[px] -= fx
        gen[py] -= fy
        rate[nx_dev + 2] += power
    if p[18] != 0.0:  # the displacement restrainer: the plate pushes it with (fx, fy), it pushes back
        fx, fy, F, _, drate = restrainer_force_scalar(ux, uy, vx, vy, p[19], p[20], p[21], p[22])
        gen[px] -= fx
        gen[py] -= fy
        rate[nx_dev + 3] = F * drate
    return 0


@njit(MOTION_SIG, cache=True, _nrt=False)
def seismic_motion(t, p, q, qd, qdd):
    """The base's planar joint (base_x, base_y, base) follows the ground; no rotation. Six
    prescribed coordinates (a fixed base): the plate's planar joint follows it too."""
    q[0], q[1], qd[0], qd[1], qdd[0], qdd[1] = ground_values(t, p, 0)
    q[2] = qd[2] = qdd[2] = 0.0
    for k in range(3, q.shape[0]):
        q[k], qd[k], qdd[k] = q[k - 3], qd[k - 3], qdd[k - 3]
    return 0


def seismic_force_params(mech, g, structure, ground_block, device: bool) -> np.ndarray:
    ix = {name: (mech.names.index(name) if name in mech.names else -1)
          for name in ("plate_x", "plate_y", "plate", "base_x", "base_y", "base", "cap", "wall")}
    dev = device_force_params(g) if device else np.zeros(0)
    s = structure
    iso = s.isolator if not device else None
    n_extra = (g.n_wires + 1) if device else (2 if iso is not None else 0)
    header = [1.0 if device else 0.0, len(dev), n_extra, HEADER + len(dev),
              *ix.values(), s.stiffness, s.damping, s.stiffness * s.support_radius ** 2,
              s.damping * s.support_radius ** 2, g.params.rod_length if device else math.inf,
              float(np.sum(mech.mass))]
    r = s.restrainer
    header += [1.0, *r.block()] if r is not None else [0.0, 0.0, 0.0, 1.0, 0.0]
    header.append(HEADER + len(dev) + len(ground_block))
    bld = building_block(mech, s.building)
    header.append(HEADER + len(dev) + len(ground_block) + len(bld) if iso is not None else -1.0)
    assert len(header) == HEADER
    return np.concatenate([header, dev, ground_block, bld, iso.block() if iso is not None else np.zeros(0)])


def seismic_model(system, g, structure, ground, device: bool):
    """The immutable compiled model of a system built by nsd_core.structure.seismic.seismic_system."""
    elements = None
    if device:
        el = system.forces.device.elements
        elements = (el.body_up, el.pts_up, el.body_lo, el.pts_lo)
    block = np.ascontiguousarray(ground.block(), dtype=float)
    return build_model(system.m, system.partition, system.prescribed, elements,
                       seismic_force_params(system.m, g, structure, block, device), block,
                       n_extra=system.n_extra, newton_tol=system.newton_tol)


@njit(cache=True, inline="always")
def _kinetic_and_height(m, w, vgx, vgy):
    """Kinetic energy relative to the frame translating with the ground, and sum m g z_com."""
    kin, height = 0.0, 0.0
    for i in range(m.mass.shape[0]):
        mi = m.mass[i]
        if mi == 0.0:
            continue
        g = np.zeros(3)
        for a in range(3):
            g[a] = w.r[i, a] + w.A[i, a, 0] * m.com[i, 0] + w.A[i, a, 1] * m.com[i, 1] + w.A[i, a, 2] * m.com[i, 2]
        om = w.Z[i, 3:]
        v0 = w.Z[i, 0] + om[1] * g[2] - om[2] * g[1] - vgx
        v1 = w.Z[i, 1] + om[2] * g[0] - om[0] * g[2] - vgy
        v2 = w.Z[i, 2] + om[0] * g[1] - om[1] * g[0]
        rot = 0.0  # w . (A J A^T) w = (A^T w) . J (A^T w)
        wl = np.zeros(3)
        for a in range(3):
            wl[a] = w.A[i, 0, a] * om[0] + w.A[i, 1, a] * om[1] + w.A[i, 2, a] * om[2]
        for a in range(3):
            for b in range(3):
                rot += wl[a] * m.inertia[i, a, b] * wl[b]
        kin += 0.5 * (mi * (v0 * v0 + v1 * v1 + v2 * v2) + rot)
        height += mi * g[2] * -m.gravity[2]
    return kin, height


def _sample_outputs(m, w, forces, motion, evaluator, ts, Y, table, tensions, lengths):
    """Evaluate the model once at every sample (t_k, y_k) (the states from the step's dense output)
    for what the state does not hold: accelerations, multipliers, element forces, energies.
    Returns the first failing status (0: all done)."""
    p = m.force_params
    has_dev, og = p[0] != 0.0, int(p[3])
    px, py, pl, bx, by, bs, cap, wall = (int(p[4]), int(p[5]), int(p[6]), int(p[7]), int(p[8]), int(p[9]),
                                         int(p[10]), int(p[11]))
    nr = int(p[HEADER]) if has_dev else 0
    nw = int(p[HEADER + 1]) if has_dev else 0
    dydt = np.zeros(Y.shape[1])
    on_cap = np.zeros(3)
    for k in range(ts.shape[0]):
        code = derivatives(evaluator, ts[k], Y[k], m, w, forces, motion, dydt, bool(True))
        if code != 0:
            return code
        row = table[k]
        row[0], row[1], row[2], row[3], row[4], row[5] = ground_values(ts[k], p, og)
        row[6], row[7], row[8] = w.z[px] - w.z[bx], w.z[py] - w.z[by], w.z[pl] - w.z[bs]
        row[9], row[10], row[11] = w.zd[px] - w.zd[bx], w.zd[py] - w.zd[by], w.zd[pl] - w.zd[bs]
        row[12], row[13] = w.zdd[px], w.zdd[py]
        if has_dev:  # device_F: the plate's force on the device = -(rod + ropes + wires on the cap)
            on_cap[:] = 0.0
            for j in range(m.rows.shape[0]):
                on_cap[m.rows[j]] = w.lam[j]
            for e in range(nr + nw):
                for a in range(3):
                    on_cap[a] -= w.T[e] * w.N[e, a]
            row[14], row[15] = -on_cap[0], -on_cap[1]
            row[16], row[17] = w.r[cap, 2], w.z[wall]
        clo = 0.0
        for v in w.Phi:
            clo = max(clo, abs(v))
        row[18] = clo
        row[19], row[20] = _kinetic_and_height(m, w, row[2], row[3])
        copy_into(tensions[k], w.T)  # not tensions[k] = w.T: its shape check compiles a raise path
        copy_into(lengths[k], w.L)
    return 0


F1, F2 = types.float64[::1], types.float64[:, ::1]
SAMPLE_SIG = types.int64(MODEL_TYPE, WORK_TYPE, FORCE_FN, MOTION_FN, EVAL_FN, F1, F2, F2, F2, F2)
_sample_kernel = njit(cache=True)(_sample_outputs)
SAMPLES = unit("seismic_outputs", ((_sample_kernel, SAMPLE_SIG),))


def sample_outputs(m, w, forces, motion, evaluator, ts, Y, table, tensions, lengths):
    """_sample_outputs compiled once (for SAMPLE_SIG)."""
    compile_once(SAMPLES)
    return _sample_kernel(m, w, forces, motion, evaluator, ts, Y, table, tensions, lengths)


def run(model, z0, y0, t_eval, method, rtol, atol, max_step, first_step, progress=None, evaluator=None):
    """Integrate the seismic model over t_eval in compiled chunks of CHUNK model seconds (each starts
    from the last state of the one before, with first_step) and evaluate the outputs at every sample.

    Returns a dict: y (samples, len(y0)), table (samples, COLUMNS), tensions, lengths (samples,
    elements), done (samples computed), steps, nfev, status (0 ok, else the kernel's code) and, on a
    failure, t_fail, z_fail, q_fail (the time, configuration and prescribed motion being evaluated).
    evaluator: an EVAL_FN (nsd_core.engine.compiled_model); default the one generated for the model
    (nsd_core.engine.codegen; NSD_EVALUATOR=generic: the generic one)."""
    evaluator = evaluator or evaluator_for(model)
    # all three at once: processes started together (a pool's workers) share them out
    compile_once(*((EVALUATE,) if evaluator is generic_evaluator else ()), STEP_LOOP, SAMPLES)
    ns, ny, ne = len(t_eval), len(y0), len(model.elem_up)
    n, nd, npr = len(model.parent), len(model.dependent), len(model.prescribed)
    res = dict(y=np.zeros((ns, ny)), table=np.zeros((ns, len(COLUMNS))), tensions=np.zeros((ns, ne)),
               lengths=np.zeros((ns, ne)), done=0, steps=0, nfev=0, status=0)
    ws, ws_out = make_workspace(model, z0), make_workspace(model, z0)  # stepping, outputs
    tab = tableau(method)
    per_chunk = max(1, int(round(CHUNK / (t_eval[-1] - t_eval[0]) * (ns - 1)))) if ns > 1 else 1
    y = np.ascontiguousarray(y0, dtype=float)
    a = 0
    while True:
        b = min(a + per_chunk, ns - 1)
        ts = np.ascontiguousarray(t_eval[a:b + 1])
        out = make_outputs(len(ts), ny, n, nd, npr, ne)
        stats = np.zeros(4, dtype=np.int64)
        settings = np.array([rtol, atol, max_step, first_step, float(STEPS_PER_SECOND * max(1.0, ts[-1] - ts[0]))])
        status = 0
        if len(ts) > 1:
            status = integrate_kernel(model, ws, seismic_forces, seismic_motion, evaluator, tab, y, ts, settings,
                                      out, stats)
        done = len(ts) if status == 0 else int(stats[3])
        res["steps"] += int(stats[0])
        res["nfev"] += int(stats[1])
        if len(ts) == 1:
            out.y[0] = y
        if status != 0:
            res.update(status=int(status), t_fail=float(ws.time[0]), z_fail=ws.z.copy(), q_fail=ws.q.copy())
        first = 0 if a == 0 else 1  # a chunk's first sample is the last one of the chunk before
        if done > first:
            sl = slice(a + first, a + done)
            res["y"][sl] = out.y[first:done]
            # row slices of C arrays are C-contiguous: the kernel writes into res in place
            code = sample_outputs(model, ws_out, seismic_forces, seismic_motion, evaluator, ts[first:done].copy(),
                                  res["y"][sl], res["table"][sl], res["tensions"][sl], res["lengths"][sl])
            if code != 0 and status == 0:  # pragma: no cover (the samples were evaluated once already)
                res.update(status=int(code), t_fail=float(ws_out.time[0]), z_fail=ws_out.z.copy(),
                           q_fail=ws_out.q.copy())
                return res
        res["done"] = a + done
        if status != 0 or b == ns - 1:
            return res
        if progress:
            progress((t_eval[b] - t_eval[0]) / (t_eval[-1] - t_eval[0]))
        y = np.ascontiguousarray(out.y[-1])
        a = b
