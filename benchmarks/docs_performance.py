"""docs/performance.md's generated tables (and docs/architecture.md's device models), from
benchmarks/results/*.json (benchmarks.docs writes them)."""
from __future__ import annotations

from benchmarks.docs_common import g, load, plain, provenance, table


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


def bench_subnormals() -> str:
    """The peers' gate runs with subnormal numbers flushed and kept (benchmarks/bench_subnormals.py)."""
    rec = load("bench_subnormals")
    d = rec["data"]
    rows = [[r["engine"], r["case"], plain(r["cpu_s_kept"]), plain(r["cpu_s_flushed"]), g(r["ratio"]),
             str(r["subnormal_kept"]), str(r["subnormal_flushed"]), g(r["largest_difference"])] for r in d["rows"]]
    return (provenance(rec) + "\n"
            + table(["peer", "case", "CPU s, kept", "CPU s, flushed", "kept / flushed [-]",
                     "subnormal outputs, kept", "subnormal outputs, flushed", "largest difference [-]"], rows))


def bench_exudyn_forces() -> str:
    """Exudyn's compiled forces, revision against revision (benchmarks/bench_exudyn_forces.py)."""
    rec = load("bench_exudyn_forces")
    d = rec["data"]
    labels = list(d["summary"][0]["runs_s"])
    rows = [[f"`{s['revision']}` ({s['commit'][:7]})", g(s["evaluate_us"]), g(s["advance_us"]),
             *[plain(s["runs_s"][k]) for k in labels]] for s in d["summary"]]
    same = ", ".join(f"{k}: {'yes' if v else 'NO'}" for k, v in d["same_numbers"].items())
    return (provenance(rec) + "\n"
            + f"Median of {d['repeats']} fresh processes a revision, alternating; the calls from a compiled loop of "
              f"{d['calls']} (numba's dispatch from Python excluded). Every output the same bit for bit in the two "
              f"revisions: {same}.\n\n"
            + table(["revision", "evaluate, us a call", "advance (pre-step), us a call",
                     *[f"{k}, run s" for k in labels]], rows))


def bench_csv_text() -> str:
    """The gate's CSVs written both ways (benchmarks/bench_csv_text.py)."""
    rec = load("bench_csv_text")
    d = rec["data"]
    rows = [[way, plain(d["median_cpu_s"][key]), g(d["ns_per_number"][key])]
            for way, key in (("Python's \"%.10g\" a value, numpy.loadtxt to read back", "python"),
                             ("compiled (nsd_core.device.decimal_text), the numbers returned", "compiled"))]
    return (provenance(rec) + "\n"
            + f"The default gate's {d['tables']} tables ({d['rows']} rows, {d['numbers']} numbers, "
              f"{g(d['bytes'] / 1e6)} MB), written and read back in one process, median of {d['repeats']} "
              f"alternating passes: {g(d['ratio'])}x less CPU; the files the same bytes: "
              f"{'yes' if d['same_text'] else 'NO'}; the numbers the same bits: {'yes' if d['same_numbers'] else 'NO'}.\n\n"
            + table(["how", "CPU s, every table", "ns a number"], rows))
