"""The tables of docs/validation.md, docs/performance.md and docs/engine-codegen.md, generated from benchmarks/results/*.json.

    python -m benchmarks.docs            rewrite every generated block from the JSON
    python -m benchmarks.docs --check    exit 1 if a block differs from what the JSON gives

A generated block sits between ``<!-- generated: NAME -->`` and ``<!-- end generated: NAME -->``;
everything outside the blocks is hand-written and left alone. Each block starts with where its
numbers come from (command, date, machine, load, versions, commit: ``benchmarks/measure.py``
records them). Numbers are shown to 3 significant digits; the JSON holds them whole.
"""
from __future__ import annotations

import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
DOCS = (ROOT / "docs" / "validation.md", ROOT / "docs" / "performance.md", ROOT / "docs" / "engine-codegen.md",
        ROOT / "docs" / "models.md", ROOT / "docs" / "p695.md", ROOT / "docs" / "architecture.md")
BLOCK = re.compile(r"(<!-- generated: (?P<name>[a-z0-9_-]+) -->\n)(?P<body>.*?)(<!-- end generated: (?P=name) -->)", re.S)


def g(v, digits: int = 3) -> str:
    """A number to ``digits`` significant digits (the JSON keeps every digit)."""
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    return f"{v:.{digits}g}"


def plain(v, digits: int = 3) -> str:
    """As ``g`` but without an exponent (1180, not 1.18e+03) for numbers a table reads as plain."""
    return f"{float(f'{v:.{digits}g}'):g}"


def load(name: str) -> dict:
    return json.loads((RESULTS / f"{name}.json").read_text())


def loaded(m: dict) -> bool:
    """Other work shared the CPUs: the load average before the command above the CPU count, or after it
    above the CPU count + 1 (the load after counts the command's own processes, up to 2 workers)."""
    return m["load_average_before"][0] > m["cpus"] or m["load_average_after"][0] > m["cpus"] + 1


def provenance(rec: dict) -> str:
    m = rec["measured"]
    v = m["versions"]
    vers = ", ".join(f"{k} {v[k]}" for k in ("python", "numpy", "scipy", "numba", "mujoco", "exudyn") if k in v)
    load_text = (f"load average {m['load_average_before'][0]:g} before, {m['load_average_after'][0]:g} after"
                 + (" (**loaded**: other jobs shared the CPUs, so times are longer than on a quiet machine)"
                    if loaded(m) else ""))
    return (f"*Measured {m['date_utc']} UTC by `{rec['command']}` (exit {rec['exit_code']}, {m['wall_s']:.0f} s), "
            f"`python -m benchmarks.measure {rec['name']}`; {m['machine']}, {m['cpus']} CPUs, {load_text}; "
            f"{vers}; commit {m['git_commit'][:12]}{m['git_commit'][40:]}.*\n")


def table(head: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines) + "\n"


# ---- validation.md ----

def _metric(data: dict, case: str, engine: str, metric: str) -> dict | None:
    return next((m for m in data["metrics"] if m["case"] == case and m["engine"] == engine and m["metric"] == metric),
                None)


def _value_limit(m: dict | None) -> str:
    if m is None:
        return "–"
    mark = "" if m["pass"] else " **FAIL**"
    return f"{g(m['value'])} ({g(m['limit'])}){mark}"


def _verdict_rows(d: dict) -> list[list[str]]:
    """One row per case and engine: the verdict, its largest difference / bound and error / tolerance."""
    rows = []
    for case, per in (d.get("verdicts") or {}).items():
        for e, v in per.items():
            gated = [m for m in d["metrics"] if m["case"] == case and m["engine"] == e and m["gated"]]
            bound = [m for m in gated if m.get("bound")]
            wb = max(bound, key=lambda m: m["value"] / m["bound"]) if bound else None
            wt = max(gated, key=lambda m: max(m.get("estimate") or 0.0, m["value"]) / m["tolerance"]) if gated else None
            ev = v.get("evidence") or {}
            p_obs = ev.get("observed_order")
            rows.append([case, e, "PASS" if v["pass"] else "**FAIL**",
                         f"{g(wb['value'] / wb['bound'])} ({wb['metric']})" if wb else "–",
                         f"{g(max(wt.get('estimate') or 0.0, wt['value']) / wt['tolerance'])} ({wt['metric']})"
                         if wt else "–",
                         (f"rtol {g(ev.get('step'))}" if ev.get("setting") == "rtol" else
                          f"{g(ev.get('step'))} s, p {g(ev.get('order'))}") if ev.get("step") else "–",
                         g(p_obs) if isinstance(p_obs, (int, float)) and p_obs == p_obs else "–",
                         "" if v["pass"] else v["text"]])
    return rows


VERDICT_HEAD = ["case", "engine", "verdict", "largest difference / bound (metric)",
                "largest error / tolerance (metric)", "step, order p", "observed order", "why it fails"]


def _verdict_text(d: dict) -> str:
    n = sum(len(per) for per in (d.get("verdicts") or {}).values())
    ok = sum(v["pass"] for per in (d.get("verdicts") or {}).values() for v in per.values())
    return f"Verdict **{d['verdict']}**: {ok} of {n} case-engine verdicts pass ({len(d['runs'])} cases).\n\n"


def compare_variant() -> str:
    out = []
    for name, what in (("compare_variant", "as judged"), ("compare_variant_refine", "with --refine")):
        rec = load(name)
        d = rec["data"]
        refined = d.get("refined") or []
        out.append(provenance(rec) + "\n" + f"**{what}**. " + _verdict_text(d)
                   + ("Refined: " + "; ".join(f"{r['case']} {r['engine']} {r['setting']} {g(r['from'])} -> {g(r['to'])} s"
                                              for r in refined) + ".\n\n" if refined else "")
                   + table(VERDICT_HEAD, [r for r in _verdict_rows(d) if r[2] != "PASS" or r[1] != "semirecursive"]))
    return "\n".join(out)


def power() -> str:
    rec = load("power")
    d = rec["data"]
    rows = [[t["injection"], "yes" if t["seen_at_nominal"] else "**no**", ", ".join(t["engines_seeing"]) or "–",
             t["best_metric"] or "–", g(t["best_ratio"]), t["best_case"] or "–",
             "–" if t["smallest_seen_scale"] is None else f"x{g(t['smallest_seen_scale'])}"]
            for t in d["table"]]
    seen = sum(t["seen_at_nominal"] for t in d["table"])
    kinds: dict[str, int] = {}
    for r in d["rows"]:
        if r.get("failed") and r.get("scale") == 1.0:
            kinds[r.get("kind", "-")] = kinds.get(r.get("kind", "-"), 0) + 1
    return (provenance(rec) + "\n"
            + f"**{seen} of {len(d['table'])}** injected errors at 0.1 % (lengths 0.02 mm) fail the default gate "
              f"(cases {', '.join(c['name'] for c in d['cases'])}; engines {', '.join(d['engines'])}). Failing "
              "runs at the listed size by verdict: "
            + ", ".join(f"{k} {n}" for k, n in sorted(kinds.items())) + ". Largest difference / bound per error "
              "(the engine and case that saw it most); smallest seen: the ladder's size (x10, x100) at which one that "
              "passed was seen.\n\n"
            + table(["injected error", "seen", "by", "metric", "difference / bound", "on case", "smallest seen"], rows))


def verdict_cost() -> str:
    rec = load("bench_verdict_cost")
    d = rec["data"]
    med = d["median_compare_wall_s"]
    rows = []
    for side in ("baseline", "current"):
        for k, r in enumerate(d["rows"][side]):
            rows.append([side, str(k + 1), r.get("rule", "?"), g(r.get("compare_wall_s")), g(r.get("command_wall_s")),
                         g(r.get("command_cpu_s")), str(r.get("runs")), str(r.get("load_before")), str(r.get("verdict"))])
    cur = d["rows"]["current"][-1].get("run_cpu_s_by_kind") or {}
    return (provenance(rec) + "\n"
            + f"Warm gate, default cases: median compare wall **{g(med['baseline'])} s** with fixed limits (revision "
              f"{d['baseline']}) against **{g(med['current'])} s** with the per-run verdict: ratio "
              f"**{g(d['ratio'])}** (aim: at most 2), interleaved in one run.\n\n"
            + table(["code", "repeat", "rule", "compare wall s", "command wall s", "command CPU s", "runs",
                     "load before", "verdict"], rows)
            + "\nWhere the current gate's run CPU seconds go (last repeat): "
            + ", ".join(f"{k} {g(v)}" for k, v in sorted(cur.items(), key=lambda kv: -kv[1])) + ".\n")


def compare_gate() -> str:
    rec = load("compare")
    d = rec["data"]
    if (d.get("rule") or {}).get("name") == "estimated":
        return (provenance(rec) + "\n" + _verdict_text(d)
                + "Per case and engine: the largest ratio of a difference from the converged reference to its bound "
                  "k x (estimated error + reference's), the largest ratio of the error (the larger of the estimate "
                  "and the difference) to the engineering tolerance, the step and the order the estimate assumed, "
                  "and the order observed against the reference (h against h/2):\n\n"
                + table(VERDICT_HEAD, _verdict_rows(d)))
    seismic_cases = {m["case"] for m in d["metrics"] if m["metric"] == "max_du_rel"}
    drive_metrics = ("max_dF_rel", "rms_dF_rel", "loop_area_rel", "peak_force_rel")
    seismic_metrics = ("max_du_rel", "max_dF_device_rel", "peak_u_rel", "peak_a_rel")
    drive_rows, seismic_rows = [], []
    for case, per in d["runs"].items():
        seismic = case in seismic_cases
        for e in ("mujoco", "exudyn"):
            if e not in per:
                continue
            rows = seismic_rows if seismic else drive_rows
            if per[e]["status"] != "ok":
                rows.append([case, e, f"ERROR: {per[e]['message']}"] + [""] * 3)
                continue
            rows.append([case, e] + [_value_limit(_metric(d, case, e, m))
                                     for m in (seismic_metrics if seismic else drive_metrics)])
    gated = [m for m in d["metrics"] if m["gated"]]
    failed = [m for m in gated if not m["pass"]]
    worst = {}
    for m in d["metrics"]:
        if m["metric"] in ("energy_balance_rel", "energy_residual_rel", "closure_max", "tracking_error"):
            key = (m["engine"], m["metric"])
            if key not in worst or m["value"] > worst[key]["value"]:
                worst[key] = m
    own_rows = [[e, metric, g(m["value"]), m["case"], g(m["limit"]), "pass" if m["pass"] else "**FAIL**"]
                for (e, metric), m in sorted(worst.items())]
    return (provenance(rec) + "\n"
            + f"Verdict **{d['verdict']}**: {len(gated) - len(failed)} of {len(gated)} gated metrics within their limits "
              f"({len(d['runs'])} cases). Value (limit) of each peer against the in-house reference; drive cases on "
              "the steady cycle (force vector, loop work, peak |F|):\n\n"
            + table(["case", "engine", "max\\|ΔF\\|/max\\|F\\|", "rms\\|ΔF\\|/max\\|F\\|", "loop area",
                     "peak force"], drive_rows)
            + "\nSeismic cases, at every output time (plate displacement, device force, peak displacement, peak "
              "absolute acceleration):\n\n"
            + table(["case", "engine", "max\\|Δu\\|/max\\|u\\|", "max\\|ΔF_device\\|/max\\|F_device\\|",
                     "peak \\|u\\|", "peak \\|a_abs\\|"], seismic_rows)
            + "\nEach engine's own checks, its worst case (energy balance of a drive cycle, energy residual of a "
              "seismic run, loop closure [m], drive tracking [m]):\n\n"
            + table(["engine", "metric", "worst value", "on case", "limit", "verdict"], own_rows))


def convergence() -> str:
    rec = load("compare")
    c = rec["data"].get("convergence")
    if not c:
        return provenance(rec) + "\n(no convergence study in this run)\n"
    return provenance(rec) + "\n" + _convergence_table(c)


def _convergence_table(c: dict) -> str:
    if "error" in c:
        return f"The convergence study failed: {c['error']}\n"
    first = next(iter(c.values()))
    out = [f"Case {first['case']}, against {first['reference']}; max\\|ΔF\\|/max\\|F\\| and loop area (relative) on "
           "the last cycle, wall seconds per cycle:\n"]
    for engine, sweep in c.items():
        pts = sweep["points"]
        head = [f"{engine}: {sweep['setting']}"] + [g(p["value"]) for p in pts]
        rows = [["max\\|ΔF\\|/max\\|F\\|"] + [g(p.get("max_dF_rel")) if "error" not in p else "failed" for p in pts],
                ["loop area"] + [g(p.get("loop_area_rel")) if "error" not in p else "" for p in pts],
                ["wall s per cycle"] + [g(p.get("wall_time")) if "error" not in p else "" for p in pts]]
        out.append(table(head, rows))
    return "\n".join(out)


def tables_5_6() -> str:
    rec = load("tables")
    rows = rec["data"]
    keys = list(rows[0]) if rows else []
    diffs = [abs(float(r["difference [mm]"])) for r in rows]
    return (provenance(rec) + "\n"
            + f"{len(rows)} entries; largest \\|X_max model − paper\\| = {g(max(diffs))} mm (columns as in "
              "`tables.csv`, the model's values to 4 significant digits):\n\n"
            + table(keys, [[r[k] if not _isfloat(r[k]) else g(float(r[k]), 4) for k in keys] for r in rows]))


def _isfloat(s) -> bool:
    try:
        float(s)
        return True
    except (TypeError, ValueError):
        return False


def engine_benchmarks() -> str:
    rec = load("benchmark")
    d = rec["data"]
    rows = []
    for name, r in d["problems"].items():
        rows.append([name, g(r.get("error")), g(r.get("energy_drift")), g(r.get("cpu_time")),
                     "pass" if r.get("passed") else "**not met**"])
    return (provenance(rec) + "\n"
            + table(["problem", "error vs reference", "energy drift [J]", "CPU [s]", "goal"], rows))


def model_benchmarks() -> str:
    """nsd compare --model on every description under models/ (benchmarks/bench_models.py)."""
    rec = load("bench_models")
    rows = []
    for name, m in rec["data"].items():
        if "cases" not in m:
            rows.append([name, "-", "-", "failed: " + " ".join(m.get("error", [])), "-", "-", "-"])
            continue
        for case, c in m["cases"].items():
            for e, v in c["engines"].items():
                step = ", ".join(f"{k} {plain(x) if isinstance(x, (int, float)) else x}" for k, x in v["settings"].items()) or "-"
                rows.append([name, case, e, "PASS" if v["pass"] else "**FAIL**", g(v["worst_ratio"]),
                             g(v["worst_error"]), f"{plain(v['wall_time'])} ({step})" if v.get("wall_time") else "-"])
    return (provenance(rec) + "\n"
            + table(["model", "case", "engine", "verdict", "largest difference / bound", "largest error / tolerance",
                     "wall s (settings)"], rows))


def campaign() -> str:
    """The randomized differential campaign (benchmarks/campaign.py; benchmarks/docs_campaign.py)."""
    from benchmarks.docs_campaign import campaign as render
    return render(load, provenance, table, g, plain)


def first_command() -> str:
    """The README's first command before and after, side by side (benchmarks/docs_first_command.py)."""
    from benchmarks.docs_first_command import first_command as render
    return render(load, provenance, table, g, plain)


def symbolic_equations() -> str:
    """The symbolic engine's derived equations of one small mechanism (benchmarks/docs_symbolic.py)."""
    from benchmarks.docs_symbolic import equations as render
    return render(load, provenance, table, g, plain)


def symbolic_models() -> str:
    """The symbolic engine on every benchmark description (benchmarks/docs_symbolic.py)."""
    from benchmarks.docs_symbolic import models as render
    return render(load, provenance, table, g, plain)


def symbolic_device() -> str:
    """The device's drive description in the symbolic engine (benchmarks/docs_symbolic.py)."""
    from benchmarks.docs_symbolic import device as render
    return render(load, provenance, table, g, plain)


def symbolic_campaign() -> str:
    """Ten generated mechanisms with the symbolic engine as a 4th peer (benchmarks/docs_symbolic.py)."""
    from benchmarks.docs_symbolic import campaign as render
    return render(load, provenance, table, g, plain)


def model_builders() -> str:
    """The device's description in MuJoCo against the hand-written adapter (bench_model_builders)."""
    rec = load("bench_model_builders")
    d = rec["data"]
    names = {"a_adapter": "hand-written adapter (Euler)", "b_builder_euler": "description builder, compiled, Euler",
             "b_builder_rk4": "description builder, compiled, RK4 (its default)"}
    rows = [[names.get(k, k), g(v["median_wall_s"]), g(v["ratio_to_adapter"]), g(v["max_abs_dF_x_over_peak"])]
            for k, v in d["runs"].items()]
    c = d["case"]
    return (provenance(rec) + "\n"
            + f"The device driven at {g(c['amplitude_m'] * 1e3)} mm, {g(c['frequency_hz'])} Hz, {c['cycles']} cycles, "
              f"h = {g(c['timestep_s'])} s, the runs interleaved; wall seconds of the stepping (median), and F_x "
              "against the adapter's over its peak.\n\n"
            + table(["MuJoCo model", "wall s", "ratio to the adapter", "max abs ΔF_x / peak"], rows))


def described_gate() -> str:
    """The gate's drive cases: each peer's hand-written adapter against its description builder
    (benchmarks/bench_described_gate.py)."""
    rec = load("bench_described_gate")
    d = rec["data"]
    names = {"adapter": "hand-written adapter", "described": "builder, the adapter's settings",
             "described_rk4": "builder, RK4 at the adapter's step", "described_rk4_2h": "builder, RK4 at twice the step",
             "described_predicted": "builder, forces once a step (predicted)"}
    rows = []
    for case, row in d["cases"].items():
        for engine, runs in row["engines"].items():
            for path, r in runs.items():
                if not isinstance(r, dict):
                    continue
                step = r["settings"].get("timestep", r["settings"].get("step_size"))
                how = f"{r['settings'].get('integrator', '')} {g(step)} s".strip() if step else "its defaults (the builder rows: the same step)"
                rows.append([case, engine, names.get(path, path), how, "PASS" if r["passes"] else "FAIL",
                             g(r["difference"]), g(r["estimate"]), plain(r["wall_s"]),
                             g(r["time_ratio"]) if "time_ratio" in r else "1"])
    return (provenance(rec) + "\n"
            + f"Rule: {d['rule']}; the difference is the steady cycle's max \\|F − F_ref\\| / peak \\|F_ref\\| against "
              "the gate's converged in-house reference; the estimate Richardson from h and h/2; wall seconds of the h "
              "run's stepping.\n\n"
            + table(["case", "engine", "model", "integrator, step", "verdict", "difference", "estimate", "wall s",
                     "time / adapter's"], rows))


def gate_described() -> str:
    """The gate's drive cases through the adapters and through the builders (bench_gate_described)."""
    rec = load("bench_gate_described")
    d = rec["data"]
    a, b = d["runs"]["adapters"], d["runs"]["described"]
    rows = []
    for case, engines in a["cases"].items():
        for e, r in engines.items():
            o = b["cases"][case][e]
            rows.append([case, e, "PASS" if r["pass"] else "FAIL", "PASS" if o["pass"] else "FAIL",
                         plain(r["cpu_s"]), plain(o["cpu_s"]), g(d["cpu_ratio_described_over_adapter"][case][e])])
    text = (provenance(rec) + "\n"
            + f"`nsd compare --cases` on the gate's cases, every metric and the gate's rule, twice: the peers' "
              f"adapters (verdict {a['verdict']}), then `model = \"described\"` with Exudyn's builder at `builder_forces = "
              f"\"{d['exudyn_forces']}\"` (drive) and \"{d.get('exudyn_seismic_forces', 'compiled')}\" (seismic) "
              f"(verdict {b['verdict']}); CPU seconds of each peer's h run in its warm worker.\n\n"
            + table(["case", "peer", "adapter", "builder", "adapter CPU s", "builder CPU s", "builder / adapter"], rows))
    drive = d.get("drive_timing_interleaved") or {}
    if drive:
        drows = []
        for case, per in drive.items():
            for e in ("mujoco", "exudyn"):
                if e not in per:
                    continue
                best = {m: min(x["cpu_s"] for x in per[e]["runs"][m]) for m in ("adapter", "described")}
                drows.append([case, e, plain(best["adapter"]), plain(best["described"]),
                              g(per[e]["cpu_ratio_described_over_adapter"]),
                              plain(max(x["load_before"] for v in per[e]["runs"].values() for x in v), 2)])
        text += ("\n\nThe drive cases again, each peer's whole run timed from outside for both models (CPU seconds "
                 "of `run_engine`, the model's build included: the table above takes an adapter's own `cpu_time`, "
                 "its stepping only), adapter and builder interleaved in one process after an untimed warm-up, "
                 "the fastest of the rounds, and the 1-minute load before the runs:\n\n"
                 + table(["case", "peer", "adapter CPU s", "builder CPU s", "builder / adapter", "load (max)"], drows))
    timing = d.get("seismic_timing_interleaved") or {}
    if timing:
        trows = []
        for case, per in timing.items():
            for e in ("mujoco", "exudyn"):
                if e not in per:
                    continue
                best = {m: min(per[e]["runs"][m], key=lambda x: x["cpu_s"]) for m in ("adapter", "described")}
                trows.append([case, e, plain(per["model_duration_s"]), plain(best["adapter"]["cpu_s"]),
                              plain(best["described"]["cpu_s"]), g(per[e]["cpu_ratio_described_over_adapter"]),
                              plain(best["adapter"]["wall_s_per_model_s"]), plain(best["described"]["wall_s_per_model_s"]),
                              plain(max(x["load_before"] for v in per[e]["runs"].values() for x in v), 2)])
        text += ("\n\nThe seismic cases again, each peer's whole run (the model's build included) adapter and builder "
                 "interleaved in one process after an untimed warm-up, the fastest of the rounds; wall seconds per "
                 "model second (the aim: at most 1) and the 1-minute load before the runs:\n\n"
                 + table(["case", "peer", "model s", "adapter CPU s", "builder CPU s", "builder / adapter",
                          "adapter wall s / model s", "builder wall s / model s", "load (max)"], trows))
    return text


def direction_study() -> str:
    rec = load("polar")
    d = rec["data"]
    fields = (("x_max", 1e3, "mm", "X_max"), ("k0", 1e-3, "kN/m", "K0"), ("k_min", 1e-3, "kN/m", "K_min"),
              ("loop_area", 1.0, "J", "loop area"), ("peak_force", 1.0, "N", "peak \\|F\\|"))
    rows = []
    for n, des in d["designs"].items():
        cells = []
        for f, scale, unit, _ in fields:
            mean = sum(des[f]) / len(des[f])
            cells.append(f"{plain(mean * scale)} {unit} ({plain(100 * des['spread'][f], 2)} %)")
        rows.append([n] + cells)
    return (provenance(rec) + "\n"
            + f"n = n_w = n_r, quasi-static, ψ every {g(d['step_deg'])}°, A = {g(d['amplitude'] * 1e3)} mm; the mean "
              "over the turn and, in brackets, the spread (max − min) / \\|mean\\|:\n\n"
            + table(["n"] + [h for *_, h in fields], rows))


# ---- performance.md ----

def bench_cycle() -> str:
    rec = load("bench_cycle")
    d = rec["data"]
    rows = [[f"line, A = {g(c['amplitude'] * 1e3)} mm, {g(c['frequency'])} Hz", g(1e3 * c["median_s_per_cycle"]),
             g(1e3 * c["median_cpu_s_per_cycle"]), str(c["steps"]), str(c["nfev"]), g(c["dF"])] for c in d["cases"]]
    return (provenance(rec) + "\n"
            + f"In-house engine, {d['solver'].get('method')} rtol {g(d['solver'].get('rtol'))}"
            + "".join(sorted({f", the {c['evaluation']} evaluation" for c in d["cases"] if c.get("evaluation")}))
            + ", 2 cycles of 2000 samples, "
              f"median of {d['cases'][0]['runs']} runs after a warm-up (compilation excluded):\n\n"
            + table(["case", "ms per cycle, wall", "ms per cycle, CPU", "steps / 2 cycles", "rhs / 2 cycles",
                     "max\\|ΔF\\|/max\\|F\\| vs rtol 1e-10"], rows))


def device_models() -> str:
    """The hand-built device model against the description-built one (benchmarks/bench_device_models.py)."""
    rec = load("bench_device_models")
    d = rec["data"]
    rows = [[r["case"], plain(1e3 * r["hand_built_s"]), plain(1e3 * r["description_built_s"]), g(r["ratio"]),
             g(r["max_dF_x_rel"])] for r in d["rows"]]
    return (provenance(rec) + "\n"
            + f"Two cycles of 500 samples, {d['settings']['method']} rtol {g(d['settings']['rtol'])}, each model warm, "
              f"median of {d['repeats']} alternating runs:\n\n"
            + table(["case", "hand-built [ms]", "description-built [ms]", "ratio [-]",
                     "max\\|ΔF_x\\|/max\\|F_x\\| [-]"], rows))


def bench_rhs() -> str:
    rec = load("bench_rhs")
    d = rec["data"]
    rows = [[part, g(1e6 * s)] for part, s in d["seconds"].items()]
    return (provenance(rec) + "\n"
            + f"One evaluation of the device model (the Figure 6 drive A = 15 mm, 1 Hz, near its start), the least "
              f"of {d['repeats']} loops of {d['loops']} calls each in a compiled loop; the parts on the same state. "
              f"Newton iterations per assembly: {g(d['newton_iterations_per_assembly'])} (generic), "
              f"{g(d['newton_iterations_per_assembly_generated'])} (generated).\n\n"
            + table(["what", "µs a call"], rows))


def bench_seismic() -> str:
    rec = load("bench_seismic")
    d = rec["data"]
    rows = [[c["case"], g(c["model_s"]), g(c["wall_s_per_model_s"]), g(c["cpu_s_per_model_s"]), str(c["steps"]),
             str(c["nfev"]), g(1e3 * c["peak_u_m"]), g(c["energy_relative_residual"])] for c in d["cases"]]
    return (provenance(rec) + "\n"
            + table(["run", "model s", "wall s per model s", "CPU s per model s", "steps", "rhs", "peak \\|u\\| [mm]",
                     "energy residual"], rows))


def gate_times() -> str:
    rec = load("compare")
    d = rec["data"]
    engines = sorted({e for per in d["runs"].values() for e in per}, key=["semirecursive", "mujoco", "exudyn"].index)

    def cell(r):   # an in-house run names its evaluation (generated or generic)
        return g(r.get("wall_time")) + (f" ({r['evaluation']})" if r.get("evaluation") else "")

    rows = [[case] + [cell(per[e]) if e in per else "–" for e in engines] for case, per in d["runs"].items()]
    used = any(per[e].get("evaluation") for per in d["runs"].values() for e in per)
    evaluation = (" In brackets, the evaluation each in-house run used (NSD_EVALUATOR=auto: the generic kernels "
                  "unless that structure's generated evaluation was already compiled, docs/compilation.md)."
                  if used else "")
    return (provenance(rec) + "\n"
            + "Wall seconds of each engine's run of each default case in the gate (the run alone: start-up and "
              "imports excluded; the cases run in parallel on the workers)." + evaluation + "\n\n"
            + table(["case"] + engines, rows))


def bench_start() -> str:
    rec = load("bench_start")
    d = rec["data"]
    rows = []
    for i, pair in enumerate(d["pairs"], 1):
        for state in ("cold", "warm"):
            r = pair[state]
            comp = ", ".join(f"{e} {g(v)}" for e, v in (r.get("compile_in_runs_s") or {}).items() if v) or "0"
            rows.append([f"{state}" + (f" ({i})" if len(d["pairs"]) > 1 else ""), g(r["command_wall_s"]),
                         g(r["command_cpu_s"]), g(r.get("compare_wall_s")), g(r.get("worker_ready_s")),
                         g(r.get("worker_warm_s")), comp, f"{r.get('verdict', r.get('error'))} (exit {r['exit_code']})"])
    if len(d["pairs"]) > 1:   # the figure to quote: the median of the pairs, each column on its own
        for state in ("cold", "warm"):
            m = d["median"][state]
            rows.append([f"**{state}, median**", g(m["command_wall_s"]), g(m["command_cpu_s"]),
                         g(m.get("compare_wall_s")), g(m.get("worker_ready_s")), g(m.get("worker_warm_s")), "", ""])
    return (provenance(rec) + "\n"
            + f"`{d['command']}` in a fresh process, cold (an empty cache folder: every kernel compiled) then warm "
              "(the same command again); wall and CPU seconds of the whole command, the compare's own wall seconds, "
              "the slowest worker's start-up (spawn, imports and warm-up: where the compilation goes) and its "
              "warm-up alone, and compilation left inside the runs:\n\n"
            + table(["cache", "command wall s", "command CPU s", "compare wall s", "worker ready s", "of which warm-up s",
                     "compile in runs s", "verdict"], rows))


def compile_units() -> str:
    rec = load("compile_units")
    d = rec["data"]
    rows = [[" ".join([r["item"], r.get("what", "")]).strip(), g(r["cold_cpu_s"]), g(r["warm_cpu_s"]), g(r["cold_cpu_s"] - r["warm_cpu_s"])] for r in d["rows"]]
    rows.append(["**sum**", g(d["cold_cpu_s"]), g(d["warm_cpu_s"]), g(d["cold_cpu_s"] - d["warm_cpu_s"])])
    return (provenance(rec) + "\n"
            + "The gate's worker warm-up for the default cases, each item alone in one process, on an empty cache "
              "folder (cold) and on the cache it left (warm); CPU seconds. In the gate two workers share the "
              "compiling; the peers' tiny runs (warm-call) run in each worker.\n\n"
            + table(["item", "cold CPU s", "warm CPU s", "compilation CPU s"], rows))


def bench_record_set() -> str:
    rec = load("bench_record_set")
    d = rec["data"]
    rows = [[r["record"], g(r["single_wall_s"]), g(r["set_wall_s"]), g(r["ratio_set_over_single"]),
             g(r["single_cpu_s"]), g(r["set_cpu_s"])] for r in d["rows"]]
    verdict = "met" if d["met"] else "**not met**"
    return (provenance(rec) + "\n"
            + f"Set {d['set']}, records {d['records']}, window {g(d['window_record_s'][0])}–{g(d['window_record_s'][1])} "
              f"record s, each with and without the device; {d['workers']} workers, median of {d['repeats']}. Seconds "
              "per record (its two runs): alone in a warm process, and in the set as its workers timed them; the "
              f"workers' start-up is apart (median {g(d['startup_ready_s_median'])} s until ready, of which warm-up "
              f"{g(d['startup_warm_s_median'])} s; the set's elapsed time {g(d['set_elapsed_s_median'])} s). Worst "
              f"ratio {g(d['worst_ratio'], 5)}, aim ≤ {g(d['aim_ratio'])}: {verdict}"
              + (f"; the solver's CPU seconds in the set over alone: {g(d['median_cpu_ratio'])} (median)"
                 if "median_cpu_ratio" in d else "")
              + {True: "; this kernel shares CPU time per session (sched_autogroup on)", False: "",
                 None: ""}[d.get("sched_autogroup")] + ".\n\n"
            + table(["record", "single warm run s", f"in the set ({d['workers']} workers) s", "ratio",
                     "single CPU s (solver)", "set CPU s (solver)"], rows))


def bench_ida_farfield() -> str:
    """The far-field set through nsd ida with the peers' cross-check (benchmarks/bench_ida.py)."""
    rec = load("bench_ida_farfield")
    m, d = rec["measured"], rec["data"]
    check = d.get("elapsed_cross_check_s") or 0.0
    n_check = sum(c["runs"] for c in (d.get("cross_check_cost") or {}).values())
    rows = [["the IDA's runs (in-house, 2 workers)", str(d["runs"] - n_check), plain(m["wall_s"] - check),
             "elapsed, start-up included"]]
    for e, c in (d.get("cross_check_cost") or {}).items():
        rows.append([f"cross-check: {e}", str(c["runs"]), plain(c["wall_s"]), "each run's own wall s"])
    rows.append(["cross-check, elapsed", "-", plain(check), f"{100 * check / m['wall_s']:.0f} % of the whole"])
    rows.append(["whole command", "-", plain(m["wall_s"]), f"aim ≤ 600 s: {'met' if m['wall_s'] <= 600 else 'not met'}"])
    dev = ((d.get("cross_check") or {}).get("device") or {})
    verdicts = ", ".join(f"{e} du {v['du']:.1e}" + (f" (estimate {v['estimates']['du']['estimate']:.1e}, {v['verdict']}"
                                                     + _refined(v) + ")" if isinstance(v.get("estimates"), dict) else "")
                         for e, v in (dev.get("engines") or {}).items() if "du" in v)
    load_text = (f"load average {m['load_average_before'][0]:g} before, {m['load_average_after'][0]:g} after"
                 + (" (**loaded**)" if m.get("loaded") else ""))
    return (f"*Measured {m['date_utc']} UTC by `{rec['command']}` (exit {rec['exit_code']}), "
            f"`python benchmarks/bench_ida.py --record-set farfield --records 1-22 --engines semirecursive,mujoco,exudyn "
            f"--out benchmarks/results/bench_ida_farfield.json`; {m['cpus']} CPUs, {load_text}; "
            f"commit {m.get('git_commit', '')[:12]}.*\n\n"
            + f"{d['runs']} runs in all ({d['runs_stopped']} stopped by the rod's reach), "
              f"{plain(d['model_seconds_completed_runs'])} model s in the completed ones; the median record "
              f"({dev.get('record')}) with the device: {verdicts or 'not cross-checked'}.\n\n"
            + table(["part", "runs", "wall s", "note"], rows))


def _refined(v: dict) -> str:
    """A refined peer's cross-check (nsd_cli.ida_refine): its first step and verdict, the step it ran again at."""
    r, first = v.get("refined"), v.get("first") or {}
    if not r:
        return ""
    (k, a), (_, b) = next(iter(r["from"].items())), next(iter(r["to"].items()))
    worst = max(((m, e) for m, e in (first.get("estimates") or {}).items()), key=lambda x: x[1]["estimate"],
                default=None)
    said = f", its largest estimate {worst[0]} {worst[1]['estimate']:.1e}" if worst else ""
    dF = v.get("dF")
    cap = f" (its runs asked {g(r['asked'])} s; at most 8 x the steps)" if r.get("capped") else ""
    return (f"; refined: {k} {g(a)} -> {g(b)} s{cap}, where its first pair said {first.get('verdict')}{said}"
            + (f"; dF {dF:.1e}, estimate {v['estimates']['dF']['estimate']:.1e}" if dF is not None else ""))


def _setting(s: dict) -> str:
    return ", ".join(f"{k} {g(v) if isinstance(v, float) else v}" for k, v in s.items()) or "case default"


def work_precision() -> str:
    rec = load("work_precision")
    d = rec["data"]
    rows = []
    for c in d["cases"]:
        ih = c["at_aim"].get("semirecursive")
        peer = c.get("best_peer")
        p = c["at_aim"].get(peer) if peer else None
        rows.append([c["name"], f"{g(ih['cpu_per_cycle'])} ({_setting(ih['settings'])})" if ih else "not reached",
                     f"{g(p['cpu_per_cycle'])} ({peer}, {_setting(p['settings'])})" if p else "not reached",
                     g(c["ratio_best_peer_over_in_house"])])
    ratios = [c["ratio_best_peer_over_in_house"] for c in d["cases"] if c["ratio_best_peer_over_in_house"] is not None]
    behind = sum(r < 1 for r in ratios)
    return (provenance(rec) + "\n"
            + f"CPU seconds per cycle (outputs included, median of {d['repeats']}) at the cheapest setting within the "
              f"{g(d['aim'])} aim (last-cycle max\\|ΔF\\|/max\\|F\\| against the in-house model at rtol 1e-10), the "
              "engines interleaved per case; ratio ≥ 1: the in-house engine is the cheaper. In-house behind on "
              f"{behind} of {len(ratios)} cases.\n\n"
            + table(["case", "in-house CPU s (setting)", "best peer CPU s (engine, setting)",
                     "ratio best peer / in-house"], rows))


def bench_cold() -> str:
    rec = load("bench_cold")
    d = rec["data"]
    names = [n for n in d["after"]["median"] if n in d["before"]["median"]]
    rows = []
    for n in names:
        for state in ("cold", "warm"):
            b, a = d["before"]["median"][n].get(state), d["after"]["median"][n].get(state)
            if not (a and b):
                continue
            rows.append([n.replace("sequence:", "one cache: "), state, g(b["wall_s"]), g(a["wall_s"]), g(b["cpu_s"]),
                         g(a["cpu_s"]), f"{g(b['compile_notices'])} / {g(a['compile_notices'])}",
                         f"{g(b['load_before'])} / {g(a['load_before'])}"] + [g(x.get("compare_wall_s")) for x in (b, a)])
    return (provenance(rec) + "\n"
            + f"A newcomer's first commands, before and after {d.get('change', 'compiling every mode at once')} (each "
              "commit a `git archive`, the two run one after the other on the same machine; median of "
              f"{d['after'].get('repeats', 1)}, each repeat on its own empty cache): `cycle` (`nsd cycle --amplitude 0.015 --frequency 1`), `sweep` "
              "(`nsd sweep --paper`) and `compare` (the README's first command, `nsd compare --convergence --report`) "
              "each on its own empty cache folder, cold then warm; `one cache:` a drive cycle, a seismic window and "
              "the same window under a 3-story building one after another on one empty cache (how many times each "
              "compiles). Wall and CPU seconds of the whole command (its workers and helpers included), the "
              "\"nsd: compiling\" lines it printed and the 1-minute load when it started. On a loaded machine the "
              "CPU seconds are the figure to compare; wall seconds stretch with the load.\n\n"
            + table(["command", "cache", "wall s before", "wall s after", "CPU s before", "CPU s after",
                     "compile lines before / after", "load before / after", "compare wall s before",
                     "compare wall s after"], rows))


def bench_peer_seismic() -> str:
    rec = load("bench_peer_seismic")
    d = rec["data"]
    rows, diffs = [], {}
    for r in d["rows"]:
        if "largest_relative_difference" in r:
            diffs[r["case"]] = r["largest_relative_difference"]
            continue
        rows.append([r["case"], r["variant"], g(r["model_s"]), g(r["wall_s_per_model_s"]), g(r["cpu_s_per_model_s"]),
                     _setting(r["settings"])])
    return (provenance(rec) + "\n"
            + f"Each peer on each seismic case of comparisons/cases.toml at the case's settings, the whole window, "
              f"median of {d['repeats']} (variants interleaved); seconds per model second. MuJoCo and Exudyn run the "
              "models their builders make from the seismic description; MuJoCo its compiled passive forces and step "
              "loop by default (comparisons/builders/mujoco_compiled.py) and its Python ones as the check: "
              "the largest difference between the two over every column, relative to the column's peak, "
              + ", ".join(f"{c} {g(v)}" for c, v in diffs.items()) + ". Aim: each peer ≤ 1 wall s per model s on a "
              "quiet machine (CPU s per model s is what a quiet machine's wall s would be). The in-house engine runs "
              "its generated evaluation (the benchmark's docstring says why).\n\n"
            + table(["case", "engine", "model s", "wall s / model s", "CPU s / model s", "settings"], rows))


def bench_dask() -> str:
    """A record set's IDA on a Dask cluster of local worker processes, beside the local pool."""
    rec = load("bench_dask")
    d = rec["data"]
    rows = [[r["where"], str(r["workers"]), str(r["runs"]), g(r["ida_elapsed_s"]), g(r["sum_of_run_wall_s"]),
             g(r["efficiency_from_1"]) if "efficiency_from_1" in r else "–",
             g(1e3 * r["overhead_per_task_s"]) if "overhead_per_task_s" in r else "–",
             f"{g(r['load_before'])} / {g(r['load_after'])}"] for r in d["rows"]]
    m = rec["measured"]
    load_text = (f"load average {m['load_average_before'][0]:g} before, {m['load_average_after'][0]:g} after"
                 + (" (**loaded**)" if m.get("loaded") else ""))
    return (f"*Measured {m['date_utc']} UTC by `{rec['command']}` (exit {rec['exit_code']}, {m['wall_s']:.0f} s), "
            f"`python benchmarks/bench_dask.py --records {d['records']} --out benchmarks/results/bench_dask.json`; "
            f"{m['machine']}, {m['cpus']} CPUs, {load_text}; commit {m['git_commit'][:12]}{m['git_commit'][40:]}.*\n\n"
            + f"`nsd ida` over far-field records {d['records']} with and without the device (hunt and fill, "
              "in-house engine, no cross-check), on a Dask `LocalCluster` of 1 and 2 worker processes (one thread "
              "each, warmed before: their start-up is not in the number) and on the local pool of 2 workers (its "
              "start-up is). IDA s: from the first job submitted to the last result stored; efficiency from 1 "
              "worker: T1 / (k Tk); overhead per task: empty tasks mapped onto the cluster and gathered, wall "
              "ms per task; load: the 1-minute load when each command started / ended.\n\n"
            + table(["where", "workers", "runs", "IDA s", "sum of the runs' own wall s", "efficiency from 1 worker",
                     "overhead per empty task, ms", "load start / end"], rows))


def p695_evaluation() -> str:
    """A whole nsd p695 run (benchmarks/p695_results.py; benchmarks/docs_p695.py)."""
    from benchmarks.docs_p695 import evaluation
    return evaluation(load, table, g, plain)


def p695_what_passes() -> str:
    """What passes: the capacities, the device variant, its three engines (benchmarks/docs_p695.py)."""
    from benchmarks.docs_p695 import what_passes
    return what_passes(load, table, g, plain)


RENDER = {"compare-gate": compare_gate, "convergence": convergence, "tables-5-6": tables_5_6,
          "engine-benchmarks": engine_benchmarks, "direction-study": direction_study, "bench-cycle": bench_cycle,
          "bench-rhs": bench_rhs, "bench-seismic": bench_seismic,
          "gate-times": gate_times, "bench-start": bench_start, "compile-units": compile_units,
          "bench-record-set": bench_record_set, "compare-variant": compare_variant, "power": power,
          "verdict-cost": verdict_cost, "model-benchmarks": model_benchmarks, "campaign": campaign,
          "first-command": first_command,
          "model-builders": model_builders, "described-gate": described_gate,
          "gate-described": gate_described,
          "work-precision": work_precision, "bench-cold": bench_cold, "bench-peer-seismic": bench_peer_seismic,
          "bench-ida-farfield": bench_ida_farfield, "bench-dask": bench_dask,
          "symbolic-equations": symbolic_equations, "symbolic-models": symbolic_models,
          "symbolic-campaign": symbolic_campaign, "symbolic-device": symbolic_device,
          "p695-evaluation": p695_evaluation, "p695-what-passes": p695_what_passes, "device-models": device_models}


def regenerate(text: str) -> str:
    def sub(m: re.Match) -> str:
        name = m.group("name")
        if name not in RENDER:
            raise SystemExit(f"benchmarks.docs: unknown generated block {name!r}; known: {', '.join(RENDER)}")
        return m.group(1) + RENDER[name]() + m.group(4)
    return BLOCK.sub(sub, text)


def stale() -> list[str]:
    """The documents whose generated blocks differ from what the JSON gives."""
    return [str(p.relative_to(ROOT)) for p in DOCS if p.is_file() and regenerate(p.read_text()) != p.read_text()]


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv == ["--check"]:
        bad = stale()
        for p in bad:
            print(f"{p}: generated tables differ from benchmarks/results/*.json (run python -m benchmarks.docs)",
                  file=sys.stderr)
        return 1 if bad else 0
    if argv:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    from nsd_core.common.files import atomic_write_text
    for p in DOCS:
        if p.is_file():
            atomic_write_text(p, regenerate(p.read_text()))
            print(f"wrote {p.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
