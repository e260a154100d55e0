"""The gate's rows (comparisons.harness): each metric of each engine against the converged reference
and the other engines, with the limit it is held to and where that limit came from; the converged
reference's own checks; the observed order's rows; a seismic run's peaks."""
from __future__ import annotations

from comparisons.config import SeismicCase
from comparisons.energy import energy_balance_rel
from comparisons.engines import REFERENCE
from comparisons.metrics import own_metrics, pair_metrics
from comparisons.reference import CONVERGED, order_rows
from comparisons.seismic import gate_metrics, own_seismic_metrics
from nsd_core.device.geometry import device_geometry
from nsd_core.device.results import RunResult


class AppliedLimit(float):
    """A limit that knows where it came from: "default" ([limits]), "engine" ([limits.ENGINE]) or
    "case" ([limits.ENGINE.case."CASE"]); ``_row`` writes both into results.json."""
    source = "default"

    def __new__(cls, value: float, source: str):
        obj = super().__new__(cls, value)
        obj.source = source
        return obj


def limit_for(tolerances, engine, case, metric):
    """Per-engine-and-case limits when the tolerances have them (tolerance_file.Limits), else the flat one;
    the most specific wins, returned as an AppliedLimit that names its source (None: no limit)."""
    own = getattr(tolerances, "engines", {}).get(engine, {})
    for source, table in (("case", own.get("case", {}).get(case, {})), ("engine", own), ("default", tolerances)):
        if metric in table and table[metric] is not None:
            return AppliedLimit(table[metric], source)
    return None


def _metrics(cases, engines, tolerances, runs, results) -> list[dict]:
    """Every engine, the in-house one included, against the converged reference (gated); every
    engine against the in-house run at its case settings and every other pair (reported, not gated)."""
    rows = []
    others = [e for e in engines if e != REFERENCE]
    pairs = [(e, CONVERGED, True) for e in engines]
    pairs += [(e, REFERENCE, False) for e in others if REFERENCE in engines]
    pairs += [(a, b, False) for i, a in enumerate(others) for b in others[i + 1:]]
    for c in cases:
        if isinstance(c, SeismicCase):
            rows += _seismic_rows(c, engines, pairs, tolerances, results)
            continue
        for e in engines:
            if (c.name, e) in results:
                own = own_metrics(results[(c.name, e)])
                own["energy_balance_rel"] = energy_balance_rel(results[(c.name, e)], device_geometry(c.params),
                                                               c.drive.frequency, c.drive.unit_vector)
                for k, v in own.items():
                    if (lim := limit_for(tolerances, e, c.name, k)) is not None:
                        rows.append(_row(c.name, e, None, k, v, lim, True))
        for a, b, gated in pairs:
            if (c.name, a) in results and (c.name, b) in results:
                ra, rb = runs[c.name][a]["summary"], runs[c.name][b]["summary"]
                m = pair_metrics(results[(c.name, a)], results[(c.name, b)], ra, rb, c.drive.amplitude,
                                 c.drive.frequency)
                for k, v in m.items():
                    if (lim := limit_for(tolerances, a, c.name, k)) is not None:
                        rows.append(_row(c.name, a, b, k, v, lim, gated))
    return rows


def _seismic_rows(c, engines, pairs, tolerances, results) -> list[dict]:
    """A seismic case: each engine's own energy balance and closure, every engine against the reference
    on the time histories (comparisons.seismic.gate_metrics)."""
    rows = []
    for e in engines:
        if (c.name, e) in results:
            for k, v in own_seismic_metrics(results[(c.name, e)]).items():
                if (lim := limit_for(tolerances, e, c.name, k)) is not None:
                    rows.append(_row(c.name, e, None, k, v, lim, True))
    for a, b, gated in pairs:
        if (c.name, a) in results and (c.name, b) in results:
            for k, v in gate_metrics(results[(c.name, b)], results[(c.name, a)]).items():
                if (lim := limit_for(tolerances, a, c.name, k)) is not None:
                    rows.append(_row(c.name, a, b, k, v, lim, gated))
    return rows


def _converged_own(cases, results) -> dict:
    """The converged reference's own metrics per case (closure, tracking, energy balance; seismic:
    energy residual, closure): the floor of the limits on those (benchmarks/derive_limits.py)."""
    out = {}
    for c in cases:
        r = results.get((c.name, CONVERGED))
        if r is None:
            continue
        if isinstance(c, SeismicCase):
            out[c.name] = own_seismic_metrics(r)
        else:
            own = own_metrics(r)
            own["energy_balance_rel"] = energy_balance_rel(r, device_geometry(c.params), c.drive.frequency,
                                                           c.drive.unit_vector)
            out[c.name] = own
    return out


def _order_rows(order, engines, by_name, results, tolerances) -> tuple[list[dict], dict]:
    """Each listed peer's error at its case step, halved and quartered, against the converged
    reference: the observed order, gated within its band (comparisons.reference.order_rows)."""
    from comparisons.reference import ORDER_DIVISORS, ORDER_METRIC
    errors = {}
    for e, spec in order.items():
        c = by_name.get(spec["case"])
        labels = [e] + [f"{e}_h{d}" for d in ORDER_DIVISORS]
        if e not in engines or c is None or not all((c.name, lab) in results for lab in labels + [CONVERGED]):
            continue
        ref = results[(c.name, CONVERGED)]
        d = c.drive
        errors[e] = [pair_metrics(results[(c.name, lab)], ref, {}, {}, d.amplitude, d.frequency)[ORDER_METRIC]
                     for lab in labels]
    # the band: the tolerance file's order_deviation; 0.5 under the estimated rule, where the rows are evidence
    return order_rows(order, errors, _row, lambda e, case: limit_for(tolerances, e, case, "order_deviation") or 0.5)


def _seismic_peaks(r: RunResult) -> dict:
    """Peaks of a seismic run (with their times) for results.json."""
    import numpy as np
    t = r["t"]

    def peak(v):
        k = int(np.argmax(v))
        return {"value": float(v[k]), "t": float(t[k])}

    out = {"peak_displacement": peak(np.hypot(r["x"], r["y"])),
           "peak_absolute_acceleration": peak(np.hypot(r["ax_abs"], r["ay_abs"])),
           "peak_device_force": peak(np.hypot(r["device_Fx"], r["device_Fy"]))}
    out.update(own_seismic_metrics(r))
    return out


def _row(case, engine, reference, metric, value, limit, gated):
    return {"case": case, "engine": engine, "reference": reference, "metric": metric, "value": value,
            "limit": float(limit), "limit_source": getattr(limit, "source", "default"),
            "pass": bool(value <= limit), "gated": gated}
