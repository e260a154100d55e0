"""What passes FEMA P695: the displacement capacity (moat gap, stroke) at which a configuration's ACMR
reaches the acceptable ACMR20 % (and ACMR10 %), read from the IDA the evaluation ran (docs/p695.md).

Each record's IDA curve is its runs' (level, peak |u|) points; a run the rod's reach stopped counts as
an infinite peak (the device spent: collapse at every capacity). At a capacity c a record collapses
at the lowest level whose peak is >= c; the level is read between that run and the highest run below
it whose peak is < c, by interpolation of ln level against ln peak (exact for a linear system, whose
peak is proportional to the level; the geometric midpoint when the upper run was stopped). A record
whose runs never reached c is extrapolated along the secant, in ln-ln, from its highest finite point
to the highest one at most SECANT_SPAN of its level (again exact for a linear system; an estimate
otherwise, counted in ``n_extrapolated``).

S_CT(c) is the ceil(n/2)-th smallest of these levels; mu_T(c) is the pushover to delta_u = c; SSF,
beta_TOT and the acceptable ACMRs follow (nsd_core.study.p695.evaluate). The capacity that passes is
the least c on a scan of CAPACITY_RANGE x the evaluated capacity at which ACMR(c) >= ACMR_p(c), refined
by bisection to TOLERANCE (relative); with the device c stays below the rod's length (beyond it the
rod's reach ends the run whatever the moat).
"""
from __future__ import annotations

import math

import numpy as np

from nsd_core.study import p695

CAPACITY_RANGE = (0.5, 4.0)   # scanned capacities, times the evaluated capacity
SCAN = 60                     # log-spaced scan points
TOLERANCE = 1e-4              # relative, on the capacity
SECANT_SPAN = 2 / 3           # the extrapolating secant's lower point at most this x the highest level: two
                              # points of one bracket (5 % apart) would give a slope their noise dominates


def curves(traces, store) -> dict:
    """{configuration: {record: [(level, peak |u| [m]; inf: stopped by the rod's reach)]}} from
    the stored runs (a failed run is left out)."""
    from nsd_core.study.limit_state_outputs import configuration
    from nsd_core.study.limit_states import SPENT
    out: dict = {}
    for tr in traces:
        pts = []
        for level, _, _, key in tr.history:
            rec = store.load(key)
            if rec["status"] == "ok":
                pts.append((level, float(rec["metrics"]["peak_displacement"]["value"])))
            elif (rec.get("metrics") or {}).get("reason") in SPENT:
                pts.append((level, math.inf))
        out.setdefault(configuration(tr), {})[tr.record] = sorted(pts)
    return out


def _loglog(x0: float, y0: float, x1: float, y1: float, y: float) -> float:
    """x at y on the line through (ln x0, ln y0), (ln x1, ln y1)."""
    if y1 == y0:
        return math.sqrt(x0 * x1)
    return math.exp(math.log(x0) + (math.log(y) - math.log(y0)) * (math.log(x1) - math.log(x0))
                    / (math.log(y1) - math.log(y0)))


def collapse_level(points: list[tuple[float, float]], c: float) -> tuple[float | None, str]:
    """(the record's collapse level at capacity c, how: interpolated | extrapolated | none)."""
    hit = [(lv, pk) for lv, pk in points if pk >= c]
    if hit:
        hi, pk_hi = hit[0]
        below = [(lv, pk) for lv, pk in points if lv < hi and pk < c]
        if not below:
            return 0.5 * hi, "interpolated"
        lo, pk_lo = below[-1]
        if math.isinf(pk_hi) or pk_lo <= 0:
            return math.sqrt(lo * hi), "interpolated"
        return _loglog(lo, pk_lo, hi, pk_hi, c), "interpolated"
    finite = [(lv, pk) for lv, pk in points if 0 < pk < math.inf]
    if not finite:
        return None, "none"
    if len(finite) == 1:
        lv, pk = finite[0]
        return lv * c / pk, "extrapolated"
    x1, y1 = finite[-1]   # the highest point, and one at most SECANT_SPAN of its level (the lowest otherwise)
    x0, y0 = next(((lv, pk) for lv, pk in reversed(finite[:-1]) if lv <= SECANT_SPAN * x1), finite[0])
    if y1 <= y0:   # the curve flattened or turned back: no ln-ln secant to follow
        return None, "none"
    return _loglog(x0, y0, x1, y1, c), "extrapolated"


def s_ct_at(config_curves: dict, c: float) -> dict:
    """S_CT(c): the ceil(n/2)-th smallest collapse level (None: the median record's level unknown)."""
    levels = {r: collapse_level(pts, c) for r, pts in config_curves.items()}
    order = sorted(levels.items(), key=lambda kv: math.inf if kv[1][0] is None else kv[1][0])
    k = math.ceil(len(order) / 2) - 1
    rid, (value, how) = order[k]
    return {"S_CT": value, "record": rid, "how": how,
            "n_extrapolated": sum(h == "extrapolated" for v, h in levels.values())}


def acmr_at(c: float, config_curves: dict, pushover_at, level: dict, ratings: dict) -> dict:
    """The evaluation at capacity c: S_CT(c), mu_T(c), SSF, beta_TOT, ACMR and the acceptable ACMRs."""
    s = s_ct_at(config_curves, c)
    mu = pushover_at(c)
    ev = p695.evaluate(s["S_CT"], level["S_MT"], mu, level["T"], level["sdc"], ratings)
    return {"capacity": c, **{k: ev[k] for k in ("S_CT", "CMR", "mu_T", "SSF", "beta_TOT", "ACMR", "ACMR10",
                                                  "ACMR20")}, "median_record": s["record"], "how": s["how"],
            "n_extrapolated": s["n_extrapolated"]}


def least_passing(target: str, config_curves: dict, pushover_at, level: dict, ratings: dict,
                  lo: float, hi: float) -> dict:
    """The least capacity in [lo, hi] with ACMR >= ``target`` (ACMR20 or ACMR10), or why none."""
    def margin(c):
        e = acmr_at(c, config_curves, pushover_at, level, ratings)
        return (None if e["ACMR"] is None else e["ACMR"] - e[target]), e
    grid = np.geomspace(lo, hi, SCAN)
    prev = None
    for c in grid:
        m, e = margin(float(c))
        if m is not None and m >= 0:
            if prev is None:
                return {**e, "found": False, "note": f"passes already at the scan's lowest capacity {c:.4g} m"}
            a, b = prev, float(c)
            while (b - a) > TOLERANCE * b:
                mid = 0.5 * (a + b)
                mm, _ = margin(mid)
                a, b = (a, mid) if (mm is not None and mm >= 0) else (mid, b)
            _, e = margin(b)
            return {**e, "found": True, "bracket": [a, b]}
        prev = float(c)
    _, e = margin(float(grid[-1]))
    return {**e, "found": False, "note": f"ACMR stays below {target} up to {hi:.4g} m"}


def lines(wp: dict) -> list[str]:
    """The printed lines: per configuration, the capacity that passes each acceptable ACMR."""
    out = [f"what passes (displacement capacity; evaluated at {wp['evaluated_capacity'] * 1e3:.4g} mm):"]
    for name, c in wp["configurations"].items():
        cells = []
        for t in ("ACMR20", "ACMR10"):
            e = c[t]
            cells.append(f"{t} {e['capacity'] * 1e3:.4g} mm (S_CT {e['S_CT']:.4g} m/s^2, ACMR {e['ACMR']:.3g} vs "
                         f"{e[t]:.3g}, {e['how']})" if e["found"] and e["S_CT"] is not None
                         else f"{t}: none, {e.get('note', '')}")
        out.append(f"  {name}: " + "; ".join(cells))
    return out


def what_passes(all_curves: dict, capacity: float, pushovers: dict, level: dict, ratings: dict,
                rod_length: float | None) -> dict:
    """Per configuration, the least capacity that passes ACMR20 % and ACMR10 %; ``pushovers``:
    {configuration: (device, function c -> mu_T)}."""
    out = {"rule": "least displacement capacity c with ACMR(c) >= ACMR_p(c), S_CT(c) from the IDA's peak "
                   "displacements (nsd_core/study/p695_capacity.py)", "evaluated_capacity": capacity,
           "tolerance": TOLERANCE, "configurations": {}}
    for name, cc in all_curves.items():
        device, mu_at = pushovers[name]
        hi = CAPACITY_RANGE[1] * capacity
        if device and rod_length is not None:
            hi = min(hi, rod_length * (1 - 1e-9))
        lo = min(CAPACITY_RANGE[0] * capacity, 0.5 * hi)
        out["configurations"][name] = {
            "at_capacity": acmr_at(capacity, cc, mu_at, level, ratings),
            **{t: least_passing(t, cc, mu_at, level, ratings, lo, hi) for t in ("ACMR20", "ACMR10")},
            "scan": [lo, hi], "bound": "the rod's length" if device and hi < CAPACITY_RANGE[1] * capacity else None}
    return out
