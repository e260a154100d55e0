"""The estimated rule's verdict as text: one line per case, engine and metric, then the verdicts in words."""
from __future__ import annotations


def _g(x, fmt="11.3e") -> str:
    return f"{x:{fmt}}" if x is not None else f"{'-':>{fmt.split('.')[0]}}"


def format_estimated(summary: dict) -> str:
    """The table of ``nsd compare`` under the estimated rule: each gated metric's difference from the
    converged reference, the engine's estimated error, the bound k x (estimate + reference's), the
    engineering tolerance (relative, and in units), and the two verdicts; then each case and engine
    in words."""
    head = (f"{'case':22s} {'engine':13s} {'metric':18s} {'difference':>11s} {'est. error':>11s} {'bound':>11s} "
            f"{'tolerance':>11s} {'tolerance in units':>20s}  verdict")
    lines = [head]
    for m in summary["metrics"]:
        if not m["gated"]:
            continue
        unit = _in_units(m)
        if m.get("consistent") is None and m.get("bound") is None:
            verdict = "ok" if m["accurate"] else "NOT ACCURATE"
        else:
            verdict = ("ok" if m["consistent"] else "DISAGREES") + ("" if m["accurate"] else ", NOT CONVERGED")
        lines.append(f"{m['case']:22s} {m['engine']:13s} {m['metric']:18s} {_g(m['value'])} {_g(m.get('estimate'))} "
                     f"{_g(m.get('bound'))} {_g(m.get('tolerance'))} {unit:>20s}  {verdict}")
    lines.append("")
    lines.append("verdict per case and engine:")
    for case, per in summary.get("verdicts", {}).items():
        for engine, v in per.items():
            lines.append(f"  {case:22s} {engine:13s} {'PASS' if v['pass'] else 'FAIL'}  {v['text']}")
    for c, per in summary["runs"].items():
        for e, r in per.items():
            if r["status"] != "ok":
                lines.append(f"  {c:22s} {e:13s} ERROR {r['message']}")
    return "\n".join(lines)


def _in_units(m: dict) -> str:
    tol, unit = m.get("tolerance_abs"), m.get("unit")
    if tol is None or unit is None:
        return "-"
    if unit == "m":
        return f"{tol * 1e3:.3g} mm"
    return f"{tol:.3g} {unit}"
