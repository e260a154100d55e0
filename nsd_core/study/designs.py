"""Designs of a parametric sweep: the paper's Section 4.3 studies (Figures 8-20).

A *design* is one full parameter set with one drive, one engine and its solver settings. Its key
is a SHA-256 of exactly those (canonical JSON), so the nominal device, which every one of the
seven studies contains, runs once, and a resumed sweep recognises finished work.
"""
from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field

from nsd_core.device.params import ParameterError, Params, with_overrides

# Section 4.3 (paper-data.toml [parametric]): f = 10 Hz, A = 0.024 m, drive along +X.
PAPER_FREQUENCY, PAPER_AMPLITUDE = 10.0, 0.024
PAPER_STUDIES = {
    "rod_length": ([0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09, 0.10], "Figure 8, Table 5"),
    "n_ropes": ([3, 4, 5, 6, 7, 8, 9], "Figure 9"),
    "rope_stiffness": ([3.0e5, 5.0e5, 7.0e5, 9.0e5], "Figure 10"),
    "precompression_force": ([2400.0, 2600.0, 2800.0, 3000.0, 3200.0, 3400.0, 3600.0, 3800.0],
                             "Figure 11, Table 6"),
    "wire_diameter": ([0.0012, 0.0016, 0.0020, 0.0024], "Figures 12-13"),
    "n_wires": ([3, 4, 5, 6, 7, 8, 9, 10], "Figures 14-16"),
    "wire_inclination_deg": ([0.0, 3.2, 6.4, 9.6, 12.8, 16.0, 19.2, 22.4], "Figures 17-20"),
}
WORKING_RANGE_FRACTION = 0.95  # A = min(0.024, 0.95 X_max): stay inside each design's range (Figure 8)


@dataclass(frozen=True)
class Design:
    study: str                 # the swept parameter (the study's name)
    value: float               # its value in this design
    params: dict               # the full parameter set (Params.to_dict())
    amplitude: float
    amplitude_rule: str
    frequency: float
    direction_deg: float = 0.0
    cycles: int = 2
    samples_per_cycle: int = 500
    engine: str = "semirecursive"
    settings: dict = field(default_factory=dict)

    @property
    def key(self) -> str:
        """Hash of what determines the run (not the study it is listed under)."""
        ident = {"params": self.params, "amplitude": self.amplitude, "frequency": self.frequency,
                 "direction_deg": self.direction_deg, "cycles": self.cycles,
                 "samples_per_cycle": self.samples_per_cycle, "engine": self.engine, "settings": self.settings}
        return hashlib.sha256(json.dumps(ident, sort_keys=True).encode()).hexdigest()[:20]

    @property
    def label(self) -> str:
        return f"{self.study}={self.value:g}" + ("" if self.engine == "semirecursive" else f"@{self.engine}")


def make_designs(param: str, values: list[float], base: Params | None = None, amplitude: float | None = None,
                 frequency: float = PAPER_FREQUENCY, engines: tuple[str, ...] = ("semirecursive",),
                 settings: dict | None = None, cycles: int = 2, samples_per_cycle: int = 500,
                 direction_deg: float = 0.0) -> list[Design]:
    """One design per value (and engine). amplitude None: min(0.024, 0.95 X_max) per design."""
    from nsd_core.device.model import DEFAULT_SOLVER
    from nsd_core.device.working_range import SlackPointError, x_max_at_slack
    base = base or Params()
    if not values:
        raise ParameterError(f"--values for {param}: give at least one value")
    out = []
    for v in values:
        p = with_overrides(base, {param: v})
        if amplitude is None:
            try:
                xm = x_max_at_slack(p, direction_deg)
            except SlackPointError:
                xm = math.inf
            a = min(PAPER_AMPLITUDE, WORKING_RANGE_FRACTION * xm)
            rule = "0.024 m" if a == PAPER_AMPLITUDE else f"0.95 * X_max = 0.95 * {xm:.6f} m (0.024 m exceeds X_max)"
        else:
            a, rule = amplitude, "fixed (--amplitude)"
        for eng in engines:
            s = dict(DEFAULT_SOLVER, **(settings or {})) if eng == "semirecursive" else {}
            out.append(Design(param, float(v), p.to_dict(), float(a), rule, float(frequency), direction_deg,
                              cycles, samples_per_cycle, eng, s))
    return out


def paper_designs(**kw) -> list[Design]:
    """All seven studies of Section 4.3 at f = 10 Hz (A per the working-range rule)."""
    return [d for name, (vals, _) in PAPER_STUDIES.items() for d in make_designs(name, vals, **kw)]
