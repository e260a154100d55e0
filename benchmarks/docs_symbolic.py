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


def device(load, provenance, table, g, plain) -> str:
    return models(load, provenance, table, g, plain, "symbolic_device")


def models(load, provenance, table, g, plain, name: str = "symbolic_models") -> str:
    rec = load(name)
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
            + (f"Over the first {g(d['duration'])} s of each case (no reference solution over a shortened window). "
               if d.get("duration") else "")
            + f"Each description judged with engines {', '.join(d['engines'])} (`nsd compare --model`'s "
              "rule, the symbolic engine's estimate from its own run at rtol x 0.01 and, with loops, at 10 x its "
              "regularisation), each derivation on an empty cache: derivation, code generation and run seconds "
              "of its first run (its estimate's runs find the cache: 0 s deriving), the integrator's steps, sympy's operation count of the derived "
              "quantities, its largest difference from the converged in-house reference (a fraction of the "
              "output's scale), its largest loop-closure residual [m]:\n\n"
            + table(["model", "case", "symbolic", "derive s", "generate s", "run s", "steps", "operations",
                     "largest difference", "closure m", "verdict"], rows))


def campaign(load, provenance, table, g, plain) -> str:
    rec = load("campaign_symbolic")
    d = rec["data"]
    rows = []
    for r in d["records"]:
        last = r.get("refined") or r.get("first") or {}
        for case, per in last.items():
            sym = per.get("symbolic", {})
            others = [e for e, v in per.items() if e != "symbolic" and not v.get("pass")]
            ref = (r.get("referee") or {}).get(case, {})
            rows.append([str(r["seed"]), r.get("family", ""), f"`{r['cls']}`",
                         "PASS" if sym.get("pass") else ("–" if not sym else "FAIL"),
                         g(sym.get("ratio", (sym.get("worst") or {}).get("ratio"))),
                         ", ".join(others) or "–",
                         ", ".join(f"{p}: {f['side']} ({g(f.get('symbolic_vs_peer_ratio'))})" for p, f in ref.items())
                         or "–",
                         ("" if sym.get("pass") else (sym.get("text") or "")[:140]).replace("|", "/")])
        if not last:
            rows.append([str(r["seed"]), r.get("family", ""), f"`{r['cls']}`", "–", "–", "–", "–",
                         (r.get("reason") or "")[:140].replace("|", "/")])
    sides = ", ".join(f"{k} {v}" for k, v in sorted(d.get("referee", {}).items())) or "none (no peer disagreed)"
    return (provenance(rec) + "\n"
            + f"{d['n']} generated mechanisms (seeds {d['seeds'][0]}-{d['seeds'][1]}) with the symbolic engine as a "
              f"4th peer, in {plain(d['wall_s'])} s: classes {', '.join(f'{k} {v}' for k, v in sorted(d['classes'].items()))}; "
              f"the referee's sides: {sides}. Per mechanism and case: the symbolic engine's verdict and its "
              "largest difference from the converged reference over its bound (PASS verdicts), the peers that "
              "did not pass, and the referee's side where one disagreed (in brackets: the symbolic engine's largest "
              "difference from that peer over k x (its estimate + the peer's)):\n\n"
            + table(["seed", "family", "class", "symbolic", "difference / bound", "peers not passing", "referee",
                     "symbolic's verdict when not PASS"], rows))
