"""Where the in-house step-size controller spends its steps: at the force laws' kinks? (docs/performance.md)

    .venv/bin/python benchmarks/steps_at_kinks.py --out out/steps_at_kinks
    .venv/bin/python benchmarks/steps_at_kinks.py --out /tmp/kinks --cases A15mm_f10Hz --no-scan

The in-house right-hand side has kinks (a derivative jumps) where a rope goes slack or taut
(Eq. 16: T = k_r (l_r - l_r0) H(l_r - l_r0)) and where the spring lifts off its seat or lands (Eq. 18:
push-only): the two asked about first (``STATE_KINKS``); and also where a wire's stress crosses zero
(Eq. 17a: T = sigma A_w H(sigma)), where a wire's strain crosses zero or its strain rate changes sign
(|eps|, sgn(deps) and H(-eps deps) in Eq. 17b-d), where the spring's zeta or compression rate changes
sign (sgn(zeta dx_s) in Eq. 18b), and, in the seismic mode, at every sample of the record (the ground
acceleration is linear between samples). An embedded Runge-Kutta pair assumes a smooth solution;
across a kink its error estimate is off and the controller may reject trials and shrink its step
there. Event location (ending a step at the kink) would pay only if a good part of the work is spent
there.

Part 1, the steps (default cases of comparisons/cases.toml: every drive case and seismic_nf1_pulse, at
the default solver settings DOP853, rtol 1e-7, atol 1e-12, max_step 1e-3): the compiled step loop
(nsd_core.engine.rk._step_loop) is copied here in Python, calling the same compiled pieces (stages,
error norm, dense output, the model's evaluation) in the same order on the same workspace, and every
trial step is logged: start, size, error norm, accepted or rejected. The copy is checked against the
real kernel: its accepted step ends must equal the kernel's (``rk.make_outputs(keep_steps=...)``) bit
for bit, and its counts of steps and evaluations the kernel's stats. At the start and the end of every
trial the signs of the kinks' switching functions (``switching``) are evaluated on a second workspace
(which does not disturb the run); a trial *crosses* a kink when a sign differs. Reported per case:
accepted and rejected trials, the rejected ones classed by the kinks their step's trials cross
(``rope_or_lift``, ``other_kink``, ``no_kink``), by kind, and by the state entry with the largest
error (the one that failed the test), the evaluations they cost, and the *recovery*: after a kink-crossing
step the controller grows its step by at most 10x a step, so the accepted steps until the step is
back to the size it had before the kink, minus the steps the smooth step size would have needed over
that span, are the accepted steps the kink cost. ``saving_bound`` = the evaluations of the rejected
kink-crossing trials plus those of the recovery's extra steps, over the run's evaluations: the most
that event location could save; ``saving_net_estimate`` takes one trial per event off (the crossing
trial or the restart's first step), not counting the root search.

Part 2, the erratic error (skipped with ``--no-scan``): on figure8_A15mm_f10Hz and A15mm_f10Hz_psi45
the in-house run at rtol = 1e-7 x {0.7, 0.85, 0.95, 1, 1.05, 1.2, 1.4} against the converged reference
(comparisons.reference.CONVERGED_SETTINGS, rtol 1e-10): max|dF|/max|F| on the last cycle (the gate's
max_dF_rel, comparisons.metrics.pair_metrics), the time of the worst sample and the accepted step it
lies in (its size, error norm, the kinks it crossed, whether the sample is the step's end or comes
from its dense output), and the largest increases of the state's error from one sample to the next
(``error_jumps``), each with its step.

The model's evaluation is the one the runs use (nsd_core.engine.codegen.evaluator_for: the generated
one, or the generic kernels with NSD_EVALUATOR=generic). Deterministic (same inputs, same numbers).
CPU times are not measured here (the counts are the cost).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))   # run as a script: the repository's benchmarks package

from benchmarks.traced_steps import (KINDS, STATE_KINKS, Setup, components, drive_setup,  # noqa: E402
                                     kernel_run, seismic_setup, traced_run)
from comparisons.config import SeismicCase, load_cases  # noqa: E402
from nsd_core.common.files import atomic_write_json, atomic_write_text  # noqa: E402
from nsd_core.engine.codegen import prefer_generated  # noqa: E402

SCAN_CASES = ("figure8_A15mm_f10Hz", "A15mm_f10Hz_psi45")
SCAN_FACTORS = (0.7, 0.85, 0.95, 1.0, 1.05, 1.2, 1.4)
DEFAULT_SEISMIC = ("seismic_nf1_pulse",)


def _recovery(h_acc: np.ndarray, kink_acc: np.ndarray) -> tuple[float, int, list]:
    """After each accepted step that crossed a kink, the accepted steps until the step is back to
    h_before (the accepted step before it), minus span / h_before: the extra accepted steps."""
    extra, episodes, shrink, j = 0.0, 0, [], 1
    while j < len(h_acc):
        if not kink_acc[j]:
            j += 1
            continue
        h_before, span, n, jj = h_acc[j - 1], 0.0, 0, j
        while jj < len(h_acc) and (jj == j or h_acc[jj] < 0.999 * h_before):
            span += h_acc[jj]
            n += 1
            jj += 1
        extra += max(0.0, n - span / h_before)
        shrink.append(h_acc[j] / h_before)
        episodes += 1
        j = jj
    return extra, episodes, shrink


def _episodes(acc: np.ndarray) -> list[tuple[int, int]]:
    """(first, last) trial of every step: its rejected trials, then the accepted one (last)."""
    out, i = [], 0
    while i < len(acc):
        j = i
        while j < len(acc) and not acc[j]:
            j += 1
        out.append((i, min(j, len(acc) - 1)))
        i = j + 1
    return out


def step_report(s: Setup, tr: dict) -> dict:
    """Where the rejected trials fall and what they and the recovery after each kink cost.

    A step's rejected trials are classed by the kinks its trials cross: ``rope_or_lift`` (a rope
    slack/taut or the spring's lift-off: what event location would stop at), ``other_kink`` (only the
    other kinks of KINDS), ``no_kink`` (none: the controller's ordinary probing in a smooth stretch,
    one rejection with the step cut by ~0.8). ``named`` / ``any``: the crossings, recovery and the
    bound on the saving for the rope/lift-off kinks and for every kink."""
    acc, h = tr["accepted"], tr["h"]
    per = 12  # DOP853: 12 evaluations per trial (the 13th stage is the next step's first: FSAL)
    crossed = [set(c) for c in tr["crossed"]]
    by_kind = {}
    for kind in KINDS:
        on = np.array([kind in c for c in crossed])
        by_kind[kind] = {"accepted": int(np.sum(on & acc)), "rejected": int(np.sum(on & ~acc))}
    names = components(s)
    worst = tr["worst"]
    classes = {c: {"steps": 0, "rejected": 0, "steps_with_2_or_more": 0} for c in ("rope_or_lift", "other_kink",
                                                                                   "no_kink")}
    for i, j in _episodes(acc):
        n_rej = j - i if acc[j] else j - i + 1
        if n_rej == 0:
            continue
        seen = set().union(*crossed[i:j + 1])
        c = "rope_or_lift" if seen & set(STATE_KINKS) else ("other_kink" if seen else "no_kink")
        classes[c]["steps"] += 1
        classes[c]["rejected"] += n_rej
        classes[c]["steps_with_2_or_more"] += int(n_rej >= 2)
    out = {"accepted": int(np.sum(acc)), "rejected": int(np.sum(~acc)), "trials": len(h), "nfev": int(tr["nfev"]),
           "rejected_by_class": classes, "by_kind": by_kind,
           "rejected_by_error_component": {names[i]: int(np.sum((worst == i) & ~acc))
                                           for i in sorted(set(worst[~acc].tolist()))}}
    acc_idx = np.flatnonzero(acc)
    h_acc = h[acc_idx]
    for label, group in (("named", set(STATE_KINKS)), ("any", set(KINDS) | {"unknown"})):
        on = np.array([bool(c & group) for c in crossed])
        extra, episodes, shrink = _recovery(h_acc, on[acc_idx])
        rej = classes["rope_or_lift"]["rejected"] + (classes["other_kink"]["rejected"] if label == "any" else 0)
        out[label] = {"accepted_crossing": int(np.sum(on & acc)), "rejected": rej, "episodes": episodes,
                      "recovery_extra_steps": extra,
                      "step_shrink_median": float(np.median(shrink)) if shrink else None,
                      "evaluations": per * (rej + extra), "saving_bound": per * (rej + extra) / tr["nfev"],
                      # event location still takes about one trial per event (the crossing trial, or the
                      # restart's first step) on top of its root search (not counted)
                      "saving_net_estimate": per * max(0.0, rej + extra - episodes) / tr["nfev"]}
    if len(s.knots):
        knot = tr["knot"]
        anyk = np.array([bool(c) for c in crossed])
        out["record_knots"] = {"accepted": int(np.sum(knot & acc)), "rejected": int(np.sum(knot & ~acc)),
                               "rejected_without_a_state_kink": int(np.sum(knot & ~acc & ~anyk))}
    out["accepted_at_max_step"] = int(np.sum(np.isclose(h_acc, s.settings[2], rtol=1e-9, atol=0.0)))
    out["step_size"] = {"median": float(np.median(h_acc)), "max": float(np.max(h_acc))}
    return out


def kink_times(tr: dict, group=STATE_KINKS) -> np.ndarray:
    """Midpoints of the accepted steps that crossed a kink of ``group`` (the crossing lies inside)."""
    acc = tr["accepted"]
    idx = [i for i in np.flatnonzero(acc) if set(tr["crossed"][i]) & set(group)]
    return np.array([tr["t"][i] + 0.5 * tr["h"][i] for i in idx])


def check_copy(s: Setup, tr: dict) -> dict:
    """The copy against the real kernel: the same accepted step ends (bit for bit), steps and nfev."""
    ends, stats, out = kernel_run(s, keep_steps=len(tr["step_ends"]) + 10)
    same = len(ends) == len(tr["step_ends"]) and bool(np.array_equal(ends, tr["step_ends"]))
    return {"kernel_steps": int(stats[0]), "kernel_nfev": int(stats[1]), "copy_steps": int(tr["steps"]),
            "copy_nfev": int(tr["nfev"]), "step_ends_identical": same,
            "outputs_identical": bool(np.array_equal(out.y, tr["outputs"].y))}


def error_jumps(tr: dict, y: np.ndarray, y_ref: np.ndarray, t_eval: np.ndarray, top: int = 3) -> list[dict]:
    """Where the run's error is made: the global error per sample, e_k = max_i |y_ki - y_ref,ki| /
    max_k |y_ref,ki| over the state's entries (the hysteretic stresses and zeta keep an error once made),
    its ``top`` largest increases from one sample to the next, and the accepted step each falls in:
    its size, error norm and the kinks it crossed."""
    e = np.max(np.abs(y - y_ref) / np.maximum(np.max(np.abs(y_ref), axis=0), 1e-300), axis=1)
    inc = np.diff(e)
    acc = np.flatnonzero(tr["accepted"])
    ends = tr["t"][acc] + tr["h"][acc]
    out = []
    for k in np.argsort(inc)[::-1][:top]:
        tk = t_eval[k + 1]
        i = acc[min(int(np.searchsorted(ends, tk)), len(acc) - 1)]  # the step whose end is the first >= tk
        out.append({"t": float(tk), "increase": float(inc[k]), "error_after": float(e[k + 1]),
                    "final_error": float(e[-1]), "step_start": float(tr["t"][i]), "step_h": float(tr["h"][i]),
                    "step_error_norm": float(tr["err"][i]), "crossed": sorted(tr["crossed"][i]),
                    "rejections_before": int(i - (acc[acc < i][-1] + 1 if np.any(acc < i) else 0))})
    return out


def scan(cases: dict, names, factors, log) -> dict:
    """Part 2: the in-house error against the converged reference for rtol = 1e-7 x factor."""
    from comparisons.metrics import pair_metrics
    from comparisons.reference import CONVERGED_SETTINGS
    from nsd_core.device.cycle import steady_cycle
    from nsd_core.device.model import simulate
    out = {}
    for name in names:
        case = cases[name]
        ref = simulate(case.params, case.drive, **CONVERGED_SETTINGS)
        conv = CONVERGED_SETTINGS
        _, _, ref_out = kernel_run(drive_setup(case, conv["rtol"], conv["atol"], conv["max_step"]), 0)
        f = case.drive.frequency
        cyc = steady_cycle(ref, f)
        rows = []
        for fac in factors:
            rtol = 1e-7 * fac
            run = simulate(case.params, case.drive, rtol=rtol)
            gate = pair_metrics(run, ref, {}, {}, case.drive.amplitude, f)["max_dF_rel"]
            Fr = np.column_stack([ref["F_x"][cyc], ref["F_y"][cyc]])
            dF = np.linalg.norm(np.column_stack([run["F_x"][cyc], run["F_y"][cyc]]) - Fr, axis=1)
            setup = drive_setup(case, rtol=rtol)
            tr = traced_run(setup)
            rep = step_report(setup, tr)
            jumps = error_jumps(tr, tr["outputs"].y, ref_out.y, setup.t_eval)
            t_worst = float(ref["t"][cyc][int(np.argmax(dF))])
            acc = np.flatnonzero(tr["accepted"])
            i = acc[min(int(np.searchsorted(tr["t"][acc] + tr["h"][acc], t_worst)), len(acc) - 1)]
            in_step = {"start": float(tr["t"][i]), "h": float(tr["h"][i]), "error_norm": float(tr["err"][i]),
                       "crossed": sorted(tr["crossed"][i]),
                       "at_step_end": bool(abs(tr["t"][i] + tr["h"][i] - t_worst) < 1e-12)}
            rows.append({"rtol": rtol, "factor": fac, "max_dF_rel": gate, "t_worst": t_worst,
                         "worst_sample_step": in_step, "steps": rep["accepted"],
                         "rejected": rep["rejected"], "rejected_at_rope_or_lift": rep["named"]["rejected"],
                         "rejected_at_any_kink": rep["any"]["rejected"], "error_jumps": jumps})
            j = jumps[0]
            log(f"  {name} rtol {rtol:.3g}: max_dF_rel {gate:.3e} (worst at t = {t_worst:.5f} s, inside the step "
                f"[{in_step['start']:.6f} s + {in_step['h']:.2e} s], error norm {in_step['error_norm']:.3g}, crossing "
                f"{in_step['crossed']}); "
                f"{rep['accepted']} steps, {rep['rejected']} rejected; largest state-error jump "
                f"{j['increase']:.2e} (final {j['final_error']:.2e}) at t = {j['t']:.5f} s in the step "
                f"[{j['step_start']:.6f} s + {j['step_h']:.2e} s] (error norm {j['step_error_norm']:.3g}, "
                f"{j['rejections_before']} rejections before) crossing {j['crossed']}; next: "
                + "; ".join(f"{x['increase']:.1e} at {x['t']:.5f} crossing {x['crossed']}" for x in jumps[1:]))
        out[name] = rows
    return out


def table(results: dict) -> str:
    lines = ["case | accepted | rejected: at rope/lift-off, other kinks, smooth | accepted crossing rope/lift-off | "
             "recovery extra steps (rope/lift-off, any) | nfev | saving bound (rope/lift-off, any kink)",
             "--- | --- | --- | --- | --- | --- | ---"]
    for name, r in results.items():
        n, a, c = r["named"], r["any"], r["rejected_by_class"]
        lines.append(f"{name} | {r['accepted']} | {r['rejected']}: {c['rope_or_lift']['rejected']}, "
                     f"{c['other_kink']['rejected']}, {c['no_kink']['rejected']} | {n['accepted_crossing']} | "
                     f"{n['recovery_extra_steps']:.1f}, {a['recovery_extra_steps']:.1f} | {r['nfev']} | "
                     f"{n['saving_bound']:.2%}, {a['saving_bound']:.2%}")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    # the in-house engine as the studies run it (the generated evaluation); here, not at import, so that
    # importing this module (a test does) leaves the environment alone
    prefer_generated()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--cases", default=None, help="comma-separated case names (default: every drive case and "
                                                  "seismic_nf1_pulse)")
    ap.add_argument("--no-scan", action="store_true", help="skip part 2 (the rtol scan)")
    args = ap.parse_args(argv)
    log = lambda s: print(s, file=sys.stderr, flush=True)  # noqa: E731
    cases = {c.name: c for c in load_cases()}
    names = args.cases.split(",") if args.cases else \
        [c for c, v in cases.items() if not isinstance(v, SeismicCase)] + list(DEFAULT_SEISMIC)
    results, checks = {}, {}
    for name in names:
        case = cases[name]
        s = seismic_setup(case) if isinstance(case, SeismicCase) else drive_setup(case)
        start = time.perf_counter()
        tr = traced_run(s)
        checks[name] = check_copy(s, tr)
        results[name] = step_report(s, tr)
        r = results[name]
        log(f"{name}: {r['accepted']} accepted, {r['rejected']} rejected {r['rejected_by_class']}; "
            f"by the entry that failed the "
            f"test: {r['rejected_by_error_component']}; copy == kernel: {checks[name]} "
            f"({time.perf_counter() - start:.1f} s)")
    doc = {"settings": {"method": "DOP853", "rtol": 1e-7, "atol": 1e-12, "max_step": 1e-3},
           "steps": results, "copy_vs_kernel": checks}
    if not args.no_scan:
        doc["scan"] = scan(cases, [n for n in SCAN_CASES if n in cases], SCAN_FACTORS, log)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "steps_at_kinks.json", doc)
    atomic_write_text(out / "steps_at_kinks.md", table(results))
    print(table(results))
    bad = [n for n, c in checks.items() if not c["step_ends_identical"]]
    if bad:
        print(f"the copy of the step loop differs from the kernel on {', '.join(bad)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
