"""What every engine's builder returns for one run of a described model."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class ModelRun:
    """Outputs of one engine on one case: every named output sampled at ``t``.

    stats: at least ``wall_time`` [s] (the integration and its outputs, not the model's build),
    ``steps``, ``closure_max`` [m] (the largest loop-closure residual at the output times) and, with
    prescribed motions, ``tracking_error`` (the largest |q - q(t)| of a prescribed coordinate)."""
    engine: str
    t: np.ndarray
    outputs: dict[str, np.ndarray]
    units: dict[str, str]
    stats: dict = field(default_factory=dict)


def output_times(duration: float, dt_out: float) -> np.ndarray:
    """0, dt_out, ..., duration (the last sample exactly at ``duration``)."""
    n = max(1, int(round(duration / dt_out)))
    return np.linspace(0.0, duration, n + 1)
