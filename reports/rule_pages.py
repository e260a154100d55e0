"""Report text of the gate's rule (comparisons/verdict.py): the engineering tolerances in units on
page 1, and the definitions page with the rule and every metric's tolerance."""
from __future__ import annotations

from reports.metric_tables import in_units
from reports.style import fmt


def tolerance_line(s: dict) -> str:
    """The engineering tolerances in words and in units (their range over the cases)."""
    by_metric: dict[str, list] = {}
    for r in s["metrics"]:
        if r["gated"] and r.get("tolerance_abs") is not None and r.get("reference"):
            by_metric.setdefault(r["metric"], []).append(r)
    parts = []
    for m, rows in by_metric.items():
        lo, hi = min(r["tolerance_abs"] for r in rows), max(r["tolerance_abs"] for r in rows)
        unit = rows[0]["unit"]
        span = in_units(lo, unit) if lo == hi else f"{in_units(lo, unit)} to {in_units(hi, unit)}"
        parts.append(f"{m} {fmt(rows[0]['tolerance'], 2)} ({span})")
    own = (s["rule"].get("engineering") or {})
    return ("Engineering tolerances (a fraction of the reference's peak; in units over the cases): " + "; ".join(parts)
            + f"; own checks: closure {in_units(own.get('closure_max'), 'm')}, tracking "
              f"{in_units(own.get('tracking_error'), 'm')}, energy balance {fmt(own.get('energy_balance_rel'), 2)} "
              f"of the work.")


OF = {"max_dF_rel": "peak force", "rms_dF_rel": "peak force", "peak_force_rel": "peak force",
      "loop_area_rel": "work per cycle", "region_shift_rel": "amplitude", "closure_max": "m (absolute)",
      "tracking_error": "m (absolute)", "energy_balance_rel": "drive work per cycle",
      "max_du_rel": "peak plate displacement", "peak_u_rel": "peak plate displacement",
      "max_dF_device_rel": "peak device force", "peak_a_rel": "peak absolute acceleration",
      "energy_residual_rel": "peak input energy", "max_dfloor_rel": "peak floor displacement",
      "max_ddrift_rel": "peak story drift", "max_dfloor_a_rel": "peak floor acceleration"}


def rule_pages(s: dict, defs: dict, units: dict, table_pages, subtitle) -> list:
    """The estimated rule: every metric with its definition and engineering tolerance, and the rule."""
    rule = s["rule"]
    rows = [[m, units.get(m, "-"), defs.get(m, "-"), fmt(tol, 3), OF.get(m, "-")]
            for m, tol in (rule.get("engineering") or {}).items()]
    cols = [("metric", 1, "l"), ("unit", 1, "c"), ("definition (F_ref, u_ref: the converged reference's)", 1, "l"),
            ("engineering\ntolerance", 1, "r"), ("a fraction of", 1, "l")]
    k, beta = rule.get("k"), rule.get("beta")
    text = [["estimated error", "a fixed-step peer: its difference between its runs at h and 2h / (r^p - 1), "
             "p its method's order (MuJoCo Euler 1, RK4 2, Exudyn 2); the in-house engine: its difference from the "
             "converged reference; the reference: its difference from its rtol 1e-11 check"],
            ["consistent", f"difference from the converged reference <= {fmt(k, 3)} x (estimated error + "
             "reference's); otherwise DISAGREES beyond numerical error: the engines differ about the model"],
            ["accurate enough", "max(estimated error, difference) <= the engineering tolerance; otherwise NOT "
             "CONVERGED at these settings, with the step the estimate asks for (nsd compare --refine runs it)"],
            ["own checks", "closure, tracking and energy balance against their tolerance; an energy balance beyond the "
             "converged reference's own (the output grid's quadrature error)"],
            ["undecided", "beyond the bound, where the engine's own estimate is over the tolerance, where its "
             "companion run (the same model at the other step) is within the bound, or where the difference did not "
             "fall with the step (observed order < p - 1) and is within the bound at first order: its two runs "
             "cannot call it numerical or not; nsd compare --refine decides at a finer step (one that has still not "
             "fallen there DISAGREES)"],
            ["scalar metrics", f"a peak or loop-work difference can cancel by chance between h and 2h: its estimate "
             f"is at least {fmt(beta, 3)} x the estimate of the max-norm difference it comes from, and its bound at "
             "least what that metric's bound implies for it (a peak: the same; the loop work: x peak force x path "
             "length / work)"],
            ["PASS", rule.get("text", "")]]
    blocks = [("The rule (comparisons/verdict.py; the constants: the tolerance file's [verdict])",
               [("", 1, "l"), ("", 1, "l")], text),
              ("Metrics and their engineering tolerances ([engineering] of the tolerance file)", cols, rows)]
    sub = subtitle(s, "", "the rule's default tolerance")
    return table_pages("Metrics: definitions, the rule and the engineering tolerances", sub, blocks)
