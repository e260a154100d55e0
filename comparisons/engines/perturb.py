"""Deliberate modelling errors injected into ONE engine's own model (the gate's detection power).

An engine that accepts the setting ``perturb`` builds its model from
``perturbed(device_geometry(params), settings["perturb"])`` instead of the shared geometry, so the
error lives in that engine's bodies, attachment points, elements or rest state only; the reference
engine and the shared force laws are untouched. A perturbation is a small dict:

    {"what": "cap_mass", "by": 0.01}                           relative: mass x (1 + by)
    {"what": "wire_wall_point", "index": 0, "axis": "z", "by": 2e-4}   absolute: point moved [m]
    {"what": "gravity", "by": -1.0}                            relative: -1 switches gravity off
    {"what": "rod_length", "by": 2e-4}                         absolute [m]: the model rebuilt with it
    {"what": "rest_ignores_weight"}                            ropes' natural length from F_press, not F_press - W
    {"what": "isolated_mass", "by": 0.02}                      seismic mode: M x (1 + by) (perturbed_structure)

Relative kinds change a value as it stands in the engine's model (a typo in its MJCF, say): the
rest state is not recomputed, so a constant off by 1 % also leaves the rest state slightly out of
balance, as such a typo would.
"""
from __future__ import annotations

import copy
import dataclasses

import numpy as np

from nsd_core.device.geometry import DeviceGeometry, RigidBody, device_geometry
from nsd_core.device.params import ParameterError

BODIES = ("cap", "wall", "rod")
POINTS = ("rope_base_points", "rope_cap_points", "wire_cap_points", "wire_wall_points")
SPRING = ("kse", "ksd", "beta", "gamma")
KINDS = {  # what -> (unit of "by", description)
    **{f"{b}_mass": ("-", f"{b} mass (and inertia) x (1 + by)") for b in BODIES},
    **{p[:-1]: ("m", f"one {p[:-7].replace('_', ' ')} point moved by 'by' along 'axis'") for p in POINTS},
    "gravity": ("-", "gravity x (1 + by); by = -1: off"),
    "rod_length": ("m", "rod length + by, model rebuilt consistently"),
    "rope_stiffness": ("-", "stiffness of rope 'index' x (1 + by)"),
    **{f"spring_{k}": ("-", f"spring's {k} x (1 + by)") for k in SPRING},
    "wire_area": ("-", "every wire's area x (1 + by)"),
    "spring_zeta0": ("-", "the spring's hysteretic force at rest x (1 + by)"),
    "rest_ignores_weight": ("-", "ropes' natural length set for F_press instead of F_press - W"),
    "isolated_mass": ("-", "seismic mode: the isolated mass M (and its polar inertia) x (1 + by)"),
}
AXES = {"x": 0, "y": 1, "z": 2}
# Bounds of "by": an injected error is a modelling slip, not another device; beyond these a run fails
# or overflows instead of showing the gate's response (the power study's ladder tops at 100x its
# listed sizes: 1.0 relative, 0.02 m)
MAX_FACTOR = 101.0   # a relative change multiplies by 1 + by <= MAX_FACTOR
MAX_SHIFT = 0.05     # m, a moved point or a longer/shorter rod


def describe(spec: dict) -> str:
    """A short label, e.g. 'cap_mass +1%' or 'wire_wall_point[0] z +0.2 mm'."""
    what, by = spec["what"], spec.get("by", 0.0)
    unit = KINDS[what][0]
    if what == "rest_ignores_weight":
        return what
    amount = f"{by * 1e3:+g} mm" if unit == "m" else ("off" if what == "gravity" and by == -1 else f"{by * 100:+g}%")
    idx = f"[{spec.get('index', 0)}]" if what in ("rope_stiffness",) or what + "s" in POINTS else ""
    axis = f" {spec.get('axis', 'z')}" if what + "s" in POINTS else ""
    return f"{what}{idx}{axis} {amount}"


def check(spec) -> dict | None:
    """Validate a perturbation (None: none); one-line ParameterError naming the field otherwise."""
    if spec is None:
        return None
    if not isinstance(spec, dict):
        raise ParameterError(f"perturb = {spec!r}: must be a table, e.g. {{ what = \"cap_mass\", by = 0.01 }} "
                             f"(what: {', '.join(KINDS)})")
    if spec.get("what") not in KINDS:
        raise ParameterError(f"perturb.what = {spec.get('what')!r}: unknown; allowed: {', '.join(KINDS)}")
    bad = set(spec) - {"what", "by", "index", "axis"}
    if bad:
        raise ParameterError(f"perturb.{sorted(bad)[0]}: unknown key; allowed: what, by, index, axis")
    by = spec.get("by", 0.0)
    if isinstance(by, bool) or not isinstance(by, (int, float)) or not np.isfinite(by):
        raise ParameterError(f"perturb.by = {by!r}: must be a finite number")
    if KINDS[spec["what"]][0] == "m":
        if not abs(by) <= MAX_SHIFT:
            raise ParameterError(f"perturb.by = {by!r}: a length in m, allowed -{MAX_SHIFT} .. {MAX_SHIFT}")
    elif not (-1.0 <= by if spec["what"] == "gravity" else -1.0 < by) or not by <= MAX_FACTOR - 1.0:
        low = "-1 (off)" if spec["what"] == "gravity" else "above -1 (a factor 1 + by > 0)"
        raise ParameterError(f"perturb.by = {by!r}: a relative change, allowed {low} .. {MAX_FACTOR - 1.0:g}")
    index = spec.get("index", 0)
    if isinstance(index, bool) or not isinstance(index, int) or index < 0:
        raise ParameterError(f"perturb.index = {index!r}: must be a whole number >= 0")
    if spec.get("axis", "z") not in AXES:
        raise ParameterError(f"perturb.axis = {spec.get('axis')!r}: allowed x, y, z")
    return dict(spec)


def _scaled_body(b: RigidBody, factor: float) -> RigidBody:
    return dataclasses.replace(b, mass=b.mass * factor, inertia=b.inertia * factor)


def perturbed_structure(structure, spec: dict | None):
    """The isolated structure with an ``isolated_mass`` error (any other kind: unchanged)."""
    spec = check(spec)
    if spec is None or spec["what"] != "isolated_mass":
        return structure
    return dataclasses.replace(structure, mass=structure.mass * (1.0 + float(spec.get("by", 0.0))))


def perturbed(g: DeviceGeometry, spec: dict | None, seismic: bool = False) -> DeviceGeometry:
    """The geometry with one modelling error injected (``spec`` as in the module docstring)."""
    spec = check(spec)
    if spec is None:
        return g
    what, by, i = spec["what"], float(spec.get("by", 0.0)), int(spec.get("index", 0))
    if what == "isolated_mass":   # not part of the device: perturbed_structure
        if seismic:
            return g
        raise ParameterError("perturb.what = 'isolated_mass': applies to seismic cases only")
    if what.endswith("_mass"):
        body = what[:-5]
        return dataclasses.replace(g, **{body: _scaled_body(getattr(g, body), 1.0 + by)})
    if what + "s" in POINTS:
        pts = np.array(getattr(g, what + "s"), dtype=float)
        if not 0 <= i < len(pts):
            raise ParameterError(f"perturb.index = {i}: allowed 0 .. {len(pts) - 1}")
        pts[i, AXES[spec.get("axis", "z")]] += by
        return dataclasses.replace(g, **{what + "s": pts})
    if what == "gravity":   # Params rejects g <= 0 as input; an injected error may switch it off
        p = copy.copy(g.params)
        object.__setattr__(p, "gravity", g.params.gravity * (1.0 + by))
        return dataclasses.replace(g, params=p)
    if what == "rod_length":
        return device_geometry(g.params.replace(rod_length=g.params.rod_length + by))
    if what == "rope_stiffness":
        k = np.full(g.n_ropes, float(g.rope_stiffness))
        if not 0 <= i < g.n_ropes:
            raise ParameterError(f"perturb.index = {i}: allowed 0 .. {g.n_ropes - 1}")
        k[i] *= 1.0 + by
        return dataclasses.replace(g, rope_stiffness=k)
    if what.startswith("spring_") and what[7:] in SPRING:
        key = what[7:]
        return dataclasses.replace(g, spring=g.spring._replace(**{key: getattr(g.spring, key) * (1.0 + by)}))
    if what == "wire_area":
        return dataclasses.replace(g, wire=g.wire._replace(area=g.wire.area * (1.0 + by)))
    if what == "spring_zeta0":
        return dataclasses.replace(g, spring_zeta0=g.spring_zeta0 * (1.0 + by))
    # rest_ignores_weight: the ropes pre-stretched for the whole F_press, the weight forgotten
    p = g.params
    rest = np.linalg.norm(g.rope_cap_points + [0.0, 0.0, g.cap_rest_z] - g.rope_base_points, axis=1)
    cos_v = (g.rope_cap_points[:, 2] + g.cap_rest_z - g.rope_base_points[:, 2]) / rest
    tension = p.precompression_force / (p.n_ropes * cos_v)
    return dataclasses.replace(g, rope_natural_length=rest - tension / g.rope_stiffness)
