"""The limit states of an IDA reported together (docs/ida.md), written next to ida.json:

    limit_states.json   per configuration and state: the lognormal fit (nsd_core.study.fragility),
                        each record's limit intensity and first time, the censored and never
                        observed records; per run, which states it reached and when
    limit_states.csv    the table: one row per configuration and state
    limit_states.png    the fragilities, one panel per configuration

The states and their rules are nsd_core.study.limit_states's.
"""
from __future__ import annotations

import csv
import io

import numpy as np

from nsd_core.common.files import atomic_write_json, atomic_write_text
from nsd_core.study.fragility import fit_lognormal, fragility_curve
from nsd_core.study.limit_states import STATES, LimitStates, classify, trace_states
from nsd_core.study.store import Store

TABLE_COLUMNS = [("configuration", ""), ("state", ""), ("threshold", ""), ("median", "m/s^2"), ("dispersion", "-"),
                 ("n_reached", ""), ("n_censored", ""), ("n_not_observed", ""), ("first_t_median", "s"),
                 ("first_t_median_low", "s"), ("first_t_median_high", "s"), ("n_first_t_unknown", ""), ("note", "")]


def configuration(trace) -> str:
    """A trace's configuration name: its own ``config`` (nsd p695), else 'device', the baseline
    isolator's kind its runs without the device stand on (nsd ida --isolator), or 'nodevice'."""
    if getattr(trace, "config", None):
        return trace.config
    if trace.device:
        return "device"
    iso = (trace.common.get("structure") or {}).get("isolator")
    return iso["kind"] if isinstance(iso, dict) else "nodevice"


def limit_states_of(traces) -> LimitStates | None:
    d = traces[0].common.get("states") if traces else None
    return LimitStates(**d) if d else None


def state_report(traces, store: Store, ls: LimitStates) -> dict:
    """limit_states.json's content."""
    configs: dict[str, dict] = {}
    runs = []
    for tr in traces:
        name = configuration(tr)
        history = []
        for level, _, _, key in tr.history:
            c = classify(store.load(key), ls, tr.device)
            history.append((level, c))
            runs.append({"record": tr.record, "configuration": name, "im": level,
                         "reached": {s: v["reached"] for s, v in c.items()},
                         "t": {s: v["t"] if v["t"] is not None else v.get("before_t") for s, v in c.items()}})
        states = [s for s in STATES if ls.applies(s, tr.device)]
        per = trace_states(history, states)
        cfg = configs.setdefault(name, {s: {"records": []} for s in states})
        for s in states:
            cfg[s]["records"].append({"record": tr.record, **per[s]})
    for name, cfg in configs.items():
        for s, entry in cfg.items():
            recs = entry["records"]
            fit = fit_lognormal([r["limit_im"] for r in recs if r["limit_im"] is not None],
                                [r["censored_at"] for r in recs if r["censored_at"] is not None])
            entry.update(fit, state=s, threshold=ls.describe(s), n_not_observed=sum(r["masked"] for r in recs),
                         **first_time_median([(r["t"], r.get("before_t")) for r in recs if r["limit_im"] is not None]))
    return {"states": {s: DESCRIPTION_OF[s] for s in STATES}, "thresholds": ls.to_dict(),
            "rules": ("a run stopped by the rod's reach counts as reaching the capacity (and a zero-force restrainer "
                      "engagement) when their thresholds lie below the rod's length (|u| passed them); drift and "
                      "floor acceleration were not observed in it ('stroke exhausted'): censored at the trace's last "
                      "level below, never counted; t: the first output time at or over the threshold (before_t: "
                      "before the stop at the rod's reach)"),
            "configurations": configs, "runs": runs}


def first_time_median(times: list[tuple[float | None, float | None]]) -> dict:
    """The median first time over every record that reached a state, [(t, before_t)]: t known, or
    unknown and bounded by 0 and before_t (reached before the run stopped; no bound when None).
    The median lies between the median with every unknown at 0 and with each at its upper bound;
    ``first_t_median`` is it when the two agree (the unknowns cannot move it), else None, and
    ``first_t_median_range`` gives both."""
    n = len(times)
    unknown = sum(t is None for t, _ in times)
    if n == 0:
        return {"first_t_median": None, "first_t_median_range": None, "n_first_t_unknown": 0}
    low = float(np.median([0.0 if t is None else t for t, _ in times]))
    high = float(np.median([t if t is not None else (b if b is not None else np.inf) for t, b in times]))
    return {"first_t_median": low if low == high else None,
            "first_t_median_range": [low, None if np.isinf(high) else high], "n_first_t_unknown": unknown}


DESCRIPTION_OF = {"stroke": "device stroke (the rod's reach)", "restrainer": "restrainer impact",
                  "capacity": "isolator displacement capacity", "drift": "story drift",
                  "floor_acceleration": "floor acceleration"}


def _cell(v) -> str:
    if v is None:
        return ""
    return f"{v:.6g}" if isinstance(v, float) else str(v)


def state_table(report: dict) -> str:
    """limit_states.csv: one row per configuration and state."""
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    w.writerow([f"{n} [{u}]" if u else n for n, u in TABLE_COLUMNS])
    for name, cfg in report["configurations"].items():
        for s, e in cfg.items():
            w.writerow([_cell(v) for v in (name, s, e["threshold"], e["median"], e["dispersion"], e["n_reached"],
                                           e["n_censored"], e["n_not_observed"], e["first_t_median"],
                                           *(e.get("first_t_median_range") or [None, None]), e.get("n_first_t_unknown"),
                                           e.get("note", ""))])
    return text.getvalue()


def draw_states(report: dict, measure: str, path) -> None:
    """limit_states.png: per configuration, every fitted state's fragility and its records' limit
    intensities (dots at their empirical fraction); states without a fit are named in the legend."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    configs = report["configurations"]
    fig, axes = plt.subplots(1, len(configs), figsize=(5.2 * len(configs), 4.0), squeeze=False, sharey=True)
    top = max([r["limit_im"] or r["censored_at"] or 0.0 for cfg in configs.values() for e in cfg.values()
               for r in e["records"]] + [1e-3]) * 1.3
    x = np.linspace(top / 400, top, 400)
    for ax, (name, cfg) in zip(axes[0], configs.items()):
        for s, e in cfg.items():
            color = f"C{STATES.index(s)}"   # one colour per state in every panel
            ims = sorted(r["limit_im"] for r in e["records"] if r["limit_im"] is not None)
            n = len(e["records"])
            if e["median"] is not None:
                ax.plot(x, fragility_curve(e["median"], e["dispersion"], x), color=color,
                        label=f"{DESCRIPTION_OF[s]}: {e['median']:.3g} m/s^2, b={e['dispersion']:.2f}")
            else:
                ax.plot([], [], color=color, label=f"{DESCRIPTION_OF[s]}: no fit ({e['n_reached']} of {n} reached)")
            if ims:
                ax.plot(ims, np.arange(1, len(ims) + 1) / n, "o", color=color, ms=3)
        ax.set_title(f"{name}: limit states")
        ax.set_xlabel(f"{measure} [m/s^2]")
        ax.set_ylim(0, 1.02)
        ax.set_xlim(0, top)   # every panel on one scale, so configurations compare at a glance
        ax.legend(fontsize=6.5, loc="lower right")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("P(state reached | IM)")
    fig.tight_layout()
    save_png(fig, path)


def write_states(traces, store: Store, measure: str) -> dict | None:
    """limit_states.json, .csv and .png under the store's root (None: the runs carry no states)."""
    ls = limit_states_of(traces)
    if ls is None:
        return None
    report = state_report(traces, store, ls)
    atomic_write_json(store.root / "limit_states.json", report)
    atomic_write_text(store.root / "limit_states.csv", state_table(report))
    draw_states(report, measure, store.root / "limit_states.png")
    return report


def summary_lines(report: dict) -> list[str]:
    """One printed line per configuration and state."""
    out = []
    for name, cfg in report["configurations"].items():
        for s, e in cfg.items():
            fit = (f"median {e['median']:.4g} m/s^2, dispersion {e['dispersion']:.3f}" if e["median"] is not None
                   else "no fit")
            t = _time_text(e)
            out.append(f"  {name} {DESCRIPTION_OF[s]}: {fit} ({e['n_reached']} reached, {e['n_censored']} censored, "
                       f"{e['n_not_observed']} not observed{t})")
    return out


def _time_text(e: dict) -> str:
    """The median first time, or the range it lies in when some records' times are unknown."""
    rng = e.get("first_t_median_range")
    if e["first_t_median"] is not None:
        return f", first reached at t ~ {e['first_t_median']:.3g} s (median)"
    if not rng:
        return ""
    hi = "?" if rng[1] is None else f"{rng[1]:.3g}"
    return (f", first reached at t between {rng[0]:.3g} and {hi} s (median; {e['n_first_t_unknown']} record(s) "
            "without a known time)")


def save_png(fig, path) -> None:
    """The figure as a PNG, written atomically (a temporary file beside it, then renamed)."""
    import os
    from pathlib import Path
    import matplotlib.pyplot as plt
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp.png")
    try:
        fig.savefig(tmp, dpi=130)
        os.replace(tmp, path)
    finally:
        plt.close(fig)
        if tmp.exists():
            tmp.unlink()
