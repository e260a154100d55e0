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
from benchmarks.docs_validation import compare_gate, compare_variant, convergence, power, tables_5_6, verdict_cost
from benchmarks.docs_performance import (bench_cold, bench_cycle, bench_dask, bench_ida_farfield, bench_peer_seismic,
                                        bench_record_set, bench_rhs, bench_seismic, bench_start, bench_subnormals,
                                        bench_csv_text, bench_exudyn_forces,
                                        compile_units,
                                        device_models, gate_times, work_precision)

DOCS = (ROOT / "docs" / "validation.md", ROOT / "docs" / "performance.md", ROOT / "docs" / "engine-codegen.md",
        ROOT / "docs" / "models.md", ROOT / "docs" / "p695.md", ROOT / "docs" / "architecture.md")
BLOCK = re.compile(r"(<!-- generated: (?P<name>[a-z0-9_-]+) -->\n)(?P<body>.*?)(<!-- end generated: (?P=name) -->)", re.S)


# ---- validation.md ----

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


def model_first() -> str:
    """A user's first nsd compare --model, new description and again (benchmarks/docs_first_command.py)."""
    from benchmarks.docs_first_command import model_first as render
    return render(load, provenance, table, g, plain)


def report_drawing() -> str:
    """The report's drawing under two matplotlib versions, side by side (benchmarks/docs_first_command.py)."""
    from benchmarks.docs_first_command import report_drawing as render
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
          "model-first": model_first, "report-drawing": report_drawing,
          "model-builders": model_builders, "described-gate": described_gate,
          "gate-described": gate_described,
          "work-precision": work_precision, "bench-cold": bench_cold, "bench-peer-seismic": bench_peer_seismic,
          "bench-ida-farfield": bench_ida_farfield, "bench-dask": bench_dask,
          "symbolic-equations": symbolic_equations, "symbolic-models": symbolic_models,
          "symbolic-campaign": symbolic_campaign, "symbolic-device": symbolic_device,
          "p695-evaluation": p695_evaluation, "p695-what-passes": p695_what_passes, "device-models": device_models,
          "bench-subnormals": bench_subnormals, "exudyn-forces": bench_exudyn_forces,
          "csv-text": bench_csv_text}


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
