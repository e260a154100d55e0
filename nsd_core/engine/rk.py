"""Embedded Runge-Kutta pairs with the step loop compiled: Dormand-Prince 5(4) and DOP853.

The algorithm is scipy's ``RK45``/``DOP853`` step for step (Hairer, Norsett & Wanner, Sec. II.4
and II.10): the same initial step selection, error norms, step-size factors (safety 0.9, factors
in [0.2, 10], no growth right after a rejection), and dense output; tests/test_compiled.py checks
the accepted steps against scipy's on the same right-hand side. The Butcher tableaus are read from
scipy's own coefficient arrays at import (data, not code). Outputs at the requested times come
from each step's dense output, and the model is evaluated there once (reactions, kinematics).
The model's evaluation is an argument (compiled_model.EVAL_FN: nsd_core.engine.compiled's
generic_evaluator, or a mechanism's own), called through a function pointer.
"""
from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

from numba import typeof, types

from nsd_core.engine.compiled import DYNAMICS, EVALUATE, OK, VELOCITIES, copy_into, derivatives, generic_evaluator
from nsd_core.engine.compiled_model import EVAL_FN, FORCE_FN, MODEL_TYPE, MOTION_FN, WORK_TYPE
from nsd_core.engine.compile_once import compile_once, unit

Tableau = namedtuple("Tableau", "A B C E E3 E5 P D A_extra C_extra info")
# info: [n_stages, error_estimator_order, dop853 (1) or interpolating polynomial (0)]
Outputs = namedtuple("Outputs", "y z zd r lam tau closure lengths step_t")  # step_t: accepted step ends
NOT_FINITE, TOO_SMALL_STEP, TOO_MANY_STEPS = 20, 21, 22


def _f(x):
    return np.ascontiguousarray(x, dtype=float)

METHODS = ("DOP853", "RK45")   # the pairs the compiled step loop offers (``tableau``)


def tableau(method: str) -> Tableau:
    """scipy's coefficients of the pair ``method`` (scipy.integrate imported here, at the first run)."""
    from scipy.integrate import DOP853, RK45
    if method == "RK45":
        s = RK45
        return Tableau(_f(s.A), _f(s.B), _f(s.C), _f(s.E), np.zeros(0), np.zeros(0), _f(s.P), np.zeros((0, 0)),
                       np.zeros((0, 0)), np.zeros(0), np.array([s.n_stages, s.error_estimator_order, 0.0]))
    if method == "DOP853":
        s = DOP853
        return Tableau(_f(s.A), _f(s.B), _f(s.C), np.zeros(0), _f(s.E3), _f(s.E5), np.zeros((0, 0)), _f(s.D),
                       _f(s.A_EXTRA), _f(s.C_EXTRA), np.array([s.n_stages, s.error_estimator_order, 1.0]))
    raise ValueError(method)


def make_outputs(n_samples: int, ny: int, n: int, nd: int, npr: int, ne: int, keep_steps: int = 0) -> Outputs:
    """Arrays for the samples; the first ``keep_steps`` accepted step ends are kept too (tests)."""
    return Outputs(np.zeros((n_samples, ny)), np.zeros((n_samples, n)), np.zeros((n_samples, n)),
                   np.zeros((n_samples, n, 3)), np.zeros((n_samples, nd)), np.zeros((n_samples, npr)),
                   np.zeros(n_samples), np.zeros((n_samples, ne)), np.zeros(keep_steps))


# The step loop's helpers below are inlined into it by numba (inline="always"): compiled as functions of
# their own, each would be a library whose machine code numba generates twice, alone and again linked
# into the loop (docs/compilation.md). The loop's arithmetic is the same, its outputs bit for bit.
@njit(cache=True, _nrt=False, inline="always")
def _rms(v):
    acc = 0.0
    for x in v:
        acc += x * x
    return math.sqrt(acc / v.shape[0])


@njit(cache=True, _nrt=False, inline="always")
def _record(k, t, y, m, w, forces, motion, evaluator, out):
    code = evaluator(t, y, m, w, forces, motion, True)
    copy_into(out.y[k], y)
    copy_into(out.z[k], w.z)
    copy_into(out.zd[k], w.zd)
    copy_into(out.r[k], w.r)
    copy_into(out.lam[k], w.lam)
    copy_into(out.tau[k], w.tau)
    c = 0.0
    for v in w.Phi:
        c = max(c, abs(v))
    out.closure[k] = c
    copy_into(out.lengths[k], w.L)
    return code


@njit(cache=True, _nrt=False, inline="always")
def _error_norm(tab, K, h, scale, err, err3):
    ny = scale.shape[0]
    ns = int(tab.info[0])
    if tab.info[2] == 0.0:  # RK45: rms(h K^T E / scale)
        for i in range(ny):
            acc = 0.0
            for s in range(ns + 1):
                acc += K[s, i] * tab.E[s]
            err[i] = acc * h / scale[i]
        return _rms(err)
    e5, e3 = 0.0, 0.0  # DOP853: the 5th- and 3rd-order estimates combined
    for i in range(ny):
        a5, a3 = 0.0, 0.0
        for s in range(ns + 1):
            a5 += K[s, i] * tab.E5[s]
            a3 += K[s, i] * tab.E3[s]
        e5 += (a5 / scale[i]) ** 2
        e3 += (a3 / scale[i]) ** 2
    if e5 == 0.0 and e3 == 0.0:
        return 0.0
    return abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * ny)


@njit(cache=True, _nrt=False, inline="always")
def _stage_state(K, coeffs, s, h, y, out):
    for i in range(y.shape[0]):
        acc = 0.0
        for j in range(s):
            acc += K[j, i] * coeffs[j]
        out[i] = y[i] + acc * h


@njit(cache=True, _nrt=False, inline="always")
def _dense(tab, K, F, t_old, h, y_old, y_new, f_new, tq, out):
    """Value of the step's interpolant at tq into out (F prepared by _prepare_dense for DOP853)."""
    x = (tq - t_old) / h
    ny = y_old.shape[0]
    if tab.info[2] == 0.0:
        order = tab.P.shape[1]
        for i in range(ny):
            acc, p = 0.0, 1.0
            for j in range(order):
                p *= x
                q = 0.0
                for s in range(K.shape[0]):
                    q += K[s, i] * tab.P[s, j]
                acc += q * p
            out[i] = y_old[i] + h * acc
        return
    nF = F.shape[0]
    for i in range(ny):
        acc = 0.0
        for k in range(nF):
            acc += F[nF - 1 - k, i]
            acc *= x if k % 2 == 0 else 1.0 - x
        out[i] = acc + y_old[i]


@njit(cache=True, _nrt=False, inline="always")
def _done(stats, steps, nfev, code, k):
    """The loop's counts (accepted steps, evaluations, status, samples done) into stats; returns the status."""
    stats[0], stats[1], stats[2], stats[3] = steps, nfev, code, k
    return code


@njit(cache=True, _nrt=False, inline="always")
def _first_step(m, w, forces, motion, evaluator, tab, t0, t1, y, f, settings, vectors):
    """scipy's select_initial_step from (t0, y) and f = f(t0, y): returns (status, first step size)."""
    f_new, ys, scale, err, err3 = vectors[3], vectors[4], vectors[5], vectors[6], vectors[7]
    rtol, atol, max_step = settings[0], settings[1], settings[2]
    for i in range(y.shape[0]):
        scale[i] = atol + abs(y[i]) * rtol
        err[i] = y[i] / scale[i]
        err3[i] = f[i] / scale[i]
    d0, d1 = _rms(err), _rms(err3)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, t1 - t0)
    for i in range(y.shape[0]):
        ys[i] = y[i] + h0 * f[i]
    code = derivatives(evaluator, t0 + h0, ys, m, w, forces, motion, f_new, bool(False))
    if code != OK:
        return code, 0.0
    for i in range(y.shape[0]):
        err[i] = (f_new[i] - f[i]) / scale[i]
    d2 = _rms(err) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (tab.info[1] + 1.0))
    return OK, min(100.0 * h0, h1, t1 - t0, max_step)


@njit(cache=True, _nrt=False, inline="always")
def _advance(m, w, forces, motion, evaluator, tab, t, t1, h_abs, min_step, y, f, K, settings, vectors):
    """Trial steps from (t, y) until one passes the error test (scipy's step-size control): returns
    (status, t_new, h, the next step size, evaluations made); the accepted step's stages in K, y_new, f_new."""
    y_new, f_new, ys, scale, err, err3 = vectors[1], vectors[3], vectors[4], vectors[5], vectors[6], vectors[7]
    rtol, atol, ns = settings[0], settings[1], int(tab.info[0])
    err_exp = -1.0 / (tab.info[1] + 1.0)
    nfev, rejected = 0, False
    while True:
        if not h_abs >= min_step:   # (NaN too: a NaN step size would loop here for ever)
            return TOO_SMALL_STEP, t, 0.0, h_abs, nfev
        t_new = t + h_abs
        if t_new - t1 > 0:
            t_new = t1
        h = t_new - t
        h_abs = abs(h)
        copy_into(K[0], f)
        for s in range(1, ns):  # the stages, then the new state and its derivative
            _stage_state(K, tab.A[s], s, h, y, ys)
            code = derivatives(evaluator, t + tab.C[s] * h, ys, m, w, forces, motion, K[s], bool(False))
            nfev += 1
            if code != OK:
                return code, t_new, h, h_abs, nfev
        _stage_state(K, tab.B, ns, h, y, y_new)
        code = derivatives(evaluator, t + h, y_new, m, w, forces, motion, f_new, bool(False))
        nfev += 1
        if code != OK:
            return code, t_new, h, h_abs, nfev
        copy_into(K[ns], f_new)
        for i in range(y.shape[0]):
            scale[i] = atol + max(abs(y[i]), abs(y_new[i])) * rtol
        en = _error_norm(tab, K, h, scale, err, err3)
        if en < 1.0:
            factor = 10.0 if en == 0.0 else min(10.0, 0.9 * en ** err_exp)
            if rejected:
                factor = min(1.0, factor)
            return OK, t_new, h, h_abs * factor, nfev
        h_abs *= max(0.2, 0.9 * en ** err_exp)
        rejected = True


@njit(cache=True, _nrt=False, inline="always")
def _prepare_dense(m, w, forces, motion, evaluator, tab, t, h, y, y_new, f_new, K, F, ys):
    """DOP853's three extra stages and its interpolant's coefficients F for the step (t, h): (status, evaluations)."""
    ns, nk = int(tab.info[0]), K.shape[0]
    for s in range(ns + 1, nk):
        _stage_state(K, tab.A_extra[s - ns - 1], s, h, y, ys)
        code = derivatives(evaluator, t + tab.C_extra[s - ns - 1] * h, ys, m, w, forces, motion, K[s], bool(False))
        if code != OK:
            return code, s - ns
    for i in range(y.shape[0]):
        dy = y_new[i] - y[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (f_new[i] + K[0, i])
        for j in range(tab.D.shape[0]):
            acc = 0.0
            for s in range(nk):
                acc += tab.D[j, s] * K[s, i]
            F[3 + j, i] = h * acc
    return OK, nk - ns - 1


@njit(cache=True, _nrt=False, inline="always")
def _record_step(k, t, h, t_new, t_eval, tab, K, F, y, y_new, f_new, yq, m, w, forces, motion, evaluator, out):
    """The requested times from sample k up to t_new recorded from the step's dense output: (status, next k)."""
    while k < t_eval.shape[0] and t_eval[k] <= t_new:
        if t_eval[k] == t_new:
            copy_into(yq, y_new)
        else:
            _dense(tab, K, F, t, h, y, y_new, f_new, t_eval[k], yq)
        code = _record(k, t_eval[k], yq, m, w, forces, motion, evaluator, out)
        if code != OK:
            return code, k
        k += 1
    return OK, k


@njit(cache=True, _nrt=False)
def _step_loop(m, w, forces, motion, evaluator, tab, t_eval, settings, out, stats, K, F, vectors):
    """The step loop of integrate_kernel on preallocated arrays; compiled without reference counting
    (the workspace's arrays are read through namedtuples in the inner loops, where NRT's atomic counts
    cost more than the arithmetic)."""
    y, y_new, f, f_new, yq = vectors[0], vectors[1], vectors[2], vectors[3], vectors[8]
    dop, max_step = tab.info[2] == 1.0, settings[2]
    t0, t1 = t_eval[0], t_eval[t_eval.shape[0] - 1]
    nfev, steps, t = 0, 0, t0
    # the samples at t0 (t_eval[0]: the state y itself); int(): _record for an int64 k, not a Literal 0
    code, k = _record_step(int(0), t, 0.0, t, t_eval, tab, K, F, y, y, f, yq, m, w, forces, motion, evaluator, out)
    if code == OK:
        code = derivatives(evaluator, t, y, m, w, forces, motion, f, bool(False))
        nfev += 1
    h_abs = settings[3]
    if code == OK and h_abs <= 0.0:
        code, h_abs = _first_step(m, w, forces, motion, evaluator, tab, t0, t1, y, f, settings, vectors)
        nfev += 1
    if code != OK:
        stats[2], stats[3] = code, k
        return code
    while t < t1:
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < min_step:
            h_abs = min_step
        code, t_new, h, h_abs, n = _advance(m, w, forces, motion, evaluator, tab, t, t1, h_abs, min_step, y, f, K,
                                            settings, vectors)
        nfev += n
        if code != OK:
            return _done(stats, steps, nfev, code, k)
        if steps < out.step_t.shape[0]:
            out.step_t[steps] = t_new
        steps += 1
        if steps > settings[4]:
            return _done(stats, steps, nfev, TOO_MANY_STEPS, k)
        if k < t_eval.shape[0] and t_eval[k] <= t_new and t_eval[k] != t_new and dop:
            code, n = _prepare_dense(m, w, forces, motion, evaluator, tab, t, h, y, y_new, f_new, K, F, vectors[4])
            nfev += n
            if code != OK:
                return _done(stats, steps, nfev, code, k)
        code, k = _record_step(k, t, h, t_new, t_eval, tab, K, F, y, y_new, f_new, yq, m, w, forces, motion,
                               evaluator, out)
        if code != OK:
            return _done(stats, steps, nfev, code, k)
        for i in range(y.shape[0]):
            if not math.isfinite(y_new[i]):
                return _done(stats, steps, nfev, NOT_FINITE, k)
        t = t_new
        copy_into(y, y_new)
        copy_into(f, f_new)
    return _done(stats, steps, nfev, OK, k)


# the type of either pair's tableau (a test checks it against both): its arrays' dimensions, not
# scipy's numbers, so that importing this module does not import scipy.integrate
TABLEAU_TYPE = typeof(Tableau(*(np.zeros((0,) * n) for n in (2, 1, 1, 1, 1, 1, 2, 2, 2, 1, 1))))
OUTPUTS_TYPE = typeof(make_outputs(1, 1, 1, 1, 1, 1, 1))
F1, F2, I1 = types.float64[::1], types.float64[:, ::1], types.int64[::1]
# explicit signatures: the force, motion and evaluation callbacks are typed as function pointers, so
# each kernel is compiled (and cached on disk) once for every mechanism, force law and evaluator
STEP_LOOP_SIG = types.int64(MODEL_TYPE, WORK_TYPE, FORCE_FN, MOTION_FN, EVAL_FN, TABLEAU_TYPE, F1, F1, OUTPUTS_TYPE,
                            I1, F2, F2, F2)
RHS_SIG = types.int64(types.float64, F1, MODEL_TYPE, WORK_TYPE, FORCE_FN, MOTION_FN, EVAL_FN, F1)


@njit(cache=True, _nrt=False)
def _rhs(t, y, m, w, forces, motion, evaluator, dydt):
    return derivatives(evaluator, t, y, m, w, forces, motion, dydt, bool(True))


STEP_LOOP = unit("step_loop", ((_step_loop, STEP_LOOP_SIG),))
RHS = unit("rhs_entry", ((_rhs, RHS_SIG),), shared=False)  # scipy's solvers and the tests only


def engine_units() -> tuple:
    """The units every in-house run needs (nsd_core.engine.compile_once): the step loop, and the generic
    evaluation unless NSD_EVALUATOR=generated (with "auto" a structure whose evaluation is not yet
    generated runs on it). A pool's warm-up makes them ready first (device.worker_warmup)."""
    import os
    generic = (VELOCITIES, DYNAMICS, EVALUATE)  # its parts first: two workers take one each
    return (() if os.environ.get("NSD_EVALUATOR") == "generated" else generic) + (STEP_LOOP,)


def _units(evaluator, *units):
    """The units a kernel call needs: the generic evaluation's too when it is the one passed."""
    return ((EVALUATE,) if evaluator is generic_evaluator else ()) + units


def integrate_kernel(m, w, forces, motion, evaluator, tab, y0, t_eval, settings, out, stats):
    """Integrate from t_eval[0] to t_eval[-1], evaluating the model at every t_eval into out.

    evaluator: an EVAL_FN (nsd_core.engine.compiled.generic_evaluator, or a mechanism's own).
    settings: rtol, atol, max_step, first_step (0 = select), max_steps (accepted steps; more is a
    runaway: TOO_MANY_STEPS). stats: steps, nfev, status, samples done. Returns the status (0 ok)."""
    compile_once(*_units(evaluator, STEP_LOOP))
    ny, ns = y0.shape[0], int(tab.info[0])
    dop = tab.info[2] == 1.0
    nk = tab.A_extra.shape[0] + ns + 1 if dop else ns + 1
    K = np.zeros((nk, ny))
    F = np.zeros((7 if dop else 0, ny))
    vectors = np.zeros((9, ny))  # y, y_new, f, f_new, ys, scale, err, err3, yq
    vectors[0] = y0
    return _step_loop(m, w, forces, motion, evaluator, tab, t_eval, settings, out, stats, K, F, vectors)


def rhs_entry(t, y, m, w, forces, motion, evaluator, dydt):
    """One right-hand side (with the reactions) callable from Python (scipy's solvers, the tests)."""
    compile_once(*_units(evaluator, RHS))
    return _rhs(t, y, m, w, forces, motion, evaluator, dydt)
