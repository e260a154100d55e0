"""Fit the values the paper does not print (Tables 3 and 4 are missing; h_ru is not given) to the
X_max of its Tables 5 and 6, by least squares on the quasi-static X_max.

Residuals: model minus paper X_max [mm] for the 16 entries (Table 5's 0.03 m column and Table 6's
3800 N column are the same design, so 15 distinct points). X_max is evaluated with the direct
slack-point construction of ``nsd_core.tables`` (the same quantity as ``quasistatic.x_max``,
checked in the tests), milliseconds per entry.

What X_max can identify: at the slack point the ropes pull nothing and the spring's push equals
the carried weight, so X_max depends on the spring only through the extension from the
precompressed state to P = W, and on the ropes only through their geometry and natural length.
The wires do not enter at all (their Jacobian columns are exactly zero), so no wire value is
fitted. Several spring values can trade off against each other; the Jacobian's singular values,
rank and condition number say how many combinations the tables pin down.

Uncertainty: cov = s^2 (J^T J)^-1 in the fitted variables (log of the positive parameters, h_ru
in mm), with s^2 = RSS / (m - rank); also reported with s = 0.0289 mm, the standard deviation of
the paper's rounding to 0.1 mm. Directions with a singular value below 1e-6 of the largest are
reported as unidentifiable (no finite uncertainty).
"""
from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from nsd_core import __version__
from nsd_core.device.params import FIELDS, ParameterError, Params
from nsd_core.common.files import atomic_write_json, atomic_write_text
from nsd_core.device.working_range import x_max_at_slack
from nsd_core.study.tables import TABLE5, TABLE6

DEFAULT_FIT = ("rope_upper_height", "spring_kse", "spring_ksd", "spring_beta", "spring_gamma")
LINEAR = {"rope_upper_height": 1e-3}   # fitted linearly, in mm; the rest in log (they stay positive)
ROUNDING_SD_MM = 0.1 / math.sqrt(12.0)  # the paper prints X_max to 0.1 mm: the data's own noise
PRIOR_SD = 0.5  # on the log of each positive fitted value: a factor e^0.5 = 1.65 either way
WIRE_PROBES = ("wire_diameter", "wire_E", "wire_Y")  # shown to have zero sensitivity


def entries(base: Params) -> list[tuple[str, Params, float]]:
    out = []
    for spec in (TABLE5, TABLE6):
        for v, xm in zip(spec["values"], spec["x_max"]):
            out.append((f"{spec['where']} {spec['parameter']}={v:g}", base.replace(**{spec["parameter"]: v}), xm))
    return out


def _to_vars(p: Params, fit) -> np.ndarray:
    return np.array([getattr(p, n) / LINEAR[n] if n in LINEAR else math.log(getattr(p, n)) for n in fit])


def _to_values(x, fit) -> dict[str, float]:
    return {n: float(v * LINEAR[n] if n in LINEAR else math.exp(v)) for n, v in zip(fit, x)}


def residuals_mm(base: Params, changes: dict | None = None) -> np.ndarray:
    """Model minus paper X_max [mm], entry by entry, for ``base`` with ``changes``."""
    return np.array([(x_max_at_slack(q) - xm) * 1e3 for _, q, xm in entries(base.replace(**(changes or {})))])


def _check_fit(fit) -> None:
    for n in fit:
        if n not in FIELDS:
            raise ParameterError(f"--fit {n}: unknown parameter; allowed: {', '.join(sorted(FIELDS))}")
        if FIELDS[n].metadata["kind"] is int:
            raise ParameterError(f"--fit {n}: a whole-number parameter cannot be fitted by least squares")
        if n in ("rod_length", "precompression_force"):
            raise ParameterError(f"--fit {n}: is the tables' own variable; it cannot be fitted")
    if len(set(fit)) != len(fit) or not fit:
        raise ParameterError(f"--fit {','.join(fit)}: name each parameter once, at least one")


def calibrate(base: Params | None = None, fit=DEFAULT_FIT, prior_sd: float = PRIOR_SD) -> dict:
    """Fit ``fit`` to Tables 5 and 6: values, residuals, uncertainty and identifiability.

    Objective: sum (r_i / s_round)^2 + sum ((x_j - x0_j) / prior_sd)^2, r in mm, x the fitted
    variables (log values; h_ru in mm, no prior). The weak prior only holds the combinations the
    tables cannot see at their nominal values; prior_sd = 0 drops it (pure least squares, which then
    drifts along the flat directions). Identifiability is judged on the data Jacobian alone.
    """
    base = base or Params()
    fit = tuple(fit)
    _check_fit(fit)
    if not (prior_sd >= 0 and math.isfinite(prior_sd)):
        raise ParameterError(f"prior_sd = {prior_sd}: must be a finite number >= 0")
    start = time.perf_counter()
    ent = entries(base)
    x0 = _to_vars(base, fit)
    has_prior = np.array([prior_sd > 0 and n not in LINEAR for n in fit])

    def data(x):
        ch = _to_values(x, fit)
        try:
            return np.array([(x_max_at_slack(q.replace(**ch)) - xm) * 1e3 for _, q, xm in ent])
        except (ParameterError, ValueError, ArithmeticError):
            return np.full(len(ent), 1e3)  # an impossible device: a large, flat penalty

    def fun(x):
        prior = (x - x0)[has_prior] / prior_sd if has_prior.any() else np.zeros(0)
        return np.concatenate([data(x) / ROUNDING_SD_MM, prior])
    r0 = data(x0)
    sol = least_squares(fun, x0, jac="3-point", method="trf", x_scale="jac", diff_step=1e-6,
                        xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=400)
    m = len(ent)
    r = sol.fun[:m] * ROUNDING_SD_MM
    Jd = sol.jac[:m] * ROUNDING_SD_MM        # d r [mm] / d x, data only
    U, sv, Vt = np.linalg.svd(Jd, full_matrices=False)
    rank = int(np.sum(sv > (sv[0] * 1e-6 if sv[0] > 0 else 0.0)))
    k = len(fit)
    s2 = float(r @ r) / max(m - rank, 1)
    data_inv = (Vt[:rank].T / sv[:rank] ** 2) @ Vt[:rank]  # (J^T J)^+ on the identified subspace
    post_cov = np.linalg.pinv(sol.jac.T @ sol.jac)           # whitened: the posterior covariance
    values = _to_values(sol.x, fit)
    unc = {}
    for i, n in enumerate(fit):
        in_null = rank < k and np.max(np.abs(Vt[rank:, i])) > 1e-3
        scale = LINEAR[n] if n in LINEAR else values[n]      # d(value) / d(variable)
        sd_data = math.inf if in_null else math.sqrt(s2 * data_inv[i, i]) * scale
        sd_post = math.sqrt(post_cov[i, i]) * scale
        informed = not has_prior[i] or math.sqrt(post_cov[i, i]) < 0.9 * prior_sd
        unc[n] = {"value": values[n], "start": getattr(base, n), "unit": FIELDS[n].metadata["unit"],
                  "sd_data": sd_data, "relative_sd_data": sd_data / abs(values[n]) if values[n] else math.inf,
                  "sd_posterior": sd_post, "informed_by_tables": bool(informed)}
    probes = {}
    for n in WIRE_PROBES:  # X_max at +10 % of each wire value: the wires do not enter
        probes[n] = float(np.max(np.abs(residuals_mm(base.replace(**values), {n: getattr(base, n) * 1.1}) - r)))
    return {
        "fit": list(fit), "values": values, "uncertainty": unc, "start": {n: getattr(base, n) for n in fit},
        "prior_sd_log": prior_sd, "rounding_sd_mm": ROUNDING_SD_MM, "residual_sd_mm": math.sqrt(s2),
        "entries": [e[0] for e in ent], "paper_x_max": [e[2] for e in ent],
        "residuals_start_mm": r0.tolist(), "residuals_mm": r.tolist(),
        "rms_start_mm": float(np.sqrt(np.mean(r0 ** 2))), "rms_mm": float(np.sqrt(np.mean(r ** 2))),
        "max_abs_start_mm": float(np.max(np.abs(r0))), "max_abs_mm": float(np.max(np.abs(r))),
        "singular_values": sv.tolist(), "rank": rank, "n_params": k, "n_residuals": m,
        "condition_number": float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf,
        "right_singular_vectors": [dict(zip(fit, np.round(v, 4).tolist())) for v in Vt],
        "wire_sensitivity_mm_per_10pct": probes, "status": sol.message, "nfev": sol.nfev,
        "wall_time": time.perf_counter() - start, "version": __version__,
    }


def format_report(c: dict) -> str:
    out = [f"calibration of {', '.join(c['fit'])} to Tables 5 and 6 ({c['n_residuals']} entries, X_max in mm)",
           f"  rms residual {c['rms_start_mm']:.4f} -> {c['rms_mm']:.4f} mm; max |residual| "
           f"{c['max_abs_start_mm']:.4f} -> {c['max_abs_mm']:.4f} mm; the paper's rounding alone gives an rms "
           f"of {c['rounding_sd_mm']:.4f} mm ({c['nfev']} evaluations, {c['wall_time']:.1f} s)"]
    for n, u in c["uncertainty"].items():
        sd = ("unidentifiable" if not math.isfinite(u["sd_data"])
              else f"+/- {u['sd_data']:.3g} ({100 * u['relative_sd_data']:.2g} %)")
        post = "" if u["informed_by_tables"] else "  [set by the prior, not by the tables]"
        out.append(f"  {n:>20} = {u['value']:.6g} {u['unit']} (start {u['start']:.6g}); data-only sd {sd}; "
                   f"posterior sd {u['sd_posterior']:.3g}{post}")
    out.append(f"  data Jacobian: singular values {', '.join(f'{s:.3g}' for s in c['singular_values'])}; rank "
               f"{c['rank']} of {c['n_params']}; condition number {c['condition_number']:.3g}")
    out.append(f"  weakest direction (log variables): {c['right_singular_vectors'][-1]}")
    out.append("  wires: |change of X_max| for +10 % = " + ", ".join(
        f"{n} {v:.1e} mm" for n, v in c["wire_sensitivity_mm_per_10pct"].items()) + " (not identifiable: not fitted)")
    for name, r0, r in zip(c["entries"], c["residuals_start_mm"], c["residuals_mm"]):
        out.append(f"    {name:>36}: {r0:+.4f} -> {r:+.4f} mm")
    return "\n".join(out)


def params_toml(c: dict, base: Params, start_file: str | None = None) -> str:
    """Flat ``name = value`` (loadable by ``nsd cycle --params``) plus a [provenance] table."""
    p = base.replace(**c["values"])
    defaults = Params()
    names = [n for n in FIELDS if n in c["values"] or getattr(p, n) != getattr(defaults, n)]
    lines = ["# Parameter set calibrated to Tables 5 and 6 of Dai et al. 2024 (nsd calibrate).",
             f"# Least squares on the quasi-static X_max; rms residual {c['rms_start_mm']:.4f} -> {c['rms_mm']:.4f} mm,",
             f"# max {c['max_abs_start_mm']:.4f} -> {c['max_abs_mm']:.4f} mm. Jacobian rank {c['rank']} of "
             f"{c['n_params']}, condition {c['condition_number']:.3g}.",
             "# Unlisted parameters keep their defaults (nsd_core/params.py).", ""]
    for n in names:
        u = c["uncertainty"].get(n)
        note = "" if u is None else (f"  # fitted; start {u['start']:.6g}; sd " +
                                     ("unidentifiable" if not math.isfinite(u["sd_data"]) else f"{u['sd_data']:.3g}"))
        lines.append(f"{n} = {float(getattr(p, n))!r}{note}" if FIELDS[n].metadata["kind"] is float
                     else f"{n} = {int(getattr(p, n))}{note}")
    lines += ["", "[provenance]", f'method = "scipy.optimize.least_squares on quasi-static X_max (nsd calibrate)"',
              f'data = "Dai et al. 2024, Tables 5 and 6 (16 entries)"', f'version = "{c["version"]}"',
              f'start = "{start_file or "nominal defaults (nsd_core/params.py)"}"',
              f"rms_residual_mm = {c['rms_mm']:.6g}", f"max_abs_residual_mm = {c['max_abs_mm']:.6g}",
              f"jacobian_rank = {c['rank']}", f"prior_sd_log = {c['prior_sd_log']}", f"condition_number = {c['condition_number']:.6g}",
              f'fitted = [{", ".join(repr(n).replace(chr(39), chr(34)) for n in c["fit"])}]',
              'note = "wire values do not affect X_max and are not fitted"', ""]
    return "\n".join(lines)


def write_outputs(c: dict, out: str | Path, base: Params | None = None, start_file: str | None = None) -> list[Path]:
    out = Path(out)
    base = base or Params()
    atomic_write_text(out / "calibrated_params.toml", params_toml(c, base, start_file))
    atomic_write_json(out / "calibration.json", c)
    return [out / "calibrated_params.toml", out / "calibration.json"]
