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

from . import __version__
from .params import FIELDS, ParameterError, Params
from .results import atomic_write_json, atomic_write_text
from .tables import TABLE5, TABLE6, x_max_at_slack

DEFAULT_FIT = ("rope_upper_height", "spring_kse", "spring_ksd", "spring_beta", "spring_gamma")
LINEAR = {"rope_upper_height": 1e-3}   # fitted linearly, in mm; the rest in log (they stay positive)
ROUNDING_SD_MM = 0.1 / math.sqrt(12.0)  # the paper prints X_max to 0.1 mm
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


def calibrate(base: Params | None = None, fit=DEFAULT_FIT) -> dict:
    """Least-squares fit of ``fit`` to Tables 5 and 6; returns values, residuals, uncertainty."""
    base = base or Params()
    fit = tuple(fit)
    _check_fit(fit)
    start = time.perf_counter()
    ent = entries(base)
    x0 = _to_vars(base, fit)

    def fun(x):
        ch = _to_values(x, fit)
        try:
            return np.array([(x_max_at_slack(q.replace(**ch)) - xm) * 1e3 for _, q, xm in ent])
        except (ParameterError, ValueError):
            return np.full(len(ent), 1e3)  # an impossible device: a large, flat penalty
    r0 = fun(x0)
    sol = least_squares(fun, x0, jac="3-point", method="trf", x_scale="jac", diff_step=1e-6,
                        xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=400)
    J, r = sol.jac, sol.fun
    m, k = J.shape
    U, sv, Vt = np.linalg.svd(J, full_matrices=False)
    tol = sv[0] * 1e-6 if len(sv) and sv[0] > 0 else 0.0
    rank = int(np.sum(sv > tol))
    rss = float(r @ r)
    s2 = rss / max(m - rank, 1)
    inv = (Vt[:rank].T / sv[:rank] ** 2) @ Vt[:rank]   # pseudo-inverse of J^T J on the identified subspace
    values = _to_values(sol.x, fit)
    unc = {}
    for i, n in enumerate(fit):
        in_null = rank < k and np.max(np.abs(Vt[rank:, i])) > 1e-3
        sd_var = math.sqrt(s2 * inv[i, i]) if not in_null else math.inf
        sd_round = math.sqrt(ROUNDING_SD_MM ** 2 * inv[i, i]) if not in_null else math.inf
        scale = LINEAR[n] if n in LINEAR else values[n]   # d(value)/d(variable)
        unc[n] = {"value": values[n], "start": getattr(base, n), "unit": FIELDS[n].metadata["unit"],
                  "sd": sd_var * scale, "sd_from_rounding": sd_round * scale,
                  "relative_sd": sd_var * scale / abs(values[n]) if values[n] else math.inf}
    # zero sensitivity of the wire values: X_max at +10 % of each
    probes = {}
    for n in WIRE_PROBES:
        r_plus = residuals_mm(base.replace(**values), {n: getattr(base, n) * 1.1})
        probes[n] = float(np.max(np.abs(r_plus - r)))
    return {
        "fit": list(fit), "values": values, "uncertainty": unc, "start": {n: getattr(base, n) for n in fit},
        "entries": [e[0] for e in ent], "paper_x_max": [e[2] for e in ent],
        "residuals_start_mm": r0.tolist(), "residuals_mm": r.tolist(),
        "rms_start_mm": float(np.sqrt(np.mean(r0 ** 2))), "rms_mm": float(np.sqrt(np.mean(r ** 2))),
        "max_abs_start_mm": float(np.max(np.abs(r0))), "max_abs_mm": float(np.max(np.abs(r))),
        "singular_values": sv.tolist(), "rank": rank, "n_params": k, "n_residuals": m,
        "condition_number": float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf,
        "null_directions": [dict(zip(fit, np.round(v, 4).tolist())) for v in Vt[rank:]],
        "weakest_direction": dict(zip(fit, np.round(Vt[-1], 4).tolist())),
        "wire_sensitivity_mm_per_10pct": probes, "status": sol.message, "nfev": sol.nfev,
        "wall_time": time.perf_counter() - start, "version": __version__,
    }


def format_report(c: dict) -> str:
    out = [f"calibration of {', '.join(c['fit'])} to Tables 5 and 6 ({c['n_residuals']} entries, X_max in mm)",
           f"  rms residual {c['rms_start_mm']:.4f} -> {c['rms_mm']:.4f} mm; max |residual| "
           f"{c['max_abs_start_mm']:.4f} -> {c['max_abs_mm']:.4f} mm ({c['nfev']} evaluations, {c['wall_time']:.1f} s)"]
    for n, u in c["uncertainty"].items():
        sd = "unidentifiable" if not math.isfinite(u["sd"]) else f"+/- {u['sd']:.4g} ({100 * u['relative_sd']:.2g} %)"
        out.append(f"  {n:>20} = {u['value']:.6g} {u['unit']} (start {u['start']:.6g}) {sd}")
    out.append(f"  Jacobian: singular values {', '.join(f'{s:.3g}' for s in c['singular_values'])}; rank "
               f"{c['rank']} of {c['n_params']}; condition number {c['condition_number']:.3g}")
    out.append(f"  weakest direction (log variables): {c['weakest_direction']}")
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
                                     ("unidentifiable" if not math.isfinite(u["sd"]) else f"{u['sd']:.3g}"))
        lines.append(f"{n} = {float(getattr(p, n))!r}{note}" if FIELDS[n].metadata["kind"] is float
                     else f"{n} = {int(getattr(p, n))}{note}")
    lines += ["", "[provenance]", f'method = "scipy.optimize.least_squares on quasi-static X_max (nsd calibrate)"',
              f'data = "Dai et al. 2024, Tables 5 and 6 (16 entries)"', f'version = "{c["version"]}"',
              f'start = "{start_file or "nominal defaults (nsd_core/params.py)"}"',
              f"rms_residual_mm = {c['rms_mm']:.6g}", f"max_abs_residual_mm = {c['max_abs_mm']:.6g}",
              f"jacobian_rank = {c['rank']}", f"condition_number = {c['condition_number']:.6g}",
              f'fitted = [{", ".join(repr(n).replace(chr(39), chr(34)) for n in c["fit"])}]',
              'note = "wire values do not affect X_max and are not fitted"', ""]
    return "\n".join(lines)


def write_outputs(c: dict, out: str | Path, base: Params | None = None, start_file: str | None = None) -> list[Path]:
    out = Path(out)
    base = base or Params()
    atomic_write_text(out / "calibrated_params.toml", params_toml(c, base, start_file))
    atomic_write_json(out / "calibration.json", c)
    return [out / "calibrated_params.toml", out / "calibration.json"]
