"""The symbolic engine as the campaign's referee: when a peer disagrees with the converged in-house
reference beyond numerical error, the symbolic engine (comparisons.builders.symbolic: Kane's equations,
no formulation shared with either side) runs the same case and says whose side it takes.

For each disagreeing peer of a case (``referee``):
- the symbolic engine is judged against the converged reference by the gate's rule (its estimate from
  its tolerance ladder and, with loops, its formulation companion): ``agrees_with_reference``;
- and against the peer's run: its largest difference over k x (its estimate + the peer's), each
  output's, ``agrees_with_peer``;
- ``side``: ``reference`` (it agrees with the reference, not the peer: the peer is wrong), ``peer``
  (the reverse: the reference is suspect), ``both`` (the disagreement lies within the referee's own
  error) or ``neither``.
The symbolic engine's runs are re-used when it already ran as a peer.
"""
from __future__ import annotations

import time

REFEREE = "symbolic"


def disagreeing(summary: dict) -> dict:
    """case -> the peers that disagree beyond numerical error there (the referee itself excluded)."""
    return {case: [e for e, v in entry["verdicts"].items() if v.get("consistent") is False and e != REFEREE
                   and e in summary["engines"]]
            for case, entry in summary["cases"].items()
            if any(v.get("consistent") is False and e != REFEREE for e, v in entry["verdicts"].items())}


def referee(model, cases: list, summary: dict) -> dict:
    """case -> peer -> the referee's finding (see the module docstring); {} when no peer disagrees."""
    from comparisons.model_compare import (CHECK, CONVERGED, adaptive_estimate, differences, judge, model_rule,
                                           run_one, run_plan, scales)
    rule = model_rule(model, summary["rule"]["k"])
    out = {}
    by_name = {c.name: c for c in cases}
    for name, peers in disagreeing(summary).items():
        case, runs = by_name[name], dict(summary["runs"].get(name, {}))
        if CONVERGED not in runs or CHECK not in runs:
            continue
        start, failure = time.perf_counter(), None
        for label, engine, settings in run_plan(model, case, [REFEREE]):
            if engine == REFEREE and label not in runs:
                res = run_one(model, case, engine, settings)
                if res["status"] == "ok":
                    runs[label] = res["run"]
                else:
                    failure = res["message"]
        wall = time.perf_counter() - start
        sc = scales(model, runs[CONVERGED])
        estimate = None if failure else adaptive_estimate(model, case, REFEREE, runs, sc)
        if estimate is None:
            out[name] = {p: {"side": "referee_failed", "message": failure, "wall_s": wall} for p in peers}
            continue
        rows, verdicts = judge(model, case, [REFEREE], runs, rule)
        mine = verdicts[REFEREE]
        own = estimate[0]
        found = {}
        for p in peers:
            est_p = {r["metric"]: r["estimate"] or 0.0 for r in summary["rows"] if r["case"] == name and r["engine"] == p}
            d = differences(runs[REFEREE], runs[p], sc) if p in runs else {}
            ratio = max((v / (rule.k * (own[k] + est_p.get(k, 0.0)) + 1e-15) for k, v in d.items()), default=None)
            with_ref, with_peer = bool(mine.get("consistent")), ratio is not None and ratio <= 1.0
            side = {(True, False): "reference", (False, True): "peer", (True, True): "both"}.get(
                (with_ref, with_peer), "neither")
            found[p] = {"side": side, "agrees_with_reference": with_ref, "agrees_with_peer": with_peer,
                        "symbolic_text": mine.get("text", ""), "symbolic_vs_peer_ratio": ratio, "wall_s": wall}
        out[name] = found
    return out
