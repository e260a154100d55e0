"""The prescribed drive of the parametric analysis (Table 1, first row): u(t) = A sin(2 pi f t)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from nsd_core.device.params import ParameterError, Params


@njit(cache=True)
def sine_displacement(amplitude, omega, t):
    """u = A sin(omega t) and its first two derivatives; compiled, so the compiled model's motion
    (nsd_core.device.compiled) and Drive.displacement are one formula."""
    s = np.sin(omega * t)
    return amplitude * s, amplitude * omega * np.cos(omega * t), -amplitude * omega * omega * s


class DriveError(ValueError):
    """A drive the mechanism cannot follow (|u| >= l_d), or a state it drives the device into that
    lies outside the force laws' validity: exit code 4."""


@dataclass(frozen=True)
class Drive:
    """Plate displacement u(t) = A sin(2 pi f t) along azimuth psi in the horizontal plane."""
    amplitude: float          # A [m]
    frequency: float          # f [Hz]
    direction_deg: float = 0.0  # psi [deg], 0 = +X (the first wire's direction)
    cycles: int = 2           # the last one is the steady cycle that is compared
    samples_per_cycle: int = 1000

    # Bounds that keep one run's work finite (issue 12): below F_MIN a cycle is so long that the
    # 250 Hz vertical mode must be resolved over minutes of simulated time; above F_MAX the drive's
    # inertia force m_c A (2 pi f)^2 leaves the range any force law here was written for.
    F_MIN, F_MAX = 0.05, 100.0   # Hz
    CYCLES_MAX = 1000
    SAMPLES_MAX = 200_000        # per cycle
    TOTAL_SAMPLES_MAX = 2_000_000

    def __post_init__(self):
        for name in ("amplitude", "frequency", "direction_deg"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ParameterError(f"{name} = {v!r}: must be a finite number")
        if self.amplitude < 0:
            raise ParameterError(f"amplitude = {self.amplitude}: must be >= 0 m (0 holds the device at rest)")
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

    def check_followable(self, p: Params) -> None:
        if self.amplitude >= p.rod_length:
            raise DriveError(f"amplitude = {self.amplitude} m: the mechanism cannot follow a drive with "
                             f"|u| >= rod_length = {p.rod_length} m")

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

    def displacement(self, t):
        """u, du/dt, d2u/dt2 at time t (a number or an array of times)."""
        t = np.asarray(t, dtype=float)
        return sine_displacement(float(self.amplitude), self.omega, float(t) if t.ndim == 0 else t)

    def output_times(self) -> np.ndarray:
        n = self.cycles * self.samples_per_cycle
        return np.linspace(0.0, self.duration, n + 1)
