"""The estimated rule's verdict as text: one line per case, engine and metric, then the verdicts in words."""
from __future__ import annotations

from comparisons.verdict import row_word


def _g(x, fmt="11.3e") -> str:
    return f"{x:{fmt}}" if x is not None else f"{'-':>{fmt.split('.')[0]}}"


# What each peer model is, in words (the run's stats["model"]; comparisons.engines.base.DEFAULT_MODEL)
MODEL_WORDS = {"described": "model built from the description", "adapter": "hand-written adapter"}


def peer_models(summary: dict) -> dict[str, dict[str, list[str]]]:
    """{peer: {model: [cases]}} of the runs that succeeded, read from each run's stats: the described
    builders record ``model = "described"``; a peer run that records no model ran its hand-written adapter
    (the only model before the described ones). The reference engine has no model choice and is left out."""
    reference = summary.get("reference") or "semirecursive"
    out: dict[str, dict[str, list[str]]] = {}
    for engine in summary.get("engines") or ():   # in the run's engine order
        for case, per in (summary.get("runs") or {}).items():
            run = (per or {}).get(engine)
            if engine == reference or not isinstance(run, dict) or run.get("status") != "ok":
                continue
            model = (run.get("stats") or {}).get("model") or "adapter"
            out.setdefault(engine, {}).setdefault(str(model), []).append(case)
    return out


def model_words(models: dict[str, list[str]]) -> str:
    """One peer's model(s) in words; where its cases ran different models, each with its cases."""
    if len(models) == 1:
        return MODEL_WORDS.get(next(iter(models)), f"model {next(iter(models))!r}")
    return "; ".join(f"{MODEL_WORDS.get(m, f'model {m!r}')} ({', '.join(cases)})" for m, cases in models.items())


def peer_models_line(summary: dict) -> str:
    """'peer models: mujoco, exudyn: model built from the description' (one phrase per engine where they
    differ; '' with no peer run)."""
    words = {e: model_words(m) for e, m in peer_models(summary).items()}
    if not words:
        return ""
    if len(set(words.values())) == 1:
        return f"peer models: {', '.join(words)}: {next(iter(words.values()))}"
    return "peer models: " + "; ".join(f"{e}: {w}" for e, w in words.items())


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
            verdict = row_word(m) + ("" if m["accurate"] else ", NOT CONVERGED")
        lines.append(f"{m['case']:22s} {m['engine']:13s} {m['metric']:18s} {_g(m['value'])} {_g(m.get('estimate'))} "
                     f"{_g(m.get('bound'))} {_g(m.get('tolerance'))} {unit:>20s}  {verdict}")
    lines.append("")
    if peer_models_line(summary):
        lines.append(peer_models_line(summary))
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
