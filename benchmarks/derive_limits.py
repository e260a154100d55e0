"""Print per-engine limits derived from a default comparison (the evidence behind tolerances.toml).

    python benchmarks/derive_limits.py out/compare/results.json

Rule (documented in comparisons/tolerances.toml): per engine and case, CASE_FACTOR x the measured
value rounded up to one significant digit, never below the metric's floor; per engine (for cases
not listed) ENGINE_FACTOR x the largest measured value over the default cases, rounded up to two
digits; a case's limit is never looser than its engine's. Metrics whose measured value is 0 (region shifts on a sampled grid) keep the default.
"""
from __future__ import annotations

import json
import math
import sys
from collections import defaultdict

CASE_FACTOR, ENGINE_FACTOR = 3.0, 1.5
FLOORS = {"max_dF_rel": 2e-6, "rms_dF_rel": 1e-6, "loop_area_rel": 1e-6, "peak_force_rel": 1e-6,
          "closure_max": 1e-12, "tracking_error": 1e-12, "energy_balance_rel": 1e-5}
PER_CASE = ("max_dF_rel", "rms_dF_rel", "loop_area_rel", "peak_force_rel")


def round_up(x: float, digits: int) -> float:
    if x <= 0:
        return 0.0
    e = math.floor(math.log10(x)) - digits + 1
    return math.ceil(x / 10 ** e - 1e-9) * 10 ** e


def derive(summary: dict) -> dict[str, dict]:
    measured: dict[str, dict[str, dict[str, float]]] = defaultdict(lambda: defaultdict(dict))
    for m in summary["metrics"]:
        if m["gated"] and m["metric"] in FLOORS:
            measured[m["engine"]][m["metric"]][m["case"]] = m["value"]
    out = {}
    for engine, metrics in measured.items():
        own = {}
        cases = defaultdict(dict)
        for metric, by_case in metrics.items():
            own[metric] = max(round_up(ENGINE_FACTOR * max(by_case.values()), 2), FLOORS[metric])
            if metric in PER_CASE:
                for case, v in by_case.items():
                    # never looser than the engine's own limit (which is >= 1.5x every case's value)
                    cases[case][metric] = min(max(round_up(CASE_FACTOR * v, 1), FLOORS[metric]), own[metric])
        out[engine] = {"own": own, "case": dict(cases)}
    return out


def to_toml(limits: dict[str, dict]) -> str:
    lines = []
    for engine, d in limits.items():
        lines.append(f"[limits.{engine}]")
        lines += [f"{k} = {v:.2g}" for k, v in d["own"].items()]
        for case, ms in d["case"].items():
            lines.append(f'[limits.{engine}.case."{case}"]')
            lines += [f"{k} = {v:.2g}" for k, v in ms.items()]
        lines.append("")
    return "\n".join(lines)


if __name__ == "__main__":
    print(to_toml(derive(json.load(open(sys.argv[1])))))
