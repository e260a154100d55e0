"""The prescribed drive of the parametric analysis (Table 1, first row): u(t) = A sin(2 pi f t)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nsd_core.device.params import ParameterError, Params


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

    def __post_init__(self):
        for name in ("amplitude", "frequency", "direction_deg"):
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ParameterError(f"{name} = {v!r}: must be a finite number")
        if self.amplitude < 0:
            raise ParameterError(f"amplitude = {self.amplitude}: must be >= 0 m (0 holds the device at rest)")
        if self.frequency <= 0:
            raise ParameterError(f"frequency = {self.frequency}: must be > 0 Hz")
        if not isinstance(self.cycles, int) or self.cycles < 1:
            raise ParameterError(f"cycles = {self.cycles!r}: must be a whole number >= 1")
        if not isinstance(self.samples_per_cycle, int) or self.samples_per_cycle < 16:
            raise ParameterError(f"samples_per_cycle = {self.samples_per_cycle!r}: must be a whole number >= 16")

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
        """u, du/dt, d2u/dt2 at time t."""
        w = self.omega
        s, c = np.sin(w * t), np.cos(w * t)
        return self.amplitude * s, self.amplitude * w * c, -self.amplitude * w * w * s

    def output_times(self) -> np.ndarray:
        n = self.cycles * self.samples_per_cycle
        return np.linspace(0.0, self.duration, n + 1)
