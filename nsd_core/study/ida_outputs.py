"""The outputs of an incremental dynamic analysis (nsd_core.study.ida), written from the store after
every trace has ended (each file atomically; a resumed IDA writes the same bytes):

    ida.csv          one row per run: record, device on/off, configuration, level (IM), scale, peaks,
                     limit reached
    fragility.json   per configuration: the lognormal fit (nsd_core.study.fragility), each record's
                     limit intensity, the records that never reached the limit (censored) and those
                     left undetermined
    ida.json         the index: set, measure, limit, tracing settings, each trace's levels and outcome
    limit_states.*   the five limit states apart, when the runs carry their thresholds
                     (nsd_core.study.limit_state_outputs)
"""
from __future__ import annotations

import csv
import io

from nsd_core.common.files import atomic_write_json, atomic_write_text
from nsd_core.study.fragility import fit_lognormal
from nsd_core.study.ida import SPENT, Trace, trace_result
from nsd_core.study.seismic_set import peak_drift_ratio, worst_building_peak
from nsd_core.study.store import Store

CONFIGS = {True: "device", False: "nodevice"}
IDA_COLUMNS = [  # name, unit ("" for text)
    ("set", ""), ("record", ""), ("device", ""), ("configuration", ""), ("order", ""), ("im", "m/s^2"), ("scale", "-"),
    ("peak_u", "m"), ("peak_a_abs", "m/s^2"), ("peak_base_shear", "N"), ("residual_u", "m"),
    ("peak_drift_ratio", "-"), ("peak_floor_a_abs", "m/s^2"),   # the worst story / floor of a building, if any
    ("stop_t", "s"), ("limit_reached", ""), ("why", ""), ("status", ""), ("key", ""),
]


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(v)
    return str(v)


def row_status(rec: dict) -> str:
    """ida.csv's status of a stored run: ``ok`` (the whole record ran), ``stopped`` (the device was
    spent, the rod's reach or a wire's validity: the limit is reached), ``failed`` (a solver failure:
    the run cannot tell)."""
    if rec["status"] == "ok":
        return "ok"
    return "stopped" if (rec.get("metrics") or {}).get("reason") in SPENT else "failed"


def ida_rows(traces: list[Trace], store: Store) -> list[dict]:
    """One row per run, by record, configuration and level."""
    from nsd_core.study.limit_state_outputs import configuration
    rows = []
    rank: dict[str, int] = {}
    for tr in traces:
        name = configuration(tr)   # device, nodevice, or the baseline isolator the runs stand on
        rank.setdefault(name, len(rank))
        for order, (level, reached, why, key) in enumerate(tr.history, 1):
            rec = store.load(key)
            row = {"set": tr.common["set"], "record": tr.record, "device": "yes" if tr.device else "no",
                   "configuration": name, "order": order, "im": level, "scale": rec["design"]["ground"]["scale"],
                   "limit_reached": {True: "yes", False: "no", None: "unknown"}[reached], "why": why,
                   "status": row_status(rec), "key": key}
            m = rec.get("metrics") or {}
            if rec["status"] == "ok":
                row.update(peak_u=m["peak_displacement"]["value"], peak_a_abs=m["peak_absolute_acceleration"]["value"],
                           peak_base_shear=m["peak_base_shear"]["value"], residual_u=m["residual_displacement"]["u"],
                           peak_drift_ratio=peak_drift_ratio(m),
                           peak_floor_a_abs=worst_building_peak(m, "peak_floor_acceleration"))
            else:
                row["stop_t"] = m.get("t")
            rows.append(row)
    rows.sort(key=lambda r: (r["record"], rank[r["configuration"]], r["im"]))
    return rows


def fragility(traces: list[Trace], measure: dict, limit_text: str) -> dict:
    """fragility.json's content: per configuration, the fit and the records behind it."""
    out = {"measure": measure, "limit": limit_text, "configurations": {}}
    # a trace's own configuration name where it carries one (nsd p695: device and each baseline apart)
    names = list(dict.fromkeys(tr.config or CONFIGS[tr.device] for tr in traces)) or list(CONFIGS.values())
    for name in names:
        results = [trace_result(tr) for tr in traces if (tr.config or CONFIGS[tr.device]) == name]
        reached = [r for r in results if r["limit_im"] is not None]
        censored = [r for r in results if r["censored_at"] is not None]
        fit = fit_lognormal([r["limit_im"] for r in reached], [r["censored_at"] for r in censored])
        out["configurations"][name] = {
            **fit, "records": results,
            "never_reached": [{"record": r["record"], "censored_at": r["censored_at"]} for r in censored],
            "undetermined": [{"record": r["record"], "why": r["undetermined"]} for r in results if r["undetermined"]],
            "stroke_exhausted": [{"record": r["record"], "at_im": r["stroke_exhausted_at"],
                                  "censored_at": r["censored_at"], "limit_im": r["limit_im"]}
                                 for r in results if r.get("stroke_exhausted_at") is not None],
            "note": fit.get("note", "") + ("; " if fit.get("note") and censored else "")
                    + ("records that never reached the limit are right-censored at their highest level"
                       if censored else ""),
        }
    return out


def write_ida(traces: list[Trace], store: Store, index: dict) -> dict:
    """ida.csv, fragility.json and ida.json under the store's root; returns ida.json's content."""
    root = store.root
    rows = ida_rows(traces, store)
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    w.writerow([f"{n} [{u}]" if u else n for n, u in IDA_COLUMNS])
    for row in rows:
        w.writerow([_cell(row.get(n)) for n, _ in IDA_COLUMNS])
    atomic_write_text(root / "ida.csv", text.getvalue())
    frag = fragility(traces, index["measure"], index["limit"])
    atomic_write_json(root / "fragility.json", frag)
    from nsd_core.study.limit_state_outputs import write_states
    states = write_states(traces, store, index["measure"].get("measure", "IM"))
    if states is not None:   # the limit states apart (limit_states.json): their fits in the index too
        index = {**index, "limit_states": {name: {s: {k: e[k] for k in ("median", "dispersion", "n_reached",
                                                                           "n_censored", "n_not_observed")}
                                                  for s, e in cfg.items()}
                                           for name, cfg in states["configurations"].items()},
                 "limit_state_thresholds": states["thresholds"]}
    index = {**index, "columns": dict(IDA_COLUMNS), "runs": len(rows),
             "traces": [{"name": tr.name, "record": tr.record, "device": tr.device, "im_at_scale_1": tr.im1,
                         "levels": [lv for lv, *_ in tr.history], **trace_result(tr)} for tr in traces],
             "fragility": {name: {k: c[k] for k in ("median", "dispersion", "n_reached", "n_censored")}
                           for name, c in frag["configurations"].items()}}
    atomic_write_json(root / "ida.json", index)
    return index
