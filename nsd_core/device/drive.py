"""The prescribed drive of the parametric analysis (Table 1, first row): the plate's path in the plane.

nsd-model.md, "Drive and outputs" and "Two-dimensional drive paths". The plate's rotation is held
at 0 and its position p(t) = (x, y) follows one of these paths, written in the path's own frame
(a along e_psi, b along e_z x e_psi) and rotated by psi:

- line:     a = A sin(w t), b = 0 (the paper's drive, along azimuth psi);
- circle:   a = r(t) sin(w t), b = r(t) cos(w t), r(t) = A (1 - cos(pi f t))/2 in the first
            cycle, then A (starts from rest at the centre and spirals out);
- ellipse:  as the circle with semi-axes A (along psi) and B (``minor``);
- figure8:  a = A sin(w t), b = B sin(2 w t) (starts at the centre as it is; B defaults to A/2);
- a table (t, x, y) read from a CSV file, interpolated by a clamped cubic spline (continuous
  velocity and acceleration, at rest at both ends); x and y are world coordinates, psi is ignored.

Every engine asks the Drive for the plate's position, velocity and acceleration vectors
(``plate``/``plate_at``) instead of re-deriving a sine. All of them, and the compiled engine's motion
callback (nsd_core.device.compiled), evaluate one compiled function, ``plate_motion``, on the
Drive's packed parameters (``motion_params``): one implementation of every path.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numba import njit

from nsd_core.device.params import ParameterError, Params

PATHS = ("line", "circle", "ellipse", "figure8")
# Output samples per cycle, the one default of the API (Drive), `nsd cycle` and the case files of
# `nsd compare`: the gate's limits were derived at 2000, and the energy balance's quadrature error on
# the output grid falls as 1/samples^2 (~2e-6 of the drive work at 2000, ~8e-6 at 1000, ~7e-4 at 100;
# comparisons/tolerances.toml), so 2000 keeps it 50x below its 1e-4 limit. Each sample costs one
# model evaluation (~3.6 us in-house: ~7 ms per cycle). `nsd sweep` keeps its own 500 (the study).
SAMPLES_PER_CYCLE = 2000
MAX_TABLE_BYTES = 50_000_000  # ~1e6 rows of t,x,y: far beyond any record a run could follow
MAX_TABLE_ROWS = 1_000_000
TABLE_DT_MIN = 1e-6   # s between rows: finer than any output step a run allows
TABLE_T_MAX = 20_000.0  # s: the longest drive (1000 cycles at 0.05 Hz)
TABLE_REACH_MAX = 1.0   # m: a sanity bound far beyond any rod length; |u| >= l_d stays exit 4


# path kinds in motion_params[0]; an ellipse is a circle with B != A
LINE, SPIRAL, FIGURE8, TABLE = 0, 1, 2, 3
HEADER = 8  # [kind, A, B, omega, T_ramp = 1/f, cos psi, sin psi, n_intervals]; a table's knots and
#             coefficients follow (n + 1 knots, then the cubic's coefficients c[m, i, axis] as scipy's PPoly)


@njit(cache=True, _nrt=False)
def _cubic(p, base, n, i, axis, s):
    """Value and two derivatives of the table's cubic on interval i, s = t - x_i (Horner)."""
    c0, c1 = p[base + i * 2 + axis], p[base + (n + i) * 2 + axis]
    c2, c3 = p[base + (2 * n + i) * 2 + axis], p[base + (3 * n + i) * 2 + axis]
    return ((c0 * s + c1) * s + c2) * s + c3, (3.0 * c0 * s + 2.0 * c1) * s + c2, 6.0 * c0 * s + 2.0 * c1


@njit(cache=True, _nrt=False)
def plate_motion(t, p):
    """x, y, x', y', x'', y'' of the plate at time t for the packed path p (see ``Drive.motion_params``).

    The closed forms of the module docstring in the path's frame (a along e_psi, b across), rotated
    by psi; a table is the clamped cubic spline's piecewise polynomial (scipy's PPoly evaluation:
    the interval x_i <= t < x_(i+1), the end intervals extended beyond the knots)."""
    kind = int(p[0])
    if kind == TABLE:
        n = int(p[7])
        knots = p[HEADER:HEADER + n + 1]
        i = np.searchsorted(knots, t, side="right") - 1
        i = min(max(i, 0), n - 1)
        s = t - knots[i]
        base = HEADER + n + 1
        x, xd, xdd = _cubic(p, base, n, i, 0, s)
        y, yd, ydd = _cubic(p, base, n, i, 1, s)
        return x, y, xd, yd, xdd, ydd
    A, B, w = p[1], p[2], p[3]
    s, c = math.sin(w * t), math.cos(w * t)
    a0, a1, a2 = A * s, A * w * c, -A * w * w * s
    b0, b1, b2 = 0.0, 0.0, 0.0
    if kind == FIGURE8:
        s2, c2 = math.sin(2 * w * t), math.cos(2 * w * t)
        b0, b1, b2 = B * s2, 2 * B * w * c2, -4 * B * w * w * s2
    elif kind == SPIRAL:  # r(t)/R = (1 - cos(pi f t))/2 in the first cycle, then 1
        r, rd, rdd = 1.0, 0.0, 0.0
        if t < p[4]:
            k = 0.5 * w
            r, rd, rdd = 0.5 * (1.0 - math.cos(k * t)), 0.5 * k * math.sin(k * t), 0.5 * k * k * math.cos(k * t)
        a0, a1, a2 = A * r * s, A * (rd * s + r * w * c), A * (rdd * s + 2 * rd * w * c - r * w * w * s)
        b0, b1, b2 = B * r * c, B * (rd * c - r * w * s), B * (rdd * c - 2 * rd * w * s - r * w * w * c)
    e0, e1 = p[5], p[6]
    return (e0 * a0 - e1 * b0, e1 * a0 + e0 * b0, e0 * a1 - e1 * b1, e1 * a1 + e0 * b1,
            e0 * a2 - e1 * b2, e1 * a2 + e0 * b2)


@njit(cache=True)
def _plate_series(t, p):
    out = np.empty((t.shape[0], 6))
    for k in range(t.shape[0]):
        out[k, 0], out[k, 1], out[k, 2], out[k, 3], out[k, 4], out[k, 5] = plate_motion(t[k], p)
    return out


class DriveError(ValueError):
    """A drive the mechanism cannot follow (|u| >= l_d), or a state it drives the device into that
    lies outside the force laws' validity: exit code 4."""


def read_path_table(path: str | Path):
    """A (t, x, y) table [s, m, m] from CSV (an optional header line), validated; one-line errors.

    Returns a scipy CubicSpline of (x, y) in t, clamped (zero velocity) at both ends so that the
    plate starts from rest, as the rest state the engines start from requires.
    """
    from scipy.interpolate import CubicSpline
    from nsd_core.common.files import printable, read_input_text
    where = f"path = {printable(repr(str(path)))}"
    if not os.path.lexists(path):
        raise ParameterError(f"{where}: no such file; allowed: {', '.join(PATHS)} or a CSV file of t,x,y")
    try:
        lines = read_input_text(path, "path", MAX_TABLE_BYTES, "a CSV file of t,x,y").splitlines()
    except ParameterError:
        raise
    except ValueError as e:  # InputError of nsd_core.common.files: one line naming the path
        raise ParameterError(f"{e}; allowed: {', '.join(PATHS)} or a CSV file of t,x,y") from None
    rows, seen = [], 0
    for k, line in enumerate(lines, start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        seen += 1
        cells = [c.strip() for c in line.split(",")]
        try:
            vals = [float(c) for c in cells]
        except ValueError:
            if seen == 1:
                continue  # a header line
            raise ParameterError(f"{where}, line {k}: {line.strip()!r} is not three numbers t,x,y") from None
        if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
            raise ParameterError(f"{where}, line {k}: {line.strip()!r} must be three finite numbers t,x,y")
        rows.append(vals)
        if len(rows) > MAX_TABLE_ROWS:
            raise ParameterError(f"{where}: more than {MAX_TABLE_ROWS} rows; a path table may hold at most "
                                 f"{MAX_TABLE_ROWS} rows of t,x,y")
    if len(rows) < 4:
        raise ParameterError(f"{where}: {len(rows)} rows; a path table needs at least 4 rows of t,x,y")
    a = np.array(rows)
    if a[0, 0] != 0.0:
        raise ParameterError(f"{where}: first t = {a[0, 0]!r}; the table must start at t = 0")
    if a[0, 1] != 0.0 or a[0, 2] != 0.0:
        raise ParameterError(f"{where}: first (x, y) = ({a[0, 1]!r}, {a[0, 2]!r}); the plate must start at the "
                             "centre (0, 0), the rest state")
    dt = np.diff(a[:, 0])
    if np.any(dt <= 0.0):
        k = int(np.flatnonzero(dt <= 0.0)[0]) + 1
        raise ParameterError(f"{where}: t = {a[k, 0]!r} at row {k + 1} does not increase; t must be strictly increasing")
    if np.min(dt) < TABLE_DT_MIN:
        k = int(np.argmin(dt)) + 1
        raise ParameterError(f"{where}: t = {a[k, 0]!r} at row {k + 1} lies {dt[k - 1]:.3g} s after the row before; "
                             f"rows must be at least {TABLE_DT_MIN:g} s apart")
    if a[-1, 0] > TABLE_T_MAX:
        raise ParameterError(f"{where}: last t = {a[-1, 0]!r} s; a path table may span at most {TABLE_T_MAX:g} s")
    reach = float(np.max(np.hypot(a[:, 1], a[:, 2])))
    if reach > TABLE_REACH_MAX:
        raise ParameterError(f"{where}: |(x, y)| reaches {reach:.6g} m; a plate position must stay within "
                             f"{TABLE_REACH_MAX:g} m of the centre (the device's rod is centimetres long)")
    return CubicSpline(a[:, 0], a[:, 1:], bc_type="clamped")


@dataclass(frozen=True)
class Drive:
    """The plate's path p(t) = (x, y) in the horizontal plane (see the module docstring)."""
    amplitude: float          # A [m]: the line's amplitude, the circle's radius, the major semi-axis
    frequency: float          # f [Hz]
    direction_deg: float = 0.0  # psi [deg], 0 = +X (the first wire's direction)
    cycles: int = 2           # the last one is the steady cycle that is compared
    samples_per_cycle: int = SAMPLES_PER_CYCLE
    path: str = "line"        # line | circle | ellipse | figure8 | a CSV file of t,x,y
    minor: float | None = None  # B [m]: ellipse (required), figure8 (default A/2)
    _table: object = field(default=None, init=False, repr=False, compare=False)
    _packed: object = field(default=None, init=False, repr=False, compare=False)

    # Bounds that keep one run's work finite (docs/limits.md): below F_MIN a cycle is so long that the
    # 250 Hz vertical mode must be resolved over minutes of simulated time; above F_MAX the drive's
    # inertia force m_c A (2 pi f)^2 leaves the range any force law here was written for.
    F_MIN, F_MAX = 0.05, 100.0   # Hz
    A_MIN = 1e-6                 # m, a named path's amplitude (1 um: 4e-5 of the 25 mm working range)
    CYCLES_MAX = 1000
    SAMPLES_MAX = 200_000        # per cycle
    TOTAL_SAMPLES_MAX = 2_000_000

    def __post_init__(self):
        for name in ("amplitude", "frequency", "direction_deg"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ParameterError(f"{name} = {v!r}: must be a finite number")
        if self.amplitude < 0:
            raise ParameterError(f"amplitude = {self.amplitude}: must be >= 0 m (0 for a table path)")
        if self.path in PATHS and self.amplitude < self.A_MIN:
            raise ParameterError(f"amplitude = {self.amplitude:g}: must be >= {self.A_MIN:g} m for the {self.path} path "
                                 "(a smaller cycle has no loop or stiffness to measure: its forces are round-off)")
        if not self.F_MIN <= self.frequency <= self.F_MAX:
            raise ParameterError(f"frequency = {self.frequency}: must be in [{self.F_MIN}, {self.F_MAX}] Hz")
        if not -360.0 <= self.direction_deg <= 360.0:
            raise ParameterError(f"direction_deg = {self.direction_deg}: must be in [-360, 360] deg")
        for name, top in (("cycles", self.CYCLES_MAX), ("samples_per_cycle", self.SAMPLES_MAX)):
            v = getattr(self, name)
            low = 1 if name == "cycles" else 16
            if isinstance(v, bool) or not isinstance(v, int) or not low <= v <= top:
                raise ParameterError(f"{name} = {v!r}: must be a whole number in [{low}, {top}]")
        if self.cycles * self.samples_per_cycle > self.TOTAL_SAMPLES_MAX:
            raise ParameterError(f"cycles x samples_per_cycle = {self.cycles * self.samples_per_cycle}: must be "
                                 f"<= {self.TOTAL_SAMPLES_MAX} output samples")
        if not isinstance(self.path, str) or not self.path:
            raise ParameterError(f"path = {self.path!r}: allowed: {', '.join(PATHS)} or a CSV file of t,x,y")
        if self.minor is not None and (isinstance(self.minor, bool) or not isinstance(self.minor, (int, float))
                                       or not math.isfinite(self.minor) or self.minor < 0):
            raise ParameterError(f"minor = {self.minor!r}: must be a finite number >= 0 m")
        if self.path == "ellipse" and self.minor is None:
            raise ParameterError("minor: missing; an ellipse needs its minor semi-axis B (--minor) [m]")
        if self.path in ("line", "circle") and self.minor is not None:
            raise ParameterError(f"minor = {self.minor}: only an ellipse or a figure8 takes a minor semi-axis")
        if self.path not in PATHS:
            if self.minor is not None:
                raise ParameterError(f"minor = {self.minor}: a table path {self.path!r} gives its own positions; "
                                     "leave the minor semi-axis out")
            if self.direction_deg != 0.0:
                raise ParameterError(f"direction_deg = {self.direction_deg}: a table path {self.path!r} gives world "
                                     "x, y; leave the direction out")
            spline = read_path_table(self.path)
            if spline.x[-1] < self.duration * (1 - 1e-12):
                raise ParameterError(f"path = {self.path!r}: the table ends at t = {spline.x[-1]:g} s, before "
                                     f"cycles/frequency = {self.duration:g} s")
            object.__setattr__(self, "_table", spline)
        object.__setattr__(self, "_packed", self._pack())

    def _pack(self) -> np.ndarray:
        psi = math.radians(self.direction_deg)
        if self._table is not None:
            x, c = self._table.x, self._table.c  # c: (4, n, 2), highest power first
            head = [TABLE, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, len(x) - 1]
            p = np.concatenate([head, x, np.ascontiguousarray(c).ravel()])
        else:
            kind = {"line": LINE, "figure8": FIGURE8}.get(self.path, SPIRAL)
            p = np.array([kind, self.amplitude, self.minor_axis, self.omega, 1.0 / self.frequency,
                          math.cos(psi), math.sin(psi), 0.0])
        p = np.ascontiguousarray(p, dtype=float)
        p.setflags(write=False)
        return p

    @property
    def motion_params(self) -> np.ndarray:
        """The path packed for ``plate_motion`` (read-only): what the compiled engine's motion
        callback receives, and what ``plate``/``plate_at`` evaluate."""
        return self._packed

    @property
    def is_line(self) -> bool:
        return self.path == "line"

    @property
    def minor_axis(self) -> float:
        """B [m] of the ellipse / figure eight (A for a circle, 0 for a line)."""
        if self.path == "circle":
            return self.amplitude
        if self.path == "figure8" and self.minor is None:
            return 0.5 * self.amplitude
        return float(self.minor or 0.0)

    def check_followable(self, p: Params) -> None:
        reach = self.extent()
        if reach >= p.rod_length:
            raise DriveError(f"amplitude = {reach} m: the mechanism cannot follow a drive with "
                             f"|u| >= rod_length = {p.rod_length} m")

    def extent(self) -> float:
        """The largest distance of the plate from the centre along the path [m]."""
        if self._table is not None:
            t = np.union1d(self._table.x[self._table.x <= self.duration],
                           np.linspace(0.0, self.duration, 200_001))
            return float(np.max(np.linalg.norm(self._table(t), axis=1)))
        if self.path == "figure8":  # max over s of A^2 sin^2 s + B^2 sin^2 2s, on a fine grid
            s = np.linspace(0.0, 0.5 * math.pi, 20001)
            return float(np.sqrt(np.max((self.amplitude * np.sin(s)) ** 2 + (self.minor_axis * np.sin(2 * s)) ** 2)))
        return max(self.amplitude, self.minor_axis)

    @property
    def omega(self) -> float:
        return 2.0 * math.pi * self.frequency

    @property
    def duration(self) -> float:
        return self.cycles / self.frequency

    @property
    def unit_vector(self) -> np.ndarray:
        a = math.radians(self.direction_deg)
        return np.array([math.cos(a), math.sin(a), 0.0])

    def plate(self, t):
        """Plate position, velocity and acceleration (x, y) at times t: three arrays of shape t.shape + (2,)."""
        t = np.asarray(t, dtype=float)
        out = _plate_series(np.ascontiguousarray(t.ravel()), self._packed).reshape(t.shape + (3, 2))
        return out[..., 0, :], out[..., 1, :], out[..., 2, :]

    def plate_at(self, t: float) -> tuple[float, float, float, float, float, float]:
        """x, y, x', y', x'', y'' at one time t (``plate_motion``: cheap enough for a right-hand side)."""
        return plate_motion(float(t), self._packed)

    def displacement(self, t):
        """u, du/dt, d2u/dt2 at time t: the plate's motion projected on e_psi (the whole motion for a line)."""
        e = self.unit_vector[:2]
        return tuple(q @ e for q in self.plate(t))

    def output_times(self) -> np.ndarray:
        n = self.cycles * self.samples_per_cycle
        return np.linspace(0.0, self.duration, n + 1)

    def describe(self) -> dict:
        d = {"path": self.path, "amplitude": self.amplitude, "frequency": self.frequency,
             "direction_deg": self.direction_deg, "cycles": self.cycles}
        if not self.is_line and self._table is None:
            d["minor"] = self.minor_axis
        return d
