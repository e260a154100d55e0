"""The displacement restrainer of the seismic mode (docs/seismic.md): a moat wall or bumper.

A radial, compression-only contact between plate and base that engages when the plate's
displacement relative to the base |u| exceeds the gap u_gap < l_d. Its law is Hunt and Crossley's
(1975, J Appl Mech 42:440), one implementation in ``nsd_core.device.forces.restrainer_force_scalar``
that every engine calls:

    delta = |u| - u_gap,   F = max(k delta^n (1 + alpha delta'), 0)   while delta > 0,

acting on the plate along -u/|u| (and on the base, the opposite). Why Hunt-Crossley rather than a
linear spring-dashpot: its force is zero at first touch and at separation, so a step-size controller
sees no jump in the force, and its dashpot cannot pull the plate back at separation (a linear
dashpot does, an artefact of the law). The exponent n = 3/2 (Hertz) also makes the force's slope
continuous at touch.

Default constants (assumed, with the rule that gives them, recorded in ``provenance``):
* u_gap = GAP_FRACTION l_d = 0.8 x 30 mm = 24 mm: inside the device's working range (X_max =
  25.46 mm for the nominal device, where the ropes go slack), so the plate is held where the device
  keeps its precompression, and 6 mm short of the rod's length (room for the bumper to indent);
* n = 3/2 (Hertz);
* k: an impact of the isolated mass M at V_REF = 0.3 m/s (model scale; 0.95 m/s full scale under the
  1:10 similitude, the order of a near-field pulse's peak ground velocity) is stopped, without
  damping, within DELTA_REF = half the room, 0.5 (l_d - u_gap): M V^2 / 2 = k delta^(n+1) / (n+1);
* alpha: Hunt and Crossley's first-order relation e = 1 - (2/3) alpha v_in for a restitution
  coefficient E_REF = 0.5 at V_REF (a rubber bumper), alpha = 3 (1 - e) / (2 V_REF).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from nsd_core.device.params import ParameterError

GAP_FRACTION = 0.8   # u_gap / l_d
EXPONENT = 1.5       # Hertz
V_REF = 0.3          # m/s, model scale: design impact velocity
E_REF = 0.5          # restitution at V_REF
ROOM_FRACTION = 0.5  # DELTA_REF / (l_d - u_gap)

FIELDS = ("gap", "stiffness", "exponent", "damping")
# Upper bounds (docs/limits.md; the defaults: k ~ 8.5e8 N/m^1.5, n = 1.5, alpha = 2.5 s/m): alpha = 20 s/m
# already stops every impact faster than 5 cm/s dead (e = 1 - 2/3 alpha v); beyond n = 3 the law is no
# contact model in use. The contact's tangent stiffness n k (l_d - u_gap)^(n-1) on the isolated mass
# must ring at most at FREQUENCY_MAX (the default: 26 Hz), so that a run's steps stay bounded.
UPPER = {"stiffness": (1e13, "N/m^n"), "exponent": (3.0, "-"), "damping": (20.0, "s/m")}
FREQUENCY_MAX = 500.0  # Hz
KEYS = tuple(f"restrainer_{f}" for f in FIELDS)   # names in --structure and a case's structure table


@dataclass(frozen=True)
class Restrainer:
    """Hunt-Crossley contact constants [SI]: u_gap [m], k [N/m^n], n [-], alpha [s/m]."""
    gap: float
    stiffness: float
    exponent: float
    damping: float
    provenance: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        for name in FIELDS:
            v = getattr(self, name)
            low_ok = v >= 0 if name == "damping" else (v >= 1.0 if name == "exponent" else v > 0)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or not low_ok:
                allowed = {"damping": ">= 0 s/m", "exponent": ">= 1"}.get(name, "> 0")
                raise ParameterError(f"structure restrainer_{name} = {v!r}: must be a finite number {allowed}")
            if name in UPPER and v > UPPER[name][0]:
                raise ParameterError(f"structure restrainer_{name} = {v!r}: must be <= {UPPER[name][0]:g} "
                                     f"{UPPER[name][1]}")

    def block(self) -> np.ndarray:
        """[u_gap, k, n, alpha]: what the compiled path reads."""
        return np.array([self.gap, self.stiffness, self.exponent, self.damping], dtype=float)

    def to_dict(self) -> dict:
        return asdict(self)


def default_restrainer(params, structure) -> Restrainer:
    """The default restrainer for the rod length of ``params`` and the isolated mass of ``structure``."""
    ld = params.rod_length
    gap = GAP_FRACTION * ld
    delta_ref = ROOM_FRACTION * (ld - gap)
    k = (EXPONENT + 1.0) / 2.0 * structure.mass * V_REF ** 2 / delta_ref ** (EXPONENT + 1.0)
    alpha = 3.0 * (1.0 - E_REF) / (2.0 * V_REF)
    prov = {"gap": f"assumed: {GAP_FRACTION} l_d (inside the nominal working range X_max = 25.46 mm, "
                   f"{1 - GAP_FRACTION:.1f} l_d short of the rod's length)",
            "stiffness": f"assumed rule: an impact of M at {V_REF} m/s stops within {ROOM_FRACTION} (l_d - u_gap) "
                         f"= {delta_ref * 1e3:.4g} mm without damping: k = (n+1) M V^2 / (2 delta^(n+1))",
            "exponent": "assumed: 3/2 (Hertz); force and its slope continuous at touch",
            "damping": f"assumed rule: Hunt-Crossley e = 1 - (2/3) alpha v_in with e = {E_REF} at {V_REF} m/s",
            "law": "Hunt and Crossley (1975): F = max(k delta^n (1 + alpha delta'), 0), delta = |u| - u_gap > 0"}
    return Restrainer(gap, k, EXPONENT, alpha, prov)


def restrainer_from(value) -> Restrainer | None:
    """A Restrainer from itself, a dict (Structure.to_dict's form) or None."""
    if value is None or isinstance(value, Restrainer):
        return value
    if isinstance(value, dict):
        try:
            return Restrainer(**{k: value[k] for k in FIELDS}, provenance=dict(value.get("provenance", {})))
        except KeyError as e:
            raise ParameterError(f"structure restrainer: missing {e.args[0]!r}") from None
    raise ParameterError(f"structure restrainer = {value!r}: must be a table of {', '.join(FIELDS)}")


def with_restrainer(structure, params, on: bool, overrides: dict | None = None):
    """``structure`` with the restrainer: the default one when ``on`` or when any restrainer_* key is
    overridden, those keys (values may be strings) applied over it. ``overrides`` holds only
    restrainer_* keys. Without either, ``structure`` unchanged."""
    overrides = dict(overrides or {})
    bad = [k for k in overrides if k not in KEYS]
    if bad:
        raise ParameterError(f"structure {bad[0]}: unknown; allowed: {', '.join(KEYS)}")
    if not on and not overrides:
        return structure
    base = structure.restrainer or default_restrainer(params, structure)
    values = {f: getattr(base, f) for f in FIELDS}
    prov = dict(base.provenance)
    for key, value in overrides.items():
        name = key[len("restrainer_"):]
        try:
            values[name] = float(value)
        except (TypeError, ValueError):
            raise ParameterError(f"structure {key} = {value!r}: not a number") from None
        prov[name] = "override"
    r = Restrainer(**values, provenance=prov)
    if r.gap >= params.rod_length:
        raise ParameterError(f"structure restrainer_gap = {r.gap!r}: must be < rod_length = {params.rod_length} m")
    room = params.rod_length - r.gap
    f_c = math.sqrt(r.exponent * r.stiffness * room ** (r.exponent - 1.0) / structure.mass) / (2.0 * math.pi)
    if f_c > FREQUENCY_MAX:
        raise ParameterError(f"structure restrainer_stiffness = {r.stiffness:.4g}: the contact on the isolated mass "
                             f"would ring at up to {f_c:.4g} Hz; at most {FREQUENCY_MAX:g} Hz (a softer restrainer)")
    return structure.with_restrainer(r)


def split_overrides(overrides: dict) -> tuple[dict, dict]:
    """(the structure's own fields, the restrainer_* keys) of a --structure / case table."""
    return ({k: v for k, v in overrides.items() if k not in KEYS},
            {k: v for k, v in overrides.items() if k in KEYS})


def engagement_events(t, u, F, delta_rate, mass: float, absorbed=None, stored=None) -> list[dict]:
    """Intervals where the restrainer pushes (F > 0) on the output samples: start, end, duration,
    peak force, the radial velocity at the first engaged sample and the isolated mass's kinetic
    energy of that radial motion (the impact energy, M v^2 / 2), the energy the restrainer dissipated
    over the interval (``absorbed`` and ``stored``: the run's E_restrainer columns, when given), and
    the sampling resolution (an engagement shorter than a sample interval can be missed)."""
    on = np.asarray(F) > 0.0
    out = []
    if not on.any():
        return out
    edges = np.flatnonzero(np.diff(on.astype(int)))
    starts = list(edges[~on[edges]] + 1)
    ends = list(edges[on[edges]])
    if on[0]:
        starts = [0] + starts
    if on[-1]:
        ends = ends + [len(t) - 1]
    res = float(t[1] - t[0]) if len(t) > 1 else 0.0
    for a, b in zip(starts, ends):
        v = float(delta_rate[a])
        ev = {"kind": "restrainer_engaged", "start": float(t[a]), "end": float(t[b]), "duration": float(t[b] - t[a]),
              "u_start": float(u[a]), "u_max": float(np.max(u[a:b + 1])), "peak_force": float(np.max(F[a:b + 1])),
              "impact_velocity": v, "impact_energy": 0.5 * mass * v * v, "resolution": res}
        if absorbed is not None and stored is not None:
            after = min(b + 1, len(t) - 1)
            before = (absorbed[a - 1] - stored[a - 1]) if a else 0.0
            ev["dissipated"] = float(absorbed[after] - stored[after] - before)
        out.append(ev)
    return out
