"""The unit of every time-series column any engine writes (drive and seismic runs, the building
above the slab, the restrainer): one table, read by every writer of ``cycle.csv``, ``seismic.csv``
and the peers' CSVs, a sweep's steady.csv, an IDA's exact.csv (``nsd_core.device.results.write_columns``
looks every header's unit up here).

Indexed families (``rope{i}_tension``, ``floor{j}_x``, ``story_shear{j}_y`` ...) are one row each,
with ``{i}`` for the index. A column that is not in the table is an error (``KeyError``), never a
guessed unit.
"""
from __future__ import annotations

import re

# name (with {i} for a rope, wire, story or floor index) -> SI unit ("-" dimensionless)
COLUMN_UNITS = {
    # time and the drive mode's plate and forces
    "t": "s", "u": "m", "x": "m", "y": "m",
    "F": "N", "F_device": "N", "F_rod": "N", "F_ropes": "N", "F_wires": "N",
    "F_x": "N", "F_y": "N", "F_tangent": "N", "F_radial": "N",
    # a sweep's steady cycle (steady.csv): the tangent stiffness dF/du, the wires' elongations
    "stiffness": "N/m", "wire{i}_elongation": "m",
    # the cap, the spring's wall, the loop's closure
    "spring_push": "N", "spring_zeta": "N", "cap_z": "m", "wall_z": "m", "closure": "m",
    # elements
    "rope{i}_tension": "N", "rope{i}_F": "N",
    "wire{i}_tension": "N", "wire{i}_F": "N", "wire{i}_strain": "-", "wire{i}_stress": "Pa",
    # seismic mode: the ground, the slab's motion relative to it, forces on the ground
    "x_g": "m", "y_g": "m", "ax_g": "m/s^2", "ay_g": "m/s^2",
    "theta": "rad", "vx": "m/s", "vy": "m/s", "omega": "rad/s", "ax_abs": "m/s^2", "ay_abs": "m/s^2",
    "support_Fx": "N", "support_Fy": "N", "support_torque": "N m",
    "device_Fx": "N", "device_Fy": "N", "base_shear_x": "N", "base_shear_y": "N",
    # the restrainer (moat wall)
    "isolator_zx": "-", "isolator_zy": "-", "restrainer_Fx": "N", "restrainer_Fy": "N", "restrainer_F": "N", "restrainer_indentation": "m",
    # the building above the slab: floor i relative to the ground, story i's drift and shear
    "floor{i}_x": "m", "floor{i}_y": "m", "floor{i}_vx": "m/s", "floor{i}_vy": "m/s",
    "floor{i}_ax_abs": "m/s^2", "floor{i}_ay_abs": "m/s^2",
    "drift{i}_x": "m", "drift{i}_y": "m", "story_shear{i}_x": "N", "story_shear{i}_y": "N",
    # energies
    "E_input": "J", "E_kinetic": "J", "E_gravity": "J", "E_supports_stored": "J", "E_supports_dissipated": "J",
    "E_device": "J", "E_restrainer_stored": "J", "E_restrainer_dissipated": "J", "E_building_stored": "J",
    "E_building_dissipated": "J", "E_residual": "J",
}

_EXACT = {k: v for k, v in COLUMN_UNITS.items() if "{i}" not in k}
_FAMILIES = [(re.compile("^" + re.escape(k).replace(r"\{i\}", r"\d+") + "$"), v)
             for k, v in COLUMN_UNITS.items() if "{i}" in k]


def unit_of(name: str) -> str:
    """The unit of column ``name`` (KeyError for a column the table does not know)."""
    if name in _EXACT:
        return _EXACT[name]
    for pattern, unit in _FAMILIES:
        if pattern.match(name):
            return unit
    raise KeyError(f"column {name!r} has no unit in nsd_core.device.columns.COLUMN_UNITS")


def units_of(names) -> dict[str, str]:
    """{name: unit} for the columns ``names``, in their order."""
    return {name: unit_of(name) for name in names}
