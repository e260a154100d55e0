"""``nsd compare``: the cross-validation gate. Prints the table, writes results, optional JUnit XML."""
from __future__ import annotations

import argparse
from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

from comparisons.config import PROFILES, load_cases, load_convergence, load_order
from comparisons.tolerance_file import load_tolerances
from comparisons.engines import REFERENCE
from nsd_cli.options import (WORKERS_HELP, add_param_arguments, base_params, check_out_dir, check_out_file,
                             parse_engines, resolved_workers)
from nsd_core.device.params import ParameterError
from nsd_core.common.files import atomic_write_text

HELP = "run engines side by side against tolerances"


DEFAULT_CASES = Path(__file__).resolve().parents[1] / "comparisons" / "cases.toml"


def default_cases_text() -> str:
    """What the default case file holds, read from the file itself (the help text follows the file)."""
    import tomllib
    try:
        cases = tomllib.loads(DEFAULT_CASES.read_text(encoding="utf-8")).get("case", [])
    except (OSError, tomllib.TOMLDecodeError):
        return "comparisons/cases.toml"
    seismic = [c.get("name", "?") for c in cases if c.get("mode") == "seismic"]
    drives = [c.get("name", "?") for c in cases if c.get("mode", "drive") != "seismic"]
    return (f"comparisons/cases.toml: {len(drives)} drive cases ({', '.join(drives)}) and {len(seismic)} seismic "
            f"({', '.join(seismic)}); format: docs/cases.md")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--cases", help=f"case file (TOML); default: {default_cases_text()}; with --model, a file of "
                   "[[case]] tables (default: the model file's own)")
    p.add_argument("--model", help="a mechanism's description (TOML, docs/models.md): cross-validate it in every "
                   "engine instead of the device (e.g. models/andrews.toml)")
    p.add_argument("--tolerances", help="tolerance file (TOML): [engineering] tolerances of the per-run verdict or "
                                        "fixed [limits]; default: comparisons/tolerances.toml (format: docs/cases.md)")
    p.add_argument("--engines", default="semirecursive,mujoco,exudyn",
                   help="comma-separated engines; must include the reference, semirecursive")
    add_param_arguments(p, "parameter overrides applied to every case")
    p.add_argument("--workers", type=int, default=None, help=WORKERS_HELP)
    p.add_argument("--junit", help="write JUnit XML here (one test per case and engine)")
    p.add_argument("--convergence", action="store_true",
                   help="also run the case file's [convergence] study (discrepancy vs step size per engine)")
    p.add_argument("--report", action="store_true", help="also write the validation report into OUT/report")
    p.add_argument("--refine", action="store_true",
                   help="re-run each peer that is 'not converged at these settings' once at the step its own error "
                        "estimate asks for (at most 8x its steps) and judge again; the settings used are reported")
    p.add_argument("--power", action="store_true",
                   help="measure the gate's detection power instead: inject small modelling errors into one "
                        "engine's own model at a time (OUT/power.json; exit 1 if one is not seen)")
    p.add_argument("--power-engines", default="mujoco,exudyn", help="engines whose own model gets the errors")
    p.add_argument("--power-cases", default=None,
                   help="comma-separated case names for --power (default: every case of the case file)")
    p.add_argument("--power-profiles", default=None,
                   help="--power: comma-separated profiles whose gates are measured side by side (default: "
                        "default,strict; with --cases or --tolerances: those files alone)")
    p.add_argument("--power-size", type=float, default=None,
                   help="--power: the size of the listed errors (relative; 0.001 = 0.1 %%; the 0.2 mm "
                        "lengths scale with it: 0.02 mm at 0.001; default: the listed sizes, 1 %% and 0.2 mm)")
    p.add_argument("--profile", choices=sorted(PROFILES), default="default",
                   help="default: comparisons/cases.toml judged by the per-run verdict (tolerances.toml: each engine "
                        "within its own estimated error and the engineering tolerances); strict: finer peer settings "
                        "(cases_strict.toml), the same verdict; regression, regression-strict: fixed limits derived "
                        "on the nominal device (limits_regression*.toml); --cases / --tolerances still override")
    p.add_argument("--out", required=True, help="output folder")




def check_settings(cases, engines, convergence=None) -> None:
    """Every engine's settings in every case (and the convergence study), checked by the engine's
    own ``check_settings`` before anything runs or is written: a bad setting is exit 2."""
    from comparisons.config import SeismicCase
    from comparisons.engines import get_engine
    from comparisons.engines.base import SeismicSettings, check_settings as check
    from comparisons.engines.perturb import perturbed
    from nsd_core.device.geometry import device_geometry
    named = set(engines) | {e for c in cases for e in c.settings}
    for e in sorted(named):
        eng = get_engine(e)
        for c in cases:
            seismic = isinstance(c, SeismicCase)
            where = f"case {c.name}: settings.{e}"
            check(SeismicSettings(eng) if seismic else eng, c.settings.get(e), where)
            perturbation = (c.settings.get(e) or {}).get("perturb")
            if perturbation is not None:   # what needs the case's device (an index in range): applied once here
                try:
                    perturbed(device_geometry(c.params_for(e)), perturbation, seismic=seismic)
                except ParameterError as err:
                    raise ParameterError(f"{where}.{err}") from None
            if seismic and not c.device and e != REFERENCE and e in engines:
                raise ParameterError(f"case {c.name}.device = false: the supports alone run on the in-house engine "
                                     f"only; run it with --engines {REFERENCE}")
    if convergence:
        check(get_engine(REFERENCE), convergence["reference"], "convergence.reference")
        for e, spec in convergence["sweep"].items():
            eng = get_engine(e)
            where = f"convergence.sweep.{e}"
            if spec["setting"] not in eng.default_settings:
                raise ParameterError(f"{where}.setting = {spec['setting']!r}: unknown; allowed: "
                                     f"{', '.join(sorted(eng.default_settings))}")
            fixed = {**convergence["case"].settings.get(e, {}), **spec.get("settings", {})}
            for v in spec["values"]:
                check(eng, {**fixed, spec["setting"]: v}, where)


def format_table(summary: dict) -> str:
    if summary.get("rule", {}).get("name") == "estimated":
        from comparisons.report_text import format_estimated
        return format_estimated(summary)
    lines = [f"{'case':16s} {'engine':14s} {'vs':14s} {'metric':18s} {'value':>11s} {'limit':>11s}  verdict"]
    defaulted = set(summary.get("tolerances_defaulted", ()))
    for m in summary["metrics"]:
        verdict = ("PASS" if m["pass"] else "FAIL") if m["gated"] else ("ok" if m["pass"] else "over")
        note = " (default limit)" if m["metric"] in defaulted else ""
        lines.append(f"{m['case']:16s} {m['engine']:14s} {m['reference'] or '-':14s} {m['metric']:18s} "
                     f"{m['value']:11.3e} {m['limit']:11.3e}  {verdict}{note}")
    for c, per in summary["runs"].items():
        for e, r in per.items():
            if r["status"] != "ok":
                lines.append(f"{c:16s} {e:14s} {'-':14s} {'run':18s} {'-':>11s} {'-':>11s}  ERROR: {r['message']}")
    return "\n".join(lines)


def _refine(cases, engines, tolerances, out, args, conv, order, summary) -> dict:
    """--refine: the not-converged peers once more at the step their estimates ask for."""
    from comparisons.harness import compare
    from comparisons.refine import refine_text, refinements
    from nsd_core.common.files import atomic_write_json
    refined, changes = refinements(cases, summary)
    if not changes:
        print("--refine: no peer is 'not converged at these settings', undecided or with an uncertain estimate; nothing to re-run")
        summary["refined"] = []
        atomic_write_json(out / "results.json", summary)
        return summary
    for line in refine_text(changes):
        print(line)
    check_settings(refined, engines, None)
    summary = compare(refined, engines, tolerances, out, workers=args.workers, convergence=conv,
                      tally=args.tally, order=order)
    summary["refined"] = changes
    atomic_write_json(out / "results.json", summary)
    return summary


def _failure_text(m: dict) -> str:
    vs = m["reference"] or "own bound"
    return f"{m['metric']} = {m['value']:.4g} > {m['limit']:.4g} (vs {vs})"


def junit_xml(summary: dict) -> str:
    cases = []
    for c, per in summary["runs"].items():
        for e, r in per.items():
            name = quoteattr(f"{c}.{e}")
            t = r.get("wall_time", 0.0)
            if r["status"] != "ok":
                cases.append(f'  <testcase classname="nsd.compare" name={name} time="{t:.3f}">'
                             f'<error message={quoteattr(r["message"])}/></testcase>')
                continue
            v = (summary.get("verdicts") or {}).get(c, {}).get(e)
            if v is not None:   # the estimated rule: the verdict in words
                body = "" if v["pass"] else (f'<failure message={quoteattr(v["text"].split(":")[0])}>'
                                             f'{escape(v["text"])}</failure>')
                cases.append(f'  <testcase classname="nsd.compare" name={name} time="{t:.3f}">{body}</testcase>')
                continue
            bad = [m for m in summary["metrics"] if m["case"] == c and m["engine"] == e and m["gated"] and not m["pass"]]
            body = "".join(f'<failure message={quoteattr(m["metric"])}>{escape(_failure_text(m))}</failure>' for m in bad)
            cases.append(f'  <testcase classname="nsd.compare" name={name} time="{t:.3f}">{body}</testcase>')
    n = len(cases)
    fails = sum(1 for x in cases if "<failure" in x)
    errs = sum(1 for x in cases if "<error" in x)
    return (f'<?xml version="1.0" encoding="utf-8"?>\n<testsuite name="nsd compare" tests="{n}" '
            f'failures="{fails}" errors="{errs}">\n' + "\n".join(cases) + "\n</testsuite>\n")


def run(args) -> int:
    for flag in ("model", "cases", "tolerances", "junit"):   # '' is no file, not the default one
        given = getattr(args, flag, None)
        if given is not None and not given.strip():
            raise ParameterError(f"--{flag} {given!r}: name a file")
    if args.model:
        from nsd_cli.compare_model import run as run_model
        return run_model(args)
    engines = parse_engines(args.engines)
    if REFERENCE not in engines:
        raise ParameterError(f"--engines {args.engines}: must include the reference {REFERENCE}; without it "
                             "nothing is gated and the verdict would mean nothing")
    args.workers = resolved_workers(args.workers)
    own_files = bool(args.cases or args.tolerances)
    args.cases = args.cases or PROFILES[args.profile][0]
    args.tolerances = args.tolerances or PROFILES[args.profile][1]
    base = base_params(args)
    cases = load_cases(args.cases, base)
    tolerances = load_tolerances(args.tolerances)
    if getattr(args, "refine", False) and getattr(tolerances, "rule", None) is None:
        raise ParameterError(f"--refine: {args.tolerances} holds fixed limits (the regression profile); --refine needs "
                             "a tolerance file with [engineering] tolerances, whose estimates give the step to refine to")
    conv = load_convergence(args.cases, cases) if args.convergence else None
    if args.convergence and conv is None:
        raise ParameterError("--convergence: the case file has no [convergence] table")
    if args.power_size is not None and not (args.power and 0 < args.power_size <= 0.1):
        raise ParameterError(f"--power-size {args.power_size!r}: " + ("a size in (0, 0.1] (0.001 = 0.1 %)"
                             if args.power else "applies to --power only"))
    if args.power:
        if args.refine:
            raise ParameterError("--refine: applies to the gate, not to --power (each injected error is judged at "
                                 "the case settings, with its own 2h run)")
        return _run_power(args, base, own_files)
    for flag in ("power_cases",):
        if getattr(args, flag) is not None:
            raise ParameterError(f"--{flag.replace('_', '-')}: applies to --power only")
    cases = pin_model(cases, tolerances)
    order = load_order(args.cases, cases)
    check_settings(cases, engines, conv)
    out = check_out_dir("--out", args.out)
    check_out_file("--junit", args.junit)
    if tolerances.defaulted:
        print(f"note: {', '.join(tolerances.defaulted)} not in {args.tolerances}: default limits used "
              "(marked 'default' in the table)")
    from comparisons.harness import compare  # here, not at import: every nsd command's start-up stays light
    print(f"nsd compare: {len(cases)} cases x {len(engines)} engines -> {out}")
    summary = compare(cases, engines, tolerances, out, workers=args.workers, convergence=conv, tally=args.tally,
                      order=order)
    if args.refine:
        summary = _refine(cases, engines, tolerances, out, args, conv, order, summary)
    print(format_table(summary))
    if args.junit:
        atomic_write_text(args.junit, junit_xml(summary))
    d = summary.get("limits_derived_on") or {}
    if d:
        print(f"limits derived on mujoco {d.get('mujoco', '?')}, exudyn {d.get('exudyn', '?')}, the peers' "
              f"{d.get('model', 'described')} models ({d.get('date', '?')}); "
              f"gated against the converged reference (in-house {summary['converged_reference']['settings']})")
    for line in summary["failures"]:
        print(f"FAILED {line}")
    print(summary["rule"]["text"])
    print(f"verdict: {summary['verdict']} ({summary['total_wall_time']:.1f} s); wrote {out / 'results.json'}")
    if args.report:
        from reports.build import build_report
        paths = build_report(out, out / "report")
        print(f"report: {paths['pdf']}")
    return summary["exit_code"]


def pin_model(cases, tolerances) -> list:
    """Fixed limits hold for the peers' model they were derived on ([derived] model): "described", the peers'
    only model since the hand-written adapters were removed, runs as it is; a file derived on the adapters
    ("adapter") cannot be honoured and is refused in one line (re-derive it: benchmarks/derive_limits.py).
    A file that names none pins nothing."""
    model = (getattr(tolerances, "derived", None) or {}).get("model")
    if model in (None, "described"):
        return cases
    if model == "adapter":
        raise ParameterError("--tolerances: [derived] model = 'adapter': these limits were derived on the peers' "
                             "hand-written models, which were removed; re-derive them on the described models "
                             "(nsd compare --out DIR, then python benchmarks/derive_limits.py DIR --write)")
    raise ParameterError(f"--tolerances: [derived] model = {model!r}: allowed: described")


def _power_cases(text: str, cases, profile: str) -> list:
    """--power-cases A,B: names of the profile's cases, each once, none empty (docs/limits.md)."""
    from nsd_core.common.files import printable
    known = {c.name: c for c in cases}
    names = [n.strip() for n in text.split(",")]
    for n in names:
        if not n:
            raise ParameterError(f"--power-cases {printable(repr(text))}: an empty name; give comma-separated case "
                                 f"names from {', '.join(known)}")
        if n not in known:
            raise ParameterError(f"--power-cases {printable(repr(n))}: unknown case, not a case of the {profile} "
                                 f"profile; allowed: {', '.join(known)}")
        if names.count(n) > 1:
            raise ParameterError(f"--power-cases {printable(repr(text))}: {n} given twice; give each case once")
    return [known[n] for n in names]


def _power_profiles(args, base, own_files) -> dict[str, tuple]:
    """name -> (cases, tolerances) of each profile --power measures, the cases cut to --power-cases."""
    if own_files:
        if args.power_profiles:
            raise ParameterError("--power-profiles: not with --cases / --tolerances (those files are the one profile)")
        files = {"custom": (args.cases, args.tolerances)}
    else:
        names = [n.strip() for n in (args.power_profiles or "default,strict").split(",") if n.strip()]
        for n in names:
            if n not in PROFILES:
                raise ParameterError(f"--power-profiles {n!r}: unknown; allowed: {', '.join(PROFILES)}")
        if not names or len(set(names)) != len(names):
            raise ParameterError(f"--power-profiles {args.power_profiles!r}: give each profile once")
        files = {n: PROFILES[n] for n in names}
    out = {}
    for name, (case_file, tol_file) in files.items():
        cases = load_cases(case_file, base)
        if args.power_cases is not None:
            cases = _power_cases(args.power_cases, cases, name)
        out[name] = (cases, load_tolerances(tol_file))
    return out


def _run_power(args, base, own_files) -> int:
    from comparisons.power import INJECTIONS, combine, format_power, format_profiles, power_study, scaled
    from nsd_core.common.files import atomic_write_json
    engines = parse_engines(args.power_engines)
    if REFERENCE in engines:
        raise ParameterError(f"--power-engines {args.power_engines!r}: the reference {REFERENCE} cannot be perturbed")
    profiles = _power_profiles(args, base, own_files)
    for cases, _ in profiles.values():
        check_settings(cases, engines)
    folder = check_out_dir("--out", args.out)
    size = args.power_size
    injections = INJECTIONS if size is None else [scaled(s, size) for s in INJECTIONS]
    outs = {}
    for name, (cases, tolerances) in profiles.items():
        print(f"nsd compare --power ({name} profile{'' if size is None else f', errors at {size:g}'}): "
              f"{len(cases)} cases x {len(engines)} engines -> {folder / name}")
        outs[name] = power_study(cases, engines, tolerances, folder / name, injections=injections, workers=args.workers)
        outs[name]["profile"], outs[name]["size"] = name, size
        print(format_power(outs[name]))
        print(f"{name}: {sum(t['seen_at_nominal'] for t in outs[name]['table'])} of {len(outs[name]['table'])} "
              f"injected errors fail the gate ({outs[name]['wall_time']:.0f} s)")
    first = next(iter(outs))
    out = {**outs[first], "profiles": outs, "by_profile": combine(outs),
           "all_seen": all(o["all_seen"] for o in outs.values())}
    atomic_write_json(folder / "power.json", out)
    if len(outs) > 1:
        print(format_profiles(out["by_profile"], list(outs)))
    print(f"wrote {folder / 'power.json'}")
    if args.report and (folder / "results.json").is_file():
        from reports.build import build_report
        print(f"report: {build_report(folder, folder / 'report')['pdf']}")
    return 0 if out["all_seen"] else 1
