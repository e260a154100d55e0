"""Measure each case's runs and apply the gate's rule (comparisons/verdict.py).

For each case: every engine's difference from the converged reference (the gated values), the
reference's own error (converged against its rtol 1e-11 check), each peer's difference between its
h and 2h runs (its estimate), its own checks (closure, tracking, energy balance); and, reported but
not gated, every engine against the in-house run at its case settings and the peers against each other.
"""
from __future__ import annotations

import math

from comparisons.config import SeismicCase
from comparisons.energy import energy_balance_rel
from comparisons.engines import REFERENCE
from comparisons.estimate import STEP_SETTING
from comparisons.metrics import own_metrics, pair_metrics, path_length
from comparisons.reference import CONVERGED_SETTINGS
from comparisons.seismic import gate_metrics, own_seismic_metrics, seismic_metrics
from comparisons.verdict import (CHECK, CONVERGED, PRIMARY, Rule, case_verdicts, drive_scales, estimate_from_pair,
                                 peer_evidence, peer_label, seismic_scales)
from nsd_core.device.geometry import device_geometry


def differences(case, run, ref, run_summary: dict | None = None, ref_summary: dict | None = None) -> dict:
    """The gate's difference metrics of ``run`` against ``ref`` (drive: force vector, loop work, peak,
    regions; seismic: plate displacement, device force, peaks, the building's floors and stories)."""
    if isinstance(case, SeismicCase):
        out = gate_metrics(ref, run)
        out["max_da_rel"] = seismic_metrics(ref, run)["da"]   # bounds the peak acceleration's estimate
        return out
    d = case.drive
    return pair_metrics(run, ref, run_summary or {}, ref_summary or {}, d.amplitude, d.frequency)


def own_checks(case, run) -> dict:
    """An engine's checks on its own run: closure, tracking, energy balance."""
    if isinstance(case, SeismicCase):
        return own_seismic_metrics(run)
    out = own_metrics(run)
    out["energy_balance_rel"] = energy_balance_rel(run, device_geometry(case.params), case.drive.frequency,
                                                   case.drive.unit_vector)
    return out


def judge_case(case, engines: list[str], results: dict, entries: dict, rule: Rule) -> tuple[list[dict], dict]:
    """Rows and per-engine verdicts of one case. ``results[(case, label)]`` the runs, ``entries[label]``
    their records (status, stats, summary)."""
    conv = results.get((case.name, CONVERGED))
    if conv is None:
        return [], {}
    seismic = isinstance(case, SeismicCase)
    primary = PRIMARY["seismic" if seismic else "drive"]

    def summ(label):
        return (entries.get(label) or {}).get("summary") or {}

    def diff(a, b):
        return differences(case, results[(case.name, a)], results[(case.name, b)], summ(a), summ(b))

    check = (case.name, CHECK) in results
    ref_error = diff(CONVERGED, CHECK) if check else {}
    values, estimates, evidence = {}, {}, {}
    for e in engines:
        if (case.name, e) not in results:
            continue
        values[e] = {**diff(e, CONVERGED), **own_checks(case, results[(case.name, e)])}
        if e == REFERENCE:   # its error is proportional to its rtol: --refine can ask for a smaller one
            estimates[e] = {k: v for k, v in values[e].items()}
            rtol = ((entries.get(e) or {}).get("stats") or {}).get("rtol")
            evidence[e] = {"note": "its difference from the converged reference (the same code, rtol 1e-10)",
                           "setting": "rtol" if rtol else None, "step": rtol, "order": 1.0}
            continue
        pair = peer_label(e, case)
        if e not in STEP_SETTING or (case.name, pair) not in results:
            why = (entries.get(pair) or {}).get("message", "not run")
            evidence[e] = {"note": f"no error estimate: its companion run ({pair}) failed or did not run ({why})"}
            continue
        to_ref_pair = diff(pair, CONVERGED)
        ev = peer_evidence(e, case.settings.get(e, {}), (entries.get(e) or {}).get("stats") or {},
                           (entries.get(pair) or {}).get("stats") or {}, values[e][primary], to_ref_pair[primary],
                           seismic)
        estimates[e] = estimate_from_pair(diff(e, pair), ev["factor"], rule.beta)
        evidence[e] = {**ev, "companion": to_ref_pair, "refined": e in getattr(case, "refined", ())}
    scales = seismic_scales(conv) if seismic else drive_scales(conv, case.drive.frequency, case.drive.amplitude)
    # a stiffness-region boundary is a sample of the output grid: it can move by a sample either way
    floors = {} if seismic else {"region_shift_rel": 2.0 * 2.0 * math.pi / case.drive.samples_per_cycle}
    # the loop work's difference is at most the force's max-norm difference x the path's length (in their scales)
    work = 0.0 if seismic else scales["loop_area_rel"][0]
    implied = {"loop_area_rel": scales["max_dF_rel"][0] * path_length(conv, case.drive.frequency) / work} if work else {}
    rows, verdicts = case_verdicts(case.name, "seismic" if seismic else "drive", list(values), values, estimates,
                                   ref_error, scales, evidence, rule, floors, own_checks(case, conv),
                                   reference_rtol=CONVERGED_SETTINGS["rtol"], implied=implied)
    for e, v in verdicts.items():
        v["evidence"] = evidence.get(e, {})
        if not check:
            v["text"] += "; the reference's own error was not measured (its rtol 1e-11 check did not run)"
    rows += _reported(case, engines, results, summ, rule)
    return rows, verdicts


def _reported(case, engines, results, summ, rule: Rule) -> list[dict]:
    """Every engine against the in-house run at its case settings and the peers against each other:
    shown beside the verdict, not gated (each is already judged against the converged reference)."""
    others = [e for e in engines if e != REFERENCE]
    pairs = [(e, REFERENCE) for e in others] + [(a, b) for i, a in enumerate(others) for b in others[i + 1:]]
    rows = []
    for a, b in pairs:
        if (case.name, a) not in results or (case.name, b) not in results:
            continue
        ra, rb = results[(case.name, a)], results[(case.name, b)]
        for k, v in differences(case, ra, rb, summ(a), summ(b)).items():
            if k not in rule.engineering:
                continue
            tol = rule.engineering[k]
            rows.append({"case": case.name, "engine": a, "reference": b, "metric": k, "value": float(v),
                         "limit": tol, "limit_source": "tolerance", "tolerance": tol, "pass": bool(v <= tol),
                         "gated": False})
    return rows
