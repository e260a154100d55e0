"""``nsd compare --model FILE [--cases FILE]``: the comparison table, verdict, results and report of a
described mechanism (comparisons.model_compare). Everything is checked before anything is written:
the description, the cases, every engine's settings and whether each engine can build the model."""
from __future__ import annotations

import json
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from comparisons.engines.base import MAX_FIXED_STEPS, check_settings
from comparisons.estimate import STEP_SETTING
from comparisons.model_compare import BUILDERS, REFERENCE, builder, compare_model, table
from nsd_cli.options import check_out_dir, check_out_file
from nsd_core.device.params import ParameterError
from nsd_core.device.results import atomic_write_json, atomic_write_text

NOT_WITH_MODEL = ("convergence", "refine", "power", "power_cases", "power_profiles", "power_size", "tolerances")


def run(args) -> int:
    from comparisons.model_cases import load_model_cases
    from nsd_core.model.load import load_model
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
            if e in STEP_SETTING:   # bounded work: the h/2 run takes twice the steps, found before any run
                key = STEP_SETTING[e]
                steps = 2 * c.duration / float(merged[key])
                if steps > MAX_FIXED_STEPS:
                    raise ParameterError(f"case.{c.name}.{e}.{key} = {merged[key]!r}: {steps:.3g} steps for "
                                         f"{c.duration:g} s and its h/2 run; at most {MAX_FIXED_STEPS} (a larger step "
                                         "or a shorter duration)")
    out = check_out_dir("--out", args.out)
    check_out_file("--junit", args.junit)
    print(f"nsd compare --model {args.model}: {len(cases)} cases x {len(engines)} engines -> {out}")
    summary = compare_model(model, cases, engines)
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
