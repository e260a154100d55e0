"""The compiled path's data: an immutable model and a per-run workspace (as MuJoCo's mjModel/mjData).

``SystemModel`` holds everything that does not change during a run: the mechanism's topology and
inertias, the loop cuts, the coordinate partition (prescribed / free / dependent, Eq. 9), the
two-point elements and the parameters of the force and motion callbacks. ``Workspace`` holds
everything a run writes: the Newton warm start and predictor, the recursions' results and every
scratch array, allocated once so that a right-hand side allocates nothing. Both are namedtuples of
typed arrays, so one argument carries them into the compiled kernels (numba types them by field).

``split_state`` is the one place that knows the layout of the state vector y = [z_f, z'_f, extra].
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba import typeof, types

from nsd_core.engine.kinematics import SCRATCH_ROWS

# field name -> (dtype, ndim); the order is the namedtuple's
_MODEL_FIELDS = {
    "parent": (np.int64, 1), "jtype": (np.int64, 1), "axis": (float, 2), "offset": (float, 2),
    "mass": (float, 1), "com": (float, 2), "inertia": (float, 3), "gravity": (float, 1),
    "cut_kind": (np.int64, 1), "cut_a": (np.int64, 1), "cut_va": (float, 2), "cut_b": (np.int64, 1),
    "cut_vb": (float, 2),
    "prescribed": (np.int64, 1), "free": (np.int64, 1), "dependent": (np.int64, 1), "rows": (np.int64, 1),
    "elem_up": (np.int64, 1), "elem_pu": (float, 2), "elem_lo": (np.int64, 1), "elem_pl": (float, 2),
    "force_params": (float, 1), "motion_params": (float, 1),
    "settings": (float, 1),   # newton_tol, newton_maxit, n_extra
}
_WORK_FIELDS = {
    # warm start of Newton (keeps the assembly branch) and the first-order predictor z_dep + S dz
    "z": (float, 1), "z_start": (float, 1), "z_alt": (float, 1), "z_lin": (float, 1), "S": (float, 2),
    "has_lin": (np.int64, 1), "pred": (float, 1), "step": (float, 1),
    # recursions (Eqs. 2-5) and closure (Eqs. 13-14)
    "A": (float, 3), "r": (float, 2), "B": (float, 2), "Z": (float, 2), "vp": (float, 2),
    "Phi": (float, 1), "J": (float, 2), "c": (float, 1),
    "Jd": (float, 2), "piv": (np.int64, 1), "Jd_inv": (float, 2), "col": (float, 1),
    # motion, velocities, accelerations, reactions
    "q": (float, 1), "qd": (float, 1), "qdd": (float, 1), "zd": (float, 1), "zdd": (float, 1),
    "lam": (float, 1), "tau": (float, 1),
    # two-point elements and applied forces
    "L": (float, 1), "Ld": (float, 1), "T": (float, 1), "N": (float, 2), "P_up": (float, 2),
    "P_lo": (float, 2), "gen": (float, 1), "wrench": (float, 2), "extra": (float, 1),
    "extra_rate": (float, 1),
    # Eqs. 7-8 and the reduced Eq. 12
    "Mb": (float, 3), "Qb": (float, 2), "acc6": (float, 2), "Fsub": (float, 2), "vec": (float, 1),
    "Mv": (float, 1), "Rz": (float, 2),
    "zdd0": (float, 1), "red": (float, 2), "red_rhs": (float, 1), "red_piv": (np.int64, 1), "res": (float, 1),
    "scratch": (float, 2), "scratch6": (float, 1),   # the recursions' 3-vectors, the tree's 6-vector
    "momentum": (float, 1),  # the mechanism's linear momentum sum m_i v_com,i, for the force callback
    "time": (float, 1),  # t of the last evaluation begun (where a failure happened)
    "kin_current": (np.int64, 1),  # 1: A, r, B, Phi, Phi_z in the workspace belong to z
    "counters": (np.int64, 1),  # assemblies, Newton iterations, second Newton solves (diagnostics)
}

SystemModel = namedtuple("SystemModel", list(_MODEL_FIELDS))
Workspace = namedtuple("Workspace", list(_WORK_FIELDS))


def _template(cls, fields, readonly):
    arrays = [np.zeros((0,) * nd, dtype=dt) for dt, nd in fields.values()]
    for a in arrays:
        a.setflags(write=not readonly)
    return cls(*arrays)


MODEL_TYPE = typeof(_template(SystemModel, _MODEL_FIELDS, readonly=True))
WORK_TYPE = typeof(_template(Workspace, _WORK_FIELDS, readonly=False))
ARRAY = types.float64[::1]
PARAMS = types.Array(types.float64, 1, "C", readonly=True)  # the model's (immutable) parameters
# forces(t, z, z', P, L, L', extra, params, T out, gen out, extra_rate out) -> 0 ok, else a failure code.
# P: the mechanism's linear momentum sum m_i v_com,i (3,) (power of frame forces in a moving frame);
# T: element tensions (> 0 pulls the ends together); gen: generalized joint forces.
FORCE_SIG = types.int64(types.float64, ARRAY, ARRAY, ARRAY, ARRAY, ARRAY, ARRAY, PARAMS, ARRAY, ARRAY, ARRAY)
# motion(t, params, q out, q' out, q'' out) -> 0: the prescribed coordinates at t
MOTION_SIG = types.int64(types.float64, PARAMS, ARRAY, ARRAY, ARRAY)
FORCE_FN = types.FunctionType(FORCE_SIG)
MOTION_FN = types.FunctionType(MOTION_SIG)
# evaluate(t, y, model, workspace, forces, motion, reactions) -> 0 ok, else a status code
# (nsd_core.engine.compiled): everything at (t, y) into the workspace: w.z, w.zd, w.zdd (Eqs. 9-12),
# w.lam, w.tau when ``reactions``, w.extra_rate, the kinematics w.A, w.r, w.B, w.Z, w.Phi, the
# elements' w.L, w.Ld, w.T, w.N, w.time. The kernels (nsd_core.engine.rk, the seismic outputs) take the
# evaluation as an argument of this type, so it is compiled once, apart from them, and a mechanism
# may bring its own (a generated one) that fills the same fields.
EVAL_SIG = types.int64(types.float64, ARRAY, MODEL_TYPE, WORK_TYPE, FORCE_FN, MOTION_FN, types.boolean)
EVAL_FN = types.FunctionType(EVAL_SIG)


def build_model(mech, partition, prescribed, elements=None, force_params=(), motion_params=(),
                n_extra: int = 0, newton_tol: float = 1e-13, newton_maxit: int = 30) -> SystemModel:
    """The immutable model of a mechanism with its partition, two-point elements and callback data.

    ``elements`` is (body_up, pts_up, body_lo, pts_lo) or None; points in the bodies' frames.
    """
    a = mech.arrays
    if elements is None:
        elements = ((), np.zeros((0, 3)), (), np.zeros((0, 3)))
    up, pu, lo, pl = elements
    fields = dict(
        parent=a.parent, jtype=a.jtype, axis=mech.joint_axis, offset=mech.joint_offset, mass=mech.mass,
        com=mech.com, inertia=mech.inertia, gravity=mech.gravity, cut_kind=a.cut_kind, cut_a=a.cut_a,
        cut_va=a.cut_va, cut_b=a.cut_b, cut_vb=a.cut_vb, prescribed=prescribed, free=partition.free,
        dependent=partition.dependent, rows=partition.rows, elem_up=up, elem_pu=np.reshape(pu, (-1, 3)),
        elem_lo=lo, elem_pl=np.reshape(pl, (-1, 3)), force_params=force_params, motion_params=motion_params,
        settings=(newton_tol, float(newton_maxit), float(n_extra)))
    out = {}
    for name, (dt, nd) in _MODEL_FIELDS.items():
        arr = np.ascontiguousarray(np.asarray(fields[name], dtype=dt))
        if arr.size == 0:
            arr = np.zeros((0,) + arr.shape[1:] if arr.ndim == nd else (0,) + (3,) * (nd - 1), dtype=dt)
        arr.setflags(write=False)  # immutable: a run writes only its workspace
        out[name] = arr
    return SystemModel(**out)


def make_workspace(model: SystemModel, z0: np.ndarray) -> Workspace:
    """A fresh workspace; z0 is the full configuration that starts Newton (the assembly branch)."""
    n, nc = len(model.parent), int(sum(3 if k == 0 else 1 for k in model.cut_kind))
    nd, nf, npr = len(model.dependent), len(model.free), len(model.prescribed)
    ne, nx = len(model.elem_up), int(model.settings[2])
    shapes = dict(
        z=(n,), z_start=(n,), z_alt=(n,), z_lin=(n,), S=(nd, n), has_lin=(1,), pred=(nd,), step=(nd,),
        A=(n, 3, 3), r=(n, 3), B=(n, 6), Z=(n, 6), vp=(n, 6), Phi=(nc,), J=(nc, n), c=(nc,),
        Jd=(nd, nd), piv=(nd,), Jd_inv=(nd, nd), col=(max(nd, nf),),
        q=(npr,), qd=(npr,), qdd=(npr,), zd=(n,), zdd=(n,), lam=(nd,), tau=(npr,),
        L=(ne,), Ld=(ne,), T=(ne,), N=(ne, 3), P_up=(ne, 3), P_lo=(ne, 3), gen=(n,), wrench=(n, 6),
        extra=(nx,), extra_rate=(nx,), Mb=(n, 6, 6), Qb=(n, 6), acc6=(n, 6), Fsub=(n, 6), vec=(n,), Mv=(n,), Rz=(n, nf),
        zdd0=(n,),
        red=(nf, nf), red_rhs=(nf,), red_piv=(nf,), res=(n,), scratch=(SCRATCH_ROWS, 3), scratch6=(6,),
        momentum=(3,), time=(1,), kin_current=(1,), counters=(3,))
    ws = Workspace(**{k: np.zeros(shapes[k], dtype=dt) for k, (dt, _) in _WORK_FIELDS.items()})
    ws.z[:] = z0
    return ws


StateParts = namedtuple("StateParts", "free_positions free_velocities extra")


def split_state(y: np.ndarray, n_free: int) -> StateParts:
    """y = [z_f, z'_f, extra] -> its named parts (views; along the last axis, so a time series works)."""
    y = np.asarray(y)
    return StateParts(y[..., :n_free], y[..., n_free:2 * n_free], y[..., 2 * n_free:])
