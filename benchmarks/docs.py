"""The tables of docs/validation.md, docs/performance.md and docs/engine-codegen.md, generated from benchmarks/results/*.json.

    python -m benchmarks.docs            rewrite every generated block from the JSON
    python -m benchmarks.docs --check    exit 1 if a block differs from what the JSON gives

A generated block sits between ``<!-- generated: NAME -->`` and ``<!-- end generated: NAME -->``;
everything outside the blocks is hand-written and left alone. Each block starts with where its
numbers come from (command, date, machine, load, versions, commit: ``benchmarks/measure.py``
records them). Numbers are shown to 3 significant digits; the JSON holds them whole.
"""
from __future__ import annotations

import re
import sys

from benchmarks.docs_common import ROOT, g, load, plain, provenance, table
from benchmarks.docs_performance import (bench_cold, bench_cycle, bench_dask, bench_ida_farfield, bench_peer_seismic,
                                        bench_record_set, bench_rhs, bench_seismic, bench_start, bench_subnormals,
                                        compile_units,
                                        device_models, gate_times, work_precision)

DOCS = (ROOT / "docs" / "validation.md", ROOT / "docs" / "performance.md", ROOT / "docs" / "engine-codegen.md",
        ROOT / "docs" / "models.md", ROOT / "docs" / "p695.md", ROOT / "docs" / "architecture.md")
BLOCK = re.compile(r"(<!-- generated: (?P<name>[a-z0-9_-]+) -->\n)(?P<body>.*?)(<!-- end generated: (?P=name) -->)", re.S)




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


def device_variants() -> str:
    """The device's own description on variants the gate was not tuned on (benchmarks/docs_campaign.py)."""
    from benchmarks.docs_campaign import device_variants as render
    return render(load, provenance, table, g, plain)


def first_command() -> str:
    """The README's first command before and after, side by side (benchmarks/docs_first_command.py)."""
    from benchmarks.docs_first_command import first_command as render
    return render(load, provenance, table, g, plain)


def test_command() -> str:
    """The README's test command in fresh clones on empty caches (benchmarks/docs_first_command.py)."""
    from benchmarks.docs_first_command import test_command as render
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
          "device-variants": device_variants,
          "first-command": first_command, "test-command": test_command,
          "model-builders": model_builders, "described-gate": described_gate,
          "gate-described": gate_described,
          "work-precision": work_precision, "bench-cold": bench_cold, "bench-peer-seismic": bench_peer_seismic,
          "bench-ida-farfield": bench_ida_farfield, "bench-dask": bench_dask,
          "symbolic-equations": symbolic_equations, "symbolic-models": symbolic_models,
          "symbolic-campaign": symbolic_campaign, "symbolic-device": symbolic_device,
          "p695-evaluation": p695_evaluation, "p695-what-passes": p695_what_passes, "device-models": device_models,
          "bench-subnormals": bench_subnormals}


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
