"""Text pages of the report: the summary (verdict and failures first, what was run, tolerances,
metrics against their limits, continued over as many pages as needed) and the parameter set."""
from __future__ import annotations

import json

from reports.style import (GREEN, GREY, ORANGE, PORTRAIT, RED, fmt, natural, new_figure, rows_per_page, table, text_width,
                    wrap_rows, wrap_width)

FS = 7.0           # table font size [pt]
LINE = 1.55 * FS / 72 / PORTRAIT[1]  # one table row, figure fraction
BOTTOM = 0.05
WIDTH_PT = 0.88 * PORTRAIT[0] * 72  # usable text width [pt]
METRIC_DESC = {"max_dF_rel": "max |F - F_ref| / max |F_ref|", "rms_dF_rel": "RMS(F - F_ref) / max |F_ref|",
               "loop_area_rel": "|loop area - ref| / |ref|", "peak_force_rel": "|peak |F| - ref| / ref",
               "region_shift_rel": "largest stiffness-region boundary shift / A",
               "closure_max": "largest loop-closure violation", "tracking_error": "largest drive tracking error",
               "energy_balance_rel": "|drive work - dissipated - stored change| / drive work"}


def _wrap(text: str, size: float, bold: bool = False) -> str:
    """Wrap to the page's text width at font ``size`` (measured)."""
    return "\n".join(wrap_width(text, WIDTH_PT, size, bold, indent="   "))


def _text(fig, y: float, text: str, size: float = 8.0, color: str = "black", weight: str = "normal",
          x: float = 0.06) -> float:
    text = _wrap(text, size, weight == "bold")
    fig.text(x, y, text, ha="left", va="top", fontsize=size, color=color, weight=weight)
    return y - (text.count("\n") + 1) * 1.45 * size / 72 / PORTRAIT[1]


def _heading(fig, y: float, text: str) -> float:
    return _text(fig, y - 0.006, text, size=10, weight="bold") - 0.004


def _overrides(c: dict) -> str:
    parts = [f"{k}={fmt(v)}" for k, v in (c.get("params_overridden") or {}).items()]
    parts += [f"{e}: {k}={fmt(v)}" for e, p in (c.get("engine_params") or {}).items() for k, v in p.items()]
    parts += [f"{e} settings: " + ", ".join(f"{k}={fmt(v)}" for k, v in s.items())
              for e, s in (c.get("settings") or {}).items() if s]
    return "; ".join(parts) or "-"


def _split_name(name: str, unit: str, width: float) -> str:
    """A metric name over as many header lines as its column needs, broken before underscores."""
    tokens = name.split("_")
    parts = [tokens[0]] + ["_" + t for t in tokens[1:]] + ([f" [{unit}]"] if unit and unit != "-" else [])
    lines = [""]
    for p in parts:
        if lines[-1] and text_width(lines[-1] + p, FS, True) > width:
            lines.append(p.strip())
        else:
            lines[-1] += p
    return "\n".join(lines)


def metric_rows(data) -> tuple[list[tuple[str, float, str]], list[list[str]], list[list]]:
    """Pivot of the metrics: one row per (case, engine, compared with), one column per metric."""
    s = data.summary
    names = [m for m in s["tolerances"] if any(r.get("metric") == m for r in s["metrics"])]
    units = s.get("metric_units", {})
    texts = [[r["case"] for r in s["metrics"]] + ["case"], [r["engine"] for r in s["metrics"]] + ["engine"],
             [r.get("reference") or "(own)" for r in s["metrics"]] + ["vs"], ["result", "over*", "ERROR"]]
    fixed = [max(text_width(str(t), FS, True) for t in col) + 6 for col in texts]  # natural widths [pt]
    share = max((WIDTH_PT - sum(fixed)) / max(len(names), 1), 30.0)
    cols = [("case", fixed[0], "l"), ("engine", fixed[1], "l"), ("vs", fixed[2], "l")] + \
        [(_split_name(m, units.get(m, "-"), share - 6), share, "r") for m in names] + [("result", fixed[3], "c")]
    rows, colors = [], []
    short = [fmt(s["tolerances"][m], 2) for m in names]
    short = [f"{s['tolerances'][m]:.0e}" if "e" in t else t for m, t in zip(names, short)]
    per_engine = bool(s.get("tolerances_by_engine"))   # then the rows have their own (tighter) limits
    limit_row = ["default limit" if per_engine else "limit", "", ""] + [f"\u2264 {t}" for t in short] + [""]
    rows.append(limit_row)
    colors.append([GREY] * len(limit_row))
    keyed: dict[tuple, dict] = {}
    for r in s["metrics"]:
        keyed.setdefault((r["case"], r["engine"], r.get("reference") or "own"), {})[r["metric"]] = r
    for (case, engine, vs), ms in keyed.items():
        row, col = [case, engine, vs if vs != "own" else "(own)"], [None, None, None]
        bad_gated = bad_free = False
        for m in names:
            r = ms.get(m)
            row.append(fmt(r["value"], 2) if r else "")
            if r and not r["pass"]:
                col.append(RED if r["gated"] else ORANGE)
                bad_gated |= bool(r["gated"])
                bad_free |= not r["gated"]
            else:
                col.append(None)
        gated = any(r["gated"] for r in ms.values())
        row.append("FAIL" if bad_gated else ("over*" if bad_free else ("PASS" if gated else "ok*")))
        col.append(RED if bad_gated else (ORANGE if bad_free else (GREEN if gated else None)))
        rows.append(row)
        colors.append(col)
    for case, per in s["runs"].items():
        for engine, run in per.items():
            if run.get("status") != "ok":
                rows.append([case, engine, "-", "ERROR: " + str(run.get("message", "?"))] + [""] * (len(names) - 1)
                            + ["ERROR"])
                colors.append([RED] * len(rows[-1]))
    return cols, rows, colors


def summary_pages(data) -> list:
    """Page 1 (verdict, failures, what was run, tolerances, metrics) and the metrics' continuation."""
    s = data.summary
    cols, rows, colors = metric_rows(data)
    fig = _page_one(data)
    y = fig._nsd_y - 0.004
    y = _heading(fig, y, "Metrics against their limits")
    fit_rows = rows_per_page(y - 0.045, BOTTOM, FS)
    note = ("Gated rows compare an engine with the reference; (own) rows are an engine's own checks. Red: "
            "outside its limit. Rows marked * are engine pairs reported but not gated (orange: over the limit).")
    y = _text(fig, y, note, size=7, color=GREY) - 0.006
    first = rows[:max(fit_rows, 0)]
    if first:
        table(fig, y, cols, first, colors[:len(first)], fontsize=FS)
    else:
        _text(fig, y, "(continued on the next page)", size=8, color=GREY)
    figs = [lambda: fig]
    rest, rest_c = rows[len(first):], colors[len(first):]
    per_page = rows_per_page(0.90, BOTTOM, FS)
    for i in range(0, len(rest), per_page):
        chunk, cchunk = [rows[0]] + rest[i:i + per_page], [colors[0]] + rest_c[i:i + per_page]

        def cont(chunk=chunk, cchunk=cchunk):
            f = new_figure(PORTRAIT, "Metrics against their limits (continued)",
                           f"verdict {s['verdict']} (exit code {s['exit_code']})")
            table(f, 0.92, cols, chunk, cchunk, fontsize=FS)
            return f
        figs.append(cont)
    return figs


def _page_one(data):
    s = data.summary
    verdict, code = s["verdict"], s["exit_code"]
    fig = new_figure(PORTRAIT)
    good = verdict == "PASS"
    y = 0.975
    fig.text(0.06, y, "NSD cross-validation report", ha="left", va="top", fontsize=14, weight="bold")
    fig.text(0.94, y, f"VERDICT: {verdict}", ha="right", va="top", fontsize=15, weight="bold",
             color=GREEN if good else RED)
    y = 0.952
    y = _text(fig, y, f"exit code {code}  |  {len(data.cases)} case(s) x {len(data.engines)} engine(s), reference "
                      f"{data.reference}  |  date {s.get('date', '?')}  |  git revision {s.get('git_revision', '?')}",
              size=8, color=GREY)
    if s["failures"] or not good:
        y = _text(fig, y - 0.006, "WHAT FAILED", size=11, color=RED, weight="bold")
        lines = []
        for f in s["failures"] or [f"verdict {verdict} without a listed failure"]:
            lines += wrap_width("\u2022 " + str(f), WIDTH_PT, 8.5, indent="   ")
        if len(lines) > 14:
            lines = lines[:13] + [f"   ... {len(lines) - 13} more line(s): see the metrics table below"]
        y = _text(fig, y, "\n".join(lines), size=8.5, color=RED)
    else:
        y = _text(fig, y - 0.006, "Every gated metric is within its limit and every engine ran.", size=9,
                  color=GREEN, weight="bold")
    y = _heading(fig, y - 0.004, "What was run")
    vers = s.get("versions") or {}
    engine_v = []
    for e in data.engines:
        v = vers.get(e) or vers.get("nsd-harness" if e == "semirecursive" else e, "?")
        engine_v.append(f"{e} {v}" + (" (reference)" if e == data.reference else ""))
    other = ", ".join(f"{k} {v}" for k, v in vers.items() if k not in data.engines and k not in ("nsd-harness",))
    info = [f"Engines: {', '.join(engine_v)}", f"Software: {other or '-'}",
            f"Total wall time {fmt(s.get('total_wall_time'))} s on {s.get('workers', '?')} worker process(es); "
            f"parameters: {len(s.get('params', []))} rows (next page)"]
    y = _text(fig, y, "\n".join(info), size=7.5)
    crow = [[c["name"], fmt(c["amplitude"] * 1e3), fmt(c["frequency"]), fmt(c.get("direction_deg", 0.0)),
             str(c.get("cycles", "?")), str(c.get("samples_per_cycle", "?")), _overrides(c)] for c in data.cases]
    # engine-specific: another parameter set or other solver settings for one engine (issue 11: a
    # fresh run's per-case Exudyn step was shown in black)
    ccol = [[None] * 6 + [RED if (c.get("engine_params") or any((c.get("settings") or {}).values())) else None]
            for c in data.cases]
    ccols = [("case", 15, "l"), ("A [mm]", 7, "r"), ("f [Hz]", 6, "r"), ("psi [deg]", 8, "r"), ("cycles", 6, "r"),
             ("samples\nper cycle", 8, "r"), ("overrides (engine-specific ones in red)", 50, "l")]
    ccols = natural(ccols, crow, flex=-1, fontsize=FS)
    crow, ccol, stripe = wrap_rows(ccols, crow, ccol, FS)
    y = table(fig, y - 0.006, ccols, crow, ccol, fontsize=FS, stripe=stripe)
    y = _heading(fig, y - 0.006, "Tolerances")
    units = s.get("metric_units", {})
    by_engine = s.get("tolerances_by_engine") or {}
    trow = [[m, fmt(v, 2)] + [fmt(by_engine[e].get(m), 2) if m in by_engine[e] else "" for e in by_engine]
            + [units.get(m, "-"), METRIC_DESC.get(m, "")] for m, v in s["tolerances"].items()]
    tcols = [("metric", 16, "l"), ("default" if by_engine else "limit", 8, "r")] + \
        [(e, 8, "r") for e in by_engine] + [("unit", 5, "c"), ("definition", 50, "l")]
    y = table(fig, y, natural(tcols, trow, flex=-1, fontsize=FS), trow, fontsize=FS)
    if by_engine:
        y = _text(fig, y - 0.004, "Engine columns override the default for any case; on the default cases each "
                  "engine also has its own per-case limits (3x its measured error there, never looser than the engine "
                  "column: comparisons/tolerances.toml), so every row below is judged against its own limit.",
                  size=7.0, color=GREY)
    fig._nsd_y = y
    return fig


def parameter_pages(data) -> list:
    """The parameter set with its provenance (every row), then each engine's solver settings."""
    params = data.summary.get("params") or []
    rows = [[p.get("name", ""), fmt(p.get("value")), p.get("unit", ""), p.get("source", ""), p.get("doc", "")]
            for p in params]
    cols = natural([("parameter", 21, "l"), ("value", 9, "r"), ("unit", 6, "c"), ("source", 34, "l"),
                    ("meaning", 48, "l")], rows, flex=-1, fontsize=FS)
    rows, _, stripe = wrap_rows(cols, rows, None, FS)
    settings = _settings_rows(data)
    per_page = rows_per_page(0.90, BOTTOM, FS)
    chunks, i = [], 0
    while i < len(rows):  # a page break never splits a wrapped parameter
        j = min(i + per_page, len(rows))
        while j < len(rows) and j > i + 1 and stripe[j] == stripe[j - 1]:
            j -= 1
        chunks.append((rows[i:j], stripe[i:j]))
        i = j
    chunks = chunks or [([], [])]
    figs = []
    for k, chunk in enumerate(chunks):
        def page(chunk=chunk, k=k):
            f = new_figure(PORTRAIT, "Parameter set and provenance" + (" (continued)" if k else ""),
                           "SI values used by every case (overrides: summary page); source: the paper's table,\n"
                           "or 'assumed' with the model notes that argue for the value")
            y = (table(f, 0.9, cols, chunk[0], fontsize=FS, stripe=chunk[1]) if chunk[0]
                 else _text(f, 0.9, "no parameter rows recorded"))
            last = k == len(chunks) - 1
            if last and settings and y - BOTTOM > (3 * len(settings) + 3) * LINE:
                y = _heading(f, y - 0.01, "Engine solver settings (as recorded by each engine, first case)")
                scols = natural([("engine", 12, "l"), ("settings", 88, "l")], settings, flex=1, fontsize=FS)
                srows, _, sstripe = wrap_rows(scols, settings, None, FS)
                table(f, y, scols, srows, fontsize=FS, stripe=sstripe)
            return f
        figs.append(page)
    return figs


def _settings_rows(data) -> list[list[str]]:
    rows = []
    for e in data.engines:
        for c in data.cases:
            run = data.run(c["name"], e)
            st = (run.get("stats") or {}).get("settings")
            if st:
                rows.append([e, ", ".join(f"{k}={json.dumps(v) if isinstance(v, (list, dict)) else fmt(v)}"
                                          for k, v in st.items())])
                break
    return rows
