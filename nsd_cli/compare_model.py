"""``nsd compare --model FILE [--cases FILE]``: the comparison table, verdict, results and report of a
described mechanism (comparisons.model_compare). Everything is checked before anything is written:
the description, the cases, every engine's settings, whether each engine can build the model, each
fixed-step run's step count, and the consistent initial state every engine starts from
(nsd_core.model.assemble.initial_state: a loop that cannot close, a rate the loops forbid) -- each a
single line and exit 2, nothing written, no engine run.

``--refine``: the gate's rule (comparisons.refine.refinements): a peer that is 'not converged at these
settings' runs again at the step its estimate asks for (at most MAX_REFINE x its steps), one whose
estimate is uncertain once at half its step; only those peers' runs (at h and h/2) are new, every
other run of the case is re-used, and the case is judged again. A refined step is also held to the
step-count bound checked before any run (at most MAX_FIXED_STEPS steps for its h/2 run, and not below
the step floor): a step past it is *capped* there, and the refine line says so (a refusal could only
come after the first runs were written). The changes are ``refined`` in results.json.

A re-run into the same ``--out``: the files a previous ``nsd compare --model`` wrote there are
*removed* before the new ones are written (results.json is replaced; report/model_report.pdf and
report/model_page*.png; each CASE/LABEL.csv of the cases and runs the previous results.json lists,
and its CASE folder when that leaves it empty), so the folder never holds an earlier model's runs
beside this one's. Nothing else there is touched.
"""
from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from comparisons.engines.base import MAX_FIXED_STEPS, STEP_FLOOR, check_settings
from comparisons.estimate import STEP_SETTING, step_used
from comparisons.model_compare import (BUILDERS, CHECK, CONVERGED, REFERENCE, builder, compare_model, judge,
                                       model_rule, run_one, run_plan, table)
from nsd_cli.options import check_out_dir, check_out_file
from nsd_core.device.params import ParameterError
from nsd_core.common.files import atomic_write_json, atomic_write_text
from nsd_core.model.bounds import check_case_work

NOT_WITH_MODEL = ("convergence", "power", "power_cases", "power_profiles", "power_size", "tolerances")


def run(args) -> int:
    from comparisons.model_cases import load_model_cases
    from nsd_core.model.load import angles_in_degrees, load_model
    for flag in NOT_WITH_MODEL:
        if getattr(args, flag, None) not in (None, False):
            raise ParameterError(f"--{flag.replace('_', '-')}: does not apply to --model (a description's tolerances "
                                 "are its outputs' own; its cases are [[case]] tables)")
    if args.profile != "default" or args.set or getattr(args, "params", None):
        raise ParameterError("--profile/--set/--params: apply to the device's cases, not to --model")
    engines = [e.strip() for e in args.engines.split(",") if e.strip()]
    for e in engines:
        if e not in BUILDERS:
            raise ParameterError(f"--engines {e!r}: unknown engine; allowed: {', '.join(BUILDERS)}")
    if REFERENCE not in engines or len(set(engines)) != len(engines):
        raise ParameterError(f"--engines {args.engines}: give each engine once, the reference {REFERENCE} included")
    model = load_model(args.model)
    cases = load_model_cases(model, args.cases, engines)
    for e in engines:
        b = builder(e)
        if hasattr(b, "check"):
            b.check(model)   # a joint type or feature this engine lacks: bad input, before any run
        for c in cases:
            merged = check_settings(b, c.settings.get(e) or None, f"case.{c.name}.{e}")
            if e == REFERENCE:   # its least step count (duration / max_step), before any run
                check_case_work(f"case.{c.name}", c.duration, c.dt_out, len(model.outputs), merged)
            if e in STEP_SETTING:   # bounded work: the h/2 run takes twice the steps, found before any run
                key = STEP_SETTING[e]
                steps = 2 * c.duration / step_used(float(merged[key]), c.dt_out)
                if steps > MAX_FIXED_STEPS:
                    raise ParameterError(f"case.{c.name}.{e}.{key} = {merged[key]!r}: {steps:.3g} steps for "
                                         f"{c.duration:g} s and its h/2 run; at most {MAX_FIXED_STEPS} (a larger step "
                                         "or a shorter duration)")
    check_out_dir("--out", args.out, lock=False)   # the cheap checks first: a bad --out never waits for numba
    check_out_file("--junit", args.junit)
    check_initial(model)
    out = check_out_dir("--out", args.out)         # now locked (and made): nothing before this writes
    for line in angles_in_degrees(model):   # legal, so said, not refused (after every refusal: one line each)
        print(f"nsd: warning: {line}", file=sys.stderr)
    print(f"nsd compare --model {args.model}: {len(cases)} cases x {len(engines)} engines -> {out}")
    summary = compare_model(model, cases, engines)
    if args.refine:
        print(table(summary))
        summary = refine(model, cases, engines, summary)
    clear_previous(out)
    write(out, summary)
    print(table(summary))
    print(summary["rule"]["text"])
    verdict = "PASS" if summary["passed"] else "FAIL"
    print(f"verdict: {verdict}; wrote {out / 'results.json'}")
    if args.junit:
        atomic_write_text(args.junit, junit(summary))
    if args.report:
        from reports.model_pages import build_model_report
        paths = build_model_report(model, summary, out / "report")
        print(f"report: {paths['pdf']}")
    return summary["exit_code"]


def check_initial(model) -> None:
    """The consistent state at t = 0, computed once before any run (each engine computes it again, the
    same): a loop that cannot close, a rate the loops forbid or a position that opens a loop is one
    ModelError line (exit 2), not one failure per engine."""
    from nsd_core.model.assemble import initial_state
    from nsd_core.model.errors import ModelError
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")   # an overflow on the way is said in the one line, not beside it
            initial_state(model)
    except ParameterError:
        raise
    except Exception as e:  # noqa: BLE001 (the assembly's own failure, said as the description's mistake)
        raise ModelError(f"[initial]: the state at t = 0 cannot be computed from the description "
                         f"({' '.join(f'{type(e).__name__}: {e}'.split())[:300]}); check [initial].coordinates, "
                         "the joints and the loop points") from None


def refine(model, cases, engines: list[str], summary: dict) -> dict:
    """--refine: each peer that is not converged (or whose estimate is uncertain) once more at the step
    its estimate asks for (comparisons.refine), its case judged again with its other runs re-used."""
    from comparisons.refine import refinements
    view = {"verdicts": {name: c.get("verdicts", {}) for name, c in summary["cases"].items()}}
    refined, changes = refinements(cases, view)
    refined, changes, lines = _bounded(refined, cases, changes)
    summary["refined"] = changes
    for line in lines:
        print(line)
    if not changes:
        print("--refine: no peer is 'not converged at these settings', undecided or with an uncertain estimate; nothing to re-run")
        return summary
    rule = model_rule(model, summary["rule"]["k"])
    by_name = {c.name: c for c in refined}
    for name in dict.fromkeys(r["case"] for r in changes):
        _rejudge(model, by_name[name], engines, {r["engine"] for r in changes if r["case"] == name}, summary, rule)
    order = list(summary["cases"])
    rows = {}
    for r in summary["rows"]:
        rows.setdefault(r["case"], []).append(r)
    summary["rows"] = [r for name in order for r in rows.get(name, [])]
    verdicts = [v for c in summary["cases"].values() for v in c["verdicts"].values()]
    failed = any(c["failures"] for c in summary["cases"].values())
    summary["passed"] = bool(verdicts) and all(v["pass"] for v in verdicts) and not failed
    summary["exit_code"] = 3 if failed else (0 if summary["passed"] else 1)
    return summary


def _bounded(refined: list, cases: list, changes: list[dict]) -> tuple[list, list[dict], list[str]]:
    """The refined steps held to the bound checked before any run (the h/2 run at most MAX_FIXED_STEPS
    steps, the step not below STEP_FLOOR): a step past it is capped there; one already there is not
    refined. Returns the cases, the changes and the lines to print."""
    import dataclasses

    from comparisons.refine import refine_text
    by_name, kept, lines = {c.name: c for c in refined}, [], []
    for r in changes:
        c = by_name[r["case"]]
        if r["setting"] != STEP_SETTING.get(r["engine"]):
            kept.append(r)
            lines += refine_text([r])
            continue
        lowest = max(STEP_FLOOR, 2.0 * c.duration / MAX_FIXED_STEPS)
        if r["to"] >= lowest:
            kept.append(r)
            lines += refine_text([r])
            continue
        cap = (f"the step floor {STEP_FLOOR:g} s" if lowest == STEP_FLOOR
               else f"at most {MAX_FIXED_STEPS} steps with its h/2 run")
        if lowest >= r["from"] * (1.0 - 1e-12):   # already at the bound: the original case stands
            original = next(o for o in cases if o.name == c.name).settings.get(r["engine"], {})
            by_name[c.name] = dataclasses.replace(c, settings={**c.settings, r["engine"]: original},
                                                  refined=tuple(e for e in c.refined if e != r["engine"]))
            lines.append(f"--refine: {r['case']}: {r['engine']} not refined: its {r['setting']} {r['from']:.3g} s is "
                         f"at the bound ({cap})")
            continue
        r = {**r, "to": lowest, "capped": True, "cap": cap}
        settings = {**c.settings, r["engine"]: {**c.settings.get(r["engine"], {}), r["setting"]: lowest}}
        by_name[c.name] = dataclasses.replace(c, settings=settings)
        kept.append(r)
        lines += [refine_text([{**r, "capped": False}])[0] + f" (asked {r['asked']:.3g} s; capped: {r['cap']})"]
    return [by_name[c.name] for c in refined], kept, lines


def _rejudge(model, case, engines: list[str], redo: set, summary: dict, rule) -> None:
    """The refined peers' runs (at h and h/2) on ``case``, then the case judged again with its other
    runs as they were (compare_model's judgement of one case, on the runs it kept)."""
    entry = summary["cases"][case.name]
    runs = dict(summary["runs"][case.name])
    failures, timing = dict(entry["failures"]), dict(entry["runs"])
    for label, engine, settings in run_plan(model, case, engines):
        if engine not in redo or label in (CONVERGED, CHECK):
            continue
        print(f"  {case.name}: {label} (refined) ...")
        res = run_one(model, case, engine, settings)
        timing[label] = {"wall_time": res["wall_time"]}
        runs.pop(label, None)
        failures.pop(label, None)
        if res["status"] == "ok":
            runs[label] = res["run"]
            timing[label].update({k: v for k, v in res["run"].stats.items() if isinstance(v, (int, float, str))})
        else:
            failures[label] = res["message"]
    verdicts = {}
    if CONVERGED in runs and CHECK in runs:
        rows, verdicts = judge(model, case, [e for e in engines if e in runs], runs, rule)
        summary["rows"] = [r for r in summary["rows"] if r["case"] != case.name] + rows
    for e in engines:
        if e in failures:
            verdicts[e] = {"pass": False, "consistent": None, "accurate": False, "failed": True,
                           "text": f"failed: {failures[e]}"}
    summary["cases"][case.name] = {**entry, "failures": failures, "runs": timing, "verdicts": verdicts}
    summary["runs"][case.name] = runs


def _own_name(v) -> bool:
    """A case or run name this command could have written (model_cases' names, never '.' or '..')."""
    return isinstance(v, str) and bool(v) and v not in (".", "..") and all(c.isalnum() or c in "_-." for c in v)


def clear_previous(out: Path) -> None:
    """Remove what an earlier ``nsd compare --model`` wrote into ``out`` (see the module's docstring):
    its report's files and the CSV of each run its results.json lists; a case folder left empty goes
    too. A results.json that is not a --model summary (or not readable) names no CSVs to remove."""
    from nsd_core.common.files import read_regular_text
    try:
        prev = json.loads(read_regular_text(out / "results.json", "results.json"))
    except (OSError, ValueError):
        prev = None
    if isinstance(prev, dict) and "model_file" in prev and isinstance(prev.get("cases"), dict):
        for case, entry in prev["cases"].items():
            folder = out / str(case)
            if not _own_name(case) or not isinstance(entry, dict) or folder.is_symlink() or not folder.is_dir():
                continue
            for label in entry.get("runs") or {}:
                f = folder / f"{label}.csv"
                if _own_name(label) and (f.is_file() or f.is_symlink()):
                    f.unlink()
            try:
                folder.rmdir()   # only when empty: a file of someone else's stays, with its folder
            except OSError:
                pass
    report = out / "report"
    if report.is_dir() and not report.is_symlink():
        for f in [report / "model_report.pdf", *report.glob("model_page*.png")]:
            if f.is_file() or f.is_symlink():
                f.unlink()
        try:
            report.rmdir()
        except OSError:
            pass


def write(out: Path, summary: dict) -> None:
    """results.json (verdicts, every metric row, every run's statistics) and each run's CSV."""
    for case, runs in summary["runs"].items():
        folder = out / case
        folder.mkdir(parents=True, exist_ok=True)
        for label, r in runs.items():
            names = list(r.outputs)
            header = ",".join(["t [s]"] + [f"{n} [{r.units[n]}]" for n in names])
            data = np.column_stack([r.t] + [r.outputs[n] for n in names])
            lines = [header] + [",".join(f"{v:.17g}" for v in row) for row in data]
            atomic_write_text(folder / f"{label}.csv", "\n".join(lines) + "\n")
    kept = {k: v for k, v in summary.items() if k != "runs"}
    atomic_write_json(out / "results.json", json.loads(json.dumps(kept, default=_plain)))


def _plain(x):
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return str(x)


def junit(summary: dict) -> str:
    cases = [(c, e, v) for c, entry in summary["cases"].items() for e, v in entry["verdicts"].items()]
    fails = sum(not v["pass"] for _, _, v in cases)
    body = []
    for c, e, v in cases:
        body.append(f'  <testcase classname={quoteattr("nsd.model." + summary["model"])} name={quoteattr(c + "." + e)}>')
        if not v["pass"]:
            body.append(f'    <failure message={quoteattr(v.get("text", ""))}/>')
        body.append("  </testcase>")
    return (f'<?xml version="1.0" encoding="utf-8"?>\n<testsuite name={quoteattr("nsd compare --model")} '
            f'tests="{len(cases)}" failures="{fails}">\n' + "\n".join(body) + "\n</testsuite>\n")
