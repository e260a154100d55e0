"""The isolated structure of the seismic mode (docs/model.md, "Seismic mode").

The plate carries a rigid mass M (polar inertia M r_g^2) in parallel with viscoelastic supports
between plate and base: horizontal stiffness k_b (the same in every direction), viscous damping
c_b, and the torsional pair k_b r_b^2, c_b r_b^2. The default structure is derived by the model
document's rules, and every number records how it was obtained:

* K_dev: the device's most negative tangent stiffness dF_device/du on its steady quasi-static cycle
  of amplitude X_max (the whole working range), along psi = 0 (the first wire) and psi = 45 deg
  (between wires and ropes; with n_w = n_r = 4 these bound the square's symmetry), ropes taut,
  computed by ``nsd_core.device.quasistatic`` (independent of any multibody engine);
* k_b: the smallest stiffness with k_b + K_dev >= 0.25 k_b, i.e. k_b = -K_dev / 0.75;
* M: the supports alone have a period of 1.0 s, M = k_b (T / 2 pi)^2;
* c_b: 5 % of critical for M and k_b, c_b = 2 zeta sqrt(k_b M);
* r_g, r_b: assumed, a 1 m x 1 m slab at model scale (10 m x 10 m at full scale under the 1:10
  similitude): r_g = 1 m / sqrt(6) ~ 0.41 m, supports at the mid-sides, r_b = 0.5 m. Neither
  enters the translational response while the plate does not turn.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from nsd_core.structure.building import Building, building_dict_from
from nsd_core.structure.isolators import Isolator, isolator_from
from nsd_core.device.params import ParameterError, Params
from nsd_core.structure.restrainer import Restrainer, restrainer_from

PERIOD = 1.0          # s, supports alone (full scale ~3.2 s under the 1:10 similitude)
DAMPING_RATIO = 0.05  # of critical
MARGIN = 0.25         # k_b + K_dev >= MARGIN k_b over the working range
SLAB_SIDE = 1.0       # m, model scale (assumed)
# Bounds of an overridden structure (--structure, a seismic case's structure): generous (orders of
# magnitude around the default, M ~ 3e3 kg, k_b ~ 1e5 N/m) but finite, so that mass = 1e308 is bad
# input rather than a solver failure at t = 1e-323 s; the supports' own frequency is bounded so a
# run's step count stays near the measured ~1400 per model second.
STRUCTURE_BOUNDS = {"mass": (1e-3, 1e7, "kg"), "radius_of_gyration": (1e-4, 100.0, "m"),
                    "stiffness": (1e-3, 1e10, "N/m"), "damping": (0.0, 1e9, "N s/m"),
                    "support_radius": (1e-4, 100.0, "m")}
SUPPORT_FREQUENCY_MAX = 100.0  # Hz, sqrt(k_b / M) / 2 pi: below the device's own 250 Hz vertical mode
DIRECTIONS_DEG = (0.0, 45.0)

# device_min_stiffness(Params()) as computed on 2026-11-23 (a 20 s computation, so the nominal device
# reuses it; tests/test_seismic.py recomputes it and checks these numbers)
NOMINAL_K_DEV = {"K_dev": -110849.38066972092, "direction_deg": 45.0, "u_at": 0.012775047391098337,
                 "per_direction": {"0.0": {"K_dev": -98719.04016078584, "u_at": 0.0045696437962488585},
                                   "45.0": {"K_dev": -110849.38066972092, "u_at": 0.012775047391098337}},
                 "recorded": "device_min_stiffness(Params()), 400 points per cycle"}


@dataclass(frozen=True)
class Structure:
    """The isolated structure on the plate [SI]."""
    mass: float                 # M [kg]
    radius_of_gyration: float   # r_g [m]
    stiffness: float            # k_b [N/m], per horizontal direction
    damping: float              # c_b [N s/m]
    support_radius: float       # r_b [m]
    provenance: dict = field(default_factory=dict, compare=False)
    restrainer: Restrainer | None = None  # the displacement restrainer (nsd_core.structure.restrainer), off by default
    building: Building | None = None      # a shear building on the slab (nsd_core.structure.building), none by default
    # the baseline isolator that replaces the supports in a run without the device (nsd_core.structure.isolators)
    isolator: Isolator | None = None

    def __post_init__(self):
        object.__setattr__(self, "restrainer", restrainer_from(self.restrainer))
        object.__setattr__(self, "isolator", isolator_from(self.isolator))
        object.__setattr__(self, "building", building_dict_from(self.building))
        for name in ("mass", "radius_of_gyration", "stiffness", "support_radius"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ParameterError(f"structure {name} = {v!r}: must be a finite number > 0")
        if not (isinstance(self.damping, (int, float)) and math.isfinite(self.damping) and self.damping >= 0):
            raise ParameterError(f"structure damping = {self.damping!r}: must be a finite number >= 0")
        for name, (low, high, unit) in STRUCTURE_BOUNDS.items():  # bounded work, finite outputs (docs/limits.md)
            v = getattr(self, name)
            if not low <= v <= high:
                raise ParameterError(f"structure {name} = {v!r}: must be in [{low:g}, {high:g}] {unit}")
        f_b = math.sqrt(self.stiffness / self.mass) / (2.0 * math.pi)
        if f_b > SUPPORT_FREQUENCY_MAX:
            raise ParameterError(f"structure stiffness / mass: the supports alone ring at {f_b:.4g} Hz; at most "
                                 f"{SUPPORT_FREQUENCY_MAX:g} Hz (a stiffer or lighter structure needs a step count "
                                 "no run here can afford)")
        if self.building is not None:
            from nsd_core.structure.building import check_dynamics
            check_dynamics(self.mass, self.stiffness, self.damping, self.building)

    def replace(self, **changes) -> "Structure":
        """A copy with some fields changed (values may be strings from the command line)."""
        names = ("mass", "radius_of_gyration", "stiffness", "damping", "support_radius")
        values = {n: getattr(self, n) for n in names}
        for name, value in changes.items():
            if name not in names:
                raise ParameterError(f"structure {name}: unknown; allowed: {', '.join(names)}")
            try:
                values[name] = float(value)
            except (TypeError, ValueError):
                raise ParameterError(f"structure {name} = {value!r}: not a number") from None
        prov = dict(self.provenance)
        prov.update({n: "override" for n in changes})
        return Structure(**values, provenance=prov, restrainer=self.restrainer, building=self.building,
                         isolator=self.isolator)

    def with_restrainer(self, restrainer: Restrainer | None) -> "Structure":
        """A copy with this restrainer (None: without one)."""
        names = ("mass", "radius_of_gyration", "stiffness", "damping", "support_radius")
        return Structure(**{n: getattr(self, n) for n in names}, provenance=dict(self.provenance),
                         restrainer=restrainer, building=self.building, isolator=self.isolator)

    def with_building(self, building: Building | None) -> "Structure":
        """A copy with this building on the slab (None: without one)."""
        names = ("mass", "radius_of_gyration", "stiffness", "damping", "support_radius")
        return Structure(**{n: getattr(self, n) for n in names}, provenance=dict(self.provenance),
                         restrainer=self.restrainer, building=building, isolator=self.isolator)

    def with_isolator(self, isolator: Isolator | None) -> "Structure":
        """A copy whose runs without the device stand on this baseline isolator (None: the supports)."""
        names = ("mass", "radius_of_gyration", "stiffness", "damping", "support_radius")
        return Structure(**{n: getattr(self, n) for n in names}, provenance=dict(self.provenance),
                         restrainer=self.restrainer, building=self.building, isolator=isolator)

    def on_isolator(self) -> "Structure":
        """The structure a run without the device integrates: with a baseline isolator, its linear part
        (k_d, c) in the supports' place (the hysteretic part acts through ``isolator``); else itself."""
        iso = self.isolator
        if iso is None:
            return self
        return Structure(self.mass, self.radius_of_gyration, iso.stiffness, iso.damping, self.support_radius,
                         {**self.provenance, "stiffness": "the isolator's k_d", "damping": "the isolator's c"},
                         restrainer=self.restrainer, building=self.building, isolator=iso)

    @property
    def polar_inertia(self) -> float:
        return self.mass * self.radius_of_gyration ** 2

    @property
    def period(self) -> float:
        """Period of the supports alone, 2 pi sqrt(M / k_b) [s]."""
        return 2.0 * math.pi * math.sqrt(self.mass / self.stiffness)

    @property
    def first_period(self) -> float:
        """The first period of the structure on the supports alone [s]: 2 pi sqrt(M / k_b) without a
        building; with one, the first mode of the chain ground - k_b - slab M - story 1 - floor 1 ...
        (nsd_core.structure.building.fixed_base_modes with the supports as a story below the slab)."""
        if self.building is None:
            return self.period
        from nsd_core.structure.building import fixed_base_modes
        omega, _ = fixed_base_modes((self.mass, *self.building.masses), (self.stiffness, *self.building.stiffnesses))
        return 2.0 * math.pi / float(omega[0])

    @property
    def damping_ratio(self) -> float:
        return self.damping / (2.0 * math.sqrt(self.stiffness * self.mass))

    def to_dict(self) -> dict:
        d = asdict(self)
        if self.building is not None:
            d["building"] = self.building.to_dict()
        if self.isolator is None:
            del d["isolator"]  # a structure without one reads (and is stored) as before
        return d


def device_min_stiffness(params: Params, directions_deg=DIRECTIONS_DEG, points_per_cycle: int = 400,
                         cycles: int = 2) -> dict:
    """Most negative tangent stiffness of the device on its steady quasi-static cycle over X_max.

    Returns {"K_dev": N/m, "direction_deg", "u_at": m, "x_max": m, "per_direction": {...}}. The
    stiffness is the chord dF/du between consecutive points of the cycle u = X_max sin(2 pi s)
    (``points_per_cycle`` per cycle: 400 changes K_dev by 0.03 % against 1600), ropes taut at both
    ends; the last of ``cycles`` cycles is the steady one.
    """
    from nsd_core.device.quasistatic import quasi_static_path
    from nsd_core.device.working_range import x_max_at_slack
    per = {}
    for psi in directions_deg:
        amp = 0.999 * x_max_at_slack(params, psi)  # just inside: the ropes stay taut at the peaks
        s = np.linspace(0.0, cycles, cycles * points_per_cycle + 1)
        u = amp * np.sin(2.0 * np.pi * s)
        out = quasi_static_path(params, u, psi, substeps=4)
        du, dF = np.diff(u), np.diff(out["F_device"])
        taut = out["rope_stretch"] > 0.0
        ok = taut[1:] & taut[:-1] & (np.abs(du) > 1e-12 * amp) & (s[1:] > cycles - 1)
        k = np.where(ok, dF / np.where(ok, du, 1.0), np.inf)
        i = int(np.argmin(k))
        per[psi] = {"K_dev": float(k[i]), "u_at": float(0.5 * (u[i] + u[i + 1])), "amplitude": float(amp),
                    "cycle_phase": float(s[i] - (cycles - 1))}
    worst = min(per, key=lambda d: per[d]["K_dev"])
    return {"K_dev": per[worst]["K_dev"], "direction_deg": worst, "u_at": per[worst]["u_at"],
            "per_direction": {str(d): v for d, v in per.items()}}


NO_DEFAULT = ("{changed}: the default isolated structure cannot be sized for this device ({why}); give the structure "
              "yourself: --structure mass=VALUE --structure stiffness=VALUE (damping defaults to 5 % of critical)")


def _min_stiffness_or_input_error(params: Params) -> dict:
    """device_min_stiffness, or ParameterError (one line) where the device has no working range
    (no slack point within the rod's reach, a spring that never lets go): the rule needs one."""
    from nsd_core.device.working_range import SlackPointError
    changed = ", ".join(f"{r['name']} = {r['value']!r}" for r in params.describe() if r["source"] == "override")
    try:
        with np.errstate(all="ignore"):  # a device the quasi-static path cannot follow: said below, not warned
            k = device_min_stiffness(params)
    except SlackPointError as e:
        raise ParameterError(NO_DEFAULT.format(changed=changed or "the device", why=e)) from None
    if not math.isfinite(k["K_dev"]):
        raise ParameterError(NO_DEFAULT.format(changed=changed or "the device", why=f"K_dev = {k['K_dev']}: the "
                                               "quasi-static cycle over X_max has no finite stiffness"))
    return k


def structure_without_default(own: dict) -> "Structure":
    """A structure from --structure values alone (mass and stiffness given) for a device whose default
    cannot be sized: damping 5 % of critical unless given, r_g and r_b of the default slab."""
    values = {"radius_of_gyration": SLAB_SIDE / math.sqrt(6.0), "support_radius": SLAB_SIDE / 2.0}
    for name, value in own.items():
        try:
            values[name] = float(value)
        except (TypeError, ValueError):
            raise ParameterError(f"structure {name} = {value!r}: not a number") from None
    m, k = values["mass"], values["stiffness"]
    if "damping" not in values and m > 0 and k > 0:
        values["damping"] = 2.0 * DAMPING_RATIO * math.sqrt(k * m)
    prov = {n: "override" for n in own}
    prov.update({n: "assumed: no default for this device" for n in values if n not in own})
    return Structure(**{n: values.get(n, 0.0) for n in ("mass", "radius_of_gyration", "stiffness", "damping",
                                                        "support_radius")}, provenance=prov)


def structure_with(params: Params, own: dict) -> "Structure":
    """The default structure of ``params`` with the overrides ``own`` (mass, stiffness, ...; strings
    allowed); for a device whose default cannot be sized, the structure ``own`` gives when it holds mass
    and stiffness (else the one-line ParameterError that says to give them)."""
    try:
        structure = default_structure(params)
    except ParameterError:
        if not {"mass", "stiffness"} <= set(own):
            raise
        structure = structure_without_default(own)
    return structure.replace(**own) if own else structure


def default_structure(params: Params | None = None, k_dev: dict | None = None) -> Structure:
    """The default isolated structure by the model document's rules (k_dev: a precomputed
    ``device_min_stiffness`` result; the nominal device uses the recorded NOMINAL_K_DEV)."""
    params = params or Params()
    k_dev = k_dev or (NOMINAL_K_DEV if params == Params() else _min_stiffness_or_input_error(params))
    K = k_dev["K_dev"]
    if K >= 0:
        raise ParameterError(f"K_dev = {K:.4g} N/m: the device shows no negative stiffness; "
                             f"the rule k_b = -K_dev/(1 - {MARGIN}) needs one")
    k_b = -K / (1.0 - MARGIN)
    M = k_b * (PERIOD / (2.0 * math.pi)) ** 2
    c_b = 2.0 * DAMPING_RATIO * math.sqrt(k_b * M)
    r_g = SLAB_SIDE / math.sqrt(6.0)
    r_b = SLAB_SIDE / 2.0
    prov = {
        "K_dev": {"value": K, "unit": "N/m", "how": "most negative chord dF_device/du on the steady "
                  "quasi-static cycle of amplitude 0.999 X_max, ropes taut (nsd_core.device.quasistatic)",
                  **k_dev},
        "stiffness": f"assumed rule (docs/model.md): smallest k_b with k_b + K_dev >= {MARGIN} k_b -> -K_dev/{1 - MARGIN}",
        "mass": f"assumed rule (docs/model.md): period of the supports alone {PERIOD} s -> k_b (T/2pi)^2",
        "damping": f"assumed rule (docs/model.md): {DAMPING_RATIO:.0%} of critical for M and k_b",
        "radius_of_gyration": f"assumed: uniform {SLAB_SIDE} m square slab, side/sqrt(6)",
        "support_radius": f"assumed: supports at the mid-sides of the {SLAB_SIDE} m slab, side/2",
        "params": "nominal device (Params defaults)" if params == Params() else "overridden device",
    }
    return Structure(M, r_g, k_b, c_b, r_b, prov)


def designed_structure(design_level: bool = False) -> Structure:
    """The isolated structure of the design basis at model scale (nsd_core.structure.design): the same for
    every device. design_level: the isolation level's damping is the design's supplemental damping."""
    from nsd_core.structure.design import designed_structure_args
    return Structure(*designed_structure_args(design_level))


def designed_structure_with(params: Params, own: dict, resize: bool = False, design_level: bool = False) -> Structure:
    """The structure of the design basis (nsd_core.structure.design: the same for every device) with the
    overrides ``own``; resize: derived from the device instead (``structure_with``, the model
    document's rule), as before the design basis (docs/design.md)."""
    if resize:
        return structure_with(params, own)
    structure = designed_structure(design_level)
    return structure.replace(**own) if own else structure
