"""Pieces shared by the campaign's generators (comparisons.campaign.generate): the random source,
rotations, inertias and the tables of a description."""
from __future__ import annotations

import math

import numpy as np

GRASHOF = ("crank_rocker", "double_crank", "double_rocker", "non_grashof")
JOINTS = ("revolute", "prismatic", "universal", "spherical", "planar", "planar_translation", "translational")
SLIDES = {"prismatic": (0,), "planar": (0, 1), "planar_translation": (0, 1), "translational": (0, 1, 2)}
TURNS = {"revolute": (0,), "universal": (0, 1), "spherical": (0, 1, 2), "planar": (2,)}
MARGIN = math.sin(math.radians(25.0))   # the smallest sin of a transmission angle a loop may reach
G = 9.81


class Draws:
    """Every random choice of a description from one seed (numpy's PCG64)."""

    def __init__(self, seed: int):
        self.rng = np.random.default_rng(seed)

    def uniform(self, lo: float, hi: float) -> float:
        return float(self.rng.uniform(lo, hi))

    def integer(self, lo: int, hi: int) -> int:
        """A whole number in [lo, hi]."""
        return int(self.rng.integers(lo, hi + 1))

    def choice(self, options):
        return options[self.integer(0, len(options) - 1)]


def rotation(d) -> np.ndarray:
    """A random proper rotation (three turns about z, y, z)."""
    a, b, c = d.uniform(-math.pi, math.pi), d.uniform(0.0, math.pi), d.uniform(-math.pi, math.pi)
    return _rz(a) @ _ry(b) @ _rz(c)


def _rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def turn(axis, angle: float) -> np.ndarray:
    """The rotation by ``angle`` about unit ``axis`` (Rodrigues)."""
    k = np.asarray(axis, float)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * K @ K


def inertia(d, mass: float, length: float) -> list[float]:
    """A box's inertia about its centre, turned at random: [Ixx, Iyy, Izz, Ixy, Ixz, Iyz], the matrix
    elements (docs/models.md), physical by construction (a box's moments obey the triangle inequality)."""
    a, b, c = length * d.uniform(0.2, 1.0), length * d.uniform(0.1, 0.4), length * d.uniform(0.1, 0.4)
    J = np.diag([mass * (b * b + c * c), mass * (a * a + c * c), mass * (a * a + b * b)]) / 12.0
    R = rotation(d)
    J = R @ J @ R.T
    return [float(J[0, 0]), float(J[1, 1]), float(J[2, 2]), float(J[0, 1]), float(J[0, 2]), float(J[1, 2])]


def vec(v) -> list[float]:
    return [float(x) for x in v]


def unit(d) -> np.ndarray:
    v = np.array([d.uniform(-1, 1) for _ in range(3)])
    n = float(np.linalg.norm(v))
    return v / n if n > 0.2 else np.array([0.0, 0.0, 1.0])


def body(name, parent, joint: dict, mass: float, com, inertia_: list) -> dict:
    return {"name": name, "parent": parent, "joint": joint, "mass": mass, "com": vec(com), "inertia": inertia_}


def gravity(d) -> list[float]:
    return d.choice([[0.0, 0.0, -G], [0.0, -G, 0.0], [0.0, 0.0, 0.0], vec(-G * unit(d))])


def case(d, name: str = "run") -> dict:
    """A duration and an output grid a user would pick (dt_out divides the duration exactly)."""
    dt = d.choice([0.005, 0.01, 0.02])
    n = d.integer(25, 60) if dt < 0.02 else d.integer(15, 40)
    return {"name": name, "duration": round(n * dt, 10), "dt_out": dt}


def spring(name, a, pa, b, pb, length: float, d, mass: float) -> dict:
    """A linear spring-damper whose free length is its length at the start times 0.7-1.3."""
    k = mass * d.uniform(20.0, 600.0)
    return {"name": name, "law": "linear_spring_damper", "body_a": a, "point_a": vec(pa), "body_b": b,
            "point_b": vec(pb), "parameters": {"stiffness": k, "damping": d.uniform(0.0, 0.05) * math.sqrt(k * mass),
                                               "free_length": length * d.uniform(0.7, 1.3)}}


def outputs_for(items: list[tuple]) -> list[dict]:
    """[[outputs]] from (name, kind, fields) tuples."""
    return [{"name": n, "kind": k, **f} for n, k, f in items]
