"""The MJCF part that MuJoCo's drive model (mujoco_engine) and seismic model (mujoco_seismic) share."""
from __future__ import annotations

import numpy as np

from nsd_core.device.geometry import DeviceGeometry


def _f(x) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(x))


def wall_rod_loop_mjcf(g: DeviceGeometry, solref: str, solimp) -> str:
    """The wall on its slide, the rod on its ball joint and the cap-rod loop closed by a ``connect``:
    the part of the model the drive and the seismic MJCF share (closes the worldbody)."""
    rod_t = g.rod.inertia[0, 0]
    return f"""    <body name="wall" pos="0 0 {_f(g.wall_rest_z)}">
      <inertial pos="{_f(g.wall.com)}" mass="{_f(g.wall.mass)}" diaginertia="{_f(np.diag(g.wall.inertia))}"/>
      <joint name="wall_z" type="slide" axis="0 0 1"/>
      <body name="rod">
        <inertial pos="{_f(g.rod.com)}" mass="{_f(g.rod.mass)}" diaginertia="{_f(rod_t)} {_f(rod_t)} {_f(1e-3 * rod_t)}"/>
        <joint name="rod_ball" type="ball"/>
        <site name="rod_tip" pos="0 0 {_f(g.params.rod_length)}"/>
      </body>
    </body>
  </worldbody>
  <equality>
    <connect name="loop" body1="rod" body2="cap" anchor="0 0 {_f(g.params.rod_length)}"
             solref="{solref}" solimp="{_f(solimp)}"/>
  </equality>
"""
