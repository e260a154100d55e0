"""docs/p695.md's measured tables, from benchmarks/results/p695.json (benchmarks/p695_results.py): the
evaluation of the four configurations (Ŝ_CT with its bracket, the verdicts, the ranking) and what
passes (the capacities at ACMR20 % and ACMR10 %, the device variant and its three-engine check)."""
from __future__ import annotations

LENGTH_SCALE = 10.0   # 1:10 Froude similitude: full-scale lengths = 10 x the model's


def _provenance(rec: dict, g) -> str:
    m, d = rec["measured"], rec["data"]
    ev = d["evaluation"]
    load = (f"load average {m['load_average_before'][0]:g} before, {m['load_average_after'][0]:g} after"
            + (" (**loaded**: other jobs shared the CPUs)" if m["loaded"] else ""))
    return (f"*Measured {m['date_utc']} UTC by `{rec['command']}` (exit {rec['exit_code']}, {m['wall_s']:.0f} s "
            f"wall, IDA {ev['runtime']['ida_s']:.0f} s, {d.get('ida_runs', '?')} runs), "
            f"run by hand from a snapshot of commit {m['git_commit'][:12]} and kept by "
            f"`python -m benchmarks.p695_results`; {m['cpus']} CPUs, {load}.*\n")


def _range(a, b, num) -> str:
    return f"{num(a)}–{num(b)}"


def evaluation(load, table, g, plain) -> str:
    rec = load("p695")
    ev = rec["data"]["evaluation"]
    cfgs = ev["configurations"]
    names = list(cfgs)
    lv = ev["design_level"]

    def row(label, f):
        return [label] + [f(cfgs[n]) for n in names]

    def within(c):
        r = c["resolution"]
        out = f"{r['n_within']} / {r['n_records']}"
        return out + (f" ({', '.join(str(x['record']) + ': ' + x['why'] for x in r['not_within'])})"
                      if r["not_within"] else "")

    def verdict(c):
        if c["ACMR"] is None:
            return "undetermined"
        both = c["pass_ACMR20"] and c["pass_ACMR10"]
        return "**PASS** both" if both else ("**FAIL** both" if not c["pass_ACMR20"] else "PASS 20 %, FAIL 10 %")

    def ends(c):
        v = c["verdict_over_bracket"]
        return (f"ACMR {g(v['low']['ACMR'])} / {g(v['high']['ACMR'])}: "
                + ("same verdicts" if v["resolved"] else "**verdicts differ**"))

    def mu(c):
        p = c["pushover"]
        return f"{g(c['mu_T'], 4)} ({plain(p['V_max'], 4)} N)"

    rows = [row("Ŝ_CT [m/s²] (each record read inside its bracket)", lambda c: g(c["S_CT"], 4)),
            row("Ŝ_CT's bracket [m/s²] (width)", lambda c: f"{_range(*c['S_CT_bracket'], lambda v: g(v, 4))} "
                                                          f"({100 * c['S_CT_bracket_width']:.1f} %)"),
            row(f"records within {100 * cfgs[names[0]]['resolution']['resolution']:g} % (not: why)", within),
            row("widest record bracket", lambda c: f"{100 * c['resolution']['widest']:.1f} %"),
            row("bracket's top (the former reading)", lambda c: g(c["S_CT_top"], 4)),
            row("90 % bootstrap interval", lambda c: _range(c["S_CT_interval"]["low"], c["S_CT_interval"]["high"],
                                                            lambda v: g(v, 4))),
            row("lognormal fit: median, β", lambda c: f"{g(c['S_CT_lognormal_fit']['median'], 4)}, "
                                                     f"{g(c['S_CT_lognormal_fit']['dispersion'])}"),
            row("CMR", lambda c: g(c["CMR"])), row("μ_T (V_max at δ_u)", mu), row("SSF", lambda c: g(c["SSF"], 4)),
            row("β_TOT", lambda c: g(c["beta_TOT"])), row("ACMR", lambda c: g(c["ACMR"])),
            row("ACMR10 % / ACMR20 %", lambda c: f"{g(c['ACMR10'], 4)} / {g(c['ACMR20'], 4)}"),
            row("verdict", verdict), row("at the bracket's ends", ends),
            row("collapse modes", lambda c: ", ".join(f"{k} {v}" for k, v in c["collapse_modes"].items()))]
    rk = ev["ranking"]
    pairs = "; ".join(f"{p['higher']} > {p['lower']}: " + ("resolved" if p["resolved"] else
                      "**not resolved** (brackets " + ("overlap" if p["brackets_overlap"] else "apart")
                      + ", bootstrap intervals " + ("overlap" if p["intervals_overlap"] else "apart") + ")")
                      for p in rk["pairs"])
    head = [f"S_MT = {g(lv['S_MT'], 4)} m/s² ({g(lv['S_MT_g'])} g), SSF for {lv['sdc']}"] + names
    return (_provenance(rec, g) + "\n" + table(head, rows)
            + f"\nRanking by Ŝ_CT ({rk['rule']}): {pairs}.\n")


def _capacity(e: dict, target: str, g) -> str:
    if not e["found"]:
        if e.get("ACMR") is None:
            return f"none ({e.get('note', '')})"
        return (f"none up to {g(e['capacity'] * 1e3, 4)} mm: there Ŝ_CT {g(e['S_CT'], 4)}, ACMR {g(e['ACMR'], 3)} "
                f"< {g(e[target], 4)} (median record {e['how']})")
    return (f"**{g(e['capacity'] * 1e3, 4)} mm** ({g(e['capacity'] * 1e3 * LENGTH_SCALE, 3)} mm full scale): "
            f"Ŝ_CT {g(e['S_CT'], 4)}, ACMR {g(e['ACMR'], 4)} ≥ {g(e[target], 4)}, "
            f"μ_T {g(e['mu_T'], 4)}; median record {e['median_record']} {e['how']}, "
            f"{e['n_extrapolated']} records extrapolated")


def _own(wp: dict | None, g) -> str:
    """A check run's own what-passes: the least capacity for ACMR20 % read within its IDA."""
    e = (wp or {}).get("ACMR20") or {}
    if not e.get("found"):
        return ""
    return f"; its own IDA puts ACMR20 % at {g(e['capacity'] * 1e3, 4)} mm ({e['how']})"


def _at(c: dict, ev: dict, g) -> str:
    """At the evaluated capacity: ACMR from the evaluation's own Ŝ_CT and the verdict against ACMR20 %."""
    e = ev["configurations"][c]
    return (f"{g(ev['limit_states']['capacity'] * 1e3, 4)} mm: ACMR {g(e['ACMR'], 3)}, "
            + ("**PASS**" if e["pass_ACMR20"] else "**FAIL**"))


def what_passes(load, table, g, plain) -> str:
    rec = load("p695")
    d = rec["data"]
    ev = d["evaluation"]
    wp = ev["what_passes"]
    rows = [[name, _at(name, ev, g), _capacity(c["ACMR20"], "ACMR20", g), _capacity(c["ACMR10"], "ACMR10", g)]
            for name, c in wp["configurations"].items()]
    var = d.get("variant")
    if var:
        vev = var["evaluation"]
        c = vev["what_passes"]["configurations"]["device"]
        rows.append([f"device variant: `{' '.join(a for a in var['command'].split() if a.startswith('rod_length'))}`"
                     f" (its own IDA)", _at("device", vev, g), _capacity(c["ACMR20"], "ACMR20", g),
                     _capacity(c["ACMR10"], "ACMR10", g)])
    out = table(["configuration", "at the evaluated capacity (model scale)", "least capacity for ACMR ≥ ACMR20 %",
                 "least capacity for ACMR ≥ ACMR10 %"], rows)
    if var:
        vev = var["evaluation"]
        c = vev["configurations"]["device"]
        cap = vev["limit_states"]["capacity"]
        out += (f"\nDevice variant `{var['command']}` ({var['ida_runs']} runs, exit {var['exit_code']}, "
                f"{var['wall_s']:.0f} s wall): capacity {g(cap * 1e3, 4)} mm (its X_max; {g(cap * 1e4, 3)} mm full "
                f"scale), Ŝ_CT {g(c['S_CT'], 4)} m/s² (bracket {g(c['S_CT_bracket'][0], 4)}–"
                f"{g(c['S_CT_bracket'][1], 4)}, {c['resolution']['n_within']} of {c['resolution']['n_records']} "
                f"records within {100 * c['resolution']['resolution']:g} %"
                + "".join(f", record {x['record']} {x['why']} ({100 * x['width']:.1f} %)" if x["width"] is not None
                          else f", record {x['record']} {x['why']}" for x in c["resolution"]["not_within"])
                + f"; 90 % interval "
                f"{g(c['S_CT_interval']['low'], 4)}–{g(c['S_CT_interval']['high'], 4)}), μ_T {g(c['mu_T'], 4)}, "
                f"SSF {g(c['SSF'], 4)}, ACMR {g(c['ACMR'], 4)} against ACMR20 % {g(c['ACMR20'], 4)}: "
                f"{'**PASS**' if c['pass_ACMR20'] else '**FAIL**'}; against ACMR10 % {g(c['ACMR10'], 4)}: "
                f"{'PASS' if c['pass_ACMR10'] else 'FAIL'}; at the bracket's ends ACMR "
                f"{g(c['verdict_over_bracket']['low']['ACMR'], 4)} / {g(c['verdict_over_bracket']['high']['ACMR'], 4)}"
                f"; collapse modes {', '.join(f'{k} {v}' for k, v in c['collapse_modes'].items())}.\n")
    for x in d.get("capacity_checks") or []:
        for name, c in x["configurations"].items():
            found = wp["configurations"].get(name, {}).get("ACMR20", {})
            read = (f"; what passes read {g(found['S_CT'], 4)} at {g(found['capacity'] * 1e3, 4)} mm from the "
                    "evaluation's IDA" if found.get("found") else "")
            out += (f"\nCheck of {name} at {g(x['capacity'] * 1e3, 4)} mm (its own IDA at that capacity, {x['runs']} "
                    f"runs): Ŝ_CT {g(c['S_CT'], 4)} m/s² (bracket {g(c['S_CT_bracket'][0], 4)}–"
                    f"{g(c['S_CT_bracket'][1], 4)}{read}), ACMR "
                    f"{g(c['ACMR'], 4)} against ACMR20 % {g(c['ACMR20'], 4)}: "
                    f"{'PASS' if c['pass_ACMR20'] else 'FAIL'}" + _own(x.get("what_passes", {}).get(name), g) + ".\n")
    for x in d.get("cross_check") or []:
        gr = x.get("ground") or {}
        vev = (var or {}).get("evaluation") or ev
        level = gr.get("scale", 0.0) * vev["intensity"]["S_NRT"]
        cap = vev["limit_states"]["capacity"]
        peak = x["peak_displacement"]["value"]
        peers = "; ".join(f"{n}: du {m['du']:.2e}, dF {m['dF']:.2e}, da {m['da']:.2e} ({m['wall_time']:.0f} s)"
                          for n, m in x["engines"].items())
        over = [f"{n}'s {k} {m[k]:.2e}" for n, m in x["engines"].items() for k in ("du", "dF", "da") if m[k] > 1e-3]
        out += (f"\nThree engines on the variant's governing record (the median record, {gr.get('record', '?')}), "
                f"at {g(level, 4)} m/s² (scale {g(gr.get('scale'), 6)}): in-house peak |u| {g(peak * 1e3, 5)} mm, "
                f"{'below' if peak < cap else 'at or over'} the {g(cap * 1e3, 4)} mm capacity; {peers} "
                f"(max |Δ| / max of u, device force, a_abs; one run per engine at its default step, "
                + ("every difference within the gate's 1e-3 of each peak" if not over
                   else "over the gate's 1e-3 of the peak: " + ", ".join(over)) + ").\n")
    out += _gate_rule(d.get("gate_rule_check"), g)
    return out


def _gate_rule(x: dict | None, g) -> str:
    """The governing record by the gate's rule (nsd ida's cross-check: each peer at h and h/2)."""
    if not x or not x.get("device"):
        return ""
    parts = []
    for n, v in (x["device"].get("engines") or {}).items():
        est = v.get("estimates") or {}
        ms = ", ".join(f"{k} {v[k]:.1e} (estimate {est[k]['estimate']:.1e})" for k in ("du", "dF", "da")
                       if k in v and isinstance(est.get(k), dict))
        ref = v.get("refined")
        step = ""
        if ref:
            (k, a), (_, b) = next(iter(ref["from"].items())), next(iter(ref["to"].items()))
            step = f", refined {k} {g(a)} -> {g(b)} s (its first pair: {(v.get('first') or {}).get('verdict')})"
        why = ""
        if v.get("verdict") != "PASS" and est:
            agree = all(e.get("consistent") for e in est.values() if isinstance(e, dict))
            need = ", ".join(f"{k} <= {g(val)} s" for k, val in (v.get("step_needed") or {}).items())
            why = (" (not converged: every difference within its own estimate" if agree else " (disagrees") \
                + (f"; needs {need}" if need else "") + ")"
        parts.append(f"{n} **{v.get('verdict')}**{why}: {ms}{step}")
    return (f"\nThe same record at the upper level (the same scale: nsd ida's level is the record's own Sa) by the "
            f"gate's rule (`{x['command']}`, exit {x['exit_code']}, "
            f"{x['wall_s']:.0f} s wall: each peer at its step and half of it, judged against its own estimate "
            f"and the in-house run's error): " + "; ".join(parts) + ".\n")
