"""docs/models.md's symbolic-engine blocks, from benchmarks/results/symbolic_equations.json and
symbolic_models.json (benchmarks/bench_symbolic.py, run by ``python -m benchmarks.measure``)."""
from __future__ import annotations


def equations(load, provenance, table, g, plain) -> str:
    rec = load("symbolic_equations")
    d = rec["data"]
    q = ", ".join(f"q{i} = {c}" for i, c in enumerate(d["coordinates"]))
    lines = [f"M[{i}][{j}] = {e}" for i, row in enumerate(d["mass_matrix"]) for j, e in enumerate(row) if j >= i]
    lines += [f"F[{i}] = {e}" for i, e in enumerate(d["forcing"])]
    lines += [f"Phi[{i}] = {e}" for i, e in enumerate(d["constraints"])]
    ops = d["operations"]
    return (provenance(rec) + "\n"
            + f"`{d['model']}` as Kane's method gives it (derived in {g(d['derive_s'])} s; {q}; u = q'; "
              "(gx, gy, gz) the effective field g - a_g(t); floats shown to 4 digits, the generated code keeps "
              f"every digit; sympy's operation count: mass matrix {ops['mass_matrix']}, forcing {ops['forcing']}, "
              f"constraints with their Jacobian and gamma {ops['constraints']}, named points {ops['points']}). "
              "M u' = F + Q + Phi_q^T lambda, M symmetric (its upper triangle shown):\n\n"
            + "```\n" + "\n".join(lines) + "\n```\n")


def models(load, provenance, table, g, plain) -> str:
    rec = load("symbolic_models")
    d = rec["data"]
    rows = []
    for r in d["rows"]:
        s, diff = r["symbolic"], r["difference"] or {}
        v = r["verdicts"].get("symbolic", {})
        rows.append([r["model"], r["case"], "PASS" if v.get("pass") else "FAIL", g(s.get("derive_time")),
                     g(s.get("codegen_time")), g(s.get("wall_time")), str(s.get("steps")), str(s.get("operations")),
                     f"{diff.get('metric', '–')} {g(diff.get('value'))}" if diff else "–",
                     g(s.get("closure_max")), (v.get("text") or "").replace("|", "/")[:160]])
    return (provenance(rec) + "\n"
            + f"Each benchmark description judged with engines {', '.join(d['engines'])} (`nsd compare --model`'s "
              "rule, the symbolic engine's estimate from its own run at rtol x 0.01), each derivation on an empty "
              "cache: derivation, code generation and run seconds of its first run (its tolerance-ladder run finds "
              "the cache: 0 s deriving), the integrator's steps, sympy's operation count of the derived "
              "quantities, its largest difference from the converged in-house reference (a fraction of the "
              "output's scale), its largest loop-closure residual [m]:\n\n"
            + table(["model", "case", "symbolic", "derive s", "generate s", "run s", "steps", "operations",
                     "largest difference", "closure m", "verdict"], rows))
