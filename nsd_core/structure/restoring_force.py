"""The building codes' restoring-force check of an isolation system, on the quasi-static
force-displacement relation of the configuration actually run (docs/seismic.md, "The restoring-force
check").

Rule (ASCE/SEI 7-16 Section 17.2.4.4, "Restoring force", at the maximum displacement D_M; the same
0.025 W rule stands in ASCE 7-10 Section 17.2.4.4 at the total design displacement and in NBC Canada
2015 4.1.8.20): the isolation system's lateral force at the displacement D exceeds its force at D/2
by at least 0.025 W, W the weight the isolation system carries:

    F(D) - F(D/2) >= 0.025 W.

F(u) along the direction psi, on first loading from rest to D, by the configuration's own law:

* device: k_b u + F_device(u), the supports plus the device's quasi-static force
  (``nsd_core.device.quasistatic``, independent of any multibody engine; its hysteretic states
  carried along the path);
* linear: k_b u (the supports alone);
* bilinear (lead-rubber) and friction pendulum: k_d u + Q z(u), the baseline isolator's own law
  (``nsd_core.structure.isolator_laws``: z advanced along the path, Q at rest, the law's q_slow).

W = (M + the building's floor masses) g, g the design's (``nsd_core.structure.design.G``). Each
direction of ``DIRECTIONS_DEG`` is checked (the device is not isotropic; the baselines are, and give
the same numbers in both); the smallest margin governs.

D: given by the caller, or by default the design basis's maximum displacement D_M at model scale
(``nsd_core.structure.design``: ASCE 7-16 Eq. 17.5-1 at S_M1 = 1.5 S_D1; 19.64 mm). The least passing D
(the least D from which every D up to the scan's end passes) is bracketed on a grid and then solved
by Brent's method to ``XTOL``.
"""
from __future__ import annotations

import math

import numpy as np

from nsd_core.device.params import ParameterError, Params

CODE = "ASCE/SEI 7-16 Section 17.2.4.4"
RATIO = 0.025            # of W: the code's least F(D) - F(D/2)
DIRECTIONS_DEG = (0.0, 45.0)   # the first wire, and between wires and ropes (as the default structure's rule)
POINTS = 201             # quasi-static points from 0 to D (odd: D/2 is a point); 401 changes F by < 1e-3 N
ISOLATOR_SUBSTEPS = 16   # midpoint substeps of the isolator's z per path step
D_MIN = 1e-6             # m, the least design displacement (as a drive's least amplitude)
XTOL = 1e-8              # m, Brent's tolerance on the least passing D
DEFAULT_D = ("the design basis's maximum displacement D_M at model scale (ASCE 7-16 Eq. 17.5-1 at "
             "S_M1 = 1.5 S_D1; nsd_core.structure.design)")
CONFIGURATIONS = ("device", "linear", "bilinear", "friction-pendulum")


def weight(structure, gravity: float | None = None) -> float:
    """W [N]: the isolated mass M and the building's floors, times g (the design's, by default)."""
    from nsd_core.structure.design import G
    floors = sum(structure.building.masses) if structure.building is not None else 0.0
    return (structure.mass + floors) * (G if gravity is None else gravity)


class NoDefaultError(ParameterError):
    """The device has no working range X_max."""


def working_range(params: Params, directions_deg=DIRECTIONS_DEG) -> float:
    """X_max [m], the smallest over the directions (nsd_core.device.working_range); NoDefaultError
    (one line) for a device without one."""
    from nsd_core.device.working_range import SlackPointError, x_max_at_slack
    try:
        return min(x_max_at_slack(params, psi) for psi in directions_deg)
    except SlackPointError as e:
        raise NoDefaultError(f"the device has no working range X_max ({e})") from None


def default_design_displacement() -> float:
    """D_M [m] at model scale: the design basis's maximum displacement."""
    from nsd_core.structure.design import design
    return float(design()["D_M_model_m"])


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


def configuration_of(structure, device: bool) -> str:
    """The configuration a run isolates with: the device, else the structure's baseline isolator, else
    the linear supports."""
    if device:
        return "device"
    return structure.isolator.kind if structure.isolator is not None else "linear"


def force_path(params: Params, structure, configuration: str, u: np.ndarray, psi: float) -> np.ndarray:
    """F(u) [N] along psi [deg] on first loading from rest over the path u[0] = 0 .. u[-1], by the
    configuration's own law (see the module docstring)."""
    u = np.asarray(u, dtype=float)
    if configuration == "device":
        from nsd_core.device.quasistatic import quasi_static_path
        with np.errstate(all="ignore"):
            return structure.stiffness * u + quasi_static_path(params, u, psi, substeps=4)["F_device"]
    if configuration == "linear":
        return structure.stiffness * u
    from nsd_core.structure.isolator_laws import advance_hysteresis
    iso = structure.isolator
    if iso is None or iso.kind != configuration:
        raise ParameterError(f"restoring force: configuration {configuration!r} needs the structure's "
                             f"{configuration} isolator")
    c, s = math.cos(math.radians(psi)), math.sin(math.radians(psi))
    zx = zy = 0.0
    f = np.zeros(len(u))
    for k in range(1, len(u)):
        du = float(u[k] - u[k - 1])
        zx, zy = advance_hysteresis(du * c, du * s, zx, zy, iso.yield_displacement, iso.exponent,
                                    ISOLATOR_SUBSTEPS)
        f[k] = iso.stiffness * u[k] + iso.q_slow * (zx * c + zy * s)
    return f


def margin_at(params: Params, structure, configuration: str, d: float, psi: float) -> tuple[float, float]:
    """(F(D), F(D/2)) [N] from the path of POINTS points from rest to D."""
    f = force_path(params, structure, configuration, np.linspace(0.0, d, POINTS), psi)
    return float(f[-1]), float(f[(POINTS - 1) // 2])


def _entry(f_d: float, f_half: float, w: float) -> dict:
    diff = f_d - f_half
    return {"F_D": f_d, "F_half_D": f_half, "difference": diff, "required": RATIO * w,
            "margin": diff - RATIO * w, "difference_over_W": diff / w, "pass": bool(diff >= RATIO * w)}


def _scan(params: Params, structure, configuration: str, upto: float, psi: float, points: int = 2 * POINTS - 1):
    """The margin for every D of a grid on (0, upto] along psi from one first-loading path (its prefix
    up to D is the path to D): (grid D, margins)."""
    u = np.linspace(0.0, upto, points)
    f = force_path(params, structure, configuration, u, psi)
    return u[2::2], f[2::2] - f[1:(points + 1) // 2] - RATIO * weight(structure)


def least_passing(params: Params, structure, configuration: str, upto: float, psi: float) -> dict:
    """The least D from which every D up to ``upto`` passes along psi [m] (None: D = upto fails): the
    last failing grid point and the next bracket it, Brent's method solves it to XTOL on the margin
    of the path to D (POINTS points, as the check at D). Also the grid's failing intervals."""
    from scipy.optimize import brentq
    d, margin = _scan(params, structure, configuration, upto, psi)
    fails, start = [], None
    for k, bad in enumerate(margin < 0.0):
        if bad and start is None:
            start = k
        if start is not None and (not bad or k == len(margin) - 1):
            fails.append([float(d[start]), float(d[k if bad else k - 1])])
            start = None
    out = {"upto": float(upto), "grid_step": float(d[1] - d[0]), "failing_D_on_grid": fails,
           "least_passing_D": None, "tolerance": XTOL, "method": "grid bracket, then Brent's method (scipy brentq)"}
    if margin[-1] < 0.0:
        return out
    w = weight(structure)

    def m(x):
        f_d, f_half = margin_at(params, structure, configuration, x, psi)
        return f_d - f_half - RATIO * w
    k = int(np.flatnonzero(margin < 0.0)[-1]) if fails else -1
    step = float(d[1] - d[0])
    lo, hi = (float(d[k]) if k >= 0 else D_MIN), float(d[k + 1])
    for _ in range(4):   # the grid's path and the path to D differ by round-off: widen until they bracket
        if m(lo) < 0.0 <= m(hi):
            out["least_passing_D"] = float(brentq(m, lo, hi, xtol=XTOL))
            return out
        lo, hi = max(D_MIN, lo - step), min(float(upto), hi + step)
    out["least_passing_D"], out["method"] = float(d[k + 1]), "grid (no sign change of the margin found to refine)"
    return out


LAWS = {"device": "k_b u + the device's quasi-static force along the direction (nsd_core.device.quasistatic)",
        "linear": "k_b u (the supports alone)",
        "bilinear": "k_d u + Q_d z(u): the lead-rubber bearing's law (nsd_core.structure.isolator_laws)",
        "friction-pendulum": "(W/R) u + mu W z(u): the friction pendulum's law (nsd_core.structure.isolator_laws)"}


def restoring_force_check(params: Params, structure, design_displacement: float | None = None,
                          directions_deg=DIRECTIONS_DEG, device: bool = True, configuration: str | None = None) -> dict:
    """The code's restoring-force check of the configuration's isolation level (see the module
    docstring); configuration: device, linear, bilinear or friction-pendulum (default: the device, or
    without it the structure's baseline isolator or the linear supports).

    Returns {"code", "rule", "configuration", "law", "D", "D_source", "x_max", "W", "g", "required",
    "pass", "margin", "governing_direction_deg", "least_passing_D", "directions": {direction: {F_D,
    F_half_D, difference, required, margin, difference_over_W, pass, least_passing_D, scan}},
    "with_device" (the directions for the device, else None), "how"}; forces in N, lengths in m."""
    from nsd_core.structure.design import G, design, scale
    config = configuration or configuration_of(structure, device)
    if config not in CONFIGURATIONS:
        raise ParameterError(f"restoring force: configuration {config!r}; allowed {', '.join(CONFIGURATIONS)}")
    if design_displacement is None:
        d, source = default_design_displacement(), f"default: {DEFAULT_D}"
    else:
        d, source = check_design_displacement(design_displacement, params.rod_length), "given"
    x_max = None
    if config == "device":
        try:
            x_max = working_range(params, directions_deg)
        except NoDefaultError:
            pass
    stroke = float(design()["stroke_m"]) * scale()
    upto = max(d, x_max if x_max is not None else stroke)
    w = weight(structure)
    per = {}
    for psi in directions_deg:
        f_d, f_half = margin_at(params, structure, config, d, psi)
        if not (math.isfinite(f_d) and math.isfinite(f_half)):
            # a device the quasi-static path cannot follow (e.g. precompression_force = 1e8): no number
            raise FloatingPointError(f"F = {f_half!r} at D/2, {f_d!r} at D (direction {psi:g} deg)")
        e = _entry(f_d, f_half, w)
        if config == "device":
            e.update(device_F_D=f_d - structure.stiffness * d, device_F_half_D=f_half - structure.stiffness * d / 2)
        scan = least_passing(params, structure, config, upto, psi)
        per[f"{psi:g}"] = {**e, "least_passing_D": scan["least_passing_D"], "scan": scan}
    worst = min(per, key=lambda k: per[k]["margin"])
    least = [v["least_passing_D"] for v in per.values()]
    return {"code": CODE, "rule": f"F(D) - F(D/2) >= {RATIO} W", "configuration": config, "law": LAWS[config],
            "D": d, "D_source": source, "x_max": x_max, "W": w, "g": G, "required": RATIO * w,
            "pass": per[worst]["pass"], "margin": per[worst]["margin"], "governing_direction_deg": float(worst),
            "least_passing_D": None if None in least else max(least), "least_passing_D_tolerance": XTOL,
            "directions": per, "with_device": per if config == "device" else None,
            "how": f"F(u) = {LAWS[config]}, on first loading from rest to D ({POINTS} points); W = (M + floor "
                   "masses) g; each direction checked, the smallest margin governs"}


def describe(check: dict) -> str:
    """One line: the configuration, the numbers per direction and the verdict."""
    head = (f"restoring force ({check['code']}) of the {check['configuration']} isolation level at D = "
            f"{check['D'] * 1e3:.4g} mm{' (D_M)' if check['D_source'].startswith('default') else ''}, "
            f"0.025 W = {check['required']:.5g} N: ")
    parts = [f"{k} deg F(D) - F(D/2) = {e['F_D']:.5g} - {e['F_half_D']:.5g} = {e['difference']:.5g} N, margin "
             f"{e['margin']:+.4g} N: {'pass' if e['pass'] else 'FAIL'}" for k, e in check["directions"].items()]
    least = check.get("least_passing_D")
    where = "fails for every D up to the scan's end" if least is None else f"passes for D >= {least * 1e3:.4f} mm"
    return (head + "; ".join(parts) + f"; governing {check['governing_direction_deg']:g} deg: "
            f"{'PASS' if check['pass'] else 'FAIL'} (margin {check['margin']:+.4g} N; {where})")


def verdict_line(check: dict | None) -> str:
    """A short verdict for a report's first page: configuration, D, verdict and margin."""
    if not check:
        return "restoring force: not checked"
    if "skipped" in check:
        return f"restoring force: not checked ({check['skipped']})"
    e = check["directions"][f"{check['governing_direction_deg']:g}"]
    return (f"restoring force ({check['code']}), {check['configuration']} at D = {check['D'] * 1e3:.4g} mm: "
            f"{'PASS' if check['pass'] else 'FAIL'} along {check['governing_direction_deg']:g} deg, "
            f"F(D) - F(D/2) = {e['difference']:.5g} N vs 0.025 W = {check['required']:.5g} N, "
            f"margin {check['margin']:+.4g} N")


def checks_by_configuration(params: Params, structures: dict, design_displacement: float | None = None) -> dict:
    """{name: the check} for {name: (device, Structure)} (a study's configurations), each with its own law;
    a check the quasi-static path cannot follow says why ({"pass": None, "skipped"})."""
    out = {}
    for name, (device, structure) in structures.items():
        try:
            out[name] = restoring_force_check(params, structure, design_displacement, device=device)
        except (ValueError, RuntimeError, ArithmeticError) as e:
            out[name] = {"pass": None, "configuration": configuration_of(structure, device),
                         "skipped": " ".join(str(e).split())[:200]}
    return out
