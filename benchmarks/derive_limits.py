"""Derive the gate's limits from a comparison run: the one place the rule is written.

    nsd compare --out out/derive                     # runs (or resumes) the default cases
    python benchmarks/derive_limits.py out/derive    # prints the tables; --write replaces them
    python benchmarks/derive_limits.py out/strict --cases comparisons/cases_strict.toml \\
        --write comparisons/limits_regression_strict.toml  # the strict profile, the same way

Rule. Every gated value of the run is an engine's error against the converged reference (the
in-house engine at rtol 1e-10, comparisons/reference.py). The reference's own error on the same
metric is measured here: the in-house engine at rtol 1e-11 against it (pair metrics), and the
reference's own value (closure, tracking, energy balance, seismic energy residual). Then, per
engine and case,

    limit = FACTOR x max(engine error, reference error, FRACTION x the engine's max|dF| error
            there), rounded up to two significant digits, never below ABS_FLOOR of the metric
            (1e-12 m for closure and tracking);

per engine (any case not listed) ENGINE_FACTOR x the largest of the bracket over the run's cases,
rounded up to two digits (1.5: near 1e-4 of the peak force, the accuracy aim, docs/validation.md).

The in-house engine's "engine error" is the largest over a small ensemble of realizations: its run
at the case settings and the same run with rtol x each factor of REALIZATIONS. Its step-size
controller places steps differently for any change at round-off (a compiler, a reordered sum), and
where the rope-slack kinks of the laws fall inside a step the error at a fixed rtol is erratic:
measured on figure8_A15mm_f10Hz at rtol 1e-7 x (0.95, 1, 1.05), max|dF| 3.5e-7, 7.8e-7 and 2.7e-6
against the reference. One realization's error says nothing of the next; the ensemble's largest
does. The peers step with fixed steps (MuJoCo, Exudyn): their error is one smooth number and has
no ensemble. The FRACTION term applies to the differences other than max|dF| itself (RMS, loop work,
peak; seismic: displacement and peaks, against max|dF_device|): a difference that cancels by chance
(a peak force 1e-8 off where the force is 1e-5 off) says nothing of the engine's accuracy, and a
limit on it would fail a change that moves the engine's results at round-off. An engine that comes closer to the reference than its error at derivation can only
pass; a modelling error must exceed FACTOR x the engine's numerical error to be seen (nsd compare
--power measures what that means). Metrics measured 0 on every case (region shifts on the sampled
grid) and the observed order (its band is in the case file) keep their defaults. The tables carry
[derived]: the MuJoCo and Exudyn versions they were measured on (the gate warns when the installed
one differs), the date and the git revision of the run, and the peers' model the run used ("described"
or "adapter", read from its runs; one for every peer, else the derivation stops), which the gate then
runs the peers on (nsd_cli.compare.pin_model). Derive from the rule's profiles (default, strict): a
regression profile runs the peers on the model of the limits it would replace.
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

FACTOR, ENGINE_FACTOR = 3.0, 1.5
ABS_FLOOR = {"closure_max": 1e-12, "tracking_error": 1e-12}
FRACTION = 0.1
REALIZATIONS = (0.8, 0.9, 0.95, 1.05, 1.1, 1.25)  # in-house rtol factors (the ensemble above)
SCALE = {"rms_dF_rel": "max_dF_rel", "loop_area_rel": "max_dF_rel", "peak_force_rel": "max_dF_rel",
         "max_du_rel": "max_dF_device_rel", "peak_u_rel": "max_dF_device_rel", "peak_a_rel": "max_dF_device_rel"}
SKIP = ("region_shift_rel", "order_deviation")
MARK = "# --- below: derived by benchmarks/derive_limits.py (replaced by --write; edit the rule, not the numbers) ---"


def round_up(x: float, digits: int) -> float:
    if not x > 0:
        return 0.0
    e = math.floor(math.log10(x)) - digits + 1
    return float(f"{math.ceil(x / 10 ** e - 1e-9) * 10 ** e:.{digits}g}")


def reference_errors(out: Path, summary: dict, cases_file: str | None,
                     workers: int = 2) -> tuple[dict[str, dict], dict[str, dict]]:
    """Per case: the converged reference's own error on every metric (against CHECK_SETTINGS, pair
    metrics) and its own values (closure, tracking, energy balance / residual); and the in-house
    ensemble's largest error on every pair metric (REALIZATIONS)."""
    from comparisons.config import SeismicCase, load_cases
    from comparisons.engines import REFERENCE, run_job, run_seismic_job
    from comparisons.metrics import pair_metrics
    from comparisons.reference import CHECK_SETTINGS, CONVERGED
    from comparisons.seismic import gate_metrics
    from nsd_core.device.results import read_csv
    from nsd_core.engine.workers import worker_pool

    names = {c["name"] for c in summary["cases"] + summary.get("seismic_cases", [])}
    cases = [c for c in load_cases(cases_file) if c.name in names]
    errors = {name: dict(own) for name, own in summary["converged_reference"]["own"].items()}
    spread: dict[str, dict[str, float]] = {c.name: {} for c in cases}

    def submit(pool, c, settings):
        if isinstance(c, SeismicCase):
            return pool.submit(run_seismic_job, REFERENCE, c.params, c.isolated_structure(), c.ground,
                               c.duration, c.dt_out, settings)
        return pool.submit(run_job, REFERENCE, c.params, c.drive, settings)

    def against_reference(c, job):
        if job["status"] != "ok":
            raise SystemExit(f"{c.name}: a derivation run failed: {job['message']}")
        folder = "seismic" if isinstance(c, SeismicCase) else "cycles"
        ref = read_csv(out / folder / f"{c.name}__{CONVERGED}.csv", CONVERGED)
        if isinstance(c, SeismicCase):
            return gate_metrics(job["result"], ref)
        return pair_metrics(job["result"], ref, {}, {}, c.drive.amplitude, c.drive.frequency)

    with worker_pool(workers) as pool:
        futs = {c.name: submit(pool, c, CHECK_SETTINGS) for c in cases}
        ensemble = {(c.name, f): submit(pool, c, inhouse_settings(c, f)) for c in cases for f in REALIZATIONS}
        for c in cases:
            errors[c.name].update(against_reference(c, futs[c.name].result()))
            for f in REALIZATIONS:
                for metric, v in against_reference(c, ensemble[(c.name, f)].result()).items():
                    spread[c.name][metric] = max(spread[c.name].get(metric, 0.0), v)
    return errors, spread


def inhouse_settings(case, factor: float) -> dict:
    """The in-house engine's settings on ``case`` with its rtol multiplied by ``factor``."""
    from comparisons.config import SeismicCase
    from comparisons.engines import REFERENCE, get_engine
    engine = get_engine(REFERENCE)
    base = engine.seismic_default_settings if isinstance(case, SeismicCase) else engine.default_settings
    s = {**base, **case.settings.get(REFERENCE, {})}
    return {**s, "rtol": s["rtol"] * factor}


def derive(summary: dict, ref_errors: dict[str, dict], spread: dict[str, dict] | None = None) -> dict[str, dict]:
    """{engine: {"own": {metric: limit}, "case": {case: {metric: limit}}}} by the rule above;
    ``spread``: the in-house ensemble's largest error per case and metric (pair metrics only)."""
    from comparisons.engines import REFERENCE
    basis: dict[str, dict[str, dict[str, float]]] = {}
    gated = [m for m in summary["metrics"] if m["gated"] and m["metric"] not in SKIP]
    value = {(m["engine"], m["case"], m["metric"]): m["value"] for m in gated if m["reference"]}
    for (engine, case, metric), v in list(value.items()):   # the engine error: the ensemble's largest
        if engine == REFERENCE:
            value[(engine, case, metric)] = max(v, (spread or {}).get(case, {}).get(metric, 0.0))
    for m in gated:
        ref = ref_errors.get(m["case"], {}).get(m["metric"], 0.0)
        own = value.get((m["engine"], m["case"], m["metric"]), m["value"]) if m["reference"] else m["value"]
        scale = FRACTION * value.get((m["engine"], m["case"], SCALE.get(m["metric"], "")), 0.0) if m["reference"] else 0.0
        basis.setdefault(m["engine"], {}).setdefault(m["metric"], {})[m["case"]] = max(own, ref, scale)
    out = {}
    for engine, metrics in basis.items():
        own, cases = {}, {}
        for metric, by_case in metrics.items():
            floor = ABS_FLOOR.get(metric, 0.0)
            own[metric] = max(round_up(ENGINE_FACTOR * max(by_case.values()), 2), floor)
            for case, v in by_case.items():
                lim = max(round_up(FACTOR * v, 2), floor)
                if lim <= 0:
                    raise SystemExit(f"{engine} {case} {metric}: engine and reference both measured 0; "
                                     "give the metric an ABS_FLOOR")
                cases.setdefault(case, {})[metric] = lim
        out[engine] = {"own": own, "case": cases}
    return out


def derived_info(summary: dict) -> dict:
    from comparisons.reference import CHECK_SETTINGS, CONVERGED_SETTINGS
    v = summary.get("versions", {})
    # the peers' model the run used (comparisons.engines.base.DEFAULT_MODEL unless a case chose), read from
    # each run's stats (a described run records "described"; an adapter run records none): a profile's limits
    # hold for that model only, so the gate runs the peers on it (nsd_cli.compare.pin_model)
    models = {(r.get("stats") or {}).get("model") or "adapter" for runs in summary.get("runs", {}).values()
              for e, r in runs.items() if e in ("mujoco", "exudyn") and isinstance(r, dict) and r.get("status") == "ok"}
    if len(models) > 1:
        raise SystemExit(f"the run's peers ran different models ({', '.join(sorted(models))}): fixed limits hold for "
                         "one model; derive them from a run on one (each case's settings.ENGINE.model)")
    return {"mujoco": v.get("mujoco", ""), "exudyn": v.get("exudyn", ""), "numpy": v.get("numpy", ""),
            **({"model": models.pop()} if models else {}),
            "date": summary.get("date", dt.date.today().isoformat()), "git_revision": summary.get("git_revision", ""),
            "rule": f"{FACTOR:g} x max(engine error, reference error, {FRACTION:g} x engine max|dF| error) "
                    "against the converged reference (benchmarks/derive_limits.py); the in-house engine error: "
                    f"the largest over its run and rtol x {list(REALIZATIONS)}",
            "reference": json.dumps(CONVERGED_SETTINGS), "reference_checked_against": json.dumps(CHECK_SETTINGS)}


def to_toml(limits: dict[str, dict], info: dict, ref_errors: dict[str, dict], spread: dict[str, dict] | None = None) -> str:
    lines = ["[derived]"] + [f"{k} = {json.dumps(v)}" for k, v in info.items()] + [""]
    lines.append("# the converged reference's own error per case (the floor of each limit), for the record:")
    for case, errs in ref_errors.items():
        lines.append(f"#   {case}: " + ", ".join(f"{k} {v:.2g}" for k, v in errs.items()))
    lines.append("# the in-house ensemble's largest error per case (its engine error), for the record:")
    for case, errs in (spread or {}).items():
        lines.append(f"#   {case}: " + ", ".join(f"{k} {v:.2g}" for k, v in errs.items()))
    lines.append("")
    for engine, d in limits.items():
        lines.append(f"[limits.{engine}]")
        lines += [f"{k} = {v:.2g}" for k, v in d["own"].items()]
        for case, ms in d["case"].items():
            lines.append(f'[limits.{engine}.case."{case}"]')
            lines += [f"{k} = {v:.2g}" for k, v in ms.items()]
        lines.append("")
    return "\n".join(lines)


def write(path: Path, text: str) -> None:
    """Replace what follows MARK in the tolerance file (the hand-written [limits] defaults stay)."""
    from nsd_core.common.files import atomic_write_text
    head = path.read_text().split(MARK)[0].rstrip("\n")
    atomic_write_text(path, f"{head}\n\n{MARK}\n{text}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="the --out folder of an nsd compare run (its results.json and runs)")
    ap.add_argument("--cases", default=None, help="the case file of that run (default: comparisons/cases.toml)")
    ap.add_argument("--write", nargs="?", const=str(ROOT / "comparisons" / "limits_regression.toml"), default=None,
                    help="replace the derived tables of this tolerance file (default: comparisons/limits_regression.toml)")
    a = ap.parse_args(argv)
    out = Path(a.out)
    summary = json.loads((out / "results.json").read_text())
    errors, spread = reference_errors(out, summary, a.cases)
    text = to_toml(derive(summary, errors, spread), derived_info(summary), errors, spread)
    if a.write:
        write(Path(a.write), text)
        print(f"wrote {a.write}")
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
