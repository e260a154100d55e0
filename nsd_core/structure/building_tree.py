"""The building as more bodies of the in-house engine's generic tree (docs/building.md).

Floor i (i = 1..N) is two bodies like the plate's planar joint: ``floor{i}_x`` (prismatic along X on
the ground, massless) carrying ``floor{i}_y`` (prismatic along Y, the floor's mass m_i), at the
height of the slab plus the stories below. The coordinates are absolute (in the inertial frame, like
the plate's and the base's), so a floor's displacement relative to the ground is z - x_g. The stories
are linear spring-dampers between floor i and floor i-1 (floor 0 the slab), the Rayleigh mass part
dampers between floor i and the slab; both enter as joint forces on the floors' and the slab's
coordinates (``nsd_core.structure.building.building_forces``, the one law every engine's columns use).

The compiled path reads the building as a block of its force parameters (``building_block``).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from nsd_core.structure.building import Building, building_forces
from nsd_core.engine.mechanism import GROUND, Mechanism

X_AXIS, Y_AXIS = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)


def floor_names(n: int) -> list[str]:
    """The floors' coordinates in the tree, floor 1's X first: floor1_x, floor1_y, floor2_x, ..."""
    return [f"floor{i}_{a}" for i in range(1, n + 1) for a in ("x", "y")]


def with_floors(mech: Mechanism, building: Building, slab_height: float = 0.0) -> Mechanism:
    """``mech`` with the building's floors appended (parents first: the existing indices stay)."""
    n0, nb = mech.n, building.stories
    names, parent, jtype = list(mech.names), list(mech.parent), list(mech.joint_type)
    axis, offset = [mech.joint_axis], [mech.joint_offset]
    mass, com, inertia = [mech.mass], [mech.com], [mech.inertia]
    z = slab_height
    for i in range(nb):
        z += building.heights[i]
        m = building.masses[i]
        names += [f"floor{i + 1}_x", f"floor{i + 1}_y"]
        parent += [GROUND, n0 + 2 * i]
        jtype += ["P", "P"]
        axis.append(np.array([X_AXIS, Y_AXIS]))
        offset.append(np.array([[0.0, 0.0, z], [0.0, 0.0, 0.0]]))
        mass.append(np.array([0.0, m]))
        com.append(np.zeros((2, 3)))
        J = m * 1.0 / 6.0  # a floor's inertia never enters (it only translates); a 1 m square slab's
        inertia.append(np.array([np.zeros((3, 3)), np.diag([J / 2, J / 2, J])]))
    return dataclasses.replace(mech, names=tuple(names), parent=tuple(parent), joint_type=tuple(jtype),
                               joint_axis=np.vstack(axis), joint_offset=np.vstack(offset),
                               mass=np.concatenate(mass), com=np.vstack(com), inertia=np.concatenate(inertia))


class BuildingIndex:
    """The floors' and the slab's coordinate indices in a mechanism."""

    def __init__(self, mech: Mechanism, building: Building):
        self.b = building
        self.fx = np.array([mech.names.index(f"floor{i}_x") for i in range(1, building.stories + 1)])
        self.fy = np.array([mech.names.index(f"floor{i}_y") for i in range(1, building.stories + 1)])
        self.sx, self.sy = mech.names.index("plate_x"), mech.names.index("plate_y")
        self.gx, self.gy = mech.names.index("base_x"), mech.names.index("base_y")

    def motion(self, z, zd):
        """(d (N, 2), v (N, 2), d0 (2,), v0 (2,)) relative to the ground."""
        g = np.array([z[self.gx], z[self.gy]])
        gv = np.array([zd[self.gx], zd[self.gy]])
        d = np.column_stack([z[self.fx], z[self.fy]]) - g
        v = np.column_stack([zd[self.fx], zd[self.fy]]) - gv
        return d, v, np.array([z[self.sx], z[self.sy]]) - g, np.array([zd[self.sx], zd[self.sy]]) - gv

    def add_forces(self, gen, z, zd) -> None:
        """The building's joint forces on the floors' and the slab's coordinates, added into gen."""
        d, v, d0, v0 = self.motion(z, zd)
        f, f_slab, _, _ = building_forces(self.b, d, v, d0, v0)
        gen[self.fx] += f[:, 0]
        gen[self.fy] += f[:, 1]
        gen[self.sx] += f_slab[0]
        gen[self.sy] += f_slab[1]


def building_block(mech: Mechanism, building: Building | None) -> np.ndarray:
    """[N, slab_x, slab_y, then per floor: index_x, index_y, k_i, c_i, b_i] (N = 0: no building)."""
    if building is None:
        return np.zeros(1)
    ix = BuildingIndex(mech, building)
    rows = [[ix.fx[i], ix.fy[i], building.stiffnesses[i], building.story_damping[i], building.slab_damping[i]]
            for i in range(building.stories)]
    return np.concatenate([[building.stories, ix.sx, ix.sy], np.ravel(rows)]).astype(float)
