"""The symbolic engine's measurements behind docs/models.md ("The symbolic engine").

    python benchmarks/bench_symbolic.py equations --out DIR   the derived equations of models/fourbar_spring.toml
                                                              -> DIR/symbolic_equations.json
    python benchmarks/bench_symbolic.py models [--engines E,...] [--models a,b] [--duration S] --out DIR
                                                              every benchmark description through
                                                              ``nsd compare --model``'s judgement, with the
                                                              symbolic engine's derivation, generation and run
                                                              times -> DIR/symbolic_models.json

Each derivation runs on an empty cache folder of its own (XDG_CACHE_HOME under DIR), so its times are
those of a first run; the tolerance ladder's second run then finds the cache.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

MODELS = ("fourbar_spring", "slider_crank", "iftomm_a01_pendulum", "andrews", "iftomm_a02_fourbar",
          "iftomm_a04_bricard")
EQUATIONS_OF = "fourbar_spring"


def short(e, digits: int = 4) -> str:
    """A derived expression with its floats shown to ``digits`` significant digits."""
    import sympy as sp
    return sp.sstr(sp.nfloat(e, digits))


def equations(out: Path) -> dict:
    from comparisons.builders.symbolic_derive import derive, operations
    from nsd_core.model.load import load_model
    path = ROOT / "models" / f"{EQUATIONS_OF}.toml"
    model = load_model(path)
    t0 = time.perf_counter()
    d = derive(model)
    wall = time.perf_counter() - t0
    names = [f"{b}[{k}]" for b, k in d.coordinates]
    return {"model": f"models/{EQUATIONS_OF}.toml", "coordinates": names, "derive_s": wall,
            "operations": operations(d),
            "mass_matrix": [[short(d.M[i, j]) for j in range(d.n)] for i in range(d.n)],
            "forcing": [short(e) for e in d.F], "constraints": [short(e) for e in d.Phi]}


def models(out: Path, engines: list[str], names: list[str], duration: float | None = None) -> dict:
    from comparisons.model_cases import load_model_cases
    from comparisons.model_compare import compare_model
    from nsd_core.model.load import load_model
    rows = []
    for name in names:
        os.environ["XDG_CACHE_HOME"] = str(out / "cache" / name)   # a first derivation, on an empty cache
        model = load_model(ROOT / "models" / f"{name}.toml")
        cases = load_model_cases(model, None, engines)
        if duration:   # a shorter window of each case (said in the JSON)
            import dataclasses
            cases = [dataclasses.replace(c, duration=min(duration, c.duration), reference=None) for c in cases]
        t0 = time.perf_counter()
        s = compare_model(model, cases, engines, log=lambda *_: None)
        wall = time.perf_counter() - t0
        for case, entry in s["cases"].items():
            runs = entry["runs"]
            sym, tight, reg = (runs.get(k, {}) for k in ("symbolic", "symbolic_tight", "symbolic_regularised"))
            rows.append({"model": name, "case": case, "wall_s": wall,
                         "verdicts": {e: {"pass": v["pass"], "text": v.get("text", "")}
                                      for e, v in entry["verdicts"].items()},
                         "symbolic": {k: sym.get(k) for k in ("derive_time", "codegen_time", "load_time", "wall_time",
                                                              "steps", "nfev", "operations", "closure_max", "cache")},
                         "symbolic_tight": {k: tight.get(k) for k in ("derive_time", "wall_time", "cache")},
                         "symbolic_regularised": {k: reg[k] for k in ("derive_time", "wall_time", "cache") if k in reg},
                         "difference": _largest(s["rows"], case, "symbolic"),
                         "failures": entry["failures"]})
    return {"engines": engines, "rows": rows, "duration": duration}


def _largest(rows: list[dict], case: str, engine: str) -> dict | None:
    """The symbolic engine's largest difference from the converged reference (over the outputs, not the
    solution's) and its largest value over its bound."""
    mine = [r for r in rows if r["case"] == case and r["engine"] == engine and r.get("bound")]
    if not mine:
        return None
    worst = max(mine, key=lambda r: r["value"] / r["bound"])
    vs = [r for r in mine if not r["metric"].endswith(" vs solution") and r["metric"] not in ("closure_max",)]
    big = max(vs, key=lambda r: r["value"]) if vs else worst
    return {"metric": big["metric"], "value": big["value"], "estimate": big["estimate"],
            "worst_metric": worst["metric"], "worst_ratio": worst["value"] / worst["bound"]}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("equations", "models"))
    ap.add_argument("--engines", default="semirecursive,symbolic")
    ap.add_argument("--models", default=",".join(MODELS))
    ap.add_argument("--duration", type=float, default=None, help="run each case over at most this many seconds")
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    if a.what == "equations":
        os.environ["XDG_CACHE_HOME"] = str(out / "cache")
        data = equations(out)
    else:
        data = models(out, [e for e in a.engines.split(",") if e], [m for m in a.models.split(",") if m], a.duration)
    (out / f"symbolic_{a.what}.json").write_text(json.dumps(data, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
