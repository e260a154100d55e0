"""The description's joints on Exudyn's terms, and the description's quantities read back from the
bodies' world poses (used by comparisons.builders.exudyn).

Every joint gets one joint frame J (columns in the parent's frame; the child's frame coincides with
the parent's at zero coordinates, so J has the same components in the child's frame): Exudyn's
GenericJoint locks the axes of J that the joint does not free, a prescribed coordinate locks its own
axis with a time-dependent offset. The frame is chosen so that Exudyn's joint coordinates are the
description's: Exudyn measures the relative rotation of a GenericJoint as Tait-Bryan angles
Rx Ry Rz of J, which is the description's order for the spherical joint (x, turned y, turned z) and,
with x = axis, y = axis2, for the universal joint.
"""
from __future__ import annotations

import math

import numpy as np

from nsd_core.model.description import Body, unit
from nsd_core.model.errors import ModelError

# which of GenericJoint's six axes (translations 0-2, rotations 3-5 of J) each coordinate moves
AXIS_OF_DOF = {"revolute": (5,), "prismatic": (2,), "universal": (3, 4), "spherical": (3, 4, 5), "planar": (0, 1, 5),
               "planar_translation": (0, 1), "translational": (0, 1, 2)}


def cross(a, b) -> np.ndarray:
    """a x b of two 3-vectors, or of stacks of them (the last axis): numpy.cross's arithmetic without
    its axis handling (which cost most of the outputs' time, read at every step)."""
    c = (a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1], a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
         a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0])
    return np.array(c) if np.ndim(c[0]) == 0 else np.stack(c, axis=-1)


def transposed(R) -> np.ndarray:
    """R^T of a matrix, or of each of a stack of them."""
    return np.swapaxes(R, -1, -2)


def applied(A, x) -> np.ndarray:
    """A x of a matrix and a vector, or of stacks of them (the sample axis first)."""
    return A @ x if np.ndim(x) == 1 and np.ndim(A) == 2 else (A @ x[..., None])[..., 0]


def perpendicular(a: np.ndarray) -> np.ndarray:
    u = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))])
    return u / np.linalg.norm(u)


def frame_with_z(a) -> np.ndarray:
    """A right-handed frame whose z column is the unit vector a."""
    z = unit(a)
    x = perpendicular(z)
    return np.column_stack([x, np.cross(z, x), z])


def joint_frame(body: Body) -> np.ndarray:
    """J for ``body``'s joint (columns in the parent's frame, equally in the body's own)."""
    j = body.joint
    dofs = j.dofs()
    if j.type in ("revolute", "prismatic"):
        return frame_with_z(dofs[0][1])
    if j.type == "universal":
        x, y = dofs[0][1], dofs[1][1]
        if abs(float(x @ y)) > 1e-9:
            raise ModelError(f"bodies.{body.name}.joint.axis2 = {list(j.axis2)}: the Exudyn builder needs a "
                             "universal joint's axes perpendicular (Exudyn's universal joint is a GenericJoint "
                             "with two free rotations about perpendicular axes)")
        return np.column_stack([x, y, np.cross(x, y)])
    if j.type in ("spherical", "translational"):   # the parent's own axes
        return np.eye(3)
    u, v = dofs[0][1], dofs[1][1]
    return np.column_stack([u, v, np.cross(u, v)])   # planar, planar_translation: u, v, normal


def constrained_axes(body: Body) -> list[int]:
    free = AXIS_OF_DOF[body.joint.type]
    return [0 if k in free else 1 for k in range(6)]


def wrap(x: float) -> float:
    return (x + math.pi) % (2.0 * math.pi) - math.pi


def joint_coordinates(body: Body, J, Rp, rp, Rc, rc) -> list:
    """The joint's coordinates from the world poses (R, origin) of the parent and the child; angles
    in (-pi, pi] (``Continuous`` keeps them continuous in time). Each of Rp, rp, Rc, rc may be a stack
    over samples (the first axis): then each coordinate is an array over them."""
    M = J.T @ transposed(Rp) @ Rc @ J
    d = applied(J.T, applied(transposed(Rp), rc - rp) - np.asarray(body.joint.position))
    t = body.joint.type
    if t == "revolute":
        return [np.arctan2(M[..., 1, 0], M[..., 0, 0])]
    if t == "prismatic":
        return [d[..., 2]]
    if t == "translational":
        return [d[..., 0], d[..., 1], d[..., 2]]
    if t == "universal":          # M = Rx(q1) Ry(q2)
        return [np.arctan2(M[..., 2, 1], M[..., 1, 1]), np.arctan2(M[..., 0, 2], M[..., 0, 0])]
    if t == "spherical":          # M = Rx(q1) Ry(q2) Rz(q3)
        return [np.arctan2(-M[..., 1, 2], M[..., 2, 2]), np.arctan2(M[..., 0, 2], np.hypot(M[..., 0, 0], M[..., 0, 1])),
                np.arctan2(-M[..., 0, 1], M[..., 0, 0])]
    if t == "planar_translation":
        return [d[..., 0], d[..., 1]]
    return [d[..., 0], d[..., 1], np.arctan2(M[..., 1, 0], M[..., 0, 0])]   # planar


def joint_rate(body: Body, dof: int, J, Rp, rp, vp, wp, rc, vc, wc) -> float:
    """q' of coordinate ``dof`` when it is a slide or a turn about J's z (the coordinates a joint law's
    connector can act on, ``law_axis``) from the world velocities of the two frames' origins (v) and
    the angular velocities (w)."""
    k = AXIS_OF_DOF[body.joint.type][dof]
    a = Rp @ J[:, k % 3]
    if k >= 3:
        return float(a @ (wc - wp))
    return float(a @ (vc - vp - cross(wp, rc - rp)))   # the slide seen from the turning parent


def law_axis(body: Body, dof: int) -> int | None:
    """Which axis of J a joint law on coordinate ``dof`` acts along (0-2) or about (5), or None where
    no connector measures that coordinate: a connector measures a slide along an axis of its marker
    or a turn about its z, while the turns of universal and spherical joints are Tait-Bryan angles."""
    k = AXIS_OF_DOF[body.joint.type][dof]
    return k if k in (0, 1, 2, 5) else None


class Continuous:
    """Keeps each rotation coordinate continuous across +-pi: the turn nearest the last value (of a
    series of samples, each the turn nearest the sample before)."""

    def __init__(self, start: dict, rotational: set):
        self.last = dict(start)
        self.rotational = rotational

    def __call__(self, key, raw):
        if np.ndim(raw) > 0:
            out = np.array(raw, dtype=float)
            if key in self.rotational:
                last = self.last[key]
                for i, x in enumerate(out.tolist()):
                    last = out[i] = last + wrap(x - last)
            self.last[key] = out[-1]
            return out
        if key in self.rotational:
            raw = self.last[key] + wrap(raw - self.last[key])
        self.last[key] = raw
        return raw


def planar_normal(model, state) -> np.ndarray | None:
    """The common normal when the mechanism moves in parallel planes (every revolute axis of the
    joints and of the revolute closures parallel, every prismatic axis perpendicular to it, at t = 0
    and hence always), else None. In such a mechanism a loop closure's out-of-plane equations repeat
    what the tree's joints already hold (the Jacobian has dependent rows), so the builder constrains
    only its in-plane translations."""
    turns, slides = [], []
    for b in model.bodies:
        if b.joint.type in ("universal", "spherical"):
            return None
        R = np.eye(3) if b.parent == "ground" else state.rotation[b.parent]
        for kind, axis in b.joint.dofs():
            (turns if kind == "R" else slides).append(R @ axis)
    for lp in model.loops:
        if lp.type == "revolute":
            R = np.eye(3) if lp.body_a == "ground" else state.rotation[lp.body_a]
            turns.append(R @ unit(lp.axis_a))
    if not turns:
        return None
    n = unit(turns[0])
    if all(np.linalg.norm(np.cross(n, unit(a))) < 1e-9 for a in turns) and all(abs(n @ unit(s)) < 1e-9 for s in slides):
        return n
    return None
