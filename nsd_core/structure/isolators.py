"""The baseline isolators a designer would choose instead of the device (docs/design.md): a lead-rubber
(bilinear) bearing and a friction pendulum, sized for the same design
displacement D_D as the device system (nsd_core.structure.design). Their force law is
nsd_core.structure.isolator_laws (one implementation, every engine).

Sizing rules (full scale, then the similitude; W = M g, k_eff = M (2 pi / T_D)^2):
* bilinear: effective period T_D and effective damping beta_D at D_D (ASCE 7-16 17.8.5.2:
  k_eff = k_d + Q_d / D_D, beta_eff = 4 Q_d (D_D - D_y) / (2 pi k_eff D_D^2)), D_y = yield_fraction D_D:
  Q_d = pi beta_D k_eff D_D^2 / (2 (D_D - D_y)), k_d = k_eff - Q_d / D_D;
* friction pendulum: the same design point, T_eff = T_D and beta_eff = beta_D at D_D, with D_y its
  pre-slip: mu W = Q = pi beta_D k_eff D_D^2 / (2 (D_D - D_y)) and W / R = k_eff - Q / D_D (its two
  parameters, mu and R, fixed by the two targets; ParameterError where k_eff - Q / D_D <= 0, a
  design point no pendulum reaches).
Neither adds viscous damping (c = 0): its hysteresis is its damping.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

from nsd_core.device.params import ParameterError

KINDS = ("bilinear", "friction-pendulum")
CHOICES = ("device", "linear", *KINDS)   # --isolator: what isolates the structure


@dataclass(frozen=True)
class Isolator:
    """A baseline isolator's constants at model scale [SI]: the linear part k_d [N/m], c [N s/m], the
    hysteretic strength Q at high velocity (q_fast) and at rest (q_slow) [N], its rate parameter
    a [s/m], the yield displacement D_y [m] and the law's exponent n [-]."""
    kind: str
    stiffness: float
    damping: float
    q_fast: float
    q_slow: float
    rate: float
    yield_displacement: float
    exponent: float
    provenance: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ParameterError(f"isolator kind = {self.kind!r}: allowed {', '.join(KINDS)}")
        for name in ("stiffness", "q_fast", "yield_displacement"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ParameterError(f"isolator {name} = {v!r}: must be a finite number > 0")
        for name in ("damping", "q_slow", "rate"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ParameterError(f"isolator {name} = {v!r}: must be a finite number >= 0")
        if not (isinstance(self.exponent, (int, float)) and 2.0 <= self.exponent <= 50.0):
            raise ParameterError(f"isolator exponent = {self.exponent!r}: must be in [2, 50]")

    def block(self) -> list[float]:
        """The hysteretic law's constants in nsd_core.structure.isolator_laws' argument order."""
        return [self.q_fast, self.q_slow, self.rate, self.yield_displacement, self.exponent]

    def to_dict(self) -> dict:
        return asdict(self)


def isolator_from(value) -> Isolator | None:
    """An Isolator from itself, its dict (a stored structure's) or None."""
    if value is None or isinstance(value, Isolator):
        return value
    if isinstance(value, dict):
        return Isolator(**value)
    raise ParameterError(f"isolator = {value!r}: expected a table of the isolator's constants")


def sized(kind: str, mass: float) -> Isolator:
    """The ``kind`` isolator sized for the design displacement (the rules above) for an isolated mass
    ``mass`` [kg, model scale]."""
    from nsd_core.structure import design as ds
    if kind not in KINDS:
        raise ParameterError(f"--isolator {kind!r}: allowed {', '.join(CHOICES)}")
    s, d = ds.scale(), ds.design()
    M = mass / s ** 3                       # full scale
    T, beta, D = d["T_D_s"], d["beta_D"], d["D_D_m"]
    k_eff = M * (2.0 * math.pi / T) ** 2
    W = M * ds.G
    src = f"{ds.BASIS.name} [{kind.replace('-', '_')}]"
    if kind == "bilinear":
        f = float(ds.value("bilinear", "yield_fraction"))
        D_y = f * D
        Q = math.pi * beta * k_eff * D * D / (2.0 * (D - D_y))
        k_d = k_eff - Q / D
        n = float(ds.value("bilinear", "exponent"))
        prov = {"rule": "k_eff = M (2 pi/T_D)^2; Q_d = pi beta_D k_eff D_D^2 / (2 (D_D - D_y)); k_d = k_eff - Q_d/D_D",
                "D_y": f"yield_fraction {f:g} x D_D", "full_scale": {"Q_d_N": Q, "k_d_N_m": k_d, "D_y_m": D_y,
                                                                     "k_eff_N_m": k_eff, "D_D_m": D}}
        iso = (k_d, Q, Q, 0.0, D_y, n)
    else:
        D_y = float(ds.value("friction_pendulum", "yield_displacement"))
        Q = math.pi * beta * k_eff * D * D / (2.0 * (D - D_y))
        if not k_eff - Q / D > 0.0:
            raise ParameterError(f"friction pendulum: beta_D = {beta:g} at D_D = {D:g} m needs mu W = {Q:.4g} N >= "
                                 f"k_eff D_D = {k_eff * D:.4g} N: no pendulum radius reaches T_D")
        R, mu = W / (k_eff - Q / D), Q / W
        mu_slow = mu * float(ds.value("friction_pendulum", "mu_slow_ratio"))
        rate = float(ds.value("friction_pendulum", "rate"))
        n = float(ds.value("friction_pendulum", "exponent"))
        k_fps = W / R + mu * W / D
        beta_fps = 4.0 * mu * W * (D - D_y) / (2.0 * math.pi * k_fps * D * D)
        prov = {"rule": "T_eff = T_D, beta_eff = beta_D at D_D: mu W = pi beta_D k_eff D_D^2 / (2 (D_D - D_y)); "
                        "W / R = k_eff - mu W / D_D",
                "full_scale": {"R_m": R, "mu": mu, "mu_slow": mu_slow, "rate_s_m": rate, "W_N": W,
                               "pendulum_period_s": 2.0 * math.pi * math.sqrt(R / ds.G),
                               "T_eff_at_D_D_s": 2.0 * math.pi * math.sqrt(M / k_fps), "beta_eff_at_D_D": beta_fps}}
        iso = (W / R, mu * W, mu_slow * W, rate, D_y, n)
    k_d, q_fast, q_slow, rate, D_y, n = iso
    # similitude: stiffness x s^2, force x s^3, length x s, rate parameter [s/m] x 1/sqrt(s) (velocity x sqrt(s))
    return Isolator(kind, k_d * s ** 2, 0.0, q_fast * s ** 3, q_slow * s ** 3, rate / math.sqrt(s), D_y * s, n,
                    {"source": src, **prov})
