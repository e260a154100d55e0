"""One compiled module per set of laws for the compiled force path of comparisons.builders.exudyn
(exudyn_compiled.CompiledForces): the element loop, the laws and their states in one numba call.

Why: Exudyn calls the force function ~8 times a step (Newton's residuals) and differentiates it
numerically; a Python loop over the laws and LawStates.at cost ~20 us a call (the hand-written
adapter makes one compiled call a step). Why one module per set of laws and not per model: the
module's text names the laws it can call and nothing of the model, whose elements, counts and
offsets are data (the arrays below). Every description whose laws come from the same registering
modules (the model layer's own laws always among them) shares one compiled module: the device's
drive, its seismic model with a restrainer or a building, a mechanism of the model layer's laws.
A module made per model shape compiled its ~5 functions again for each (10-20 s of CPU each, four in
the default gate). Generated here:
- ``evaluate(q, q_t, F, I, W, f)``: the generalized forces f at Exudyn's coordinates: the kinematics
  of exudyn_kernels.arguments, each element's registry law (``_force``, ``_plane_force``: a branch
  per law, bound by name), a state's value at the end of the step by Heun's method from the committed
  (s, r) (exudyn_forces.LawStates, the same arithmetic), and exudyn_kernels.forces;
- ``jacobian(q, q_t, F, I, W, fq, fv, J)``: Exudyn's ObjectGenericODE2 jacobianUserFunction,
  J = -(fq df/dq + fv df/dq') by forward differences of ``evaluate`` inside the compiled call
  (Exudyn's own numerical Jacobian calls the Python function twice per coordinate); only the
  columns of bodies some element touches (the ``active`` block of I);
- ``commit(q, q_t, F, I, W)``: the step converged: every state and its rate move on (LawStates.commit);
- ``series(Q, Q_t, F, I, W, X, XD)``: every element's (x, x') at each of a series of samples (the rows
  of Q, Q_t) into the rows of X, XD: the outputs' law arguments (exudyn_replay), by this kinematics;
- ``values(q, q_t, F, I, W, x, xd, T)``: every element's law value at the committed states;
- ``advance(q_all, q_t_all, q_tt_all, index, h, predict, F, I, W, f)``: the pre-step's work on Exudyn's
  whole coordinate vectors in one call: ``commit``, then (``predict``) the forces at the Taylor-
  predicted end of the step into f (CompiledForces.advance).
A plane law's element comes as two consecutive joint entries (its x and y slides, exudyn_compiled):
its law is called once at the first (the second's law code is -1), giving both entries' values, its
two-component state in two consecutive slots (Heun, LawStates.at_plane's arithmetic).
Numbers live in three arrays: F (floats: the bodies' reference coordinates, the elements' geometry and
parameters, the step), I (integers: the counts and block offsets of ``HEAD``, the elements' bodies,
law codes, kinds, parameter ranges and state slots) and W (the states, the turns' last angles, the
started flag). Cached as mujoco_codegen does: the source is written as ``exudyn_forces_<hash>.py`` to
a cache folder and compiled with cache=True; the hash covers the source, exudyn_kernels (compiled
into the generated file's cache) and each law's source files (transitively through the numba
functions it calls), so an edit gives a new file.
"""
from __future__ import annotations

import numpy as np

from comparisons.builders import generated
from comparisons.builders import exudyn_kernels
from nsd_core.model.laws import PLANE

HELPERS = (exudyn_kernels,)
EPS_REL, EPS_MIN = 1e-7, 1e-2   # forward-difference step: EPS_REL max(EPS_MIN, |q_i|) (Exudyn's defaults)
# I's head: the counts, then the offsets of F's blocks, of I's blocks and of W's blocks
HEAD = ("nb", "npts", "nj", "nactive", "pa", "pb", "e", "jax", "jx", "jy", "jpos", "jorig", "h",
        "ia", "ib", "jc", "jp", "turn", "active", "code", "kind", "p0", "p1", "slot", "s", "r", "started")
# an element's kind: a scalar law without and with a state, a plane law without and with one
STATELESS, STATEFUL, PLANE_STATELESS, PLANE_STATEFUL = 0, 1, 2, 3
# the kinematics' and laws' work arrays, allocated once a compiled call (``_scratch``) and passed down: each
# is written before it is read, so one set serves every evaluation in a call (the Jacobian's 30)
SCRATCH = "x, xd, T, N, S, R, G, r, v, w"
# the module's own helpers, called only by its entry points: compiled without the Python and C entry
# wrappers numba otherwise generates for every function (machine code nothing calls; a call from Python
# would crash the process), ~1 s less a set of laws on a cold cache
HELPER_JIT = "@njit(cache=True, no_cpython_wrapper=True, no_cfunc_wrapper=True)"


def _head(*names: str, prefix: str = "") -> str:
    """``a, b = I[i], I[j]``: the named entries of I's head, as locals (``prefix`` + name)."""
    return f"    {', '.join(prefix + n for n in names)} = {', '.join(f'I[{HEAD.index(n)}]' for n in names)}"


def source(laws) -> tuple[str, dict]:
    """The generated module's text for ``laws`` (generated.law_set's list; an element's law code is its index
    there) and the law functions it expects bound by name."""
    bound = generated.bound_laws(laws)
    lines = (_dispatch_source(laws) + _state_source() + _laws_source() + _evaluate_source()
             + _commit_source() + _outputs_source())
    return "\n".join(lines), bound


def _dispatch_source(laws) -> list[str]:
    """The module's head and one branch per law: ``_force``/``_rate`` (a scalar law's value and its
    state's rate), ``_plane_force``/``_plane_rate`` (a plane law's two)."""
    lines = ['"""Generated by comparisons.builders.exudyn_codegen: do not edit."""',
             "import numpy as np",
             "from numba import njit",
             "from comparisons.builders.exudyn_kernels import arguments, forces", "", ""]
    for name, args, plane, rate in (("_force", "c, x, xd, s, p", False, False), ("_rate", "c, x, xd, s, p", False, True),
                                    ("_plane_force", "c, x, y, xd, yd, sx, sy, p", True, False),
                                    ("_plane_rate", "c, x, y, xd, yd, sx, sy, p", True, True)):
        lines += [HELPER_JIT, f"def {name}({args}):"]
        for i, law in enumerate(laws):
            if (law.acts_on == PLANE) != plane or (rate and law.rate is None):
                continue
            call = "x, y, xd, yd, sx, sy, p" if plane else ("x, xd, p" if law.state is None else "x, xd, s, p")
            lines += [f"    if c == {i}:   # {law.name}", f"        return {'rate' if rate else 'law'}_{i}({call})"]
        lines += ["    return 0.0, 0.0" if plane else "    return 0.0", "", ""]
    return lines


def _state_source() -> list[str]:
    """``_frames``, ``_scratch`` (the work arrays) and ``_state``: every element's kinematics
    (exudyn_kernels.arguments)."""
    return [
        HELPER_JIT,
        "def _frames(I):",
        "    # the bodies' poses and the elements' directions and arms",
        _head("nb", "npts", "nj"),
        "    ne = npts + nj",
        "    R, G = np.empty((nb, 3, 3)), np.empty((nb, 3, 4))",
        "    r, v, w = np.empty((nb, 3)), np.empty((nb, 3)), np.empty((nb, 3))",
        "    N, S = np.empty((ne, 3)), np.empty((ne, 2, 3))",
        "    return N, S, R, G, r, v, w",
        "", "",
        HELPER_JIT,
        "def _scratch(I):",
        _head("npts", "nj"),
        "    ne = npts + nj",
        "    N, S, R, G, r, v, w = _frames(I)",
        "    x, xd, T = np.empty(ne), np.empty(ne), np.empty(ne)",
        f"    return {SCRATCH}",
        "", "",
        HELPER_JIT,
        f"def _state(F, I, W, f, q, q_t, {SCRATCH}):",
        "    # L: the counts and the blocks' offsets exudyn_kernels.arguments reads F and I at",
        _head("npts", "nj"),
        _head("pa", "pb", "e", "jax", "jx", "jy", "jpos", "jorig", "ia", "ib", "jc", "jp", "turn", prefix="o_"),
        "    L = (npts, nj, o_pa, o_pb, o_e, o_jax, o_jx, o_jy, o_jpos, o_jorig, o_ia, o_ib, o_jc, o_jp, o_turn)",
        "    arguments(q, q_t, F, I, W, L, R, G, r, v, w, x, xd, N, S)",
        "    return L",
        "", ""]


def _laws_source() -> list[str]:
    """``_laws``: each law's value into T, a state's at the step's end by Heun (LawStates.at's and
    at_plane's arithmetic)."""
    return [
        HELPER_JIT,
        "def _laws(F, I, W, x, xd, T):",
        _head("npts", "nj"),
        _head("code", "kind", "p0", "p1", "slot", "s", "r", "started", "h", prefix="o_"),
        "    h, started = F[o_h], W[o_started] != 0.0",
        "    for j in range(npts + nj):",
        "        c, kd = I[o_code + j], I[o_kind + j]",
        "        if c < 0:   # a plane law's second entry: set with its first",
        "            continue",
        "        p = F[I[o_p0 + j]:I[o_p1 + j]]",
        f"        if kd == {STATELESS}:",
        "            T[j] = _force(c, x[j], xd[j], 0.0, p)",
        f"        elif kd == {STATEFUL}:",
        "            k = I[o_slot + j]",
        "            s = W[o_s + k]",
        "            if started:",
        "                rk = W[o_r + k]",
        "                s = s + 0.5 * h * (rk + _rate(c, x[j], xd[j], s + h * rk, p))",
        "            T[j] = _force(c, x[j], xd[j], s, p)",
        f"        elif kd == {PLANE_STATELESS}:",
        "            T[j], T[j + 1] = _plane_force(c, x[j], x[j + 1], xd[j], xd[j + 1], 0.0, 0.0, p)",
        "        else:",
        "            k = I[o_slot + j]",
        "            sx, sy = W[o_s + k], W[o_s + k + 1]",
        "            if started:",
        "                rx, ry = W[o_r + k], W[o_r + k + 1]",
        "                ax, ay = _plane_rate(c, x[j], x[j + 1], xd[j], xd[j + 1], sx + h * rx, sy + h * ry, p)",
        "                sx, sy = sx + 0.5 * h * (rx + ax), sy + 0.5 * h * (ry + ay)",
        "            T[j], T[j + 1] = _plane_force(c, x[j], x[j + 1], xd[j], xd[j + 1], sx, sy, p)",
        "    return 0",
        "", ""]


def _evaluate_source() -> list[str]:
    """``evaluate`` (the generalized forces) and ``jacobian`` (their forward differences)."""
    return [
        HELPER_JIT,
        f"def _evaluate(q, q_t, F, I, W, f, {SCRATCH}):",
        f"    L = _state(F, I, W, f, q, q_t, {SCRATCH})",
        "    _laws(F, I, W, x, xd, T)",
        "    forces(T, I, L, R, G, r, N, S, f)",
        "    return f",
        "", "",
        "@njit(cache=True)",
        "def evaluate(q, q_t, F, I, W, f):",
        f"    {SCRATCH} = _scratch(I)",
        f"    return _evaluate(q, q_t, F, I, W, f, {SCRATCH})",
        "", "",
        "@njit(cache=True)",
        "def jacobian(q, q_t, F, I, W, fq, fv, J):",
        f"    {SCRATCH} = _scratch(I)",
        _head("nb", "nactive"),
        _head("active", prefix="o_"),
        "    n = 7 * nb",
        "    f0, f1 = np.empty(n), np.empty(n)",
        "    qq, vv = q.copy(), q_t.copy()",
        f"    _evaluate(qq, vv, F, I, W, f0, {SCRATCH})",
        "    J[:, :] = 0.0",
        "    for m in range(nactive):",
        "        i = I[o_active + m]",
        "        for which in range(2):",
        "            c = fq if which == 0 else fv",
        "            if c == 0.0:",
        "                continue",
        "            z = qq if which == 0 else vv",
        "            z0 = z[i]",
        f"            d = {EPS_REL!r} * max({EPS_MIN!r}, abs(z0))",
        "            z[i] = z0 + d",
        f"            _evaluate(qq, vv, F, I, W, f1, {SCRATCH})",
        "            z[i] = z0",
        "            for k in range(n):",
        "                J[k, i] -= c * (f1[k] - f0[k]) / d",
        f"    _evaluate(q, q_t, F, I, W, f1, {SCRATCH})   # the turns' last angles back at the unperturbed state",
        "    return J",
        "", ""]


def _commit_source() -> list[str]:
    """``commit``: every state and its rate move on to the converged step's end (LawStates.commit)."""
    return [
        "@njit(cache=True)",
        "def commit(q, q_t, F, I, W):",
        f"    {SCRATCH} = _scratch(I)",
        f"    return _commit(q, q_t, F, I, W, np.empty(7 * I[{HEAD.index('nb')}]), {SCRATCH})",
        "", "",
        HELPER_JIT,
        f"def _commit(q, q_t, F, I, W, f, {SCRATCH}):",
        f"    _state(F, I, W, f, q, q_t, {SCRATCH})",
        _head("npts", "nj"),
        _head("code", "kind", "p0", "p1", "slot", "s", "r", "started", "h", prefix="o_"),
        "    h, started = F[o_h], W[o_started] != 0.0",
        "    for j in range(npts + nj):",
        "        c, kd = I[o_code + j], I[o_kind + j]",
        f"        if c < 0 or kd == {STATELESS} or kd == {PLANE_STATELESS}:",
        "            continue",
        "        p = F[I[o_p0 + j]:I[o_p1 + j]]",
        "        s_at, r_at = o_s + I[o_slot + j], o_r + I[o_slot + j]",
        f"        if kd == {STATEFUL}:",
        "            if started:",
        "                s, rk = W[s_at], W[r_at]",
        "                W[s_at] = s + 0.5 * h * (rk + _rate(c, x[j], xd[j], s + h * rk, p))",
        "            W[r_at] = _rate(c, x[j], xd[j], W[s_at], p)",
        "        else:",
        "            if started:",
        "                rx, ry = W[r_at], W[r_at + 1]",
        "                ax, ay = _plane_rate(c, x[j], x[j + 1], xd[j], xd[j + 1], W[s_at] + h * rx, W[s_at + 1] + h * ry, p)",
        "                W[s_at], W[s_at + 1] = W[s_at] + 0.5 * h * (rx + ax), W[s_at + 1] + 0.5 * h * (ry + ay)",
        "            W[r_at], W[r_at + 1] = _plane_rate(c, x[j], x[j + 1], xd[j], xd[j + 1], W[s_at], W[s_at + 1], p)",
        "    W[o_started] = 1.0",
        "    return 0",
        "", ""]


def _outputs_source() -> list[str]:
    """``series`` (each element's (x, x') per sample), ``values`` (committed law values) and ``advance``."""
    return [
        "@njit(cache=True)",
        "def series(Q, Q_t, F, I, W, X, XD):",
        f"    {SCRATCH} = _scratch(I)",
        f"    f = np.empty(7 * I[{HEAD.index('nb')}])",
        "    for k in range(Q.shape[0]):",
        f"        _state(F, I, W, f, Q[k], Q_t[k], {SCRATCH})",
        "        for j in range(x.shape[0]):   # not X[k, :] = x: its shape check's error path compiles ~2 s",
        "            X[k, j] = x[j]",
        "            XD[k, j] = xd[j]",
        "    return 0", "", "",
        "@njit(cache=True)",
        "def values(q, q_t, F, I, W, x, xd, T):",
        "    # every element's (x, x') and law value at the committed states: exudyn_work's powers",
        "    N, S, R, G, r, v, w = _frames(I)",
        f"    f = np.empty(7 * I[{HEAD.index('nb')}])",
        f"    _state(F, I, W, f, q, q_t, {SCRATCH})",
        _head("npts", "nj"),
        _head("code", "kind", "p0", "p1", "slot", "s", prefix="o_"),
        "    for j in range(npts + nj):",
        "        c, kd = I[o_code + j], I[o_kind + j]",
        "        if c < 0:",
        "            continue",
        "        p, s_at = F[I[o_p0 + j]:I[o_p1 + j]], o_s + I[o_slot + j]",
        f"        if kd == {STATELESS}:",
        "            T[j] = _force(c, x[j], xd[j], 0.0, p)",
        f"        elif kd == {STATEFUL}:",
        "            T[j] = _force(c, x[j], xd[j], W[s_at], p)",
        f"        elif kd == {PLANE_STATELESS}:",
        "            T[j], T[j + 1] = _plane_force(c, x[j], x[j + 1], xd[j], xd[j + 1], 0.0, 0.0, p)",
        "        else:",
        "            T[j], T[j + 1] = _plane_force(c, x[j], x[j + 1], xd[j], xd[j + 1], W[s_at], W[s_at + 1], p)",
        "    return 0", "", "",
        "@njit(cache=True)",
        "def advance(q_all, q_t_all, q_tt_all, index, h, predict, F, I, W, f):",
        f"    {SCRATCH} = _scratch(I)",
        "    q, q_t = q_all[index], q_t_all[index]",
        f"    _commit(q, q_t, F, I, W, f, {SCRATCH})   # f: scratch here, the forces below",
        "    if predict:   # CompiledForces.predict's Taylor step, operation for operation",
        "        a = q_tt_all[index]",
        f"        _evaluate(q + h * q_t + (0.5 * h * h) * a, q_t + h * a, F, I, W, f, {SCRATCH})",
        "    return f", ""]


def fingerprint(text: str, bound: dict) -> str:
    """The name of the generated file: its text, HELPERS and the laws it is bound to (generated.py)."""
    return generated.fingerprint(text, bound, HELPERS)


def module_for(text: str, bound: dict):
    """The generated module (evaluate, jacobian, commit, ...), compiled once per set of laws, from
    numba's disk cache when an earlier process compiled it."""
    return generated.load(text, bound, HELPERS, "exudyn_forces")


def pack(cf, laws) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict, list]:
    """F, I, W and the offsets (``sizes``, HEAD's names) of a CompiledForces ``cf`` whose module calls
    ``laws``, and each element's parameter range in F."""
    npts, nj = len(cf.ia), len(cf.jc)
    assert npts + nj == len(cf.elements)
    sizes, at, parts = {}, 0, []
    for nm in ("ref", "pa", "pb", "e", "jax", "jx", "jy", "jpos", "jorig"):
        b = getattr(cf, nm)
        sizes[nm], at = at, at + b.size
        parts.append(np.ravel(b))
    params = []
    for f in cf.elements:
        p = np.asarray(f.parameters, float)
        params.append((at, at + p.size))
        parts.append(p)
        at += p.size
    sizes["h"] = at
    parts.append(np.array([cf.states.h]))
    F = np.concatenate(parts).astype(float)
    touched = sorted({int(i) for i in np.concatenate([cf.ia, cf.ib, cf.jc, cf.jp]) if i >= 0})
    active = [7 * b + k for b in touched for k in range(7)]
    ints = [("ia", cf.ia), ("ib", cf.ib), ("jc", cf.jc), ("jp", cf.jp), ("turn", cf.turn.astype(np.int64)),
            ("active", np.array(active, dtype=np.int64))] + list(zip(("code", "kind", "p0", "p1", "slot"),
                                                                     _elements(cf.elements, laws, params)))
    at, parts = len(HEAD), []
    for nm, b in ints:
        sizes[nm], at = at, at + len(b)
        parts.append(np.asarray(b, dtype=np.int64))
    ns = len(cf.states.s)
    sizes.update(nb=len(cf.bodies), npts=npts, nj=nj, nactive=len(active), s=nj, r=nj + ns, started=nj + 2 * ns)
    I = np.concatenate([np.array([sizes[n] for n in HEAD], dtype=np.int64)] + parts).astype(np.int64)
    W = np.concatenate([cf.last, np.asarray(cf.states.s, float), np.zeros(ns), [0.0]]).astype(float)
    return F, I, W, sizes, params


def _elements(elements, laws, params) -> tuple[list, ...]:
    """Each element's law code (its law's index in ``laws``; -1 for a plane law's second entry), kind,
    parameter range in F and first state slot (a running count of the laws' state sizes)."""
    code = {law.name: i for i, law in enumerate(laws)}
    cols, k, planes = ([], [], [], [], []), 0, set()
    for f, (p0, p1) in zip(elements, params):
        plane = f.law.acts_on == PLANE
        if plane and f.name in planes:
            row = (-1, STATELESS, p0, p1, -1)
        else:
            if plane:
                planes.add(f.name)
            kind = (PLANE_STATELESS if plane else STATELESS) + (f.law.state is not None)
            row = (code[f.law.name], kind, p0, p1, k)
            k += f.law.state_size
        for col, v in zip(cols, row):
            col.append(v)
    return cols
