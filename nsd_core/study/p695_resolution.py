"""Ŝ_CT at a stated resolution: each record's collapse bracket, the estimate read inside it, the
bracket Ŝ_CT comes from, and whether the configurations' ranking is resolved (docs/p695.md).

A record's collapse bracket is (lo, hi]: hi the lowest level at which it collapsed, lo the highest
level below hi at which it did not (0 when none ran below). Its collapse level lies inside. With the
capacity surrogate the record's estimate is read from the two runs' peak displacements, ln level
interpolated against ln peak |u| at the capacity (nsd_core.study.p695_capacity.collapse_level: inside
the bracket, exact for a linear system); otherwise (a drift or impact surrogate, a run stopped by the
rod's reach) the bracket's geometric midpoint sqrt(lo hi) (hi / 2 when lo = 0): the levels and the
fragility are lognormal, so the midpoint in ln IM is the estimate whose worst error, in ln IM, is
smallest (half the bracket's log-width; 2.5 % of the level at a 5 % bracket).

Ŝ_CT is the ceil(n/2)-th smallest estimate (a record that never collapsed counted above every level,
as ``nsd_core.study.p695.median_collapse``). Its bracket is the same order statistic of the records'
lo and of their hi: since each record's true collapse level lies in its own (lo, hi], the set's
median collapse level lies in (lo_(k), hi_(k)], whatever the true levels are inside the brackets.
"""
from __future__ import annotations

import math

from nsd_core.study import p695


def record_estimate(lo: float | None, hi: float | None) -> float | None:
    """The collapse level read inside the bracket (lo, hi]: sqrt(lo hi), hi / 2 when lo is 0 or
    None (nothing ran below), None when the record never collapsed (hi None)."""
    if hi is None:
        return None
    if not lo:
        return 0.5 * hi
    return math.sqrt(lo * hi)


def _order_stat(values: list[float]) -> float | None:
    """The ceil(n/2)-th smallest (inf: a record that never collapsed); None when it is inf."""
    if not values:
        return None
    v = sorted(values)[math.ceil(len(values) / 2) - 1]
    return None if math.isinf(v) else float(v)


def s_ct_bracketed(recs: list[dict]) -> dict:
    """Ŝ_CT from records {collapse_im (hi), below_im (lo), censored_at, estimate_im (optional: the
    collapse level read inside the bracket; else its geometric midpoint)}: the median estimate, its
    bracket (the same order statistic of the records' lo and hi) and the bracket's width / hi."""
    los, his, est = [], [], []
    for r in recs:
        hi = r.get("collapse_im")
        if hi is None:   # never collapsed: above every level run; its bracket starts at its highest level
            los.append(r.get("censored_at") or 0.0)
            his.append(math.inf)
            est.append(math.inf)
        else:
            los.append(r.get("below_im") or 0.0)
            his.append(hi)
            given = r.get("estimate_im")   # interpolated from the runs' peaks (nsd_core.study.p695_capacity)
            est.append(given if given is not None else record_estimate(r.get("below_im"), hi))
    s_ct, lo, hi = _order_stat(est), _order_stat(los), _order_stat(his)
    return {"S_CT": s_ct, "S_CT_bracket": [lo, hi],
            "S_CT_bracket_width": None if (hi is None or lo is None) else (hi - lo) / hi,
            "estimate": "the ceil(n/2)-th smallest record estimate, each its collapse level read inside its "
                        "bracket: interpolated in ln level against ln peak |u| between the bracket's two runs "
                        "(capacity surrogate), else the geometric midpoint sqrt(lo hi) (hi / 2 when nothing ran "
                        "below hi)",
            "bracket": "the same order statistic of the records' lo and of their hi: the set's median collapse "
                       "level lies in (lo, hi] whatever each record's level inside its own bracket",
            "estimates": [None if math.isinf(e) else e for e in est]}


def verdict_over_bracket(bracket: list, s_mt: float, ssf: float, acmr10: float, acmr20: float) -> dict:
    """ACMR and both verdicts at the two ends of Ŝ_CT's bracket; ``resolved``: the verdicts are the
    same at both ends (the bracket cannot change them)."""
    out = {}
    for end, s in zip(("low", "high"), bracket):
        acmr = None if s is None else ssf * s / s_mt
        out[end] = {"S_CT": s, "ACMR": acmr, "pass_ACMR20": None if acmr is None else bool(acmr >= acmr20),
                    "pass_ACMR10": None if acmr is None else bool(acmr >= acmr10)}
    out["resolved"] = all(out["low"][k] is not None and out["low"][k] == out["high"][k]
                          for k in ("pass_ACMR20", "pass_ACMR10"))
    return out


def resolution_summary(recs: list[dict], resolution: float | None) -> dict:
    """How many records' brackets are within the resolution, and which are not (and why)."""
    det = [r for r in recs if not r.get("undetermined")]
    within = [r for r in det if r.get("bracket_resolved")]
    return {"resolution": resolution, "rule": "a record's bracket (hi - lo) / hi <= resolution",
            "n_within": len(within), "n_records": len(det),
            "not_within": [{"record": r["record"], "why": r.get("bracket_why"), "width": r.get("bracket_width")}
                           for r in det if not r.get("bracket_resolved")],
            "widest": max((r["bracket_width"] for r in det if r.get("bracket_width") is not None), default=None)}


def _overlap(a: list | None, b: list | None) -> bool | None:
    """Whether two intervals [lo, hi] overlap (None: an end unknown, an open end counted as unbounded)."""
    if not a or not b:
        return None
    lo_a, hi_a = a[0] if a[0] is not None else -math.inf, a[1] if a[1] is not None else math.inf
    lo_b, hi_b = b[0] if b[0] is not None else -math.inf, b[1] if b[1] is not None else math.inf
    return not (hi_a < lo_b or hi_b < lo_a)


def ranking(configs: dict) -> dict:
    """The configurations by Ŝ_CT, highest first, and for each neighbouring pair whether their
    Ŝ_CT brackets overlap (the levels run cannot order them) and whether their bootstrap intervals
    overlap (the record set cannot order them): the pair's order is ``resolved`` when neither does."""
    named = [(n, c) for n, c in configs.items() if c.get("S_CT") is not None]
    named.sort(key=lambda nc: -nc[1]["S_CT"])
    pairs = []
    for (a, ca), (b, cb) in zip(named, named[1:]):
        ia, ib = ca.get("S_CT_interval") or {}, cb.get("S_CT_interval") or {}
        brackets = _overlap(ca.get("S_CT_bracket"), cb.get("S_CT_bracket"))
        intervals = _overlap([ia.get("low"), ia.get("high")] if ia else None,
                             [ib.get("low"), ib.get("high")] if ib else None)
        pairs.append({"higher": a, "lower": b, "brackets_overlap": brackets, "intervals_overlap": intervals,
                      "resolved": brackets is False and intervals is False})
    return {"order": [n for n, _ in named], "pairs": pairs,
            "undetermined": [n for n, c in configs.items() if c.get("S_CT") is None],
            "resolved": bool(pairs) and all(p["resolved"] for p in pairs),
            "rule": "a pair is resolved when neither its Ŝ_CT brackets nor its 90 % bootstrap intervals overlap"}


def bootstrap(estimates: list[float | None], n_boot: int, seed: int) -> dict | None:
    """The percentile bootstrap interval of Ŝ_CT over the records' estimates (None: no records)."""
    return p695.bootstrap_median(estimates, n_boot, seed) if estimates else None
