"""The building above the isolation level in Exudyn's own items (docs/building.md).

Floor i is a planar mass point (NodePoint2D + ObjectMassPoint2D: X and Y only) in the frame that
translates with the ground; it carries -m_i a_g as a load set in the pre-step function, as every other
body of the seismic model. Story i is an ObjectConnectorCartesianSpringDamper between floor i and floor
i-1 (floor 0 the plate's node) with stiffness (k_i, k_i, 0) and damping (c_i, c_i, 0); the Rayleigh mass
part is a second one between floor i and the plate with damping (b_i, b_i, 0). The floors'
displacement, velocity and acceleration are Exudyn's node outputs (+ a_g for the absolute acceleration).
"""
from __future__ import annotations

import numpy as np
import exudyn as exu
from exudyn.itemInterface import (LoadForceVector, MarkerNodePosition, NodePoint2D, ObjectConnectorCartesianSpringDamper,
                                  ObjectMassPoint2D)

from nsd_core.device.building import Building, building_dissipation_rate, floor_columns

OV = exu.OutputVariableType


class ExudynFloors:
    def __init__(self, mbs, b: Building, plate_node: int, a_g0):
        self.mbs, self.b, self.plate = mbs, b, plate_node
        self.m = np.asarray(b.masses, float)
        self.nodes, self.loads, self.samples = [], [], []
        plate_marker = mbs.AddMarker(MarkerNodePosition(nodeNumber=plate_node))
        lower = plate_marker
        for i in range(b.stories):
            node = mbs.AddNode(NodePoint2D(referenceCoordinates=[0.0, 0.0], initialCoordinates=[0.0, 0.0],
                                           initialVelocities=[0.0, 0.0]))
            mbs.AddObject(ObjectMassPoint2D(physicsMass=float(b.masses[i]), nodeNumber=node))
            marker = mbs.AddMarker(MarkerNodePosition(nodeNumber=node))
            k, c, bb = float(b.stiffnesses[i]), float(b.story_damping[i]), float(b.slab_damping[i])
            mbs.AddObject(ObjectConnectorCartesianSpringDamper(markerNumbers=[lower, marker], stiffness=[k, k, 0.0],
                                                               damping=[c, c, 0.0]))
            if bb > 0:
                mbs.AddObject(ObjectConnectorCartesianSpringDamper(markerNumbers=[plate_marker, marker],
                                                                   stiffness=[0.0, 0.0, 0.0], damping=[bb, bb, 0.0]))
            self.loads.append(mbs.AddLoad(LoadForceVector(markerNumber=marker, loadVector=[
                -self.m[i] * a_g0[0], -self.m[i] * a_g0[1], 0.0])))
            self.nodes.append(node)
            lower = marker

    def set_inertial(self, mbs, a_g) -> None:
        """-m_i a_g on every floor (the frame that translates with the ground)."""
        for m, load in zip(self.m, self.loads):
            mbs.SetLoadParameter(load, "loadVector", [-m * a_g[0], -m * a_g[1], 0.0])

    def _out(self, kind) -> np.ndarray:
        return np.array([np.asarray(self.mbs.GetNodeOutput(n, kind))[:2] for n in self.nodes])

    def momentum(self) -> np.ndarray:
        return self.m @ self._out(OV.Velocity)

    def kinetic(self) -> float:
        v = self._out(OV.Velocity)
        return 0.5 * float(self.m @ np.sum(v * v, axis=1))

    def dissipation(self) -> float:
        return building_dissipation_rate(self.b, self._out(OV.Velocity),
                                         np.asarray(self.mbs.GetNodeOutput(self.plate, OV.Velocity))[:2])

    def sample(self, a_g) -> None:
        self.samples.append((self._out(OV.Position), self._out(OV.Velocity),
                             self._out(OV.Acceleration) + np.asarray(a_g)[None, :2]))

    def columns(self, x, y, vx, vy) -> dict:
        d = np.stack([s[0] for s in self.samples], axis=-1)   # (N, 2, samples)
        v = np.stack([s[1] for s in self.samples], axis=-1)
        a = np.stack([s[2] for s in self.samples], axis=-1)
        d0 = np.array([x, y])
        below = np.concatenate([d0[None], d[:-1]])
        return floor_columns(self.b, d, a, d - below, v, np.array([vx, vy]))
