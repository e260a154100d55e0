"""docs/validation.md's campaign tables, from benchmarks/results/campaign.json (benchmarks/campaign.py)."""
from __future__ import annotations

CLASSES = {
    "pass": "every engine PASS at the case's settings",
    "pass_after_refine": "a peer not converged (or its estimate uncertain); --refine's runs PASS",
    "disagrees": "an engine disagrees beyond numerical error after --refine",
    "not_converged": "still not converged after --refine (the cost cap)",
    "engine_failure": "an engine raised on the case",
    "rejected": "the description or its start refused",
    "timeout": "stopped at the time limit",
    "harness_error": "the harness itself failed",
}


def campaign(load, provenance, table, g, plain) -> str:
    rec = load("campaign")
    d = rec["data"]
    classes = [[f"`{k}`", str(d["classes"].get(k, 0)), v] for k, v in CLASSES.items()]
    fam = sorted(d["families"].items(), key=lambda kv: (-kv[1], kv[0]))
    worst = [[e, g(w["ratio"]), g(w["error_over_tolerance"]), str(w["uncertain"])]
             for e, w in sorted(d["worst_pass"].items())]
    rest = []
    for r in d["records"]:
        if r["cls"] == "pass":
            continue
        last = r.get("refined") or r.get("first") or {}
        texts = "; ".join(f"{e}: {v['text'][:140]}" for per in last.values() for e, v in per.items() if not v["pass"])
        steps = ", ".join(f"{c['engine']} {c['setting']} {g(c['from'])} -> {g(c['to'])}" for c in r.get("refine_changes", []))
        rest.append([str(r["seed"]), r.get("family", ""), f"`{r['cls']}`", steps or "-",
                     (texts or r.get("reason", "") or "PASS after --refine").replace("|", "/")])
    med = d["mechanism_wall_s"]["median"]
    return (provenance(rec) + "\n"
            + f"{d['n']} mechanisms (seeds {d['seeds'][0]}-{d['seeds'][1]}) in {plain(d['wall_s'])} s "
              f"(median {g(med)} s a mechanism, longest {g(d['mechanism_wall_s']['max'])} s).\n\n"
            + table(["class", "mechanisms", "meaning"], classes) + "\n"
            + table(["family", "mechanisms"], [[k, str(v)] for k, v in fam]) + "\n"
            + "Over every PASS verdict, each engine's largest difference from the converged reference over its "
              "bound (k x its estimated error) and largest error over its engineering tolerance:\n\n"
            + table(["engine", "largest difference / bound", "largest error / tolerance", "estimates marked uncertain"],
                    worst) + "\n"
            + ("Every mechanism that did not PASS at its case's settings:\n\n"
               + table(["seed", "family", "class", "refined", "verdict (last run)"], rest) if rest
               else "Every mechanism PASSed at its case's settings.\n"))


def device_variants(load, provenance, table, g, plain) -> str:
    """The device's description on variants the gate was not tuned on (benchmarks/device_variants.py)."""
    rec = load("device_variants")
    rows, counts = [], {"first": 0, "refined": 0, "not converged": 0, "disagrees": 0}
    for r in rec["data"]["variants"]:
        drive = f"{r['path']}, A {plain(r['amplitude_m'] * 1e3)} mm" + (
            f", B {plain(r['minor_m'] * 1e3)} mm" if r.get("minor_m") else "") + f", {plain(r['frequency_hz'])} Hz" + (
            f", psi {plain(r['direction_deg'])} deg" if r["direction_deg"] else "")
        params = ", ".join(f"{k} = {v:g}" for k, v in r["params"].items()) or "nominal"
        cells = []
        for e, last in r["refined"].items():
            first = r["first"].get(e, last)
            counts["first"] += first["pass"]
            counts["refined"] += last["pass"] and not first["pass"]
            counts["not converged"] += not last["pass"] and "not converged" in last["text"]
            counts["disagrees"] += "disagrees" in first["text"] or "disagrees" in last["text"]
            word = "PASS" if first["pass"] else ("PASS after --refine" if last["pass"] else last["text"].split(":")[0])
            cells.append(f"{e}: {word}")
        left = "; ".join(f"{', '.join(sorted(r['excluded_samples']))} at t = {', '.join(g(t) for t in ts)} s"
                         for ts in {tuple(v) for v in r["excluded_samples"].values()}) or "-"
        rows.append([drive, params, "; ".join(cells), left, plain(r["wall_s"])])
    n = sum(len(r["refined"]) for r in rec["data"]["variants"])
    return (provenance(rec) + "\n"
            + f"{len(rows)} variants x 3 engines: {counts['first']} of {n} verdicts PASS as first judged, "
              f"{counts['refined']} more after --refine, {counts['not converged']} still not converged after "
              f"its one re-run, **{counts['disagrees']} disagree**.\n\n"
            + table(["drive", "parameters", "verdict (as first judged, or after --refine)", "drive-force samples left out",
                     "wall s"], rows))
