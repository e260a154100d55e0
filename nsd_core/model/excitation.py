"""The ground's motion as a model's excitation (``[excitation]`` in a description).

A description's frame may translate with the ground: then every body feels, besides gravity, the
load -m a_g(t) at its centre of mass (d'Alembert's load of the frame's acceleration a_g). Every engine
applies it as one uniform field, the effective gravity g - a_g(t); the described coordinates are
then relative to the ground, which is how the device's seismic mode is posed (docs/model.md allows
this form for a translating base).

a_g(t) comes from the device's own ground motions (nsd_core.ground.motions): a closed form in the
syntax of ``nsd seismic --ground`` (harmonic, pulse) or a FEMA P695 record pair (A along x, B along
y, then turned in plan). Compiled code reads it through ``ground_values(t, block, 0)`` on
``Excitation.block``: one implementation of a_g for the in-house engine, MuJoCo and Exudyn.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nsd_core.ground.motions import GroundMotion, parse_ground_spec
from nsd_core.ground.records import fema_record
from nsd_core.common.errors import ParameterError
from nsd_core.model.errors import ModelError

KINDS = ("ground_acceleration",)
RECORD_KEYS = {"set", "id", "scale", "time_factor", "window", "rotate"}


@dataclass(frozen=True)
class Excitation:
    kind: str
    motion: GroundMotion
    block: np.ndarray        # ground_values' flat block (nsd_core.ground.motions)
    source: str              # as written: the closed form's text or the record's table

    def acceleration(self, t: float) -> np.ndarray:
        """a_g(t) = (a_x, a_y, 0) [m/s^2]: the ground's acceleration, horizontal."""
        a = self.motion.values_at(float(t))
        return np.array([a[4], a[5], 0.0])

    def accelerations(self, times) -> np.ndarray:
        """a_g at every time of ``times``: one row (a_x, a_y, 0) each, the floats of ``acceleration``."""
        a = self.motion(np.asarray(times, dtype=float))[2]
        return np.column_stack([a, np.zeros(len(a))])

    def gravity(self, g, t: float) -> np.ndarray:
        """The uniform field every body feels in the ground's frame: g - a_g(t) [m/s^2]."""
        return np.asarray(g, dtype=float) - self.acceleration(t)


def parse_excitation(t) -> Excitation | None:
    """``[excitation]`` as an Excitation (None when absent); a mistake is one ModelError line."""
    if t is None:
        return None
    if not isinstance(t, dict):
        raise ModelError(f"[excitation] = {t!r}: must be a table")
    for k in t:
        if k not in ("type", "ground", "record"):
            raise ModelError(f"[excitation].{k}: unknown field; allowed: ground, record, type")
    kind = t.get("type", "ground_acceleration")
    if kind not in KINDS:
        raise ModelError(f"[excitation].type = {kind!r}: allowed: {', '.join(KINDS)}")
    if ("ground" in t) == ("record" in t):
        raise ModelError("[excitation]: give exactly one of ground (a closed form, e.g. "
                         "\"harmonic:amplitude=2,frequency=1.5\") or record (a FEMA P695 pair)")
    if "ground" in t:
        try:
            motion, source = parse_ground_spec(t["ground"], "[excitation].ground"), str(t["ground"])
        except ParameterError as e:
            raise ModelError(str(e)) from None
    else:
        try:
            motion, source = _record(t["record"]), repr(t["record"])
        except ParameterError as e:
            raise ModelError(f"[excitation].record: {e}") from None
    return Excitation(kind, motion, np.ascontiguousarray(motion.block(), dtype=float), source)


def _record(r) -> GroundMotion:
    where = "[excitation].record"
    if not isinstance(r, dict):
        raise ModelError(f"{where} = {r!r}: must be a table {{ set = ..., id = ... }}")
    for k in r:
        if k not in RECORD_KEYS:
            raise ModelError(f"{where}.{k}: unknown field; allowed: {', '.join(sorted(RECORD_KEYS))}")
    for k in ("set", "id"):
        if k not in r:
            raise ModelError(f"{where}.{k}: missing (a record is a set and a FEMA P695 id)")
    kw = {}
    for k, arg in (("scale", "scale"), ("time_factor", "time_factor"), ("rotate", "rotate_deg")):
        if k in r:
            if isinstance(r[k], bool) or not isinstance(r[k], (int, float)):
                raise ModelError(f"{where}.{k} = {r[k]!r}: must be a number")
            kw[arg] = float(r[k])
    if "window" in r:
        w = r["window"]
        if not (isinstance(w, list) and len(w) == 2 and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in w)):
            raise ModelError(f"{where}.window = {w!r}: must be [t0, t1] in record seconds")
        kw["window"] = (float(w[0]), float(w[1]))
    if isinstance(r["id"], bool) or not isinstance(r["id"], int):
        raise ModelError(f"{where}.id = {r['id']!r}: must be a whole number (the FEMA P695 record id)")
    return fema_record(r["set"], r["id"], **kw)
