"""The device's plate path as a prescribed motion of a model description (motion "device_path",
registered with nsd_core.model.description.register_motion when nsd_core.device is imported)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nsd_core.common.errors import ParameterError
from nsd_core.device.drive import Drive
from nsd_core.model.description import COMPONENTS, register_motion
from nsd_core.model.errors import ModelError
from nsd_core.model.load import number

FIELDS = ("path", "amplitude", "minor", "frequency", "direction", "component")


@dataclass(frozen=True)
class PlateComponent:
    """One coordinate (0: x, 1: y) of the plate's path: q(t), q'(t), q''(t) [m, m/s, m/s^2]."""
    drive: Drive
    component: int

    def __call__(self, t: float) -> tuple[float, float, float]:
        at, c = self.drive.plate_at(t), self.component
        return at[c], at[2 + c], at[4 + c]

    def table(self, times: np.ndarray) -> np.ndarray:
        """(q, q', q'') at every time at once: 3 x len(times), the drive's own compiled path."""
        x, v, a = self.drive.plate(times)
        c = self.component
        return np.array([x[:, c], v[:, c], a[:, c]])


def parse_device_path(where: str, t: dict) -> dict:
    """A [[prescribed]] table of motion "device_path": one component of the device's plate path
    (``nsd cycle --path``'s named paths, their ramps and bounds): {"motion": PlateComponent}."""
    path, comp = t.get("path"), t.get("component")
    named = ("line", "circle", "ellipse", "figure8")
    if path not in named and not (isinstance(path, str) and path.lower().endswith(".csv")):
        raise ModelError(f"{where}.path = {path!r}: allowed: {', '.join(named)} or a CSV file of t,x,y")
    if comp not in ("x", "y"):
        raise ModelError(f"{where}.component = {comp!r}: allowed: x, y (the plate path's coordinate)")
    for k in ("amplitude", "frequency"):
        if k not in t:
            raise ModelError(f"{where}.{k}: missing (motion 'device_path' needs it)")
    minor = t.get("minor")
    values = dict(amplitude=number(f"{where}.amplitude", t["amplitude"]), frequency=number(f"{where}.frequency", t["frequency"]),
                  direction_deg=number(f"{where}.direction", t.get("direction", 0.0)), path=path,
                  minor=None if minor is None else number(f"{where}.minor", minor))
    try:   # the device's own bounds on a path (ModelError above is one already: checked first)
        drive = Drive(**values)
    except ParameterError as e:
        raise ModelError(f"{where}: {e}") from None
    return {"motion": PlateComponent(drive, COMPONENTS[comp])}


register_motion("device_path", FIELDS, parse_device_path)
