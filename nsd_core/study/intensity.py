"""Intensity measures of a ground motion for incremental dynamic analysis, in the model's time scale.

- ``sa``: the 5 %-damped pseudo-spectral acceleration Sa(T) = (2 pi / T)^2 max|u(t)| of a linear
  single-degree-of-freedom oscillator at the isolated period T (the supports-alone period of the
  structure: 1.0 s model time for the default one), computed by the ``eqsig`` package
  (``eqsig.sdof.pseudo_response_spectra``: Nigam and Jennings 1968, exact for an acceleration linear
  between samples, which is how the model reads a record too), per component; IM = sqrt(Sa_A Sa_B),
  the geometric mean of the two horizontal components (FEMA P695's convention);
- ``pga``: sqrt(PGA_A PGA_B), PGA = max|a_g| of a component.

Time scale: the records run in model time, t_model = time_factor t_record (sqrt(0.1), Froude 1:10
similitude; accelerations unchanged), so Sa(1.0 s) here is the full-scale record's Sa at
1.0 / sqrt(0.1) = 3.16 s. Each component is sampled at its own interval (DT time_factor), the ramp to
zero after its last sample included (nsd_core.ground.motions). Both measures are linear in the
record's scale factor: a record at IM = x runs with scale x / IM(scale 1).
"""
from __future__ import annotations

import math

import numpy as np

from nsd_core.device.params import ParameterError

MEASURES = ("sa", "pga")
DAMPING = 0.05  # of critical: the conventional response-spectrum damping


def component_sa(t: np.ndarray, a: np.ndarray, period: float, damping: float = DAMPING) -> float:
    """Sa of one uniformly sampled component (eqsig), m/s^2."""
    from eqsig import sdof
    h = np.diff(t)
    if len(t) < 2 or np.ptp(h) > 1e-9 * h[0]:
        raise ParameterError("intensity: a component must be sampled at a uniform interval")
    return float(sdof.pseudo_response_spectra(np.asarray(a, dtype=float), float(h[0]), np.array([period]),
                                              damping)[2][0])


def record_intensity(motion, measure: str, period: float) -> dict:
    """{"value": IM at the motion's own scale [m/s^2], "components": [A, B], ...} of a Record
    (nsd_core.ground.motions.fema_record)."""
    if measure not in MEASURES:
        raise ParameterError(f"--measure {measure!r}: unknown; allowed: {', '.join(MEASURES)}")
    comps = []
    for c in motion.comp:
        if measure == "pga":
            comps.append(float(np.max(np.abs(c.a))))
        else:
            comps.append(component_sa(c.t, c.a, period))
    out = {"measure": measure, "value": math.sqrt(comps[0] * comps[1]), "components": comps, "unit": "m/s^2",
           "combination": "geometric mean of components A and B"}
    if measure == "sa":
        out.update(period=period, damping=DAMPING, library="eqsig.sdof.pseudo_response_spectra (Nigam-Jennings)")
    out["time_scale"] = "model time (record time x time_factor)"
    return out


def design_level_scale(motion_at_scale_1) -> dict:
    """The record's scale factor at the design level: Sa(T_D) of the design spectrum over the record's
    (5 %-damped, geometric mean of the two components, at the model's T_D), scaled by the similitude
    of nsd_core.structure.design (here, in the study layer, because the intensity measure lives here)."""
    from nsd_core.structure.design import design
    d = design()
    own = record_intensity(motion_at_scale_1, "sa", d["T_D_model_s"])["value"]
    target = d["Sa_TD_model_m_s2"]
    return {"scale": target / own, "Sa_target_m_s2": target, "Sa_record_scale1_m_s2": own,
            "period_model_s": d["T_D_model_s"]}
