"""The device as engine-independent data: attachment points, inertias and the precompressed rest state.

Every engine (semirecursive, MuJoCo, Exudyn) builds its model from ``device_geometry(params)`` so
that all of them read the paper the same way (``docs/model.md``). Frames: Z up; the base reference
is the spring's lower seat at the origin; the wall reference is the rod's lower joint centre (the
spring's upper seat), at rest at z = l_s; the cap reference is the rod's upper joint centre, at
rest at z = l_s + l_d. Points below are in the body's own frame, which at rest is the world frame
translated to the body reference.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from nsd_core.device.forces import SpringLaw, WireLaw, precompressed_spring
from nsd_core.device.params import Params


@dataclass(frozen=True)
class RigidBody:
    """Mass, centre of mass (body frame) and inertia about the centre of mass (body axes)."""
    name: str
    mass: float
    com: np.ndarray
    inertia: np.ndarray


@dataclass(frozen=True)
class DeviceGeometry:
    params: Params
    rope_base_points: np.ndarray    # (n_r, 3) lower rope ends, base frame
    rope_cap_points: np.ndarray     # (n_r, 3) upper rope ends, cap frame
    wire_cap_points: np.ndarray     # (n_w, 3) upper wire ends, cap frame
    wire_wall_points: np.ndarray    # (n_w, 3) lower wire ends, wall frame
    wall_rest_z: float              # l_s
    cap_rest_z: float               # l_s + l_d
    rope_natural_length: np.ndarray  # (n_r,) L_r0
    rope_stiffness: float
    wire: WireLaw
    spring: SpringLaw
    spring_precompression: float    # x_pre
    spring_zeta0: float             # zeta at rest
    cap: RigidBody
    wall: RigidBody
    base: RigidBody
    rod: RigidBody

    @property
    def n_ropes(self) -> int:
        return len(self.rope_natural_length)

    @property
    def n_wires(self) -> int:
        return len(self.wire_cap_points)

    @property
    def gravity_vector(self) -> np.ndarray:
        return np.array([0.0, 0.0, -self.params.gravity])

    @cached_property
    def rope_offsets(self) -> np.ndarray:
        """(n_r, 3) rope vector (upper end minus lower end) minus the cap position."""
        return self.rope_cap_points - self.rope_base_points

    @cached_property
    def wire_offsets(self) -> np.ndarray:
        """(n_w, 3) wire vector minus (cap position - wall position)."""
        return self.wire_cap_points - self.wire_wall_points

    def element_vectors(self, cap_pos, wall_z):
        """Rope and wire vectors (upper end minus lower end), shapes (..., n, 3), for cap positions
        (..., 3) and wall heights (...). In the drive mode cap and wall only translate, so the body
        frames stay parallel to the world frame and the attachment points are plain offsets."""
        cap = np.asarray(cap_pos, dtype=float)[..., None, :]
        wall = np.zeros_like(cap)
        wall[..., 2] = np.asarray(wall_z, dtype=float)[..., None]
        return cap + self.rope_offsets, cap - wall + self.wire_offsets

    def initial_wire_stress(self) -> np.ndarray:
        """Wires are not pretensioned (the paper: zero force in the undeformed configuration)."""
        return np.zeros(self.n_wires)


def _ring(n: int, radius: float, z: float, first_deg: float) -> np.ndarray:
    phi = math.radians(first_deg) + 2.0 * math.pi * np.arange(n) / max(n, 1)
    return np.column_stack([radius * np.cos(phi), radius * np.sin(phi), np.full(n, z)])


def _disc(name: str, mass: float, diameter: float, density: float) -> RigidBody:
    """Uniform solid disc; its thickness is the one the mass gives at the density (assumed)."""
    r = diameter / 2.0
    t = mass / (density * math.pi * r * r)
    ixx = mass * (3 * r * r + t * t) / 12.0
    return RigidBody(name, mass, np.zeros(3), np.diag([ixx, ixx, mass * r * r / 2.0]))


def device_geometry(p: Params) -> DeviceGeometry:
    """Build the one model of docs/model.md from a parameter set."""
    rope_base = _ring(p.n_ropes, p.rope_lower_radius, 0.0, p.wire_first_azimuth_deg)
    rope_cap = _ring(p.n_ropes, p.rope_upper_radius, p.rope_upper_height, p.wire_first_azimuth_deg)
    wire_cap = _ring(p.n_wires, p.wire_upper_radius, p.wire_upper_height, p.wire_first_azimuth_deg)
    wire_wall = _ring(p.n_wires, p.wire_lower_radius, 0.0, p.wire_first_azimuth_deg)
    wall_z, cap_z = p.spring_length, p.spring_length + p.rod_length

    # Ropes: at rest they pull the cap down with F_press - W in total (exact static equilibrium).
    rope_vec = rope_cap + [0.0, 0.0, cap_z] - rope_base
    rest_len = np.linalg.norm(rope_vec, axis=1)
    cos_vertical = rope_vec[:, 2] / rest_len
    tension = (p.precompression_force - p.carried_weight) / (p.n_ropes * cos_vertical)
    rope_l0 = rest_len - tension / p.rope_stiffness

    wire_len = float(np.linalg.norm(wire_cap[0] + [0, 0, p.rod_length] - wire_wall[0])) if p.n_wires else p.wire_span
    wire = WireLaw(p.wire_E, p.wire_Y, p.wire_alpha, p.wire_n, p.wire_fT, p.wire_a, p.wire_Em,
                   p.wire_eps_t, p.wire_c, p.wire_area, wire_len)
    x_pre, zeta0 = precompressed_spring(p.spring_kse, p.spring_ksd, p.spring_beta, p.spring_gamma,
                                        p.spring_n, p.precompression_force)
    spring = SpringLaw(p.spring_kse, p.spring_ksd, p.spring_beta, p.spring_gamma, p.spring_n,
                       p.spring_length + x_pre)
    rod_inertia = np.diag([p.rod_mass * p.rod_length ** 2 / 12.0] * 2 + [0.0])  # slender: no axial term
    rod = RigidBody("rod", p.rod_mass, np.array([0.0, 0.0, p.rod_length / 2.0]), rod_inertia)
    return DeviceGeometry(
        params=p, rope_base_points=rope_base, rope_cap_points=rope_cap, wire_cap_points=wire_cap,
        wire_wall_points=wire_wall, wall_rest_z=wall_z, cap_rest_z=cap_z, rope_natural_length=rope_l0,
        rope_stiffness=p.rope_stiffness, wire=wire, spring=spring, spring_precompression=x_pre,
        spring_zeta0=zeta0, cap=_disc("cap", p.cap_mass, p.cap_diameter, p.density),
        wall=_disc("wall", p.wall_mass, p.wall_diameter, p.density),
        base=_disc("base", p.base_mass, p.base_diameter, p.density), rod=rod)
