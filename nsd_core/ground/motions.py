"""Ground motion for the seismic mode (docs/model.md, "Seismic mode").

Every ground motion is a horizontal pair: ``motion(t)`` returns the ground displacement, velocity
and acceleration, each of shape (2,) (X, Y) for a scalar t, or (len(t), 2) for an array.

- a record (``nsd_core.ground.records.fema_record``): the FEMA P695 far-field and near-field sets,
  through the PiecewiseLinear components of this module.
- ``Harmonic``: a_g = A sin(2 pi f t) along an azimuth, from rest (closed forms for d, v).
- ``Pulse``: the Mavroeidis & Papageorgiou (2003) near-fault velocity pulse along an azimuth.

A record's acceleration is linear between samples, so its velocity and displacement are integrated
exactly (quadratic and cubic per interval). Baseline: none is applied. The motion starts from rest,
d = v = 0 at the window's start; the relative response of a structure that starts at rest relative
to its base depends on a_g alone, so the constants never matter for it. The PEER-processed records
end with |v| <= 0.016 m/s and |d| <= 1 mm (full scale), except near-field 8 (Chi-Chi TCU068),
whose ground really steps by 1.36 m (fling). Past a component's last sample the acceleration ramps
to zero over one sample interval and stays zero (free vibration).

Similitude: the device is read as a 1:10 Froude model (lengths x 0.1, time x sqrt(0.1),
accelerations unchanged), so record times are multiplied by ``time_factor`` = sqrt(0.1) by default;
windows are given in the record's own (full-scale) time.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from nsd_core.common.errors import ParameterError

STANDARD_GRAVITY = 9.80665  # m/s^2: the records' unit g
SCALE_RANGE = (1e-6, 100.0)    # a record's scale (nsd seismic --scale, a case's scale, each IDA level's)
ROTATE_RANGE = (-360.0, 360.0)  # deg, a record's rotation in plan


def _number(name: str, value) -> float:
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise ParameterError(f"{name} = {value!r}: not a number") from None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ParameterError(f"{name} = {value!r}: must be a finite number")
    return float(value)


def _positive(name: str, value) -> float:
    v = _number(name, value)
    if v <= 0:
        raise ParameterError(f"{name} = {v:g}: must be > 0")
    return v


def _unit(azimuth_deg: float) -> np.ndarray:
    a = math.radians(azimuth_deg)
    return np.array([math.cos(a), math.sin(a)])


# ---- the one implementation of every ground motion: compiled scalar functions on a flat block ----
# A motion is a block of floats (``GroundMotion.block()``); ``ground_values`` evaluates it at one time.
# The Python classes call the same functions (``ground_series``), and so does the compiled seismic
# path's motion and force callbacks (nsd_core.structure.compiled_seismic), from the model's parameters.
#   record:   [0, R00, R01, R10, R11, n_a, n_b, component a (5 n_a), component b (5 n_b)]
#             a component: its sample times, a, slope, v, d (PiecewiseLinear), n values each
#   harmonic: [1, A, omega, duration, e_x, e_y]
#   pulse:    [2, A, f_p, gamma, nu (rad), e_x, e_y]
RECORD, HARMONIC, PULSE = 0.0, 1.0, 2.0


@njit(cache=True, _nrt=False)
def piecewise_linear_at(t, p, start, n):
    """(d, v, a) at t of a component stored at p[start:start + 5 n] (t_k, a_k, s_k, v_k, d_k):
    zero before t_0; a = a_k + s_k tau on [t_k, t_k+1), v and d its exact integrals."""
    if t < p[start]:
        return 0.0, 0.0, 0.0
    lo, hi = 0, n - 1  # the last k with t_k <= t (bisection; the last sample holds past the end)
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if p[start + mid] <= t:
            lo = mid
        else:
            hi = mid - 1
    tau = t - p[start + lo]
    a0, s, v0, d0 = p[start + n + lo], p[start + 2 * n + lo], p[start + 3 * n + lo], p[start + 4 * n + lo]
    return (d0 + v0 * tau + a0 * tau * tau / 2.0 + s * tau * tau * tau / 6.0,
            v0 + a0 * tau + s * tau * tau / 2.0, a0 + s * tau)


@njit(cache=True, _nrt=False)
def harmonic_at(t, A, w, duration):
    """a = A sin(w t) on [0, duration], zero outside; v, d its integrals from rest (closed forms)."""
    tc = min(max(t, 0.0), duration)
    a = A * math.sin(w * tc) if 0.0 <= t <= duration else 0.0
    v = A * (1.0 - math.cos(w * tc)) / w
    d = A * (tc / w - math.sin(w * tc) / (w * w)) + v * max(t - duration, 0.0)
    return d, v, a


@njit(cache=True, _nrt=False)
def _pulse_terms(A, f, gamma, nu, tau):
    W = 2.0 * math.pi * f
    d, v, a = 0.0, 0.0, 0.0
    for w, c in ((W, 0.5), (W * (1.0 + 1.0 / gamma), 0.25), (W * (1.0 - 1.0 / gamma), 0.25)):
        d += c * math.sin(w * tau + nu) / w
        v += c * math.cos(w * tau + nu)
        a -= c * w * math.sin(w * tau + nu)
    return A * d, A * v, A * a


@njit(cache=True, _nrt=False)
def pulse_at(t, A, f, gamma, nu):
    """Mavroeidis-Papageorgiou velocity pulse started at 0 (t_0 = gamma/(2 f)): (d, v, a)."""
    half = gamma / (2.0 * f)
    tau = min(max(t - half, -half), half)
    d, v, a = _pulse_terms(A, f, gamma, nu, tau)
    d0 = _pulse_terms(A, f, gamma, nu, -half)[0]
    if not 0.0 <= t <= 2.0 * half:
        v, a = 0.0, 0.0
    return d - d0, v, a


@njit(cache=True, _nrt=False)
def ground_values(t, p, o):
    """The ground motion of the block at p[o:] at time t: (d_x, d_y, v_x, v_y, a_x, a_y)."""
    kind = p[o]
    if kind == RECORD:
        na, nb = int(p[o + 5]), int(p[o + 6])
        da, va, aa = piecewise_linear_at(t, p, o + 7, na)
        db, vb, ab = piecewise_linear_at(t, p, o + 7 + 5 * na, nb)
        r00, r01, r10, r11 = p[o + 1], p[o + 2], p[o + 3], p[o + 4]
        return (r00 * da + r01 * db, r10 * da + r11 * db, r00 * va + r01 * vb, r10 * va + r11 * vb,
                r00 * aa + r01 * ab, r10 * aa + r11 * ab)
    if kind == HARMONIC:
        s, sd, sdd = harmonic_at(t, p[o + 1], p[o + 2], p[o + 3])
        ex, ey = p[o + 4], p[o + 5]
    else:
        s, sd, sdd = pulse_at(t, p[o + 1], p[o + 2], p[o + 3], p[o + 4])
        ex, ey = p[o + 5], p[o + 6]
    return s * ex, s * ey, sd * ex, sd * ey, sdd * ex, sdd * ey


@njit(cache=True, _nrt=False)
def ground_series(ts, p, out):
    """ground_values at every time of ts into out (len(ts), 6)."""
    for k in range(ts.shape[0]):
        out[k, 0], out[k, 1], out[k, 2], out[k, 3], out[k, 4], out[k, 5] = ground_values(ts[k], p, 0)


@njit(cache=True, _nrt=False)
def _piecewise_series(ts, p, n, out):
    for k in range(ts.shape[0]):
        out[k, 0], out[k, 1], out[k, 2] = piecewise_linear_at(ts[k], p, 0, n)


class PiecewiseLinear:
    """One acceleration component, linear between samples, integrated exactly from rest at t[0]."""

    def __init__(self, t: np.ndarray, a: np.ndarray, ramp: float | None = None):
        t, a = np.asarray(t, dtype=float), np.asarray(a, dtype=float)
        h = np.diff(t)
        if len(t) < 2 or np.any(h <= 0):
            raise ParameterError("ground acceleration: needs >= 2 samples at increasing times")
        # past the last sample: a ramp to zero over one sample interval (ramp), then zero
        t = np.append(t, t[-1] + (h[-1] if ramp is None else ramp))
        a = np.append(a, 0.0)
        h = np.diff(t)
        self.t, self.a = t, a
        self.slope = np.append(np.diff(a) / h, 0.0)
        self.v = np.concatenate([[0.0], np.cumsum(h * (a[1:] + a[:-1]) / 2.0)])
        self.d = np.concatenate([[0.0], np.cumsum(h * self.v[:-1] + h * h * (2.0 * a[:-1] + a[1:]) / 6.0)])
        self.block = np.concatenate([self.t, self.a, self.slope, self.v, self.d])  # piecewise_linear_at's layout

    def __call__(self, t):
        """(d, v, a) at t (a scalar or an array): piecewise_linear_at, the one implementation."""
        if np.ndim(t) == 0:
            return piecewise_linear_at(float(t), self.block, 0, len(self.t))
        ts = np.ascontiguousarray(t, dtype=float)
        out = np.empty((ts.size, 3))
        _piecewise_series(ts.ravel(), self.block, len(self.t), out)
        return tuple(out[:, j].reshape(ts.shape) for j in range(3))


class GroundMotion:
    """Interface: ``__call__(t) -> (d, v, a)``, each (2,) or (len(t), 2); ``duration``; ``meta``;
    ``block()``: the motion as ground_values' flat block (what the compiled path reads)."""
    duration: float
    meta: dict

    def block(self) -> np.ndarray:
        raise NotImplementedError

    def __call__(self, t):
        """ground_values on this motion's block: the one implementation, here and in the compiled path."""
        if np.ndim(t) == 0:
            v = self.values_at(float(t))
            return v[0:2], v[2:4], v[4:6]
        ts = np.ascontiguousarray(t, dtype=float)
        out = np.empty((ts.size, 6))
        ground_series(ts.ravel(), self._block(), out)
        return tuple(out[:, j:j + 2].reshape(ts.shape + (2,)) for j in (0, 2, 4))

    def values_at(self, t: float) -> np.ndarray:
        """(d_x, d_y, v_x, v_y, a_x, a_y) at one time, without an array's handling (a peer's step asks
        for the acceleration once or twice: ~1 us against ~5 us); ``__call__``'s scalar case."""
        out = np.empty((1, 6))
        ground_series(np.array([t], dtype=float), self._block(), out)
        return out[0]

    def _block(self) -> np.ndarray:
        cached = self.__dict__.get("_cached_block")
        if cached is None:
            cached = np.ascontiguousarray(self.block(), dtype=float)
            object.__setattr__(self, "_cached_block", cached)  # frozen dataclasses too
        return cached

    def describe(self) -> dict:
        return dict(self.meta)


@dataclass(frozen=True)
class Harmonic(GroundMotion):
    """a_g(t) = A sin(2 pi f t) along ``azimuth_deg`` for t in [0, duration], zero after; from rest:
    v_g = A (1 - cos wt)/w, d_g = A (t/w - sin(wt)/w^2)."""
    amplitude: float          # A [m/s^2]
    frequency: float          # f [Hz]
    azimuth_deg: float = 0.0
    duration: float = 2.0     # [s]
    meta: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        _number("amplitude", self.amplitude)
        _positive("frequency", self.frequency)
        _number("azimuth_deg", self.azimuth_deg)
        _positive("duration", self.duration)
        self.meta.update({"kind": "harmonic", "amplitude": self.amplitude, "frequency": self.frequency,
                          "azimuth_deg": self.azimuth_deg, "duration": self.duration})

    def block(self) -> np.ndarray:
        e = _unit(self.azimuth_deg)
        return np.array([HARMONIC, self.amplitude, 2.0 * math.pi * self.frequency, self.duration, e[0], e[1]])

    def scalar(self, t):
        """(d, v, a) along the azimuth at a scalar t (harmonic_at)."""
        return harmonic_at(float(t), self.amplitude, 2.0 * math.pi * self.frequency, self.duration)


@dataclass(frozen=True)
class Pulse(GroundMotion):
    """Mavroeidis & Papageorgiou (2003), BSSA 93(3), Eq. 1, started at t = 0 (t_0 = gamma/(2 f_p)):
        v(t) = (A/2) [1 + cos(2 pi f_p tau / gamma)] cos(2 pi f_p tau + nu),  |tau| <= gamma/(2 f_p),
    tau = t - t_0, zero outside; d and a in closed form (product-to-sum). gamma > 1."""
    velocity: float           # A [m/s]
    frequency: float          # f_p [Hz], the pulse's prevailing frequency
    gamma: float = 2.0        # oscillatory character (number of half cycles)
    phase_deg: float = 0.0    # nu
    azimuth_deg: float = 0.0
    meta: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        _number("velocity", self.velocity)
        _positive("frequency", self.frequency)
        if _number("gamma", self.gamma) <= 1.0:
            raise ParameterError(f"gamma = {self.gamma:g}: must be > 1 (Mavroeidis-Papageorgiou)")
        _number("phase_deg", self.phase_deg)
        _number("azimuth_deg", self.azimuth_deg)
        self.meta.update({"kind": "pulse", "velocity": self.velocity, "frequency": self.frequency,
                          "gamma": self.gamma, "phase_deg": self.phase_deg, "azimuth_deg": self.azimuth_deg,
                          "source": "Mavroeidis and Papageorgiou (2003), Eq. 1"})

    @property
    def duration(self) -> float:
        return self.gamma / self.frequency

    def block(self) -> np.ndarray:
        e = _unit(self.azimuth_deg)
        return np.array([PULSE, self.velocity, self.frequency, self.gamma, math.radians(self.phase_deg), e[0], e[1]])

    def scalar(self, t):
        """(d, v, a) along the azimuth at a scalar t (pulse_at)."""
        return pulse_at(float(t), self.velocity, self.frequency, self.gamma, math.radians(self.phase_deg))


# ---- closed-form inputs from text (nsd seismic --ground, a seismic case's ground = "...") ----
# kind -> (class, {key: (constructor argument, low, high, unit)}, required keys); every value is
# named, finite and in its range, every key given once: the bounds users read in --help
# and docs/limits.md. Each closed-form input lasts at most GROUND_DURATION_MAX model seconds.
GROUND_DURATION_MAX = 60.0  # s
GROUND_SPECS = {
    "harmonic": ("Harmonic", {"amplitude": ("amplitude", -50.0, 50.0, "m/s^2"),
                              "frequency": ("frequency", 0.05, 100.0, "Hz"),
                              "azimuth": ("azimuth_deg", -360.0, 360.0, "deg"),
                              "duration": ("duration", 1e-3, GROUND_DURATION_MAX, "s")},
                 ("amplitude", "frequency")),
    "pulse": ("Pulse", {"velocity": ("velocity", -5.0, 5.0, "m/s"),
                        "frequency": ("frequency", 0.05, 100.0, "Hz"),
                        "gamma": ("gamma", 1.0, 20.0, "(dimensionless)"),
                        "phase": ("phase_deg", -360.0, 360.0, "deg"),
                        "azimuth": ("azimuth_deg", -360.0, 360.0, "deg")},
              ("velocity", "frequency")),
}


def ground_spec_bounds() -> str:
    """The keys and ranges of every closed-form kind, for --help."""
    return "; ".join(f"{kind}: " + ", ".join(f"{k} in {'(' if k == 'gamma' else '['}{lo:g}, {hi:g}] {u}"
                                             for k, (_, lo, hi, u) in keys.items())
                     for kind, (_, keys, _) in GROUND_SPECS.items())


def parse_ground_spec(text, where: str = "--ground") -> GroundMotion:
    """A closed-form ground motion from ``KIND:KEY=VALUE,...``: an unknown kind or key, a key given
    twice, a missing required key, a value that is not a finite number in its range (gamma > 1),
    or an input longer than GROUND_DURATION_MAX is a ParameterError naming it."""
    from nsd_core.common.files import printable
    if not isinstance(text, str):
        raise ParameterError(f"{where} = {printable(repr(text))}: must be a string KIND:KEY=VALUE,... "
                             f"(kinds: {', '.join(GROUND_SPECS)})")
    kind, _, rest = text.strip().partition(":")
    if kind not in GROUND_SPECS:
        raise ParameterError(f"{where} {printable(repr(kind))}: unknown kind; allowed: {', '.join(GROUND_SPECS)}")
    cls, keys, required = GROUND_SPECS[kind]
    values: dict[str, float] = {}
    for item in filter(None, (s.strip() for s in rest.split(","))):
        k, sep, v = (x.strip() for x in item.partition("="))
        if not sep or k not in keys:
            raise ParameterError(f"{where} {kind}: {printable(repr(item))}: expected KEY=VALUE with KEY in "
                                 f"{', '.join(keys)}")
        arg, lo, hi, unit = keys[k]
        if arg in values:
            raise ParameterError(f"{where} {kind}: {k} given twice; give each key once")
        try:
            x = float(v)
        except ValueError:
            raise ParameterError(f"{where} {kind}: {k} = {printable(repr(v))}: not a number; allowed "
                                 f"[{lo:g}, {hi:g}] {unit}") from None
        open_low = k == "gamma"  # Mavroeidis-Papageorgiou: gamma > 1
        if open_low and math.isfinite(x) and x <= lo:
            raise ParameterError(f"{where} {kind}: {k} = {printable(v)}: must be > {lo:g} (Mavroeidis-Papageorgiou) "
                                 f"and <= {hi:g}")
        if not (math.isfinite(x) and (lo < x if open_low else lo <= x) and x <= hi):
            raise ParameterError(f"{where} {kind}: {k} = {printable(v)}: must be a finite number in "
                                 f"{'(' if open_low else '['}{lo:g}, {hi:g}] {unit}")
        values[arg] = x
    missing = [k for k in required if keys[k][0] not in values]
    if missing:
        raise ParameterError(f"{where} {kind}: {', '.join(missing)} required (KEY=VALUE)")
    motion = globals()[cls](**values)
    if motion.duration > GROUND_DURATION_MAX:
        raise ParameterError(f"{where} {kind}: lasts {motion.duration:g} s (gamma / frequency for a pulse); at most "
                             f"{GROUND_DURATION_MAX:g} s")
    return motion

