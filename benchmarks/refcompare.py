"""Shared by the convergence scripts: last-cycle discrepancy and the tight in-house reference."""
from __future__ import annotations

import time

import numpy as np

from nsd_core.device.cycle import loop_area
from nsd_core.device.model import simulate
from nsd_core.device.drive import Drive
from nsd_core.device.params import Params


def last_cycle(t, drive: Drive) -> slice:
    t = np.asarray(t)
    return slice(int(np.searchsorted(t, (drive.cycles - 1) / drive.frequency - 1e-12)), len(t))


def discrepancy(result, ref, drive: Drive) -> dict:
    """dF = max|F - F_ref| / max|F_ref| and dA (signed relative loop-area difference) on the last cycle."""
    sl = last_cycle(ref["t"], drive)
    F = np.interp(np.asarray(ref["t"])[sl], result["t"], result["F"])
    F_ref, u = np.asarray(ref["F"])[sl], np.asarray(ref["u"])[sl]
    a, a_ref = loop_area(u, F), loop_area(u, F_ref)
    return {"dF": float(np.max(np.abs(F - F_ref)) / np.max(np.abs(F_ref))),
            "dA": float((a - a_ref) / abs(a_ref)), "area": a, "area_ref": a_ref,
            "peak_F_ref": float(np.max(np.abs(F_ref)))}


def in_house_reference(params: Params, drive: Drive):
    """(RunResult, note): the in-house semirecursive model at tight tolerances."""
    t0 = time.perf_counter()
    r = simulate(params, drive, rtol=1e-10, atol=1e-12)
    return r, f"nsd_core.device.simulate(rtol=1e-10, atol=1e-12), {time.perf_counter() - t0:.1f} s"
