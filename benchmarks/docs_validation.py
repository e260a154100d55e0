"""docs/validation.md's generated blocks of the gate's verdicts (benchmarks.docs): the default gate, the
device variant, the power study, the verdict's cost, the convergence study and Tables 5-6."""
from __future__ import annotations

from benchmarks.docs_common import g, load, provenance, table


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
