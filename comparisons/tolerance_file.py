"""Tolerance files (TOML): fixed limits (a regression profile: [limits], per engine and per engine and
case) or the estimated rule's engineering tolerances ([engineering], [verdict]), validated into
``Limits`` with one-line errors."""
from __future__ import annotations

from pathlib import Path

from comparisons.config import DEFAULT_TOLERANCES, HERE, METRICS, _number, _read, _table
from nsd_core.device.params import ParameterError


class Limits(dict):
    """Metric -> default limit (a plain dict, as before). ``defaulted`` names the metrics a partial
    file left out, which take the default file's limit (said in the table and in results.json, so
    nothing is dropped silently); ``engines`` holds overrides per engine and per engine and case, and
    ``limit(engine, case, metric)`` takes the most specific one."""
    defaulted: tuple[str, ...] = ()
    rule = None   # comparisons.verdict.Rule for a file of engineering tolerances; None: fixed limits

    def __init__(self, *args, engines: dict[str, dict] | None = None, derived: dict | None = None):
        super().__init__(*args)
        self.engines = engines or {}
        self.derived = derived or {}   # [derived]: the peer versions (and rule) the limits came from

    def limit(self, engine: str, case: str, metric: str) -> float | None:
        e = self.engines.get(engine, {})
        return e.get("case", {}).get(case, {}).get(metric, e.get(metric, self.get(metric)))


def _metric_limits(where: str, table: dict) -> dict[str, float]:
    for k, v in table.items():
        if k not in METRICS:
            raise ParameterError(f"{where}{k}: unknown metric; allowed: {', '.join(METRICS)}")
        _number(f"{where}{k}", v)
    return {k: float(v) for k, v in table.items()}


def _engine_limits(limits: dict) -> dict[str, dict]:
    """[limits.ENGINE] metric = value and [limits.ENGINE.case."CASE"] metric = value."""
    from comparisons.engines import ENGINES
    engines = {}
    for name, table in ((k, v) for k, v in limits.items() if isinstance(v, dict)):
        if name not in ENGINES:
            raise ParameterError(f"tolerance {name}: neither a metric nor an engine; allowed metrics: "
                                 f"{', '.join(METRICS)}; engines: {', '.join(ENGINES)}")
        own = _metric_limits(f"tolerance {name}.", {k: v for k, v in table.items() if k != "case"})
        cases = _table(f"tolerance {name}.case", table.get("case", {}))
        own["case"] = {c: _metric_limits(f"tolerance {name}.case.{c}.", _table(f"tolerance {name}.case.{c}", t))
                       for c, t in cases.items()}
        engines[name] = own
    return engines


def _load_engineering(data: dict, what: str) -> Limits:
    """[verdict] k, beta and [engineering] metric = tolerance: the rule of comparisons/verdict.py. A
    metric the file leaves out takes the rule's default (named in ``defaulted``)."""
    from comparisons.verdict import BETA, ENGINEERING, K, Rule
    extra = sorted(set(data) - {"engineering", "verdict"})
    if extra:
        raise ParameterError(f"{what}: {extra[0]!r} beside [engineering] and [verdict]; allowed: those two "
                             "(fixed [limits] are a file of their own: the regression profile)")
    verdict = _table("verdict", data.get("verdict", {}))
    for k in verdict:
        if k not in ("rule", "k", "beta"):
            raise ParameterError(f"{what}: verdict.{k}: unknown; allowed: rule, k, beta")
    if verdict.get("rule", "estimated") != "estimated":
        raise ParameterError(f"{what}: verdict.rule = {verdict['rule']!r}: allowed: \"estimated\"")
    k = _number("verdict.k", verdict.get("k", K))
    beta = _number("verdict.beta", verdict.get("beta", BETA), positive=False)
    if not (1.0 <= k <= 100.0):
        raise ParameterError(f"{what}: verdict.k = {k!r}: allowed: 1 to 100 (the margin over the estimated error)")
    if not (0.0 <= beta <= 1.0):
        raise ParameterError(f"{what}: verdict.beta = {beta!r}: allowed: 0 to 1")
    eng = _table("engineering", data.get("engineering", {}))
    for m, v in eng.items():
        if m not in ENGINEERING:
            raise ParameterError(f"{what}: engineering.{m}: unknown metric; allowed: {', '.join(ENGINEERING)}")
        if not (isinstance(v, (int, float)) and not isinstance(v, bool) and 0.0 < float(v) <= 1.0):
            raise ParameterError(f"{what}: engineering.{m} = {v!r}: allowed: a number in (0, 1] (a fraction of the "
                                 "quantity's peak; m for closure_max and tracking_error)")
    rule = Rule({m: float(v) for m, v in eng.items()}, k=k, beta=beta)
    out = Limits(rule.engineering)
    out.rule = rule
    out.defaulted = tuple(m for m in ENGINEERING if m not in eng)
    return out


def load_tolerances(path: str | Path | None = None) -> Limits:
    """[limits] metric = value (or bare metric = value lines), optionally per engine
    [limits.ENGINE] and per engine and case [limits.ENGINE.case."CASE"] (the most specific wins)."""
    what = "--tolerances"
    data = _read(Path(path or DEFAULT_TOLERANCES), what)
    derived = {}
    if "engineering" in data or "verdict" in data:
        return _load_engineering(data, what)
    if "limits" in data:
        extra = sorted(set(data) - {"limits", "derived"})
        if extra:
            raise ParameterError(f"{what}: {extra[0]!r} beside [limits]; allowed: [limits] and [derived]")
        limits = _table("limits", data["limits"])
        derived = _table("derived", data.get("derived", {}))
    else:
        limits = data
    if not limits:
        raise ParameterError(f"{what} {path}: no limits; a gate that checks nothing would always pass "
                             f"(give some of: {', '.join(METRICS)})")
    out = Limits(_metric_limits("tolerance ", {k: v for k, v in limits.items() if not isinstance(v, dict)}),
                 engines=_engine_limits(limits), derived=derived)
    missing = [k for k in METRICS if k not in out]
    if missing:
        regression = HERE / "limits_regression.toml"   # a fixed-limit file's defaults are the regression profile's
        defaults = load_tolerances(regression) if path and Path(path) != regression else {}
        for k in missing:
            if k in defaults:
                out[k] = defaults[k]
        out.defaulted = tuple(k for k in missing if k in out)
    return out
