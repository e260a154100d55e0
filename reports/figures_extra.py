"""Run-level figures: convergence, cost (wall time and speed-accuracy), and the optional extra
pages (closed-loop benchmarks, parametric study) when the results folder holds them."""
from __future__ import annotations

import math
import re
import textwrap

import matplotlib
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.ticker import LogLocator, NullFormatter

from reports.style import GREEN, GREY, LANDSCAPE, RED, color, fmt, limit_lines, new_figure, no_data, style, table

SETTING_UNITS = {"rtol": "-", "atol": "-", "timestep": "s", "step_size": "s", "max_step": "s",
                 "solver_tolerance": "-", "newton_rel_tol": "-"}
FLOOR = 1e-16  # relative discrepancies of exactly zero are drawn here on log axes
MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*"]
GOALS = {"andrews": "\u2265 8 correct digits", "A04": "drift \u2264 1e-3 J, cuts \u2264 1e-6 m",
         "A02": "error, drift \u2264 1e-3", "slider_crank": "error \u2264 1e-10"}


def _setting_label(name: str) -> str:
    unit = SETTING_UNITS.get(name)
    return f"{name} [{unit}]" if unit else f"{name} [as set in the engine]"


def convergence_figure(data):
    conv = data.summary.get("convergence")
    fig = new_figure(LANDSCAPE, "Convergence: discrepancy against step size or solver tolerance",
                     "each engine's steady cycle against a tight in-house reference, as its setting is refined "
                     "(log-log); a discrepancy that falls with the setting is numerical error, a plateau is a floor")
    if not isinstance(conv, dict) or not conv or "error" in conv:
        why = (f"The convergence study failed: {conv['error']}" if isinstance(conv, dict) and "error" in conv
               else "This results folder has no convergence study.")
        how = ("To produce one, add a [convergence] table to the case file (case = a case of the file, cycles, "
               "reference = semirecursive settings, and [convergence.sweep] with setting and values per engine; "
               "comparisons/cases.toml has an example) and run:  nsd compare --cases FILE --convergence --out DIR")
        fig.text(0.5, 0.6, why, ha="center", va="center", fontsize=12, color=RED if "failed" in why else "black")
        fig.text(0.5, 0.5, "\n".join(textwrap.wrap(how, 110)), ha="center", va="top", fontsize=9.5)
        return fig
    engines = [e for e in data.engines if e in conv] + [e for e in conv if e not in data.engines]
    cols = max(len(engines), 1)
    # the engines side by side, the cost panel across the whole row beneath (no empty cells)
    gs = fig.add_gridspec(2, cols, left=0.07, right=0.78, top=0.84, bottom=0.08, hspace=0.4, wspace=0.28)
    tol = data.summary["tolerances"]
    leg = [Line2D([], [], color="k", marker="o", ls="-", label="max |dF| / max |F_ref|"),
           Line2D([], [], color="k", marker="s", ls="--", mfc="none", label="|loop area - ref| / ref"),
]
    fig.legend(handles=leg, loc="upper center", bbox_to_anchor=(0.5, 0.925), ncol=2, frameon=False, fontsize=8.5)
    speed = fig.add_subplot(gs[1, :])
    for i, e in enumerate(engines):
        ax = fig.add_subplot(gs[0, i])
        entry = conv[e]
        pts = [p for p in entry.get("points", []) if "error" not in p]
        bad = [p for p in entry.get("points", []) if "error" in p]
        if not pts:
            no_data(ax, f"{e}: no converged point" + (f" ({bad[0]['error']})" if bad else ""))
            continue
        v = np.array([p["value"] for p in pts], float)
        d1 = np.maximum([p["max_dF_rel"] for p in pts], FLOOR)
        d2 = np.maximum([p["loop_area_rel"] for p in pts], FLOOR)
        c = color(e)
        ax.loglog(v, d1, "o-", color=c, lw=1.4)
        ax.loglog(v, d2, "s--", color=c, mfc="none", lw=1.1)
        if e != data.reference:   # each limit line named in its panel
            limit_lines(ax, {k: (_engine_limits(data, k).get(e, tol.get(k)), GREY)
                             for k in ("max_dF_rel", "loop_area_rel")}, x=0.02, ha="left")
        if bad:
            ax.text(0.02, 0.02, "failed at " + ", ".join(fmt(p["value"]) for p in bad), transform=ax.transAxes,
                    fontsize=7, color=RED)
        ax.set_title(f"{e}: {entry.get('setting', '?')} (case {entry.get('case', '?')})", fontsize=9, color=c)
        ax.set_xlabel(_setting_label(entry.get("setting", "?")))
        ax.set_ylabel("relative discrepancy [-]")
        _log_ticks(ax, v)
        ax.yaxis.set_minor_formatter(NullFormatter())   # minor labels crowd a short decade
        w = np.array([p.get("wall_time", np.nan) for p in pts], float)
        ok = np.isfinite(w) & (w > 0)
        # points, not a line: cost is not monotone in the setting, a line in setting order zig-zags
        # in setting order, joined by a thin line; the coarsest setting ringed (labels would pile up)
        order = np.argsort(v[ok])[::-1]
        speed.loglog(w[ok][order], d1[ok][order], "o-", color=c, ms=5, lw=0.7,
                     label=f"{e}: {entry.get('setting', '?')} {fmt(v[ok].max())} to {fmt(v[ok].min())}")
        if ok.any():
            speed.loglog([w[ok][order][0]], [d1[ok][order][0]], "o", ms=11, mfc="none", mec=c, mew=1.0)
    ref = next((conv[e].get("reference") for e in engines if conv[e].get("reference")), "")
    speed.set_title("max |dF| against cost (warm: compilation timed apart)", fontsize=9)
    speed.set_xlabel("warm wall time per cycle [s]")
    speed.xaxis.set_minor_formatter(NullFormatter())
    speed.set_ylabel("max |dF| / max |F_ref| [-]")
    speed.set_yscale("log")
    limit_lines(speed, {e: (lim, color(e) if e in engines else GREY)
                        for e, lim in _engine_limits(data, "max_dF_rel").items()}, x=1.005, ha="left")
    if speed.lines:
        speed.legend(fontsize=7, title="ringed: the coarsest setting", title_fontsize=7, loc="upper left",
                     bbox_to_anchor=(1.01, 0.75), frameon=False)
    fig.text(0.5, 0.895, f"reference run: {_plain(ref)}", ha="center", va="top", fontsize=8, color=GREY)
    return fig


def _plain(ref) -> str:
    """'semirecursive {'rtol': 1e-10}' -> 'semirecursive, rtol = 1e-10' (no Python syntax on a page)."""
    text = str(ref)
    for k, v in re.findall(r"'(\w+)': ([^,}]+)", text):
        text = text.replace(f"'{k}': {v}", f"{k} = {v}")
    return text.replace(" {", ", ").replace("{", "").replace("}", "")


def _log_ticks(ax, values) -> None:
    """Label the sampled settings themselves when they span less than two decades (a log axis
    would otherwise show a single labelled tick)."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v) & (v > 0)]
    if v.size and np.log10(v.max() / v.min()) < 2:
        ax.set_xticks(sorted(set(v)), [fmt(x) for x in sorted(set(v))], fontsize=6.5, rotation=40, ha="right",
                      rotation_mode="anchor")
    ax.xaxis.set_minor_formatter(NullFormatter())


def _per_unit(run: dict, key: str, model_time: float | None) -> float | None:
    """A run's warm cost per cycle or per model second: wall (``wall_time``) or CPU (``cpu_time``)."""
    if run.get("status") != "ok" or not model_time:
        return None
    v = run.get(key) if key == "cpu_time" else run.get("wall_time", None)
    if key == "wall_time" and isinstance((run.get("stats") or {}).get("wall_time"), (int, float)):
        v = run["stats"]["wall_time"]
    if key == "cpu_time" and v is None:
        v = (run.get("stats") or {}).get("cpu_time")
    return v / model_time if isinstance(v, (int, float)) else None


def cost_rows(data) -> list[list[str]]:
    """Per case: each engine's wall and CPU seconds per cycle (drive) or per model second (seismic),
    and its compilation, recorded apart."""
    rows = []
    cases = [(c["name"], c.get("cycles"), "cycle") for c in data.cases]
    cases += [(c["name"], c.get("model_duration", c.get("duration")), "model s")
              for c in data.summary.get("seismic_cases", [])]
    for name, per, unit in cases:
        row = [name, f"per {unit}"]
        for e in data.engines:
            run = data.run(name, e)
            w, c = _per_unit(run, "wall_time", per), _per_unit(run, "cpu_time", per)
            comp = run.get("compile_time", (run.get("stats") or {}).get("compile_time"))
            row.append("failed" if run.get("status") != "ok" else
                       f"{fmt(w)} / {fmt(c) if c is not None else 'n/a'}  (compile {fmt(comp) if comp is not None else 'n/a'})")
        rows.append(row)
    return rows


def cost_figure(data):
    names = [c.get("name") for c in [*data.cases, *(data.summary.get("seismic_cases") or [])] if isinstance(c, dict)]
    runs = [data.summary["runs"].get(n) for n in names if isinstance(n, str)]
    stats = [p[data.reference].get("stats") for p in runs
             if isinstance(p, dict) and isinstance(p.get(data.reference), dict)]
    used = sorted({s.get("evaluation") for s in stats if isinstance(s, dict)} & {"generated", "generic"})
    evaluation = f"; the {data.reference} runs used the {' and the '.join(used)} evaluation" if used else ""
    fig = new_figure(LANDSCAPE, "Cost: warm wall and CPU time per cycle, and accuracy against cost",
                     "integration only: compilation (a tiny warm-up run in each worker) and the workers' start-up are "
                     "timed apart and never counted; engines ran in parallel worker processes on a shared machine"
                     + evaluation + " (NSD_EVALUATOR, docs/engine-codegen.md)" * bool(used))
    many = len(data.cases) > 6
    gs = fig.add_gridspec(1, 2, left=0.07, right=0.88, top=0.86, bottom=0.5 if many else 0.42, wspace=0.25,
                          width_ratios=[1.15, 1])
    ax = fig.add_subplot(gs[0])
    names = [c["name"] for c in data.cases]
    _cost_bars(ax, data, names)
    rows = cost_rows(data)
    cols = [("case", 16, "l"), ("cost", 7, "l")] + [(f"{e}: wall / CPU [s]", 25, "l") for e in data.engines]
    table(fig, 0.33 if many else 0.27, cols, rows, None, fontsize=7)
    sp = fig.add_subplot(gs[1])
    if not names:   # seismic cases only: their costs are in the table
        for a in (ax, sp):
            a.clear()
            no_data(a, "no drive case in this run: the seismic cases' costs per model second are in the table")
        return fig
    _speed_accuracy(sp, data, names)
    return fig


def _cost_bars(ax, data, names) -> None:
    """The cost panel: warm wall time per cycle (bars, "failed" where none) and CPU time (black ticks)."""
    ne = len(data.engines)
    width = 0.8 / max(ne, 1)
    x = np.arange(len(names))
    vals, cpu_shown = [], False
    for j, e in enumerate(data.engines):
        w = [_per_unit(data.run(n, e), "wall_time", c.get("cycles")) for n, c in zip(names, data.cases)]
        cpu = [_per_unit(data.run(n, e), "cpu_time", c.get("cycles")) for n, c in zip(names, data.cases)]
        h = [v if v else 0.0 for v in w]
        xx = x + (j - (ne - 1) / 2) * width
        ax.bar(xx, h, width * 0.92, color=color(e), label=f"{e}: wall")
        ok = [k for k, v in enumerate(cpu) if v]
        if ok:
            ax.plot(xx[ok], [cpu[k] for k in ok], "_", color="k", ms=9, mew=1.6,
                    label=None if cpu_shown else "CPU time (each engine)")
            cpu_shown = True
        vals += [v for v in w if v] + [v for v in cpu if v]
        for xi, v in zip(xx, w):
            if not v:
                ax.text(xi, 0.0, "failed", ha="center", va="bottom", fontsize=6.5, rotation=90, color=RED)
    if vals and max(vals) / max(min(vals), 1e-12) > 30:
        ax.set_yscale("log")
        ax.set_ylim(min(vals) / 3, max(vals) * 6)
    elif vals:
        ax.set_ylim(0, max(vals) * 1.3)
    if len(names) <= 2:
        ax.set_xlim(-1.0, len(names))  # keep single bars from filling the panel
    ax.set_xticks(x, names, rotation=90 if len(names) > 2 else 0, fontsize=6.5)
    ax.set_ylabel("seconds per cycle [s]")
    ax.set_title("warm wall time per cycle (bars) and CPU time (black ticks)", fontsize=9)
    ax.legend(fontsize=7, loc="upper left", ncol=2)
    ax.grid(axis="x", visible=False)


def _speed_accuracy(sp, data, names) -> None:
    """The speed-accuracy panel: max_dF_rel over warm wall time per cycle, the convergence study, the limits."""
    ref = data.reference
    marks = {n: MARKERS[i] if len(names) <= len(MARKERS) else "o" for i, n in enumerate(names)}
    for m in data.summary["metrics"]:
        if m.get("metric") == "max_dF_rel" and m.get("reference") == ref and m["case"] in names:
            w = _per_unit(data.run(m["case"], m["engine"]), "wall_time", next(
                c.get("cycles") for c in data.cases if c["name"] == m["case"]))
            if w:
                sp.loglog([w], [max(m["value"], FLOOR)], marks.get(m["case"], "o"), color=color(m["engine"]), ms=7,
                          mec="k", mew=0.5)
    conv = data.summary.get("convergence")
    if isinstance(conv, dict) and "error" not in conv:
        for e, entry in conv.items():
            pts = [p for p in entry.get("points", []) if "error" not in p and p.get("wall_time")]
            if pts:
                sp.loglog([p["wall_time"] for p in pts], [max(p["max_dF_rel"], FLOOR) for p in pts], ":",
                          color=color(e), marker=".", lw=1.0)
    lims = _engine_limits(data, "max_dF_rel")
    sp.set_yscale("log")
    limit_lines(sp, {(e if e in data.engines else "the"): (lim, color(e) if e in data.engines else RED)
                     for e, lim in lims.items()}, x=0.02, ha="left")
    if not sp.lines:
        no_data(sp, "no engine besides the reference ran: nothing to compare")
    else:
        sp.margins(x=0.15, y=0.15)
        _log_axis_125(sp.xaxis, sp.set_xlim, *sp.get_xlim())
    sp.set_xlabel("warm wall time per cycle [s]")
    sp.set_ylabel(f"max |F - F_ref| / max |F_ref| [-] (vs {ref})")
    sp.set_title("speed-accuracy", fontsize=9)
    handles = [Line2D([], [], ls="", marker=marks[n], color="w", mec="k", mfc=GREY, label=n) for n in names
               if len(names) <= len(MARKERS)]  # more cases than markers: one point per case, unlabelled
    handles += [Line2D([], [], ls="", marker="o", color=color(e), label=e) for e in data.engines if e != ref]
    if isinstance(conv, dict) and conv and "error" not in conv:
        handles.append(Line2D([], [], color=GREY, ls=":", marker=".", label="convergence study"))
    # below the panel, clear of the points and the limit lines
    sp.legend(handles=handles, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.15), ncol=4, frameon=False)


def _log_axis_125(axis, set_lim, lo: float, hi: float) -> None:
    """A log axis with labelled ticks at 1, 2 and 5 x 10^k, its view widened to the nearest of them on
    each side (so at least two lie in view) and minor ticks unlabelled. Left alone, matplotlib before
    3.11 falls back on a view under a decade to linear ticks 0.02 x 10^k apart, each labelled: the
    labels (1.8e-1 and 2e-1, 4.5e-2 and 5e-2) overlap."""
    if not (0 < lo < hi and math.isfinite(hi)):
        return
    steps = (1.0, 2.0, 5.0, 10.0)

    def nice(v, pick):
        k = math.floor(math.log10(v))
        return pick(c for c in steps if (c <= v / 10 ** k * (1 + 1e-12) if pick is max else
                                          c >= v / 10 ** k * (1 - 1e-12))) * 10 ** k
    set_lim(nice(lo, max), nice(hi, min))
    axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0), numticks=12))
    axis.set_minor_formatter(NullFormatter())


def _engine_limits(data, metric: str) -> dict:
    """The limit each engine's points are judged by: its own default where the tolerance file gives
    per-engine limits (results.json "tolerances_by_engine"), else the one global limit."""
    by_engine = data.summary.get("tolerances_by_engine") or {}
    own = {e: by_engine[e][metric] for e in data.engines if e != data.reference and metric in by_engine.get(e, {})}
    if own:
        return own
    lim = data.summary["tolerances"].get(metric)
    return {"all": lim} if lim else {}


def benchmark_figure(data):
    b = data.benchmark
    probs = b.get("problems", {})
    ok = all(bool(p.get("passed")) for p in probs.values())
    fig = new_figure(LANDSCAPE, "Closed-loop multibody benchmarks (generic semirecursive engine)",
                     f"nsd benchmark{' --quick' if b.get('quick') else ''}: every problem against its published "
                     f"reference; {'all goals met' if ok else 'SOME GOALS NOT MET'}")
    rows, colors = [], []
    for name, p in probs.items():
        err = p.get("error")
        digits = -np.log10(max(err, 1e-16)) if isinstance(err, (int, float)) and err > 0 else None
        if "min_digits" in p:
            digits = p["min_digits"]
        extra = []
        if "energy_drift" in p:
            extra.append(f"energy drift {fmt(p['energy_drift'], 2)} J")
        if "closure_max" in p:
            extra.append(f"closure {fmt(p['closure_max'], 2)}")
        goal = GOALS.get(name, f"error \u2264 {fmt(p['goal'])}" if "goal" in p else "-")
        rows.append([name, fmt(err, 3), fmt(digits, 3) if digits is not None else "-",
                     fmt(p.get("cpu_time", p.get("wall_time")), 3), goal, "; ".join(extra) or "-",
                     "yes" if p.get("passed") else "NO"])
        colors.append([None] * 6 + [GREEN if p.get("passed") else RED])
    y = table(fig, 0.9, [("problem", 12, "l"), ("error vs reference", 13, "r"), ("digits", 7, "r"),
                         ("wall time [s]", 10, "r"), ("goal", 20, "l"), ("also", 32, "l"), ("met", 5, "c")], rows,
              colors, fontsize=8)
    wp = probs.get("andrews", {}).get("work_precision") or []
    ax = fig.add_axes([0.1, 0.09, 0.55, max(y - 0.17, 0.2)])
    if wp:
        t = [r["wall_time"] for r in wp]
        d = [r["min_digits"] for r in wp]
        ax.semilogx(t, d, "o-", **{k: v for k, v in style("semirecursive").items() if k != "linestyle"})
        for r in wp:
            ax.annotate(f"rtol {r['rtol']:.0e}", (r["wall_time"], r["min_digits"]), textcoords="offset points",
                        xytext=(6, -10), fontsize=7)
        ax.axhline(8.0, color=GREY, ls=":", lw=1.0)
        ax.margins(x=0.12, y=0.1)
        ax.set_title(f"Andrews' squeezing mechanism: work-precision ({wp[0].get('method', '')}, t = 0.03 s)",
                     fontsize=9)
    else:
        no_data(ax, "no Andrews work-precision data in benchmark/results.json")
    ax.set_xlabel("wall time [s]")
    ax.set_ylabel("correct digits, min over the 7 angles [-]")
    fig.text(0.7, 0.3, "dotted: the goal of 8 correct digits\n(Hairer & Wanner test set reference)", fontsize=8,
             color=GREY, va="center")
    return fig


def study_figure(data, s: dict):
    summ = s["summary"]
    param = summ.get("parameter", s["name"])
    unit = next((p.get("unit") for p in data.summary.get("params", []) if p.get("name") == param), None)
    label = f"{param} [{unit or '-'}]"
    fig = new_figure(LANDSCAPE, f"Parametric study: {param}" + (f" ({summ['paper']})" if summ.get("paper") else ""),
                     f"steady cycles of the in-house model at f = {fmt(summ.get('frequency'))} Hz; amplitude per "
                     f"design as recorded (working-range rule)")
    gs = fig.add_gridspec(2, 2, left=0.07, right=0.97, top=0.88, bottom=0.09, hspace=0.35, wspace=0.25,
                          width_ratios=[1.4, 1])
    ax = fig.add_subplot(gs[:, 0])
    vals = [c["value"] for c in s["curves"]]
    if vals:
        norm = matplotlib.colors.Normalize(min(vals), max(vals) if max(vals) > min(vals) else min(vals) + 1)
        cmap = matplotlib.colors.ListedColormap(matplotlib.colormaps["viridis"](np.linspace(0, 0.85, 256)))
        for c in s["curves"]:
            ax.plot(c["u"] * 1e3, c["F"], color=cmap(norm(c["value"])), lw=1.2,
                    ls="-" if c["engine"] == "semirecursive" else "--")
        cb = fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, pad=0.02)
        cb.set_label(label)
    else:
        no_data(ax, "no finished design in this study")
    ax.set_xlabel("displacement u [mm]")
    ax.set_ylabel("force F [N]")
    ax.set_title("force-displacement, steady cycle", fontsize=9)
    ds = [d for d in summ.get("designs", []) if d.get("status") == "ok"]
    for k, (key, scale, ylab) in enumerate([("dissipated_energy", 1.0, "dissipated energy per cycle [J]"),
                                            ("x_max_quasi_static", 1e3, "X_max, quasi-static [mm]")]):
        a = fig.add_subplot(gs[k, 1])
        pts = [(d["value"], d[key] * scale) for d in ds if isinstance(d.get(key), (int, float))]
        if pts:
            a.plot(*zip(*sorted(pts)), "o-", color=color("semirecursive"))
        else:
            no_data(a, f"no {key} recorded")
        a.set_xlabel(label)
        a.set_ylabel(ylab)
    failed = [d for d in summ.get("designs", []) if d.get("status") != "ok"]
    if failed:
        fig.text(0.07, 0.03, "failed/missing designs: " + ", ".join(fmt(d["value"]) for d in failed), color=RED,
                 fontsize=8)
    return fig


def tables_figure(data):
    """The paper's Tables 5 and 6 (X_max) next to the model: values and differences."""
    fig = new_figure(LANDSCAPE, "Tables 5 and 6: maximum displacement X_max, paper against model",
                     "X_max: plate displacement at which every rope is slack (quasi-static, monotonic loading); "
                     "goal: every entry within 0.3 mm")
    gs = fig.add_gridspec(2, 2, left=0.08, right=0.97, top=0.86, bottom=0.08, hspace=0.35, wspace=0.25)
    for col, name in enumerate(("Table 5", "Table 6")):
        rows = [r for r in data.tables if r["table"] == name]
        ax, dx = fig.add_subplot(gs[0, col]), fig.add_subplot(gs[1, col])
        if not rows:
            no_data(ax, f"{name}: not in tables.csv")
            dx.set_visible(False)
            continue
        v = np.array([r["value"] for r in rows])
        unit, par = rows[0]["unit"], rows[0]["parameter"]
        ax.plot(v, [r["paper"] * 1e3 for r in rows], "o", color="k", mfc="none", label="paper")
        ax.plot(v, [r["model"] * 1e3 for r in rows], **style("semirecursive"), label="model")
        ax.set_title(f"{name}: X_max against {par}", fontsize=9)
        ax.set_xlabel(f"{par} [{unit}]")
        ax.set_ylabel("X_max [mm]")
        ax.legend(fontsize=7.5)
        d = np.array([r["diff_mm"] for r in rows])
        dx.bar(np.arange(len(v)), d, color=[RED if abs(x) > 0.3 else GREEN for x in d])
        dx.set_xticks(np.arange(len(v)), [fmt(x) for x in v])
        dx.axhline(0.3, color=GREY, ls=":", lw=1.0)
        dx.axhline(-0.3, color=GREY, ls=":", lw=1.0)
        dx.set_ylim(-0.35, 0.35)
        dx.set_title(f"model - paper (worst {np.max(np.abs(d)):.3f} mm; dotted: goal 0.3 mm)", fontsize=9)
        dx.set_xlabel(f"{par} [{unit}]")
        dx.set_ylabel("difference [mm]")
    return fig
