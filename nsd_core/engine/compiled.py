"""The semirecursive right-hand side (Eqs. 2-14) compiled end to end, for any mechanism.

The same equations as ``SemiRecursiveSystem._rhs_numpy`` (the readable specification; a test keeps
the two equal), on a ``SystemModel`` and a ``Workspace`` (nsd_core.engine.compiled_model): Newton for the
dependent coordinates with the predictor and branch check of ``SemiRecursiveSystem.assemble``, the
dependent velocities (Eq. 10), the two-point elements, the applied forces through a compiled
``forces`` callback, Eqs. 7-8 recursively and Eq. 12 in the free coordinates. Nothing is allocated
per call beyond a few 3-vectors inside the shared recursions. Small dense blocks are factored by
LU with partial pivoting written here, so a singular block is a status code, not an exception.

The whole evaluation (``evaluate``) is compiled once, as ``generic_evaluator`` for
compiled_model.EVAL_SIG, and reaches the step loop and the output kernels as an argument (a function
pointer, EVAL_FN): they are compiled small and once, and a mechanism may hand them its own evaluation.

Flags handed to the shared kernels are written bool(...) and int(...): numba types a constant
argument as a Literal and compiles the callee once per value; a plain bool or int makes one serve.

Status codes: 0 ok, 1 Newton did not converge, 2 singular dependent block, 3 singular reduced mass
matrix, >= 10 a failure reported by the force callback.
"""
from __future__ import annotations

import numpy as np
from numba import njit, types

from nsd_core.engine.closure import closure_kernel
from nsd_core.engine.compiled_model import ARRAY, EVAL_SIG, MODEL_TYPE, WORK_TYPE
from nsd_core.engine.dynamics import body_terms_kernel, linear_momentum_kernel, tree_product
from nsd_core.engine.elements import apply_tensions, element_kinematics
from nsd_core.engine.kinematics import positions_kernel, velocities_kernel
from nsd_core.engine.compile_once import DONE, announce_compilation, compile_once, unit

announce_compilation()  # one line on stderr when this process compiles the engine (a cold cache)

OK, NEWTON_FAILED, SINGULAR_BLOCK, SINGULAR_MASS = 0, 1, 2, 3

# helpers called only from compiled functions, on the model and workspace tuples (~80 arrays): compiled
# without the Python and C entry wrappers numba otherwise generates (unboxing every array; most of such a
# helper's machine code, which nothing calls). A call from Python would crash the process:
# tests/test_compiled_only.py checks that every use is inside a compiled function.
compiled_only = njit(cache=True, _nrt=False, no_cpython_wrapper=True, no_cfunc_wrapper=True)


@njit(cache=True, _nrt=False)
def copy_into(dst, src):
    """dst[...] = src, element by element (1-D or 2-D): a slice copy may allocate a temporary, and
    these kernels run without numba's reference counting, so they must not allocate."""
    if dst.ndim == 1:
        for i in range(dst.shape[0]):
            dst[i] = src[i]
    else:
        for i in range(dst.shape[0]):
            for j in range(dst.shape[1]):
                dst[i, j] = src[i, j]


@njit(cache=True, _nrt=False)
def lu_factor(a, piv):
    """In place, partial pivoting (LAPACK's getrf rule). False when a pivot is exactly zero."""
    n = a.shape[0]
    for k in range(n):
        p, big = k, abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > big:
                p, big = i, abs(a[i, k])
        piv[k] = p
        if big == 0.0:
            return False
        if p != k:
            for j in range(n):
                a[k, j], a[p, j] = a[p, j], a[k, j]
        for i in range(k + 1, n):
            a[i, k] /= a[k, k]
            f = a[i, k]
            for j in range(k + 1, n):
                a[i, j] -= f * a[k, j]
    return True


@njit(cache=True, _nrt=False)
def lu_solve(a, piv, b):
    """Solve in place with the factors of lu_factor."""
    n = a.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            b[k], b[p] = b[p], b[k]
    for i in range(n):
        for j in range(i):
            b[i] -= a[i, j] * b[j]
    for i in range(n - 1, -1, -1):
        for j in range(i + 1, n):
            b[i] -= a[i, j] * b[j]
        b[i] /= a[i, i]


@compiled_only
def _closure(m, w, with_rates, with_positions):
    """Phi and Phi_z (with_positions), c (with_rates) of the loop cuts into the workspace."""
    if with_positions:
        w.Phi[:] = 0.0
        w.J[:, :] = 0.0
    w.c[:] = 0.0
    closure_kernel(m.parent, m.cut_kind, m.cut_a, m.cut_va, m.cut_b, m.cut_vb, w.A, w.r, w.B, w.Z, w.vp,
                   with_rates, w.Phi, w.J, w.c, w.scratch, with_positions)


@compiled_only
def _factor_dependent_block(m, w):
    dep, rows = m.dependent, m.rows
    for i in range(dep.shape[0]):
        for j in range(dep.shape[0]):
            w.Jd[i, j] = w.J[rows[i], dep[j]]
    return lu_factor(w.Jd, w.piv)


@compiled_only
def _newton(m, w, z):
    """Newton on the independent loop equations for the dependent coordinates of z (in place)."""
    dep, rows = m.dependent, m.rows
    nd = dep.shape[0]
    tol, maxit = m.settings[0], int(m.settings[1])
    w.kin_current[0] = 0
    first_dep = z.shape[0]
    for i in range(nd):
        first_dep = min(first_dep, dep[i])
    for it in range(maxit):
        w.counters[1] += 1
        # after the first pass only dependent coordinates change: bodies before the first dependent
        # joint (bodies are in tree order, parents first) keep their positions
        start = 0 if it == 0 else first_dep
        positions_kernel(m.parent, m.jtype, m.axis, m.offset, z, w.A, w.r, w.B, w.scratch, start)
        _closure(m, w, bool(False), bool(True))
        res, pos = 0.0, 1.0
        for i in range(nd):
            res = max(res, abs(w.Phi[rows[i]]))
        for i in range(w.r.shape[0]):
            for a in range(3):
                pos = max(pos, abs(w.r[i, a]))
        if res <= 4e-16 * pos:  # closed to round-off of the positions
            w.kin_current[0] = 1  # A, r, B, Phi, Phi_z are those of z: the velocity stage reuses them
            return OK
        if not _factor_dependent_block(m, w):
            return SINGULAR_BLOCK
        for i in range(nd):
            w.step[i] = w.Phi[rows[i]]
        lu_solve(w.Jd, w.piv, w.step)
        smax, zmax = 0.0, 0.0
        for i in range(nd):
            z[dep[i]] -= w.step[i]
            smax = max(smax, abs(w.step[i]))
            zmax = max(zmax, abs(z[dep[i]]))
        if smax < tol * (1.0 + zmax):
            return OK
    return NEWTON_FAILED


@njit(cache=True, _nrt=False)
def _maxdiff_dep(dep, a, b):
    out = 0.0
    for i in range(dep.shape[0]):
        out = max(out, abs(a[dep[i]] - b[dep[i]]))
    return out


@njit(cache=True, _nrt=False)
def _assemble(m, w, t, zf):
    """Full configuration on the loop manifold into w.z, for free coordinates zf and w.q.

    The branch rule of SemiRecursiveSystem.assemble, taken from the other side: Newton starts from
    the first-order predictor z_dep + S dz when there is one (two iterations where the plain warm
    start needs four or five); only when its answer strays from the predictor by more than the
    predictor's own second-order error is Newton from the warm start tried as well, and the answer
    closer to the predictor kept. Both converge to the same root to round-off.
    """
    dep, n = m.dependent, w.z.shape[0]
    nd = dep.shape[0]
    z = w.z_start
    copy_into(z, w.z)
    for a in range(m.prescribed.shape[0]):
        z[m.prescribed[a]] = w.q[a]
    for a in range(m.free.shape[0]):
        z[m.free[a]] = zf[a]
    copy_into(w.z, z)
    w.kin_current[0] = 0
    if nd == 0:
        return OK
    w.counters[0] += 1
    if w.has_lin[0] == 0:
        return _newton(m, w, w.z)
    move = 0.0
    for j in range(nd):  # z_dep + S dz along the manifold (S from the last evaluation)
        acc = w.z_lin[dep[j]]
        for k in range(n):
            acc += w.S[j, k] * (z[k] - w.z_lin[k])  # S is zero on the dependent columns
        w.pred[j] = acc
        w.z[dep[j]] = acc
        move = max(move, abs(acc - w.z_lin[dep[j]]))
    code = _newton(m, w, w.z)
    dev = np.inf
    if code == OK:
        dev = 0.0
        for j in range(nd):
            dev = max(dev, abs(w.z[dep[j]] - w.pred[j]))
    if dev > 0.02 * move + 1e-10:  # maybe another branch: solve from the warm start too
        w.counters[2] += 1
        copy_into(w.z_alt, z)
        if _newton(m, w, w.z_alt) == OK:
            dev_alt = 0.0
            for j in range(nd):
                dev_alt = max(dev_alt, abs(w.z_alt[dep[j]] - w.pred[j]))
            if code != OK or (_maxdiff_dep(dep, w.z_alt, w.z) > 1e-8 and dev_alt < dev):
                copy_into(w.z, w.z_alt)
                code = OK
            else:
                w.kin_current[0] = 0  # the kinematics in w are z_alt's
        else:
            w.kin_current[0] = 0
    return code


@njit(cache=True, _nrt=False)
def velocities_and_predictor(m, w, zfd):
    """Positions at w.z, Phi_z, z' with the dependent part from Eq. 10, Z, vp, c; store the predictor."""
    dep, rows, free, pres = m.dependent, m.rows, m.free, m.prescribed
    nd, n = dep.shape[0], w.z.shape[0]
    if w.kin_current[0] == 0:
        positions_kernel(m.parent, m.jtype, m.axis, m.offset, w.z, w.A, w.r, w.B, w.scratch, int(0))
        _closure(m, w, bool(False), bool(True))
    w.kin_current[0] = 0
    w.zd[:] = 0.0
    for a in range(pres.shape[0]):
        w.zd[pres[a]] = w.qd[a]
    for a in range(free.shape[0]):
        w.zd[free[a]] = zfd[a]
    if nd:
        if not _factor_dependent_block(m, w):
            return SINGULAR_BLOCK
        for k in range(nd):  # Jd^-1, column by column
            w.col[:nd] = 0.0
            w.col[k] = 1.0
            lu_solve(w.Jd, w.piv, w.col[:nd])
            for j in range(nd):
                w.Jd_inv[j, k] = w.col[j]
        for j in range(nd):  # S = -Jd^-1 Jr with zero dependent columns
            for k in range(n):
                acc = 0.0
                for i in range(nd):
                    acc -= w.Jd_inv[j, i] * w.J[rows[i], k]
                w.S[j, k] = acc
            for i in range(nd):
                w.S[j, dep[i]] = 0.0
        for j in range(nd):
            acc = 0.0
            for k in range(n):
                acc += w.S[j, k] * w.zd[k]
            w.zd[dep[j]] = acc
        copy_into(w.z_lin, w.z)
        w.has_lin[0] = 1
    velocities_kernel(m.parent, m.jtype, w.B, w.r, w.zd, w.Z, w.vp, w.scratch)
    _closure(m, w, bool(True), bool(False))  # positions unchanged: only c is new
    return OK


@njit(cache=True, _nrt=False)
def reduced_dynamics(m, w, reactions=True):
    """Eqs. 7-8 with w.wrench, w.gen; Eq. 12 in the free coordinates; the reactions lambda, tau
    (unless ``reactions`` is False: a step's stages need only z'', the outputs need the reactions).

    Eq. 12 needs M only in products (R_z^T M R_z and M z''_0), so each is one O(n) pass of the
    recursion (dynamics.tree_product) and the n x n matrix of Eq. 8 is never formed.
    """
    dep, rows, free, pres = m.dependent, m.rows, m.free, m.prescribed
    nd, nf, npr, n = dep.shape[0], free.shape[0], pres.shape[0], w.z.shape[0]
    w.Mb[:, :, :] = 0.0
    copy_into(w.Qb, w.wrench)
    body_terms_kernel(m.mass, m.com, m.inertia, m.gravity, w.A, w.r, w.Z, True, w.Mb, w.Qb, w.scratch)
    w.Rz[:, :] = 0.0  # Eq. 10
    for a in range(nf):
        w.Rz[free[a], a] = 1.0
        for j in range(nd):
            w.Rz[dep[j], a] = w.S[j, free[a]]
    w.zdd0[:] = 0.0
    for a in range(npr):
        w.zdd0[pres[a]] = w.qdd[a]
    for j in range(nd):
        acc = 0.0
        for i in range(nd):
            rhs_i = -w.c[rows[i]]
            for a in range(npr):
                rhs_i -= w.J[rows[i], pres[a]] * w.qdd[a]
            acc += w.Jd_inv[j, i] * rhs_i
        w.zdd0[dep[j]] = acc
    # res = M zdd0 - Q; the reduced right-hand side is -R_z^T res
    tree_product(m.parent, w.B, w.vp, w.Mb, w.Qb, w.gen, w.zdd0, bool(True), w.acc6, w.Fsub, w.res)
    for b in range(nf):
        for i in range(n):
            w.vec[i] = w.Rz[i, b]
        tree_product(m.parent, w.B, w.vp, w.Mb, w.Qb, w.gen, w.vec, bool(False), w.acc6, w.Fsub, w.Mv)  # M R_z[:, b]
        for a in range(nf):
            acc = 0.0
            for i in range(n):
                acc += w.Rz[i, a] * w.Mv[i]
            w.red[a, b] = acc
    for a in range(nf):
        acc = 0.0
        for i in range(n):
            acc -= w.Rz[i, a] * w.res[i]
        w.red_rhs[a] = acc
    if nf and not lu_factor(w.red, w.red_piv):
        return SINGULAR_MASS
    lu_solve(w.red, w.red_piv, w.red_rhs)
    for i in range(n):
        acc = w.zdd0[i]
        for a in range(nf):
            acc += w.Rz[i, a] * w.red_rhs[a]
        w.zdd[i] = acc
    if not reactions:
        return OK
    # M z'' - Q = Phi_z^T lambda + E^T tau
    tree_product(m.parent, w.B, w.vp, w.Mb, w.Qb, w.gen, w.zdd, bool(True), w.acc6, w.Fsub, w.res)
    for j in range(nd):
        acc = 0.0
        for i in range(nd):
            acc += w.Jd_inv[i, j] * w.res[dep[i]]
        w.lam[j] = acc
    for a in range(npr):
        acc = w.res[pres[a]]
        for i in range(nd):
            acc -= w.J[rows[i], pres[a]] * w.lam[i]
        w.tau[a] = acc
    return OK


@njit(cache=True, _nrt=False)
def evaluate(t, y, m, w, forces, motion, reactions):
    """Everything at (t, y): w.z, w.zd, w.zdd, w.lam, w.tau (with ``reactions``), w.extra_rate, the
    kinematics (the contract of compiled_model.EVAL_SIG)."""
    nf = m.free.shape[0]  # y = [z_f, z'_f, extra]: the layout of compiled_model.split_state
    w.time[0] = t
    motion(t, m.motion_params, w.q, w.qd, w.qdd)
    code = _assemble(m, w, t, y[:nf])
    if code != OK:
        return code
    code = velocities_and_predictor(m, w, y[nf:2 * nf])
    if code != OK:
        return code
    element_kinematics(m.elem_up, m.elem_pu, m.elem_lo, m.elem_pl, w.A, w.r, w.Z, w.P_up, w.P_lo, w.N,
                       w.L, w.Ld, w.scratch)
    copy_into(w.extra, y[2 * nf:])
    w.gen[:] = 0.0
    linear_momentum_kernel(m.mass, m.com, w.A, w.r, w.Z, w.momentum)
    code = forces(t, w.z, w.zd, w.momentum, w.L, w.Ld, w.extra, m.force_params, w.T, w.gen, w.extra_rate)
    if code != OK:
        return code
    w.wrench[:, :] = 0.0
    apply_tensions(m.elem_up, m.elem_lo, w.P_up, w.P_lo, w.N, w.T, w.wrench)
    return reduced_dynamics(m, w, reactions)


# The generic evaluation for any mechanism, compiled once for compiled_model.EVAL_SIG (at its first
# use: compile_once). A kernel calls it through a function pointer, so the evaluate chain is compiled
# here only, never again inside each caller. Its unit holds _assemble first (Python calls that too:
# a start state, unit ASSEMBLE), so that the evaluation links it instead of compiling it again.
# ``evaluate`` itself, not a wrapper around it: a wrapper's compilation links and optimises the whole
# chain a second time (2.2 s of a cold `nsd cycle`'s 26 s compilation), for the same machine code.
generic_evaluator = evaluate
ASSEMBLE_SIG = types.int64(MODEL_TYPE, WORK_TYPE, types.float64, ARRAY)
# the chain's two longest parts (~4 and ~5 s of its ~18 s on a cold cache) are units of their own,
# so that a pool's two workers compile them side by side (worker_warmup); the evaluation links them
DYNAMICS = unit("dynamics", ((reduced_dynamics, types.int64(MODEL_TYPE, WORK_TYPE, types.boolean)),))
VELOCITIES = unit("velocities", ((velocities_and_predictor, types.int64(MODEL_TYPE, WORK_TYPE, ARRAY)),))
EVALUATE = unit("evaluate", ((_assemble, ASSEMBLE_SIG), (generic_evaluator, EVAL_SIG)), needs=(DYNAMICS, VELOCITIES))
ASSEMBLE = unit("assemble", ((_assemble, ASSEMBLE_SIG),), lock="evaluate")  # one lock: one _assemble


def assemble(m, w, t, zf):
    """_assemble from Python (a run's start state), compiled once (unit ASSEMBLE)."""
    if ASSEMBLE not in DONE:
        compile_once(ASSEMBLE)
    return _assemble(m, w, t, zf)


@njit(cache=True, _nrt=False, inline="always")
def _state_rates(y, m, w, dydt):
    """dy/dt = [z'_f, z''_f, extra rates] (the layout of compiled_model.split_state) from an evaluation."""
    nf = m.free.shape[0]
    for a in range(nf):
        dydt[a] = y[nf + a]
        dydt[nf + a] = w.zdd[m.free[a]]
    copy_into(dydt[2 * nf:], w.extra_rate)


@compiled_only
def derivatives(evaluator, t, y, m, w, forces, motion, dydt, reactions):
    """dy/dt = [z'_f, z''_f, extra rates] into dydt from ``evaluator`` (an EVAL_FN); the status code.
    The reactions w.lam, w.tau are computed too unless ``reactions`` is False (an integrator's stages)."""
    code = evaluator(t, y, m, w, forces, motion, reactions)
    _state_rates(y, m, w, dydt)
    return code


@njit(cache=True, _nrt=False)
def rhs_into(t, y, m, w, forces, motion, dydt, reactions):
    """``derivatives`` with the generic evaluation inlined (a direct call, no function pointer): the
    engine's kernels use ``derivatives``; the benchmarks time this form against it."""
    code = evaluate(t, y, m, w, forces, motion, reactions)
    _state_rates(y, m, w, dydt)
    return code
