"""A shear building above the isolation level (docs/building.md; the paper's "future work").

The isolated mass M of the seismic mode is the slab, level 0. Above it N stories (i = 1..N): floor i
is a rigid mass m_i translating in X and Y; story i joins floor i to floor i-1 with lateral stiffness
k_i and viscous damping c_i, the same in X and Y. With d_i the displacement relative to the ground,
per direction and ground acceleration a_g:

    m_i (d_i'' + a_g) = -S_i + S_{i+1} - b_i (d_i' - d_0'),     S_{N+1} = 0,
    S_i = k_i (d_i - d_{i-1}) + c_i (d_i' - d_{i-1}'),

and the slab carries +S_1 + sum_i b_i (d_i' - d_0') besides its supports, device and restrainer.

Damping: either per-story c_i (b_i = 0: the story law above exactly), or Rayleigh, a ratio zeta on the
first two modes of the fixed-base building (slab held to the ground): C_s = a_0 M_s + a_1 K_s acting
on the floors' displacements relative to the slab (the superstructure's damping matrix moves with the
slab, as in Naeim and Kelly 1999, Ch. 2). Its stiffness part is the story dampers c_i = a_1 k_i, its mass
part dampers b_i = a_0 m_i between floor i and the slab. With N = 1 there is one mode: c_1 = 2 zeta
omega_1 m_1, b_1 = 0.

Default building (assumed, every number's source in ``provenance`` and docs/building.md): three
stories; each floor m_i = M / N (the superstructure weighs as much as the slab); story heights
0.3 m (3 m full scale under the 1:10 Froude similitude); uniform story stiffness giving a fixed-base
first period of 0.1 N s full scale (the rule of thumb T = 0.1 N for low-rise frames), 0.3 s for three
stories, times sqrt(0.1) at model scale; zeta = 5 % Rayleigh.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from nsd_core.device.params import ParameterError

SIMILITUDE_LENGTH = 0.1                      # model / full scale (Froude 1:10)
SIMILITUDE_TIME = math.sqrt(SIMILITUDE_LENGTH)
STORY_HEIGHT_FULL = 3.0                      # m, full scale (assumed: a typical story)
PERIOD_PER_STORY_FULL = 0.1                  # s per story, full scale: T_1 = 0.1 N (rule of thumb)
DAMPING_RATIO = 0.05                         # Rayleigh, on the first two fixed-base modes
STORIES = 3
MAX_STORIES = 50
KEYS = ("stories", "mass", "stiffness", "height", "damping_ratio", "damping", "period")
# Bounds (docs/limits.md): each value, and the dynamics they make with the slab on its supports (the
# chain ground - k_b - slab - story 1 - floor 1 ...): its highest mode and its damping's fastest rate
# bound the steps a run takes (an explicit step resolves ~3 rad of the highest mode and ~6 of decay:
# 500 Hz and 1e4 1/s stay near the measured ~1400 steps per model second). The defaults: 40-45 Hz,
# rates 27-411 1/s from 1 to 50 stories.
BOUNDS = {"mass": (1e-3, 1e7, "kg"), "stiffness": (1e-3, 1e10, "N/m"), "damping": (0.0, 1e9, "N s/m"),
          "height": (1e-3, 100.0, "m"), "period": (1e-3, 100.0, "s")}
FREQUENCY_MAX = 500.0   # Hz, the highest mode of the building on the supports
RATE_MAX = 1e4          # 1/s, the largest eigenvalue of M^-1/2 C M^-1/2 of that chain


@dataclass(frozen=True)
class Building:
    """A shear building [SI], one entry per story i = 1..N (floor i sits on story i)."""
    masses: tuple            # m_i [kg]
    stiffnesses: tuple       # k_i [N/m], per direction
    heights: tuple           # h_i [m], story heights
    story_damping: tuple     # c_i [N s/m], story dampers
    slab_damping: tuple      # b_i [N s/m], dampers floor i - slab (Rayleigh's mass part)
    damping_ratio: float | None = None   # zeta (Rayleigh) or None (per-story c_i given)
    rayleigh: tuple | None = None        # (a_0 [1/s], a_1 [s]) or None
    provenance: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        n = len(self.masses)
        for name in ("masses", "stiffnesses", "heights", "story_damping", "slab_damping"):
            values = getattr(self, name)
            if len(values) != n:
                raise ParameterError(f"building {name}: {len(values)} values for {n} stories")

    @property
    def stories(self) -> int:
        return len(self.masses)

    @property
    def total_mass(self) -> float:
        return float(sum(self.masses))

    def to_dict(self) -> dict:
        d = asdict(self)
        d["stories"] = self.stories
        d["fixed_base_periods"] = [float(v) for v in fixed_base_periods(self)]
        return d


def stiffness_matrix(k) -> np.ndarray:
    """The fixed-base shear building's K (N x N): story i between floors i-1 and i, floor 0 the ground."""
    k = np.asarray(k, float)
    n = len(k)
    K = np.zeros((n, n))
    for i in range(n):
        K[i, i] += k[i]
        if i > 0:
            K[i - 1, i - 1] += k[i]
            K[i - 1, i] -= k[i]
            K[i, i - 1] -= k[i]
    return K


def damping_matrix(b: Building) -> np.ndarray:
    """The fixed-base C_s: story dampers c_i (like K) plus the floor-slab dampers b_i (diagonal)."""
    return stiffness_matrix(b.story_damping) + np.diag(np.asarray(b.slab_damping, float))


def fixed_base_modes(masses, stiffnesses) -> tuple[np.ndarray, np.ndarray]:
    """(omega [rad/s] ascending, mass-normalised mode shapes as columns) of the fixed-base building."""
    m = np.asarray(masses, float)
    K = stiffness_matrix(stiffnesses)
    s = 1.0 / np.sqrt(m)
    lam, v = np.linalg.eigh(K * s[:, None] * s[None, :])
    return np.sqrt(lam), v * s[:, None]


def fixed_base_periods(b: Building) -> np.ndarray:
    return 2.0 * math.pi / fixed_base_modes(b.masses, b.stiffnesses)[0]


def rayleigh(masses, stiffnesses, zeta: float) -> tuple[float, float, list, list]:
    """(a_0, a_1, c_i, b_i): zeta on the first two fixed-base modes, C = a_0 M + a_1 K."""
    w = fixed_base_modes(masses, stiffnesses)[0]
    if len(w) == 1:
        c1 = 2.0 * zeta * w[0] * masses[0]
        return 0.0, c1 / stiffnesses[0], [c1], [0.0]
    w1, w2 = w[0], w[1]
    a0 = 2.0 * zeta * w1 * w2 / (w1 + w2)
    a1 = 2.0 * zeta / (w1 + w2)
    return a0, a1, [a1 * k for k in stiffnesses], [a0 * m for m in masses]


def _number(name, value, low_ok, allowed):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"building {name} = {value!r}: not a number ({allowed})") from None
    if isinstance(value, bool) or not math.isfinite(v) or not low_ok(v):
        raise ParameterError(f"building {name} = {value!r}: must be a finite number {allowed}")
    if name in BOUNDS:
        lo, hi, unit = BOUNDS[name]
        if not lo <= v <= hi:
            raise ParameterError(f"building {name} = {value!r}: must be in [{lo:g}, {hi:g}] {unit}")
    return v


def check_dynamics(slab_mass: float, k_b: float, c_b: float, b: "Building") -> None:
    """The building on the slab on its supports: highest mode <= FREQUENCY_MAX, damping's fastest rate
    <= RATE_MAX (ParameterError, one line, otherwise)."""
    m = np.array((slab_mass, *b.masses), float)
    for name, values in (("stiffness", b.stiffnesses), ("damping", b.story_damping)):
        lo, hi, unit = BOUNDS[name]
        bad = [v for v in values if not lo <= v <= hi]
        if bad:
            raise ParameterError(f"building {name} (derived) = {float(bad[0]):.4g}: must be in [{lo:g}, {hi:g}] {unit} "
                                 f"(another period, mass or damping_ratio)")
    w = fixed_base_modes(m, (k_b, *b.stiffnesses))[0]
    f_max = float(w[-1]) / (2.0 * math.pi)
    if f_max > FREQUENCY_MAX:
        raise ParameterError(f"building stiffness / mass: the floors on the supports ring at up to {f_max:.4g} Hz; "
                             f"at most {FREQUENCY_MAX:g} Hz (softer stories, heavier floors or a longer period)")
    C = stiffness_matrix((c_b, *b.story_damping)) + np.diag((0.0, *b.slab_damping))
    s = 1.0 / np.sqrt(m)
    rate = float(np.linalg.eigvalsh(C * s[:, None] * s[None, :])[-1])
    if rate > RATE_MAX:
        raise ParameterError(f"building damping: its fastest decay rate is {rate:.4g} 1/s; at most {RATE_MAX:g} 1/s "
                             "(less damping, a smaller damping_ratio or heavier floors)")


def _per_story(name, value, n, low_ok, allowed) -> list[float]:
    """One number for every story, or a list of n (a comma-separated string or a TOML array)."""
    if isinstance(value, str):
        parts = [p.strip() for p in value.split(",")] if "," in value else [value.strip()]
    elif isinstance(value, (list, tuple)):
        parts = list(value)
    else:
        parts = [value]
    if len(parts) == 1:
        parts = parts * n
    if len(parts) != n:
        raise ParameterError(f"building {name} = {value!r}: {len(parts)} values for stories = {n} "
                             f"(give one value or {n})")
    return [_number(name, p, low_ok, allowed) for p in parts]


def _stories(value) -> int:
    try:
        n = int(str(value).strip()) if not isinstance(value, bool) else None
    except ValueError:
        n = None
    if n is None or str(value).strip() != str(n) or not 1 <= n <= MAX_STORIES:
        raise ParameterError(f"building stories = {value!r}: must be a whole number in 1..{MAX_STORIES}")
    return n


def building_from(slab_mass: float, overrides: dict) -> Building:
    """The default building (module docstring) with ``overrides`` (names in KEYS; values numbers,
    strings from the command line, comma lists or TOML arrays for per-story values). ParameterError,
    one line naming the field, on anything wrong."""
    bad = [k for k in overrides if k not in KEYS]
    if bad:
        raise ParameterError(f"building {bad[0]}: unknown; allowed: {', '.join(KEYS)}")
    n = _stories(overrides.get("stories", STORIES))
    pos, nonneg = (lambda v: v > 0), (lambda v: v >= 0)
    prov = {"stories": "override" if "stories" in overrides else f"assumed: {STORIES} stories"}
    if "mass" in overrides:
        masses, prov["masses"] = _per_story("mass", overrides["mass"], n, pos, "> 0 (kg)"), "override"
    else:
        masses = [slab_mass / n] * n
        prov["masses"] = ("assumed: m_i = M / N, the superstructure as heavy as the slab (mass ratio "
                          "m_s / (m_s + m_slab) = 0.5, within the 0.5-0.9 of Kelly's two-mass isolation model)")
    if "height" in overrides:
        heights, prov["heights"] = _per_story("height", overrides["height"], n, pos, "> 0 (m)"), "override"
    else:
        heights = [STORY_HEIGHT_FULL * SIMILITUDE_LENGTH] * n
        prov["heights"] = f"assumed: {STORY_HEIGHT_FULL} m full scale x {SIMILITUDE_LENGTH} (Froude 1:10)"
    if "stiffness" in overrides:
        if "period" in overrides:
            raise ParameterError("building period: give stiffness or period, not both")
        stiff = _per_story("stiffness", overrides["stiffness"], n, pos, "> 0 (N/m)")
        prov["stiffnesses"] = "override"
    else:
        if "period" in overrides:
            T = _number("period", overrides["period"], pos, "> 0 (s)")
            prov["stiffnesses"] = f"uniform, fixed-base first period {T} s (override)"
        else:
            T = PERIOD_PER_STORY_FULL * n * SIMILITUDE_TIME
            prov["stiffnesses"] = (f"assumed: uniform, fixed-base first period T_1 = {PERIOD_PER_STORY_FULL} N s "
                                   f"full scale (rule of thumb for low-rise frames) x sqrt({SIMILITUDE_LENGTH}) "
                                   f"= {T!r} s")
        w1 = fixed_base_modes(masses, [1.0] * n)[0][0]  # omega_1 for unit stiffness; omega ~ sqrt(k)
        stiff = [(2.0 * math.pi / T / w1) ** 2] * n
    if "damping" in overrides:
        if "damping_ratio" in overrides:
            raise ParameterError("building damping_ratio: give damping (per story) or damping_ratio, not both")
        c = _per_story("damping", overrides["damping"], n, nonneg, ">= 0 (N s/m)")
        prov["damping"] = "override: per-story c_i"
        return Building(tuple(masses), tuple(stiff), tuple(heights), tuple(c), (0.0,) * n, None, None, prov)
    zeta = _number("damping_ratio", overrides.get("damping_ratio", DAMPING_RATIO), lambda v: 0 <= v < 1, "in [0, 1)")
    a0, a1, c, b = rayleigh(masses, stiff, zeta)
    prov["damping"] = ("override" if "damping_ratio" in overrides else "assumed") + \
        f": Rayleigh, zeta = {zeta} on the first two fixed-base modes (C = a_0 M + a_1 K relative to the slab)"
    return Building(tuple(masses), tuple(stiff), tuple(heights), tuple(c), tuple(b), zeta, (a0, a1), prov)


def building_dict_from(data: dict | None) -> "Building | None":
    """A Building from its to_dict() (summary.json, a worker's task), or None."""
    if data is None or isinstance(data, Building):
        return data
    return Building(tuple(data["masses"]), tuple(data["stiffnesses"]), tuple(data["heights"]),
                    tuple(data["story_damping"]), tuple(data["slab_damping"]), data.get("damping_ratio"),
                    None if data.get("rayleigh") is None else tuple(data["rayleigh"]), dict(data.get("provenance", {})))


def building_forces(b: Building, d, v, d0, v0):
    """Forces of the building on its floors and on the slab, per direction (arrays broadcast over
    a trailing axis): d, v (N, ...) floors' displacement and velocity, d0, v0 the slab's.
    Returns (f (N, ...) on the floors, f_slab on the slab, S (N, ...) story element forces
    k_i drift_i + c_i drift_i', drift (N, ...))."""
    d, v = np.asarray(d, float), np.asarray(v, float)
    k = np.asarray(b.stiffnesses, float).reshape((-1,) + (1,) * (d.ndim - 1))
    c = np.asarray(b.story_damping, float).reshape(k.shape)
    bb = np.asarray(b.slab_damping, float).reshape(k.shape)
    below = np.concatenate([np.asarray(d0, float)[None], d[:-1]])
    below_v = np.concatenate([np.asarray(v0, float)[None], v[:-1]])
    drift, drift_v = d - below, v - below_v
    S = k * drift + c * drift_v
    to_slab = bb * (v - np.asarray(v0, float)[None])
    above = np.concatenate([S[1:], np.zeros_like(S[:1])])
    f = -S + above - to_slab
    return f, S[0] + to_slab.sum(0), S, drift


def building_columns(b: Building, d, v, d0, v0) -> dict:
    """The building's output columns from the floors' and slab's motion relative to the ground:
    d, v (N, 2, samples), d0, v0 (2, samples). Floor accelerations are the floors'
    force balance, a_abs = f / m_i (the exact acceleration of the sampled state). Story shears: the
    force the floors above story i take from below it, -sum_{j>=i} m_j a_abs_j (its elements plus
    the floor-slab dampers of the floors above)."""
    f, _, _, drift = building_forces(b, d, v, d0, v0)
    m = np.asarray(b.masses, float)[:, None, None]
    return floor_columns(b, d, f / m, drift, v, v0)


def floor_columns(b: Building, d, a_abs, drift, v, v0) -> dict:
    """Columns from the floors' displacement, absolute acceleration and drift (N, 2, samples); the
    stored energy and the story shears follow from them (every engine writes them this way)."""
    cols = {}
    m = np.asarray(b.masses, float)[:, None, None]
    shear = np.cumsum((m * a_abs)[::-1], axis=0)[::-1] * -1.0
    for i in range(b.stories):
        j = i + 1
        cols[f"floor{j}_x"], cols[f"floor{j}_y"] = d[i, 0], d[i, 1]
        cols[f"floor{j}_vx"], cols[f"floor{j}_vy"] = v[i, 0], v[i, 1]
        cols[f"floor{j}_ax_abs"], cols[f"floor{j}_ay_abs"] = a_abs[i, 0], a_abs[i, 1]
        cols[f"drift{j}_x"], cols[f"drift{j}_y"] = drift[i, 0], drift[i, 1]
        cols[f"story_shear{j}_x"], cols[f"story_shear{j}_y"] = shear[i, 0], shear[i, 1]
    k = np.asarray(b.stiffnesses, float)[:, None, None]
    cols["E_building_stored"] = 0.5 * np.sum(k * drift * drift, axis=(0, 1))
    return cols


def building_dissipation_rate(b: Building, v, v0) -> float:
    """sum c_i (drift_i')^2 + b_i (d_i' - d_0')^2 over both directions (v (N, 2), v0 (2,))."""
    v, v0 = np.asarray(v, float), np.asarray(v0, float)
    below = np.vstack([v0[None], v[:-1]])
    dv = v - below
    rel = v - v0[None]
    return float(np.asarray(b.story_damping) @ np.sum(dv * dv, axis=1)
                 + np.asarray(b.slab_damping) @ np.sum(rel * rel, axis=1))


def building_summary(b: Building, cols: dict) -> dict:
    """Peak drift ratio per story (|drift| / h_i, the vector's length in plan), peak floor acceleration
    per floor, peak story shear, each with its time."""
    t = cols["t"]

    def peak(values):
        k = int(np.argmax(values))
        return {"value": float(values[k]), "t": float(t[k])}

    out = {"parameters": b.to_dict(), "peak_drift_ratio": [], "peak_drift": [], "peak_floor_acceleration": [],
           "peak_story_shear": [], "peak_floor_displacement": []}
    for i in range(b.stories):
        j = i + 1
        drift = np.hypot(cols[f"drift{j}_x"], cols[f"drift{j}_y"])
        out["peak_drift"].append(peak(drift))
        out["peak_drift_ratio"].append(peak(drift / b.heights[i]))
        out["peak_floor_acceleration"].append(peak(np.hypot(cols[f"floor{j}_ax_abs"], cols[f"floor{j}_ay_abs"])))
        out["peak_story_shear"].append(peak(np.hypot(cols[f"story_shear{j}_x"], cols[f"story_shear{j}_y"])))
        out["peak_floor_displacement"].append(peak(np.hypot(cols[f"floor{j}_x"], cols[f"floor{j}_y"])))
    return out
