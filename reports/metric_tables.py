"""The gate's numbers on the page: the case x engine matrix of the worst
value / limit ratio, and the complete metric table, one row per (case, engine, compared with, metric)
with the value in full, the limit that was applied to it and where that limit came from.

Values and limits are written with ``fmt_full`` (the shortest text that reads back as the same
double): nothing on these pages is rounded away or shortened."""
from __future__ import annotations

import matplotlib

from comparisons.verdict import row_word
from reports.style import GREEN, GREY, LANDSCAPE, ORANGE, RED, fmt, fmt_full, natural, new_figure, rows_per_page, table

FS = 7.0
SOURCES = {"default": "default ([limits])", "engine": "engine ([limits.ENGINE])",
           "case": "case ([limits.ENGINE.case])"}


def limit_source(summary: dict, row: dict) -> str:
    """default / engine / case: recorded by nsd compare (``limit_source``); for a results.json written
    before it was recorded, found the way the gate looks limits up (the most specific that equals)."""
    if row.get("limit_source"):
        return row["limit_source"]
    own = (summary.get("tolerances_by_engine") or {}).get(row["engine"], {})
    m, lim = row["metric"], row.get("limit")
    if m in (own.get("case") or {}).get(row["case"], {}) and own["case"][row["case"]][m] == lim:
        return "case"
    if m in own and own[m] == lim:
        return "engine"
    return "default"


def ratio(row: dict) -> float | None:
    lim = row.get("limit")
    return row["value"] / lim if lim else None


def _order(summary: dict):
    engines = summary.get("engines", [])
    metrics = list(summary.get("tolerances", {}))
    cases = [c["name"] for c in summary.get("cases", [])] + [c["name"] for c in summary.get("seismic_cases", [])]

    def key(r):
        return (cases.index(r["case"]) if r["case"] in cases else len(cases), r["case"],
                engines.index(r["engine"]) if r["engine"] in engines else 99, r.get("reference") is not None,
                not r.get("gated"), str(r.get("reference")), metrics.index(r["metric"]) if r["metric"] in metrics else 99, r["metric"])
    return key


def result_text(row: dict) -> tuple[str, str | None]:
    if row["gated"]:
        return ("PASS", GREEN) if row["pass"] else ("FAIL", RED)
    return ("within (not gated)", None) if row["pass"] else ("over (not gated)", ORANGE)


COLUMNS = [("case", "l"), ("engine", "l"), ("compared with", "l"), ("metric", "l"), ("unit", "c"),
           ("value (in full)", "r"), ("applied limit", "r"), ("limit from", "l"), ("value /\nlimit", "r"),
           ("result", "l")]


EST_COLUMNS = [("case", "l"), ("engine", "l"), ("vs", "l"), ("metric", "l"), ("difference (in full)", "r"),
               ("estimated error (in full)", "r"), ("bound k x\n(est. + ref.)", "r"), ("tolerance\n(in units)", "r"),
               ("result", "l")]


def estimated(summary: dict) -> bool:
    """The results were judged by the estimated rule (comparisons/verdict.py), not by fixed limits."""
    return (summary.get("rule") or {}).get("name") == "estimated"


def in_units(tol, unit) -> str:
    if tol is None or unit is None:
        return "-"
    return f"{tol * 1e3:.3g} mm" if unit == "m" else f"{tol:.3g} {unit}"


def _est_result(r: dict) -> tuple[str, str | None]:
    if not r["gated"]:
        return ("ok (not gated)", None) if r["pass"] else ("over (not gated)", ORANGE)
    if r.get("consistent") is False:
        return row_word(r), RED
    if not r.get("accurate", True):
        return "NOT CONVERGED", RED
    return "PASS", GREEN


def estimated_rows(data) -> tuple[list, list[list[str]], list[list]]:
    """The metric table under the estimated rule: the difference from the converged reference, the
    engine's estimated error, the reference's, the bound, the engineering tolerance in units."""
    s = data.summary
    rows, colors = [], []
    for r in sorted(s["metrics"], key=_order(s)):
        res, col = _est_result(r)
        b = r.get("bound")
        tol = fmt(r.get("tolerance"), 2) + (f" ({in_units(r['tolerance_abs'], r.get('unit'))})"
                                              if r.get("tolerance_abs") is not None else "")
        rows.append([r["case"], r["engine"], r.get("reference") or "(own)", r["metric"], fmt_full(r["value"]),
                     fmt_full(r.get("estimate")) if r.get("estimate") is not None else "-",
                     fmt(b, 3) if b is not None else "-", tol, res])
        colors.append([None] * 4 + [col if col == RED and r.get("consistent") is False else None] + [None] * 3 + [col])
    for case, per in s["runs"].items():
        for engine, run in per.items():
            if run.get("status") != "ok":
                rows.append([case, engine, "-", "the run failed"] + [""] * 4 + ["ERROR"])
                colors.append([RED] * len(EST_COLUMNS))
    cols = natural([(h, 10, a) for h, a in EST_COLUMNS], rows, flex=-1, fontsize=FS)
    return cols, rows, colors


def metric_rows(data) -> tuple[list, list[list[str]], list[list]]:
    """(columns, rows, colours) of the complete metric table; failed runs add an ERROR row."""
    s = data.summary
    if estimated(s):
        return estimated_rows(data)
    units = s.get("metric_units", {})
    rows, colors = [], []
    for r in sorted(s["metrics"], key=_order(s)):
        res, col = result_text(r)
        q = ratio(r)
        rows.append([r["case"], r["engine"], r.get("reference") or "(own check)", r["metric"], units.get(r["metric"], "-"),
                     fmt_full(r["value"]), fmt_full(r.get("limit")), limit_source(s, r),
                     fmt(q, 3) if q is not None else "-", res])
        colors.append([None] * 5 + [RED if col == RED else None, None, None, col, col])
    for case, per in s["runs"].items():
        for engine, run in per.items():
            if run.get("status") != "ok":
                rows.append([case, engine, "-", "the run failed", "", "", "", "", "", "ERROR"])
                colors.append([RED] * len(COLUMNS))
    cols = natural([(h, 10, a) for h, a in COLUMNS], rows, flex=-1, fontsize=FS)
    return cols, rows, colors


def metric_table_pages(data) -> list:
    """The complete table over as many landscape pages as it needs (never a shortened cell)."""
    s = data.summary
    cols, rows, colors = metric_rows(data)
    per_page = rows_per_page(0.855, 0.065, FS)
    chunks = [(rows[i:i + per_page], colors[i:i + per_page]) for i in range(0, len(rows), per_page)] or [([], [])]
    figs = []
    for k, (chunk, cchunk) in enumerate(chunks):
        def page(chunk=chunk, cchunk=cchunk, k=k):
            part = f" (part {k + 1} of {len(chunks)})" if len(chunks) > 1 else ""
            if estimated(s):
                f = new_figure(LANDSCAPE, "Metrics: differences against the engines' own error estimates" + part,
                               f"consistent: difference from the converged reference <= bound = k x (estimated error "
                               f"+ reference's), k = {s['rule'].get('k', '?')}, else DISAGREES; accurate enough: "
                               "max(estimated error, difference) <= engineering tolerance, else NOT CONVERGED; "
                               "UNDECIDED: beyond the bound, but the estimate is over tolerance or the companion run "
                               "is within the bound;\n"
                               "(own): the engine's own check against the tolerance; not gated: two engines "
                               "compared, reported only; differences, estimates and bounds in full")
            else:
                f = new_figure(LANDSCAPE, "Metrics against the limits applied to them" + part,
                               "the value in full and the limit applied to it; limit from: default = [limits], engine = "
                               "[limits.ENGINE], case = [limits.ENGINE.case] of the tolerance file; (own check): an "
                               "engine's own bound; not gated: two peers compared, reported only")
            f.text(0.985, 0.99, f"verdict {s['verdict']}\n(exit code {s['exit_code']})", ha="right", va="top",
                   fontsize=8, color=GREEN if s["verdict"] == "PASS" else RED, weight="bold")
            if chunk:
                table(f, 0.86, cols, chunk, cchunk, fontsize=FS)
            else:
                f.text(0.06, 0.85, "no metric was measured", fontsize=9, color=RED)
            return f
        figs.append(page)
    return figs


def worst_cells(summary: dict) -> dict[tuple[str, str], dict]:
    """(case, engine) -> the gated row with the largest value / limit (own checks and against the
    reference both count)."""
    out: dict[tuple[str, str], dict] = {}
    for r in summary["metrics"]:
        if not r.get("gated") or not r.get("limit"):
            continue
        k = (r["case"], r["engine"])
        if k not in out or ratio(r) > ratio(out[k]):
            out[k] = r
    return out


def verdict_cell(s: dict, case: str, engine: str, v: dict) -> tuple[str, float]:
    """A cell of the matrix under the estimated rule: the verdict in words and the larger of the two
    ratios (difference / bound, error / tolerance) that shades it."""
    rows = [r for r in s["metrics"] if r["case"] == case and r["engine"] == engine and r["gated"]]
    agree = max((r["value"] / r["bound"] for r in rows if r.get("bound")), default=0.0)
    acc = max((max(r.get("estimate") or 0.0, r["value"]) / r["tolerance"] for r in rows if r.get("tolerance")),
              default=0.0)
    if v.get("consistent") is False:
        w = v.get("worst_consistency") or {}
        return f"DISAGREES {w.get('metric', '')} {fmt(w.get('ratio'), 3)}x bound", 2.0
    if v.get("consistent") is None and v.get("undecided"):
        w = v["undecided"]
        return f"UNDECIDED {w.get('metric', '')} {fmt(w.get('ratio'), 3)}x bound (--refine)", 2.0
    if not v["pass"]:
        need = v.get("needs") or {}
        tail = "".join(f" (rtol <= {fmt(x, 2)})" if k == "rtol" else f" (h <= {fmt(x, 2)} s)" for k, x in need.items())
        return f"NOT CONVERGED{tail}", 2.0
    return f"PASS  {fmt(agree, 2)} of bound, {fmt(acc, 2)} of tol", max(agree, acc)


def _shade(q: float) -> str:
    if q > 1.0:
        return "#f4b6b6"
    cmap = matplotlib.colors.LinearSegmentedColormap.from_list("ok", ["#d9f0d3", "#fff2b3"])
    return matplotlib.colors.to_hex(cmap(min(q, 1.0)))


def draw_matrix(fig, top: float, data, left: float = 0.06, right: float = 0.94, fs: float = 7.5) -> float:
    """The case x engine matrix: in each cell the worst value / limit ratio and the metric that gave
    it, shaded green (far within) to yellow (at the limit), red over it. Returns the y below."""
    s = data.summary
    cases = [c["name"] for c in s.get("cases", [])] + [c["name"] for c in s.get("seismic_cases", [])]
    engines = data.engines
    worst = worst_cells(s)
    h_in = fig.get_size_inches()[1]
    row_h = 2.5 * fs / 72 / h_in
    first = max(0.16, min(0.3, 0.012 * max(len(c) for c in cases + ["case"])))
    width = (right - left - first) / max(len(engines), 1)
    Rect = matplotlib.patches.Rectangle
    y = top
    fig.patches.append(Rect((left, y - row_h), right - left, row_h, transform=fig.transFigure, facecolor="#e6e6e6",
                            edgecolor="none", zorder=0))
    fig.text(left + 0.004, y - row_h / 2, "case \\ engine", va="center", fontsize=fs, weight="bold")
    for j, e in enumerate(engines):
        label = e + (" (reference: own checks)" if e == data.reference else " (vs reference + own checks)")
        fig.text(left + first + (j + 0.5) * width, y - row_h / 2, label, ha="center", va="center", fontsize=fs,
                 weight="bold")
    y -= row_h
    for case in cases:
        fig.text(left + 0.004, y - row_h / 2, case, va="center", fontsize=fs)
        for j, e in enumerate(engines):
            x0 = left + first + j * width
            run = s["runs"].get(case, {}).get(e, {})
            r = worst.get((case, e))
            v = (s.get("verdicts") or {}).get(case, {}).get(e)
            if run.get("status") not in (None, "ok"):
                text, face, color = "ERROR: the run failed", "#f4b6b6", RED
            elif v is not None:
                text, q = verdict_cell(s, case, e, v)
                face, color = _shade(q), (RED if not v["pass"] else "black")
            elif r is None:
                text, face, color = "no gated metric", "white", GREY
            else:
                q = ratio(r)
                text = f"{fmt(q, 3)}  {r['metric']}" + ("  FAIL" if q > 1 else "")
                face, color = _shade(q), RED if q > 1 else "black"
            fig.patches.append(Rect((x0 + 0.002, y - row_h + 0.002), width - 0.004, row_h - 0.004,
                                    transform=fig.transFigure, facecolor=face, edgecolor="white", zorder=0))
            fig.text(x0 + width / 2, y - row_h / 2, text, ha="center", va="center", fontsize=fs, color=color,
                     weight="bold" if color == RED else "normal")
        y -= row_h
    return y
