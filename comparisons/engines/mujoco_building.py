"""The building above the isolation level in MuJoCo's own elements (docs/building.md).

Floor i is a world body ``floor{i}`` at the slab's height plus the stories below, with two slide
joints ``f{i}x``, ``f{i}y`` (absolute, in the frame that translates with the ground, like the plate's
``px``, ``py``: the -m a_g load reaches the floors through MuJoCo's gravity as it reaches the plate).
Story i is a pair of fixed tendons (length f{i}x - f{i-1}x, and the same in Y; floor 0 is the plate's
px, py) with MuJoCo's own tendon stiffness k_i and damping c_i; the Rayleigh mass part is a fixed
tendon f{i}x - px (and Y) with damping b_i. The floors' displacement, velocity and acceleration are
MuJoCo's qpos, qvel and qacc (+ a_g for the absolute acceleration).
"""
from __future__ import annotations

import numpy as np

from nsd_core.device.building import Building, building_dissipation_rate, floor_columns


def _f(x) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(x))


def floors_mjcf(b: Building) -> str:
    out, z = [], 0.0
    for i in range(b.stories):
        z += b.heights[i]
        m = b.masses[i]
        J = m / 6.0  # a 1 m square floor; it never turns
        out.append(f"""    <body name="floor{i + 1}" pos="0 0 {_f(z)}">
      <inertial pos="0 0 0" mass="{_f(m)}" diaginertia="{_f([J / 2, J / 2, J])}"/>
      <joint name="f{i + 1}x" type="slide" axis="1 0 0"/>
      <joint name="f{i + 1}y" type="slide" axis="0 1 0"/>
    </body>
""")
    return "".join(out)


def tendons_mjcf(b: Building) -> str:
    rows = []
    for i in range(b.stories):
        for a, slab in (("x", "px"), ("y", "py")):
            lower = slab if i == 0 else f"f{i}{a}"
            rows.append(f"""    <fixed name="story{i + 1}{a}" stiffness="{_f(b.stiffnesses[i])}" damping="{_f(b.story_damping[i])}"
           springlength="0">
      <joint joint="f{i + 1}{a}" coef="1"/>
      <joint joint="{lower}" coef="-1"/>
    </fixed>
""")
            if b.slab_damping[i] > 0:
                rows.append(f"""    <fixed name="slab{i + 1}{a}" damping="{_f(b.slab_damping[i])}" springlength="0">
      <joint joint="f{i + 1}{a}" coef="1"/>
      <joint joint="{slab}" coef="-1"/>
    </fixed>
""")
    return "  <tendon>\n" + "".join(rows) + "  </tendon>\n"


class Floors:
    """The floors' addresses in a compiled MuJoCo model, their samples and their energy terms."""

    def __init__(self, model, b: Building, slab_dofs=(0, 1)):
        self.b = b
        self.qpos = np.array([[model.joint(f"f{i + 1}{a}").qposadr[0] for a in "xy"] for i in range(b.stories)])
        self.dof = np.array([[model.joint(f"f{i + 1}{a}").dofadr[0] for a in "xy"] for i in range(b.stories)])
        self.slab = np.array(slab_dofs)
        self.ids = [model.body(f"floor{i + 1}").id for i in range(b.stories)]
        self.samples = []

    def dissipation(self, qvel) -> float:
        return building_dissipation_rate(self.b, qvel[self.dof], qvel[self.slab])

    def kinetic(self, qvel) -> float:
        v = qvel[self.dof]
        return 0.5 * float(np.asarray(self.b.masses) @ np.sum(v * v, axis=1))

    def momentum(self, qvel) -> np.ndarray:
        return np.asarray(self.b.masses) @ qvel[self.dof]

    def sample(self, data, a_g) -> None:
        self.samples.append((data.qpos[self.qpos].copy(), data.qvel[self.dof].copy(),
                             data.qacc[self.dof] + np.asarray(a_g)[None, :]))

    def columns(self, x, y, vx, vy) -> dict:
        d = np.stack([s[0] for s in self.samples], axis=-1)   # (N, 2, samples)
        v = np.stack([s[1] for s in self.samples], axis=-1)
        a = np.stack([s[2] for s in self.samples], axis=-1)
        d0, v0 = np.array([x, y]), np.array([vx, vy])
        below = np.concatenate([d0[None], d[:-1]])
        return floor_columns(self.b, d, a, d - below, v, v0)
