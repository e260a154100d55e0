"""The gate's yardstick: a converged in-house run per case, the step-halving runs that show a peer's
error falls at its method's order, and the check that the limits belong to the installed peers.

Every engine (the in-house run at the case's settings included) is measured against the *converged
reference*: the in-house engine at a tolerance far below any engine's error (CONVERGED_SETTINGS),
computed once per case and kept like any other run. A more accurate run can then only come closer
to it: tightening the in-house tolerance, or a change that moves the in-house results at round-off,
cannot turn the gate red. Runs have labels: an engine's name, ``converged``, ``ENGINE_hN`` (the
engine with the step setting of its ``[order]`` entry divided by N) or ``ENGINE_Nh`` (its step times
N: the companion run of its error estimate, comparisons.estimate).
"""
from __future__ import annotations

import math
import re
import sys

from comparisons.engines import REFERENCE

CONVERGED = "converged"
# rtol 1e-10: its own error (against rtol 1e-11, benchmarks/derive_limits.py) is far below every
# engine's error at its case settings, and it costs ~0.1-0.2 s per cycle compiled
CONVERGED_SETTINGS = {"method": "DOP853", "rtol": 1e-10, "atol": 1e-12, "max_step": 1e-3}
# the reference's own error is measured against this (derive_limits; the floor of every limit)
CHECK_SETTINGS = {**CONVERGED_SETTINGS, "rtol": 1e-11, "atol": 1e-13}
CHECK = "converged_check"   # the run label of the reference's own check (its error estimate)
HALVED = re.compile(r"([a-z]+)_h(\d+)")
COARSER = re.compile(r"([a-z]+)_(\d+)h")
ORDER_METRIC = "max_dF_rel"   # the error whose fall with the step gives the observed order
ORDER_DIVISORS = (2, 4)       # the step halved twice


def run_spec(case, label: str, order: dict | None = None) -> tuple[str, object, dict]:
    """(engine, params, settings) of the run with this label on this case. The converged reference
    runs on the case's nominal parameters (engine_params change one engine's own model only)."""
    if label == CONVERGED:
        return REFERENCE, case.params, dict(CONVERGED_SETTINGS)
    if label == CHECK:
        return REFERENCE, case.params, dict(CHECK_SETTINGS)
    m = HALVED.fullmatch(label)
    if m:
        engine, div = m.group(1), int(m.group(2))
        return engine, case.params_for(engine), halved_settings(case, engine, div)
    m = COARSER.fullmatch(label)
    if m:
        engine, times = m.group(1), int(m.group(2))
        return engine, case.params_for(engine), halved_settings(case, engine, 1.0 / times)
    return label, case.params_for(label), case.settings.get(label, {})


def halved_settings(case, engine: str, div: float) -> dict:
    """The case's settings of ``engine`` with its step (and every cap on it) divided by ``div``
    (a ``div`` below 1 multiplies it)."""
    from comparisons.config import SeismicCase
    from comparisons.engines import get_engine
    from comparisons.estimate import refined_settings
    eng = get_engine(engine)
    own = case.settings.get(engine, {})
    defaults = eng.seismic_default_settings if isinstance(case, SeismicCase) else eng.default_settings
    return refined_settings(engine, {**defaults, **own}, own, div)


def order_labels(order: dict | None, engines: list[str]) -> list[tuple[str, str]]:
    """(case name, label) of the extra runs of the observed-order check, for the engines that run."""
    return [(spec["case"], f"{e}_h{d}") for e, spec in (order or {}).items() if e in engines
            for d in ORDER_DIVISORS]


def observed_orders(errors: list[float]) -> list[float]:
    """log2 of each error over the next one's, for a step halved each time (order p: e ~ h^p)."""
    return [math.log2(a / b) if a > 0 and b > 0 else float("nan") for a, b in zip(errors, errors[1:])]


def order_rows(order: dict, engine_errors: dict[str, list[float]], row, band) -> tuple[list[dict], dict]:
    """Gated rows ``order_deviation`` = max |p_i - expected| over the halvings (limit: ``band(engine,
    case)``, the tolerance file's order_deviation), and the evidence (errors, orders) for results.json.
    A modelling error gives a plateau (p ~ 0)."""
    rows, evidence = [], {}
    for engine, errors in engine_errors.items():
        spec = {**order[engine], "band": band(engine, order[engine]["case"])}
        p = observed_orders(errors)
        dev = max((abs(x - spec["expected"]) if math.isfinite(x) else float("inf")) for x in p)
        rows.append(row(spec["case"], engine, CONVERGED, "order_deviation", dev, spec["band"], True))
        evidence[engine] = {"case": spec["case"], "setting": spec["setting"], "divisors": [1, *ORDER_DIVISORS],
                            "metric": ORDER_METRIC, "errors": errors, "orders": p, "expected": spec["expected"],
                            "band": spec["band"]}
    return rows, evidence


PEER_PACKAGES = {"mujoco": "mujoco", "exudyn": "exudyn"}


def version_warnings(derived: dict, installed: dict, engines: list[str]) -> list[str]:
    """A line for each peer whose installed version differs from the one the limits were derived on."""
    out = []
    for e in engines:
        pkg = PEER_PACKAGES.get(e)
        want = (derived or {}).get(pkg) if pkg else None
        if want and installed.get(pkg) != want:
            out.append(f"warning: the limits of {e} were derived on {pkg} {want}; installed: "
                       f"{installed.get(pkg, 'none')} (its errors may differ; re-derive with benchmarks/derive_limits.py)")
    return out


def warn(line: str) -> None:
    print(line, file=sys.stderr)
