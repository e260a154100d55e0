"""The restoring-force check of building codes for isolation systems, on the isolation level's
quasi-static force-displacement relation (docs/seismic.md, "The restoring-force check").

Rule (ASCE/SEI 7-16 Section 17.2.4.4, "Restoring force"; the same 0.025 W rule stands in ASCE 7-10
Section 17.2.4.4 at the total design displacement and in NBC Canada 2015 4.1.8.20): the isolation
system's lateral force at the displacement D exceeds its force at D/2 by at least 0.025 W, W the
weight the isolation system carries:

    F(D) - F(D/2) >= 0.025 W.

F(u) = k_b u + F_device(u): the supports (linear, stiffness k_b per direction) plus the device's
quasi-static force along the direction (``nsd_core.device.quasistatic``, independent of any
multibody engine), on first loading from rest to D (the device's hysteretic states carried along the
path). W = (M + the building's floor masses) g. Each direction of ``DIRECTIONS_DEG`` is checked;
the smallest margin governs.

D: given by the caller, or by default the device's working range X_max (the smallest over the
checked directions; 25.46 mm for the nominal device): the largest displacement at which the device
still works as designed (ropes taut), so the largest a design displacement can honestly be. The
isolated structure has no design level of its own yet.
"""
from __future__ import annotations

import math

import numpy as np

from nsd_core.device.params import ParameterError, Params

CODE = "ASCE/SEI 7-16 Section 17.2.4.4"
RATIO = 0.025            # of W: the code's least F(D) - F(D/2)
DIRECTIONS_DEG = (0.0, 45.0)   # the first wire, and between wires and ropes (as the default structure's rule)
POINTS = 201             # quasi-static points from 0 to D (odd: D/2 is a point); 401 changes F by < 1e-3 N
D_MIN = 1e-6             # m, the least design displacement (as a drive's least amplitude)
DEFAULT_D = "the device's working range X_max (the smallest over the checked directions)"


def weight(structure, gravity: float) -> float:
    """W [N]: the isolated mass M and the building's floors, times g."""
    floors = sum(structure.building.masses) if structure.building is not None else 0.0
    return (structure.mass + floors) * gravity


class NoDefaultError(ParameterError):
    """The device has no working range X_max to take the design displacement from."""


def default_design_displacement(params: Params, directions_deg=DIRECTIONS_DEG) -> float:
    """X_max [m], the smallest over the directions (nsd_core.device.working_range); NoDefaultError
    (one line) for a device without one."""
    from nsd_core.device.working_range import SlackPointError, x_max_at_slack
    try:
        return min(x_max_at_slack(params, psi) for psi in directions_deg)
    except SlackPointError as e:
        raise NoDefaultError(f"--design-displacement: no default for this device (it has no working range: {e}); "
                             "give one in metres") from None


def check_design_displacement(value, rod_length: float, option: str = "--design-displacement") -> float:
    """D as a number in [D_MIN, 0.999 rod_length] m (ParameterError, one line, otherwise)."""
    try:
        d = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{option} {value!r}: not a number; allowed: a displacement in metres in "
                             f"[{D_MIN:g}, {0.999 * rod_length:.6g}] (below the rod's length)") from None
    if not (math.isfinite(d) and D_MIN <= d <= 0.999 * rod_length):
        raise ParameterError(f"{option} = {value}: allowed: a displacement in metres in [{D_MIN:g}, "
                             f"{0.999 * rod_length:.6g}] (below the rod's length {rod_length:g} m)")
    return d


def _entry(f_d: float, f_half: float, w: float) -> dict:
    diff = f_d - f_half
    return {"F_D": f_d, "F_half_D": f_half, "difference": diff, "required": RATIO * w,
            "margin": diff - RATIO * w, "difference_over_W": diff / w, "pass": bool(diff >= RATIO * w)}


def restoring_force_check(params: Params, structure, design_displacement: float | None = None,
                          directions_deg=DIRECTIONS_DEG, device: bool = True) -> dict:
    """The code's restoring-force check of the isolation level (see the module docstring).

    Returns {"code", "rule", "D", "D_source", "W", "required", "pass", "governing_direction_deg",
    "with_device": {direction: {F_D, F_half_D, difference, required, margin, difference_over_W, pass}},
    "supports_alone": {...}, "how"}; forces in N, displacements in m. ``device=False``: the supports
    alone only (with_device is None).
    """
    if design_displacement is None:
        d = x_max = default_design_displacement(params, directions_deg)
        source = f"default: {DEFAULT_D}"
    else:
        d, source = check_design_displacement(design_displacement, params.rod_length), "given"
        try:
            x_max = default_design_displacement(params, directions_deg) if device else None
        except NoDefaultError:
            x_max = None   # no working range to scan
    w = weight(structure, params.gravity)
    k_b = structure.stiffness
    alone = {**_entry(k_b * d, k_b * d / 2.0, w), "least_passing_D": 2.0 * RATIO * w / k_b}
    out = {"code": CODE, "rule": f"F(D) - F(D/2) >= {RATIO} W", "D": d, "D_source": source, "x_max": x_max,
           "W": w, "required": RATIO * w, "supports_alone": alone, "with_device": None,
           "how": "F(u) = k_b u + the device's quasi-static force along the direction, on first loading from rest "
                  "to D (nsd_core.device.quasistatic); W = (M + floor masses) g"}
    if device:
        from nsd_core.device.quasistatic import quasi_static_path
        per = {}
        for psi in directions_deg:
            u = np.linspace(0.0, d, POINTS)
            with np.errstate(all="ignore"):
                f_dev = quasi_static_path(params, u, psi, substeps=4)["F_device"]
            half = (POINTS - 1) // 2
            if not (math.isfinite(float(f_dev[-1])) and math.isfinite(float(f_dev[half]))):
                # a device the quasi-static path cannot follow (e.g. precompression_force = 1e8): no number
                raise FloatingPointError(f"F_device = {float(f_dev[half])!r} at D/2, {float(f_dev[-1])!r} at D "
                                         f"(direction {psi:g} deg)")
            per[f"{psi:g}"] = {**_entry(k_b * d + float(f_dev[-1]), k_b * d / 2.0 + float(f_dev[half]), w),
                               "device_F_D": float(f_dev[-1]), "device_F_half_D": float(f_dev[half])}
            if x_max is not None:
                per[f"{psi:g}"]["over_working_range"] = margin_over_range(params, structure, x_max, psi)
        worst = min(per, key=lambda k: per[k]["margin"])
        out.update(with_device=per, governing_direction_deg=float(worst), **{"pass": per[worst]["pass"]},
                   margin=per[worst]["margin"])
    else:
        out.update(governing_direction_deg=None, margin=alone["margin"], **{"pass": alone["pass"]})
    return out


def margin_over_range(params: Params, structure, upto: float, psi: float, points: int = 2 * POINTS - 1) -> dict:
    """The margin F(D) - F(D/2) - 0.025 W for every D of a grid on (0, upto] along psi, from one
    first-loading path (its prefix up to D is the path to D): the intervals of D that fail and the
    least D from which every D passes [m] (None: the largest fails)."""
    from nsd_core.device.quasistatic import quasi_static_path
    u = np.linspace(0.0, upto, points)
    with np.errstate(all="ignore"):
        f = structure.stiffness * u + quasi_static_path(params, u, psi, substeps=4)["F_device"]
    d, margin = u[2::2], f[2::2] - f[1:(points + 1) // 2] - RATIO * weight(structure, params.gravity)
    fails, start = [], None
    for k, bad in enumerate(margin < 0.0):
        if bad and start is None:
            start = k
        if start is not None and (not bad or k == len(margin) - 1):
            fails.append([float(d[start]), float(d[k if bad else k - 1])])
            start = None
    passing = None if margin[-1] < 0.0 else float(d[0] if not fails else fails[-1][1] + (d[1] - d[0]))
    return {"upto": float(upto), "step": float(d[1] - d[0]), "failing_D": fails, "least_passing_D": passing,
            "note": "the check passes for every D of the grid from least_passing_D to upto"}


def describe(check: dict) -> str:
    """One line: the numbers and the verdict."""
    def part(e):
        return (f"F(D) - F(D/2) = {e['F_D']:.5g} - {e['F_half_D']:.5g} = {e['difference']:.5g} N, margin "
                f"{e['margin']:+.4g} N: {'pass' if e['pass'] else 'FAIL'}")
    head = f"restoring force ({check['code']}) at D = {check['D'] * 1e3:.4g} mm, 0.025 W = {check['required']:.5g} N: "
    if check["with_device"] is not None:
        psi = check["governing_direction_deg"]
        e = check["with_device"][f"{psi:g}"]
        least = e.get("over_working_range", {}).get("least_passing_D")
        where = "" if least is None else f" (passes for D >= {least * 1e3:.4g} mm)"
        return (head + f"with the device (direction {psi:g} deg) {part(e)}{where}; supports alone "
                f"{part(check['supports_alone'])}")
    return head + f"supports alone {part(check['supports_alone'])}"
