"""The in-house step loop traced trial by trial, for benchmarks/steps_at_kinks.py: a run's inputs as the
device and seismic modes pass them to the compiled kernel (``Setup``, ``drive_setup``, ``seismic_setup``),
the real kernel's run (``kernel_run``), the kinks' switching functions (``switching``, ``kinds``) and
nsd_core.engine.rk._step_loop copied in Python on the same compiled pieces, logging every trial
(``traced_run``; steps_at_kinks' docstring says what is checked against the kernel)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit, types

from comparisons.config import SeismicCase
from nsd_core.engine import rk
from nsd_core.engine.codegen import evaluator_for
from nsd_core.engine.compiled import OK, derivatives
from nsd_core.engine.compiled_model import EVAL_FN, FORCE_FN, MODEL_TYPE, MOTION_FN, WORK_TYPE, make_workspace

F1 = types.float64[::1]


def _stage(t, y, m, w, forces, motion, evaluator, dydt):
    return derivatives(evaluator, t, y, m, w, forces, motion, dydt, False)  # as the step loop's stages


def _evaluate(t, y, m, w, forces, motion, evaluator):
    return evaluator(t, y, m, w, forces, motion, True)


# the compiled pieces with the callbacks typed as function pointers, as in rk.integrate_kernel
stage_rhs = njit(types.int64(types.float64, F1, MODEL_TYPE, WORK_TYPE, FORCE_FN, MOTION_FN, EVAL_FN, F1),
                 cache=True)(_stage)
evaluate_at = njit(types.int64(types.float64, F1, MODEL_TYPE, WORK_TYPE, FORCE_FN, MOTION_FN, EVAL_FN),
                   cache=True)(_evaluate)
record_sample = njit(types.int64(types.int64, types.float64, F1, MODEL_TYPE, WORK_TYPE, FORCE_FN, MOTION_FN, EVAL_FN,
                                 rk.OUTPUTS_TYPE), cache=True)(rk._record.py_func)


@dataclass
class Setup:
    """One compiled run's inputs, as nsd_core.device.model / seismic pass them to rk.integrate_kernel."""
    name: str
    model: object
    z0: np.ndarray
    y0: np.ndarray
    t_eval: np.ndarray
    forces: object
    motion: object
    settings: np.ndarray      # rtol, atol, max_step, first_step (0: select), max_steps
    n_free: int
    n_ropes: int
    n_wires: int
    rope_l0: np.ndarray
    wire_l0: float
    spring: tuple             # (k_se, free length) of Eq. 18
    knots: np.ndarray         # times where the input itself has a kink (the record's samples)
    evaluator: object = None  # the model's evaluation, as the runs choose it (codegen.evaluator_for)

    def __post_init__(self):
        self.evaluator = self.evaluator or evaluator_for(self.model)


def drive_setup(case, rtol=1e-7, atol=1e-12, max_step=1e-3) -> Setup:
    from nsd_core.device.compiled import compiled_model, device_forces, device_motion
    from nsd_core.device.model import MAX_STEPS_PER_CYCLE, device_system, rest_state
    drive = case.drive
    system, g = device_system(case.params, drive)
    z_rest, y0 = rest_state(system, g, system.workspace())
    model = compiled_model(system, g, drive, system.forces.elements)
    return Setup(case.name, model, z_rest, np.ascontiguousarray(y0, float), drive.output_times(), device_forces,
                 device_motion, np.array([rtol, atol, max_step, 0.0, float(MAX_STEPS_PER_CYCLE * drive.cycles)]),
                 len(system.partition.free), g.n_ropes, g.n_wires, np.asarray(g.rope_natural_length, float),
                 g.wire.natural_length, (g.spring.kse, g.spring.free_length), np.zeros(0))


def seismic_setup(case: SeismicCase, rtol=1e-7, atol=1e-12, max_step=1e-3) -> Setup:
    from nsd_core.structure import compiled_seismic as cs
    from nsd_core.structure.seismic import N_ENERGY, _rest, output_times, seismic_system
    structure, ground = case.isolated_structure(), case.ground
    system, g, _ = seismic_system(case.params, structure, ground, True)
    mech = system.m
    extra0 = np.concatenate([g.initial_wire_stress(), [g.spring_zeta0], np.zeros(N_ENERGY)])
    ws = system.workspace()
    z0 = _rest(g, mech, True)
    y0 = system.state(system.assemble(ws, 0.0, z0[system.partition.free]).copy(), np.zeros(mech.n), extra0)
    t_eval = output_times(case.model_duration, case.dt_out)
    assert t_eval[-1] - t_eval[0] <= cs.CHUNK, "one compiled chunk (a longer run restarts its loop per chunk)"
    model = cs.seismic_model(system, g, structure, ground, True)
    first_step = min(max_step, 1e-4, case.model_duration)  # as simulate_seismic
    knots = np.unique(np.concatenate([c.t for c in ground.comp])) if hasattr(ground, "comp") else np.zeros(0)
    return Setup(case.name, model, system.z_ref, np.ascontiguousarray(y0, float), t_eval, cs.seismic_forces,
                 cs.seismic_motion, np.array([rtol, atol, max_step, first_step,
                                              float(cs.STEPS_PER_SECOND * max(1.0, t_eval[-1] - t_eval[0]))]),
                 len(system.partition.free), g.n_ropes, g.n_wires, np.asarray(g.rope_natural_length, float),
                 g.wire.natural_length, (g.spring.kse, g.spring.free_length), knots)


def _outputs(s: Setup, keep_steps=0):
    m = s.model
    return rk.make_outputs(len(s.t_eval), len(s.y0), len(m.parent), len(m.dependent), len(m.prescribed),
                           len(m.elem_up), keep_steps)


def kernel_run(s: Setup, keep_steps: int):
    """The real compiled kernel: (accepted step ends, [steps, nfev, status, samples], outputs)."""
    out, stats = _outputs(s, keep_steps), np.zeros(4, dtype=np.int64)
    rk.integrate_kernel(s.model, make_workspace(s.model, s.z0), s.forces, s.motion, s.evaluator, rk.tableau("DOP853"),
                        s.y0.copy(), np.ascontiguousarray(s.t_eval), s.settings, out, stats)
    return out.step_t[:min(int(stats[0]), keep_steps)].copy(), stats, out


def switching(s: Setup, w, t: float, y: np.ndarray) -> np.ndarray | None:
    """The switching functions of every kink of the right-hand side at (t, y), on workspace w (None
    where the model cannot be evaluated), in the order of ``kinds``: l_r - l_r0 per rope (Eq. 16's
    H), the spring's unclipped push k_se x_s + zeta (Eq. 18, push-only), each wire's stress (Eq. 17a's
    H(sigma)), strain (|eps| in 17d and H(-eps deps) in 17c) and strain rate (sgn(deps) in 17b and
    17c), the spring's zeta and compression rate (sgn(zeta dx_s) in Eq. 18b)."""
    if evaluate_at(t, y, s.model, w, s.forces, s.motion, s.evaluator) != OK:
        return None
    nr, nw = s.n_ropes, s.n_wires
    ex = y[2 * s.n_free:]
    k_se, free = s.spring
    L, Ld, wl0 = w.L, w.Ld, s.wire_l0
    return np.concatenate([L[:nr] - s.rope_l0, [k_se * (free - L[nr + nw]) + ex[nw]], ex[:nw],
                           L[nr:nr + nw] - wl0, Ld[nr:nr + nw], [ex[nw], -Ld[nr + nw]]])


def kinds(s: Setup) -> list[str]:
    nr, nw = s.n_ropes, s.n_wires
    return (["rope"] * nr + ["spring_lift"] + ["wire_slack"] * nw + ["wire_strain_zero"] * nw
            + ["wire_reversal"] * nw + ["spring_zeta_zero", "spring_reversal"])


KINDS = ("rope", "spring_lift", "wire_slack", "wire_strain_zero", "wire_reversal", "spring_zeta_zero",
         "spring_reversal")
STATE_KINKS = ("rope", "spring_lift")  # the kinks asked about first: rope slack/taut and lift-off


def components(s: Setup) -> list[str]:
    """Names of the state's entries: the free coordinates, their rates, the extra states."""
    nf, nw = s.n_free, s.n_wires
    names = [f"z{i}" for i in range(nf)] + [f"zd{i}" for i in range(nf)] + [f"sigma{j}" for j in range(nw)] + ["zeta"]
    return names + [f"energy{i}" for i in range(len(s.y0) - len(names))]


def traced_run(s: Setup, keep_states: bool = False) -> dict:
    """rk._step_loop step for step (DOP853), in Python on the same compiled pieces, logging every trial.

    Returns arrays per trial: t (start), h, error norm, accepted, crossed (kinds whose switching sign
    differs between the trial's start and end state), knot (a record sample inside the trial); the
    accepted step ends; steps and nfev counted as the kernel counts them."""
    tab = rk.tableau("DOP853")
    m, forces, motion, ev = s.model, s.forces, s.motion, s.evaluator
    w, w2 = make_workspace(m, s.z0), make_workspace(m, s.z0)  # the run's, the switching functions'
    max_step = s.settings[2]
    t_eval = np.ascontiguousarray(s.t_eval)
    out = _outputs(s)
    ny, ns = len(s.y0), int(tab.info[0])
    nk = tab.A_extra.shape[0] + ns + 1
    K, F = np.zeros((nk, ny)), np.zeros((7, ny))
    y, y_new, f, f_new, ys = s.y0.copy(), np.zeros(ny), np.zeros(ny), np.zeros(ny), np.zeros(ny)
    scale, err, err3, yq = np.zeros(ny), np.zeros(ny), np.zeros(ny), np.zeros(ny)
    err_exp = -1.0 / (tab.info[1] + 1.0)
    t0, t1 = t_eval[0], t_eval[-1]
    nfev, steps, k, t = 0, 0, 0, t0
    while k < len(t_eval) and t_eval[k] <= t:
        assert record_sample(k, t_eval[k], y, m, w, forces, motion, ev, out) == OK
        k += 1
    assert stage_rhs(t, y, m, w, forces, motion, ev, f) == OK
    nfev += 1
    h_abs, n = _first_step(s, tab, w, y, f, ys, f_new, scale, t0, t1)
    nfev += n
    trials = {"t": [], "h": [], "err": [], "accepted": [], "crossed": [], "knot": [], "worst": []}
    step_ends, states = [], []
    sw = switching(s, w2, t, y)
    while t < t1:
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        h_abs = max_step if h_abs > max_step else (min_step if h_abs < min_step else h_abs)
        rejected = False
        while True:
            assert h_abs >= min_step, "step size underflow"
            t_new = min(t + h_abs, t1)
            h = t_new - t
            h_abs = abs(h)
            en, sw_new = _trial(s, tab, w, w2, K, t, t_new, h, y, y_new, f, f_new, ys, scale, err, err3, sw, trials)
            nfev += ns
            if en < 1.0:
                factor = 10.0 if en == 0.0 else min(10.0, 0.9 * en ** err_exp)
                if rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                break
            h_abs *= max(0.2, 0.9 * en ** err_exp)
            rejected = True
        step_ends.append(t_new)
        if keep_states:
            states.append(y_new.copy())
        steps += 1
        k, n = _samples_in_step(s, tab, w, K, F, k, t_eval, t, h, t_new, y, y_new, f_new, ys, yq, out)
        nfev += n
        t = t_new
        y[:] = y_new
        f[:] = f_new
        sw = sw_new
    res = {key: np.array(v) if key != "crossed" else v for key, v in trials.items()}
    res.update(step_ends=np.array(step_ends), steps=steps, nfev=nfev, outputs=out, states=np.array(states))
    return res


def _first_step(s: Setup, tab, w, y, f, ys, f_new, scale, t0, t1) -> tuple[float, int]:
    """The first step size and its evaluations: the settings' own (> 0), else select_initial_step as the kernel."""
    rtol, atol, max_step = s.settings[0], s.settings[1], s.settings[2]
    h_abs = s.settings[3]
    if not h_abs <= 0.0:
        return h_abs, 0
    scale[:] = atol + np.abs(y) * rtol
    d0, d1 = rk._rms(y / scale), rk._rms(f / scale)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, t1 - t0)
    ys[:] = y + h0 * f
    assert stage_rhs(t0 + h0, ys, s.model, w, s.forces, s.motion, s.evaluator, f_new) == OK
    d2 = rk._rms((f_new - f) / scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (tab.info[1] + 1.0))
    return min(100.0 * h0, h1, t1 - t0, max_step), 1


def _trial(s: Setup, tab, w, w2, K, t, t_new, h, y, y_new, f, f_new, ys, scale, err, err3, sw, trials):
    """One trial step from (t, y) to t_new = t + h: its stages (ns evaluations), y_new and f_new, its error
    norm and the switching signs at its end, returned; the trial logged in ``trials``."""
    m, forces, motion, ev = s.model, s.forces, s.motion, s.evaluator
    rtol, atol, ns = s.settings[0], s.settings[1], int(tab.info[0])
    K[0] = f
    for st in range(1, ns):
        rk._stage_state(K, tab.A[st], st, h, y, ys)
        assert stage_rhs(t + tab.C[st] * h, ys, m, w, forces, motion, ev, K[st]) == OK
    rk._stage_state(K, tab.B, ns, h, y, y_new)
    assert stage_rhs(t + h, y_new, m, w, forces, motion, ev, f_new) == OK
    K[ns] = f_new
    scale[:] = atol + np.maximum(np.abs(y), np.abs(y_new)) * rtol
    en = rk._error_norm(tab, K, h, scale, err, err3)
    a5 = (tab.E5 @ K[:ns + 1]) / scale  # DOP853's 5th-order estimate per entry (the norm's main part)
    trials["worst"].append(int(np.argmax(np.abs(a5))))
    sw_new = switching(s, w2, t_new, y_new)
    crossed = sorted({kinds(s)[i] for i in np.flatnonzero(np.sign(sw_new) != np.sign(sw))}) \
        if sw is not None and sw_new is not None else ["unknown"]
    trials["t"].append(t)
    trials["h"].append(h)
    trials["err"].append(en)
    trials["accepted"].append(en < 1.0)
    trials["crossed"].append(crossed)
    trials["knot"].append(bool(np.any((s.knots > t) & (s.knots < t_new))))
    return en, sw_new


def _samples_in_step(s: Setup, tab, w, K, F, k, t_eval, t, h, t_new, y, y_new, f_new, ys, yq, out):
    """The samples in the accepted step (t, t_new], dense ones after DOP853's extra stages: next index, evaluations."""
    m, forces, motion, ev = s.model, s.forces, s.motion, s.evaluator
    ns, nk, nfev = int(tab.info[0]), K.shape[0], 0
    if k < len(t_eval) and t_eval[k] <= t_new and t_eval[k] != t_new:  # DOP853's three extra stages
        for st in range(ns + 1, nk):
            rk._stage_state(K, tab.A_extra[st - ns - 1], st, h, y, ys)
            assert stage_rhs(t + tab.C_extra[st - ns - 1] * h, ys, m, w, forces, motion, ev, K[st]) == OK
            nfev += 1
        dy = y_new - y
        F[0], F[1], F[2] = dy, h * K[0] - dy, 2.0 * dy - h * (f_new + K[0])
        for j in range(tab.D.shape[0]):
            F[3 + j] = h * _dot_rows(tab.D[j], K)
    while k < len(t_eval) and t_eval[k] <= t_new:
        if t_eval[k] == t_new:
            yq[:] = y_new
        else:
            rk._dense(tab, K, F, t, h, y, y_new, f_new, t_eval[k], yq)
        assert record_sample(k, t_eval[k], yq, m, w, forces, motion, ev, out) == OK
        k += 1
    return k, nfev


def _dot_rows(d, K):
    """sum_s d[s] K[s, i] for every i, in the kernel's order (s ascending), so the bits agree."""
    acc = np.zeros(K.shape[1])
    for s_ in range(K.shape[0]):
        acc = acc + d[s_] * K[s_]
    return acc
