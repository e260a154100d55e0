"""Text pages of the report, all landscape: page 1 (verdict, what failed, the case x engine matrix of
worst value / limit, the run's software and cost), what was run (every case with its path and every
seismic case with its record, window, scale and structure), the metrics' definitions and limits, the
complete metric tables (reports.metric_tables) and the parameter set. No cell is ever shortened:
columns are sized to their content and long cells wrap (docs/report.md)."""
from __future__ import annotations

import json

from comparisons.report_text import model_words, peer_models, peer_models_line
from reports.metric_tables import (SOURCES, draw_matrix, estimated, in_units, metric_rows,  # noqa: F401
                                   metric_table_pages)
from reports.rule_pages import rule_pages, tolerance_line
from reports.style import (GREEN, GREY, LANDSCAPE, RED, fit_columns, fmt, fmt_full, new_figure, rows_per_page, table,
                           wrap_rows, wrap_width)

FS = 7.0           # table font size [pt]
BOTTOM = 0.05
WIDTH_PT = 0.88 * LANDSCAPE[0] * 72  # usable text width [pt]


FOOTER_TOP = 0.045   # the page footer's top (fraction of the page height)


def _line(size: float) -> float:
    return 1.45 * size / 72 / LANDSCAPE[1]


def _text(fig, y: float, text: str, size: float = 8.0, color: str = "black", weight: str = "normal",
          x: float = 0.06) -> float:
    text = "\n".join(wrap_width(text, WIDTH_PT, size, weight == "bold", indent="   "))
    fig.text(x, y, text, ha="left", va="top", fontsize=size, color=color, weight=weight)
    return y - (text.count("\n") + 1) * _line(size)


def _height(sections: list[tuple[str, str]], size: float = 7.5) -> float:
    """The height the headed text sections take on the page."""
    lines = sum(len(wrap_width(t, WIDTH_PT, size, False, indent="   ")) for _, body in sections
                for t in body.splitlines())
    return lines * _line(size) + len(sections) * (0.018 + _line(10))


def _heading(fig, y: float, text: str) -> float:
    return _text(fig, y - 0.006, text, size=10, weight="bold") - 0.004


def summary_pages(data) -> list:
    """Page 1, what was run, the metrics' definitions, then the complete metric tables."""
    return [lambda: page_one(data)] + run_pages(data) + definitions_pages(data) + metric_table_pages(data)


def _versions(data) -> list[str]:
    s = data.summary
    vers = s.get("versions") or {}
    engine_v, models = [], peer_models(s)
    for e in data.engines:
        v = vers.get(e) or vers.get("nsd-harness" if e == "semirecursive" else e, "?")
        engine_v.append(f"{e} {v}" + (" (reference)" if e == data.reference else "")
                        + ("" if e not in models else f" ({model_words(models[e])})" if len(models[e]) == 1
                           else " (models by case: 'Peer models' above)"))
    other = ", ".join(f"{k} {v}" for k, v in vers.items() if k not in data.engines and k != "nsd-harness")
    return [f"Engines: {', '.join(engine_v)}", f"Software: {other or '-'}"]


def _cost_line(data) -> str:
    s = data.summary
    comp: dict[str, float] = {}
    for per in s["runs"].values():
        for e, r in per.items():
            if isinstance(r.get("compile_time"), (int, float)):
                comp[e] = comp.get(e, 0.0) + r["compile_time"]
    start, warm = s.get("worker_startup_time"), s.get("worker_warmup") or {}
    parts = (f" (spawn and imports {fmt(warm['spawn_s'])} s, warm-up: imports, compilation, tiny runs "
             f"{fmt(warm['warm_s'])} s)") if isinstance(warm.get("spawn_s"), (int, float)) and \
        isinstance(warm.get("warm_s"), (int, float)) else ""
    text = (f"Total wall time {fmt(s.get('total_wall_time'))} s on {s.get('workers', '?')} worker process(es); "
            f"worker start-up {fmt(start) + ' s' if start is not None else 'not recorded'}{parts}; "
            "compilation inside the runs (a tiny warm-up run before the first run of its kind, or a structure "
            "met first in a run; summed over the runs): "
            + (", ".join(f"{e} {fmt(v)} s" for e, v in comp.items()) if comp else "not recorded in this folder")
            + ". Neither is in any per-cycle or per-model-second cost.")
    return text


def page_one(data):
    s = data.summary
    verdict, code = s["verdict"], s["exit_code"]
    fig = new_figure(LANDSCAPE)
    good = verdict == "PASS"
    fig.text(0.06, 0.965, "NSD cross-validation report", ha="left", va="top", fontsize=14, weight="bold")
    fig.text(0.94, 0.965, f"VERDICT: {verdict}", ha="right", va="top", fontsize=15, weight="bold",
             color=GREEN if good else RED)
    n_seis = len(s.get("seismic_cases", []))
    y = _text(fig, 0.935, f"exit code {code}  |  {len(data.cases)} drive case(s) and {n_seis} seismic case(s) x "
              f"{len(data.engines)} engine(s), reference {data.reference}  |  date {s.get('date', '?')}  |  git revision "
              f"{s.get('git_revision', '?')}", size=8, color=GREY)
    if peer_models_line(s):   # which model each peer ran: built from the description, or a hand-written adapter
        y = _text(fig, y, peer_models_line(s).replace("peer models", "Peer models", 1), size=8, color=GREY)
    if s["failures"] or not good:
        y = _text(fig, y - 0.004, "WHAT FAILED", size=11, color=RED, weight="bold")
        lines = []
        for f in s["failures"] or [f"verdict {verdict} without a listed failure"]:
            lines += wrap_width("\u2022 " + str(f), WIDTH_PT, 8.0, indent="   ")
        if len(lines) > 8:
            lines = lines[:7] + [f"   (and {len(lines) - 7} more line(s): every failure is in the metric tables)"]
        y = _text(fig, y, "\n".join(lines), size=8.0, color=RED)
    elif estimated(s):
        y = _text(fig, y - 0.004, "Every engine agrees with the reference within its own numerical error, that error is "
                  "within the engineering tolerances, and every engine ran.", size=9, color=GREEN, weight="bold")
    else:
        y = _text(fig, y - 0.004, "Every gated metric is within the limit applied to it, and every engine ran.",
                  size=9, color=GREEN, weight="bold")
    rule = s.get("rule") or {}
    if rule.get("text"):
        y = _text(fig, y - 0.002, "What PASS means: " + rule["text"], size=8, weight="bold")
    if estimated(s):
        y = _text(fig, y, tolerance_line(s), size=7.5)
        y = _heading(fig, y - 0.004, "The verdict per case and engine")
        y = _text(fig, y, "Each cell: PASS, with the largest difference / bound and the largest error / tolerance over "
                  "the metrics; DISAGREES (a difference beyond k x the estimated numerical errors: the engines differ "
                  "about the model); NOT CONVERGED (the engine's error exceeds a tolerance at its settings, with the "
                  "step its estimate asks for); UNDECIDED (a difference beyond the bound that the engine's own runs "
                  "cannot yet call numerical or not: its estimate is over tolerance, or its companion run at another "
                  "step is within the bound; --refine decides). Every number: the metric tables; the rule: the metrics page.",
                  size=7.5, color=GREY)
    else:
        y = _heading(fig, y - 0.004, "What passed, against which limit: the worst value / limit per case and engine")
        y = _text(fig, y, "Each cell: the largest ratio of a gated metric's value to the limit applied to it, and that "
                  "metric (a ratio below 1 passes). Green: far within; yellow: near the limit; red: over it. Every "
                  "value, limit and where the limit came from: the metric tables; the definitions: the metrics page.",
                  size=7.5, color=GREY)
    y = draw_matrix(fig, y - 0.004, data)
    seis = [_seismic_line(c) for c in s.get("seismic_cases", [])]
    software = ("Software, models and cost", "\n".join(_versions(data) + [_cost_line(data)]))
    tail = ([("Seismic input (details: what was run)", "\n".join(seis))] if seis else []) + [software]
    if seis and y - _height(tail) < FOOTER_TOP:   # a long failure list: the seismic input is on 'what was run'
        y = _text(fig, y - 0.008, "(the seismic input: on the page 'What was run')", size=7.5, color=GREY)
        tail = [software]
    for head, body in tail:
        y = _heading(fig, y - 0.008, head)
        y = _text(fig, y, body, size=7.5)
    return fig


def _closed_form(g: dict) -> str:
    """A closed-form ground motion (harmonic, pulse) as its kind and parameters."""
    return f"{g.get('kind', '?')}: " + ", ".join(f"{k} = {_val(v)}" for k, v in g.items() if k not in ("kind", "source"))


def _seismic_line(c: dict) -> str:
    g = c.get("ground") or {}
    w = g.get("window") or c.get("window")
    what = (f"FEMA P695 record {g['set']} : {g['record']}, {g.get('EarthquakeName', '?')}, "
            f"{g.get('RecordingStationName', '?')}" if "set" in g else _closed_form(g))
    return (f"{c['name']}: {what}; window " + (f"{fmt_full(w[0])} to {fmt_full(w[1])} record s" if w else "whole record")
            + f", scale {fmt_full(g.get('scale', c.get('scale', 1.0)))}, rotation "
            f"{fmt_full(g.get('rotate_deg', c.get('rotate_deg', 0.0)))} deg, time factor {fmt(g.get('time_factor'), 5)}, "
            f"{fmt(c.get('model_duration', c.get('duration')), 5)} model s"
            + ("" if c.get("device", True) else ", supports alone"))


def _settings_text(settings: dict | None) -> str:
    parts = []
    for e, st in (settings or {}).items():
        if st:
            parts.append(f"{e}: " + ", ".join(f"{k} = {_val(v)}" for k, v in st.items()))
    return "; ".join(parts) or "engine defaults"


def _val(v) -> str:
    if isinstance(v, (dict, list)):
        return json.dumps(v)
    return fmt_full(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else str(v)


def _overrides(c: dict) -> str:
    parts = [f"{k} = {_val(v)}" for k, v in (c.get("params_overridden") or {}).items()]
    parts += [f"{e}: {k} = {_val(v)}" for e, p in (c.get("engine_params") or {}).items() for k, v in p.items()]
    return "; ".join(parts) or "none"


def _mm(v) -> str:
    return "none" if v is None else fmt_full(round(v * 1e3, 12))


def case_rows(data) -> tuple[list, list]:
    rows = [[c["name"], c.get("path", "line"), _mm(c["amplitude"]),
             _mm(c.get("minor", c["amplitude"] if c.get("path") == "circle" else None)),
             fmt_full(c.get("direction_deg", 0.0)), fmt_full(c["frequency"]), str(c.get("cycles", "?")),
             str(c.get("samples_per_cycle", "?")), _overrides(c), _settings_text(c.get("settings"))]
            for c in data.cases]
    cols = [("case", 1, "l"), ("path", 1, "l"), ("A [mm]", 1, "r"), ("minor axis\nB [mm]", 1, "r"),
            ("direction\npsi [deg]", 1, "r"), ("f [Hz]", 1, "r"), ("cycles", 1, "r"), ("samples\nper cycle", 1, "r"),
            ("parameters overridden", 1, "l"), ("per-engine solver settings (else the defaults)", 1, "l")]
    return cols, rows


def seismic_rows(data) -> tuple[list, list, list, list]:
    """(columns, rows) of the seismic cases' ground input, and of the structure each one carried."""
    cols = [("case", 1, "l"), ("record set : id", 1, "l"), ("event", 1, "l"), ("station", 1, "l"),
            ("window\n[record s]", 1, "l"), ("scale", 1, "r"), ("rotation\n[deg]", 1, "r"), ("time\nfactor", 1, "r"),
            ("duration\n[model s]", 1, "r"), ("output\nstep [s]", 1, "r"), ("device", 1, "c"),
            ("per-engine solver\nsettings", 1, "l")]
    rows, srows = [], []
    for c in data.summary.get("seismic_cases", []):
        g = c.get("ground") or {}
        w = g.get("window") or c.get("window")
        ident = f"{g['set']} : {g['record']}" if "set" in g else _closed_form(g)
        event = g.get("EarthquakeName", g.get("earthquake"))
        event = f"{event} ({g['EarthquakeYear']}, M {fmt_full(g.get('EarthquakeMagnitude'))})" \
            if event and "EarthquakeYear" in g else (event or g.get("source", "closed form"))
        rows.append([c["name"], ident, str(event), str(g.get("RecordingStationName", g.get("station", "-"))),
                     f"{fmt_full(w[0])} to {fmt_full(w[1])}" if w else "whole record",
                     fmt_full(g.get("scale", c.get("scale", 1.0))), fmt_full(g.get("rotate_deg", c.get("rotate_deg", 0.0))),
                     fmt(g.get("time_factor"), 5), fmt(c.get("model_duration", c.get("duration")), 5),
                     fmt_full(c.get("dt_out")), "yes" if c.get("device", True) else "no (supports alone)",
                     _settings_text(c.get("settings"))])
        st = c.get("structure_used") or {}
        prov = st.get("provenance") or {}
        for key, sym, unit in (("mass", "M", "kg"), ("stiffness", "k_b", "N/m"), ("damping", "c_b", "N s/m"),
                               ("radius_of_gyration", "r_g", "m"), ("support_radius", "r_b", "m")):
            srows.append([c["name"], f"{sym} ({key.replace('_', ' ')})", fmt(st.get(key), 5), unit,
                          str(prov.get(key, "not recorded"))])
        if isinstance(prov.get("K_dev"), dict):
            k = prov["K_dev"]
            srows.append([c["name"], "K_dev (device, most negative)", fmt(k.get("value"), 5), "N/m",
                          f"{k.get('how', '')}; along psi = {fmt_full(k.get('direction_deg'))} deg"])
    scols = [("case", 1, "l"), ("structure", 1, "l"), ("value", 1, "r"), ("unit", 1, "c"), ("provenance", 1, "l")]
    return cols, rows, scols, srows


def _table_pages(title: str, subtitle: str, blocks: list[tuple[str, list, list]]) -> list:
    """Tables (heading, columns, rows) flowed over as many landscape pages as they need."""
    prepared = []
    for head, cols, rows in blocks:
        if not rows:
            continue
        cols = fit_columns(cols, rows, fontsize=FS)
        wrapped, _, stripe = wrap_rows(cols, rows, None, FS)
        prepared.append((head, cols, wrapped, stripe))
    pages, current, room = [], [], rows_per_page(0.87, BOTTOM, FS)
    for head, cols, rows, stripe in prepared:
        i = 0
        while i < len(rows):
            need_head = 4
            take = room - need_head
            if take < 3:
                pages.append(current)
                current, room = [], rows_per_page(0.87, BOTTOM, FS)
                continue
            j = min(i + take, len(rows))
            while j < len(rows) and j > i + 1 and stripe[j] == stripe[j - 1]:  # never split a wrapped row
                j -= 1
            current.append((head + (" (continued)" if i else ""), cols, rows[i:j], stripe[i:j]))
            room -= need_head + (j - i)
            i = j
    if current:
        pages.append(current)
    figs = []
    for k, content in enumerate(pages):
        def page(content=content, k=k):
            f = new_figure(LANDSCAPE, title + (f" (part {k + 1} of {len(pages)})" if len(pages) > 1 else ""), subtitle)
            y = 0.9
            for head, cols, rows, stripe in content:
                y = _heading(f, y, head)
                y = table(f, y, cols, rows, fontsize=FS, stripe=stripe) - 0.01
            return f
        figs.append(page)
    return figs


def run_pages(data) -> list:
    """What was run: every drive case, every seismic case with its record and structure."""
    ccols, crows = case_rows(data)
    scols, srows, tcols, trows = seismic_rows(data)
    blocks = [("Drive cases: the plate's path, its size and the engines' settings", ccols, crows),
              ("Seismic cases: the ground input (FEMA P695 record, window in record seconds, scale, rotation)",
               scols, srows),
              ("Seismic cases: the isolated structure on the plate, with provenance", tcols, trows)]
    return _table_pages("What was run", "every case as the engines ran it; path minor axis B: the circle's radius, "
                        "the ellipse's or figure eight's minor semi-axis (none for a line); time factor: model "
                        "seconds per record second", blocks)


def _head(name: str, chars: int = 11) -> str:
    """A metric name as a column header, broken before underscores into lines of about ``chars``."""
    lines = [""]
    for i, tok in enumerate(name.split("_")):
        part = ("_" if i else "") + tok
        if lines[-1] and len(lines[-1]) + len(part) > chars:
            lines.append(part)
        else:
            lines[-1] += part
    return "\n".join(lines)


def definitions_pages(data) -> list:
    """Every metric with unit, definition, default and engine limits; then the case limits as a
    table of (engine, case) rows against the metrics they set."""
    s = data.summary
    defs = s.get("metric_definitions")
    if not defs:
        from comparisons.config import METRICS
        defs = {k: v[1] for k, v in METRICS.items()}
    units = s.get("metric_units", {})
    if estimated(s):
        return rule_pages(s, defs, units, _table_pages, _metrics_subtitle)
    by_engine = s.get("tolerances_by_engine") or {}
    rows = []
    for m, v in s["tolerances"].items():
        per = [f"{e} {fmt_full(t[m])}" for e, t in by_engine.items() if m in t]
        rows.append([m, units.get(m, "-"), defs.get(m, "not defined in this results folder"), fmt_full(v),
                     "; ".join(per) or "-"])
    cols = [("metric", 1, "l"), ("unit", 1, "c"), ("definition (F_ref, u_ref: the reference engine's)", 1, "l"),
            ("default\nlimit", 1, "r"), ("engine limits (override the default)", 1, "l")]
    blocks = [("Metrics and their default and engine limits", cols, rows)]
    metrics = [m for m in s["tolerances"] if any(m in (t or {}) for et in by_engine.values()
                                                  for t in (et.get("case") or {}).values())]
    per_block = 7  # metric columns per table: more would not fit the page's width with their headers whole
    groups = [metrics[i:i + per_block] for i in range(0, len(metrics), per_block)]
    for n, group in enumerate(groups, start=1):
        crows = [[e, c] + [fmt_full(t[m]) if m in t else "" for m in group]
                 for e, et in by_engine.items() for c, t in (et.get("case") or {}).items()
                 if any(m in t for m in group)]
        part = f", part {n} of {len(groups)}" if len(groups) > 1 else ""
        if crows:
            blocks.append((f"Case limits (override the engine's and the default on that case; blank: not set{part})",
                           [("engine", 1, "l"), ("case", 1, "l")] + [(_head(m), 1, "r") for m in group], crows))
    sub = _metrics_subtitle(s, "; the most specific limit wins (case, then engine, then default)",
                            "taken from the default tolerance file")
    return _table_pages("Metrics: definitions and limits", sub, blocks)


def _metrics_subtitle(s: dict, rule: str, defaulted_from: str) -> str:
    """Where the metrics are taken, and which values the given file left to the defaults."""
    sub = ("drive cases on the steady (last) cycle resampled on a common phase grid; seismic cases on the time "
           "histories at every output time" + rule)
    defaulted = s.get("tolerances_defaulted") or []
    if defaulted:
        sub += f"\n{defaulted_from} (the given file left them out): " + ", ".join(defaulted)
    return sub


def parameter_pages(data) -> list:
    """The parameter set at full precision with its provenance, then each engine's solver settings."""
    params = data.summary.get("params") or []
    rows = [[p.get("name", ""), fmt_full(p.get("value")) if p.get("value") is not None else "none",
             p.get("unit", ""), p.get("source", ""), p.get("doc", "")] for p in params]
    cols = [("parameter", 1, "l"), ("value", 1, "r"), ("unit", 1, "c"), ("source", 1, "l"), ("meaning", 1, "l")]
    blocks = [("Parameters (SI)", cols, rows)]
    settings = _settings_rows(data)
    if settings:
        blocks.append(("Engine solver settings (as recorded by each engine, first case)",
                       [("engine", 1, "l"), ("settings", 1, "l")], settings))
    return _table_pages("Parameter set and provenance", "SI values used by every case at full precision (overrides: "
                        "what was run); source: the paper's table, or 'assumed' with the model notes that argue "
                        "for the value", blocks)


def _settings_rows(data) -> list[list[str]]:
    rows = []
    for e in data.engines:
        for c in data.cases:
            st = (data.run(c["name"], e).get("stats") or {}).get("settings")
            if st:
                rows.append([e, ", ".join(f"{k} = {_val(v)}" for k, v in st.items())])
                break
    return rows
