"""A mechanism as data (Section 3.1): bodies, a parent array, 1-DOF joints and cut joints.

Like Featherstone's spatial_v2, topology is a parent array; everything else (the path matrix T of
Eq. 4, the ancestor lists used by the recursions) is derived here, never typed in. Multi-DOF
joints are chains of 1-DOF joints through massless auxiliary bodies (the paper's Figure 4).
Loops are closed by cut joints: point coincidences (a cut spherical joint, Eq. 13) and
perpendicularity conditions between body-fixed vectors (with a point, a cut revolute joint).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

PRISMATIC, REVOLUTE = "P", "R"
GROUND = -1


@dataclass(frozen=True)
class Cut:
    """A loop-closure condition between body a and body b (GROUND = -1 allowed).

    kind "point": point_a on a coincides with point_b on b (3 equations, Eq. 13).
    kind "dot":   vec_a on a is perpendicular to vec_b on b (1 equation).
    Points and vectors are in the bodies' own frames.
    """
    kind: str
    body_a: int
    a: tuple
    body_b: int
    b: tuple
    name: str = ""

    @property
    def size(self) -> int:
        return 3 if self.kind == "point" else 1


@dataclass(frozen=True)
class MechanismArrays:
    parent: np.ndarray
    jtype: np.ndarray      # 0 prismatic, 1 revolute
    cut_kind: np.ndarray   # 0 point, 1 dot
    cut_a: np.ndarray
    cut_b: np.ndarray
    cut_va: np.ndarray
    cut_vb: np.ndarray


@dataclass(frozen=True)
class Mechanism:
    """Immutable model: joint i connects parent[i] to body i; joint frames given in the parent frame."""
    names: tuple[str, ...]
    parent: tuple[int, ...]
    joint_type: tuple[str, ...]
    joint_axis: np.ndarray      # (n, 3) unit axis, parent frame
    joint_offset: np.ndarray    # (n, 3) joint origin, parent frame (body origin when z = 0)
    mass: np.ndarray            # (n,)
    com: np.ndarray             # (n, 3) body frame
    inertia: np.ndarray         # (n, 3, 3) about the centre of mass, body axes
    cuts: tuple[Cut, ...] = ()
    gravity: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self):
        n = len(self.parent)
        for i, p in enumerate(self.parent):
            if not -1 <= p < i:
                raise ValueError(f"parent[{i}] = {p}: bodies must be listed parents first (-1 = ground)")
        for i, t in enumerate(self.joint_type):
            if t not in (PRISMATIC, REVOLUTE):
                raise ValueError(f"joint_type[{i}] = {t!r}: must be 'P' or 'R'")
        norms = np.linalg.norm(self.joint_axis, axis=1)
        if not np.allclose(norms, 1.0):
            raise ValueError("joint_axis: every axis must be a unit vector")
        for c in self.cuts:
            if c.kind not in ("point", "dot") or not (-1 <= c.body_a < n and -1 <= c.body_b < n):
                raise ValueError(f"cut {c.name or c}: bad kind or body index")

    @property
    def n(self) -> int:
        return len(self.parent)

    @cached_property
    def n_constraints(self) -> int:
        return sum(c.size for c in self.cuts)

    def ancestors(self, i: int) -> list[int]:
        """Joints on the path from the ground to body i, root first (a row of the path matrix)."""
        out = []
        while i != GROUND:
            out.append(i)
            i = self.parent[i]
        return out[::-1]

    @cached_property
    def ancestor_index(self) -> tuple[np.ndarray, ...]:
        """ancestors(i) as index arrays, computed once (used in every Jacobian evaluation)."""
        return tuple(np.array(self.ancestors(i), dtype=int) for i in range(self.n))

    @cached_property
    def arrays(self) -> "MechanismArrays":
        """Integer-coded topology and cut data for the compiled recursions."""
        def rows(vs):
            return np.array([v for v in vs], dtype=float).reshape(-1, 3)
        return MechanismArrays(
            parent=np.array(self.parent, dtype=np.int64),
            jtype=np.array([1 if t == REVOLUTE else 0 for t in self.joint_type], dtype=np.int64),
            cut_kind=np.array([0 if c.kind == "point" else 1 for c in self.cuts], dtype=np.int64),
            cut_a=np.array([c.body_a for c in self.cuts], dtype=np.int64),
            cut_b=np.array([c.body_b for c in self.cuts], dtype=np.int64),
            cut_va=rows([c.a for c in self.cuts]), cut_vb=rows([c.b for c in self.cuts]))

    def path_matrix(self) -> np.ndarray:
        """Eq. 4: T[i, j] = 1 when joint j lies on the path from the ground to body i (Z = T R_d z')."""
        T = np.zeros((self.n, self.n), dtype=int)
        for i in range(self.n):
            T[i, self.ancestors(i)] = 1
        return T


def mechanism(bodies: list[dict], cuts: list[Cut] = (), gravity=(0.0, 0.0, 0.0)) -> Mechanism:
    """Build a Mechanism from a list of body dicts.

    Each dict: name, parent (name or None for ground), joint ('P' or 'R'), axis (parent frame),
    offset (joint origin in the parent frame, default 0), mass (default 0: massless auxiliary body),
    com (default 0), inertia (3x3 or 3 principal values, default 0). Cuts may name bodies by name.
    """
    index = {b["name"]: i for i, b in enumerate(bodies)}

    def idx(ref):
        if ref is None or ref == "ground":
            return GROUND
        return index[ref] if isinstance(ref, str) else int(ref)

    inertia = []
    for b in bodies:
        J = np.asarray(b.get("inertia", np.zeros(3)), dtype=float)
        inertia.append(np.diag(J) if J.ndim == 1 else J)
    axis = np.array([np.asarray(b["axis"], float) / np.linalg.norm(b["axis"]) for b in bodies])
    resolved = tuple(Cut(c.kind, idx(c.body_a), tuple(c.a), idx(c.body_b), tuple(c.b), c.name) for c in cuts)
    return Mechanism(
        names=tuple(b["name"] for b in bodies), parent=tuple(idx(b.get("parent")) for b in bodies),
        joint_type=tuple(b["joint"] for b in bodies), joint_axis=axis,
        joint_offset=np.array([b.get("offset", (0.0, 0.0, 0.0)) for b in bodies], dtype=float),
        mass=np.array([b.get("mass", 0.0) for b in bodies], dtype=float),
        com=np.array([b.get("com", (0.0, 0.0, 0.0)) for b in bodies], dtype=float),
        inertia=np.array(inertia), cuts=resolved, gravity=np.asarray(gravity, dtype=float))


def revolute_cut(body_a, point_a, axis_a, body_b, point_b, axis_b, name="") -> list[Cut]:
    """A cut revolute joint: the points coincide and axis_a stays parallel to axis_b (3 + 2 equations)."""
    axis_b = np.asarray(axis_b, float) / np.linalg.norm(axis_b)
    helper = np.eye(3)[np.argmin(np.abs(axis_b))]
    v1 = np.cross(axis_b, helper)
    v1 /= np.linalg.norm(v1)
    v2 = np.cross(axis_b, v1)
    return [Cut("point", body_a, tuple(point_a), body_b, tuple(point_b), name),
            Cut("dot", body_a, tuple(axis_a), body_b, tuple(v1), name),
            Cut("dot", body_a, tuple(axis_a), body_b, tuple(v2), name)]
