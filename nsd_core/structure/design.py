"""The isolated structure designed for its records (docs/design.md).

Reads ``design_basis.toml`` (full scale, every value with unit and source) and gives, at model
scale under its similitude:

* the design spectrum of ASCE/SEI 7-16 Section 11.4.6 from S_DS, S_D1 and T_L;
* the design displacement D_D = g S_D1 T_D / (4 pi^2 B_D) (ASCE 7-10 Eq. 17.5-1; ASCE 7-16 Eq.
  17.5-1 is the same form at the MCE_R level, D_M with S_M1 = 1.5 S_D1, also reported), with B_D
  from the effective damping by Table 17.5-1 (linear between its rows);
* the designed structure: M and k_b fixed numbers of the table (not derived from the device, so a
  device variant leaves them unchanged), c_b from the damping ratio (the design level's supplemental
  damping when the study is at the design level);
* the stroke check: D_D and D_M against the device's working range X_max and the rod's reach.

Similitude (Froude, lengths x s, accelerations x 1): time x sqrt(s), mass and force x s^3,
stiffness x s^2, viscous coefficient x s^2.5; a spectrum's ordinate at full-scale period T is the
model's at T sqrt(s).
"""
from __future__ import annotations

import math
import tomllib
from functools import lru_cache
from pathlib import Path

from nsd_core.device.params import ParameterError

BASIS = Path(__file__).with_name("design_basis.toml")
G = 9.80665  # m/s^2, standard gravity (the spectra's g)
# ASCE/SEI 7-16 Table 17.5-1: effective damping [fraction] -> damping coefficient B
B_TABLE = ((0.02, 0.8), (0.05, 1.0), (0.10, 1.2), (0.20, 1.5), (0.30, 1.7), (0.40, 1.9), (0.50, 2.0))


@lru_cache(maxsize=1)
def basis() -> dict:
    """The design basis table: {section: {name: {"value", "unit", "source"}}}."""
    return tomllib.loads(BASIS.read_text())


def value(section: str, name: str):
    return basis()[section][name]["value"]


def damping_coefficient(beta: float) -> float:
    """B of ASCE 7-16 Table 17.5-1 at effective damping beta (a fraction), linear between rows,
    the end rows' values beyond them (the table's 'less than or equal to 2 %', '50 % or more')."""
    if not (math.isfinite(beta) and beta >= 0):
        raise ParameterError(f"effective damping = {beta!r}: must be a finite number >= 0")
    if beta <= B_TABLE[0][0]:
        return B_TABLE[0][1]
    for (b0, v0), (b1, v1) in zip(B_TABLE, B_TABLE[1:]):
        if beta <= b1:
            return v0 + (v1 - v0) * (beta - b0) / (b1 - b0)
    return B_TABLE[-1][1]


def spectrum(period: float, s_ds: float | None = None, s_d1: float | None = None, t_l: float | None = None) -> float:
    """Design spectral acceleration Sa(T) [g] at full-scale period T [s] (ASCE 7-16 11.4.6)."""
    s_ds = value("site", "S_DS") if s_ds is None else s_ds
    s_d1 = value("site", "S_D1") if s_d1 is None else s_d1
    t_l = value("site", "T_L") if t_l is None else t_l
    t0, ts = 0.2 * s_d1 / s_ds, s_d1 / s_ds
    if period < t0:
        return s_ds * (0.4 + 0.6 * period / t0)
    if period <= ts:
        return s_ds
    if period <= t_l:
        return s_d1 / period
    return s_d1 * t_l / period ** 2


def scale() -> float:
    return float(value("similitude", "length_scale"))


def design_displacement(s_d1: float, period: float, beta: float) -> float:
    """ASCE 7 Eq. 17.5-1: g S_D1 T / (4 pi^2 B(beta)) [m] (full scale; S_D1 in g, T in s)."""
    return G * s_d1 * period / (4.0 * math.pi ** 2 * damping_coefficient(beta))


def design() -> dict:
    """The design level, its displacements and the stroke check, full scale and model scale."""
    s = scale()
    T = float(value("isolation", "design_period"))
    beta = float(value("structure", "design_damping_ratio"))
    s_d1 = float(value("site", "S_D1"))
    d_d = design_displacement(s_d1, T, beta)
    d_m = design_displacement(1.5 * s_d1, T, beta)
    stroke, reach = float(value("isolation", "stroke")), float(value("isolation", "rod_reach"))
    sa = spectrum(T)
    return {"code": value("site", "code"), "site_class": value("site", "site_class"),
            "S_DS_g": value("site", "S_DS"), "S_D1_g": s_d1, "T_L_s": value("site", "T_L"),
            "T_D_s": T, "T_D_model_s": T * math.sqrt(s), "beta_D": beta, "B_D": damping_coefficient(beta),
            "Sa_TD_g": sa, "Sa_TD_model_m_s2": sa * G,
            "D_D_m": d_d, "D_D_model_m": d_d * s, "D_M_m": d_m, "D_M_model_m": d_m * s,
            "stroke_m": stroke, "rod_reach_m": reach,
            "margin_D_D_stroke": stroke / d_d, "margin_D_D_reach": reach / d_d,
            "margin_D_M_stroke": stroke / d_m, "margin_D_M_reach": reach / d_m,
            "similitude_length_scale": s, "source": str(BASIS.name)}


def designed_structure_args(design_level: bool = False) -> tuple:
    """The isolated structure of the design basis at model scale, as the arguments of
    nsd_core.structure.isolation.Structure (``isolation.designed_structure`` builds it: this module does
    not import isolation, which imports it): the same for every device. design_level: the isolation
    level's damping is the design's supplemental damping (``design_damping_ratio``), else the
    supports' own ``damping_ratio``."""
    s = scale()
    M = float(value("structure", "mass")) * s ** 3
    k = float(value("structure", "stiffness")) * s ** 2
    name = "design_damping_ratio" if design_level else "damping_ratio"
    zeta = float(value("structure", name))
    side = float(value("structure", "slab_side")) * s
    src = f"{BASIS.name} [structure]"
    prov = {"mass": f"{src} mass x {s:g}^3: {basis()['structure']['mass']['source']}",
            "stiffness": f"{src} stiffness x {s:g}^2: {basis()['structure']['stiffness']['source']}",
            "damping": f"{src} {name} = {zeta:g} of critical for M and k_b: {basis()['structure'][name]['source']}",
            "radius_of_gyration": f"{src} slab_side x {s:g} / sqrt(6)",
            "support_radius": f"{src} slab_side x {s:g} / 2",
            "params": "fixed by the design basis: the same for every device (--resize derives it from the device)",
            "design_level": bool(design_level)}
    return (M, side / math.sqrt(6.0), k, 2.0 * zeta * math.sqrt(k * M), side / 2.0, prov)
