"""The work-precision page: error against CPU time per cycle for the three engines on each default
case (benchmarks/work_precision.py's JSON), the cheapest setting at the 1e-4 aim and the speed ratio."""
from __future__ import annotations

from matplotlib.lines import Line2D

from reports.style import GREY, LANDSCAPE, RED, fmt, new_figure, no_data, style, table

FLOOR = 1e-9   # errors below this are drawn on it (the log axis keeps its range)
ORDER = ("semirecursive", "mujoco", "exudyn")


def _series(runs, engine):
    """Ladder rungs of one engine grouped into lines (MuJoCo: one per integrator), sorted by work."""
    groups: dict[str, list] = {}
    for r in runs:
        if r.get("engine") == engine and "dF" in r and r.get("cpu_per_cycle"):
            label = engine + (f" {r['settings'].get('integrator', 'Euler')}" if engine == "mujoco" else "")
            groups.setdefault(label, []).append(r)
    return {k: sorted(v, key=lambda r: r["cpu_per_cycle"]) for k, v in groups.items()}


def _setting_text(engine: str, best: dict) -> str:
    s, h = best.get("settings", {}), best.get("step_used")
    if engine == "semirecursive":
        return " ".join(f"{k} {fmt(s[k], 2)}" for k in ("method", "rtol", "max_step") if k in s) or "engine default"
    step = f"h {fmt(h, 3)}" if h else "engine default"
    return f"{s.get('integrator', 'Euler')} {step}" if engine == "mujoco" else step


def work_precision_figure(data):
    wp = data.work_precision
    aim = float(wp.get("aim", 1e-4))
    cases = wp.get("cases", [])
    fig = new_figure(LANDSCAPE, "Work-precision: error against CPU time per cycle, all engines",
                     f"benchmarks/work_precision.py, {wp.get('repeats', '?')} interleaved repeats (median), "
                     f"{wp.get('cpus', '?')} CPUs, load {fmt((wp.get('load_average_start') or [0])[0], 2)} at "
                     f"the start; error: last cycle max|F - F_ref|/max|F_ref| against the in-house model at "
                     f"rtol 1e-10")
    n = max(len(cases), 1)
    cols = min(n, 4)
    gs = fig.add_gridspec(1, cols, left=0.08, right=0.98, top=0.87, bottom=0.40, wspace=0.28)
    if not cases:
        no_data(fig.add_subplot(gs[0]), "work_precision.json holds no cases")
        return fig
    markers = {"semirecursive": "o", "mujoco Euler": "s", "mujoco RK4": "D", "exudyn": "^"}
    for i, c in enumerate(cases[:cols]):
        ax = fig.add_subplot(gs[i])
        for engine in ORDER:
            for label, rows in _series(c.get("runs", []), engine).items():
                ladder = [r for r in rows if not r.get("case_default")]
                st = style(engine)
                if ladder:
                    ax.loglog([r["cpu_per_cycle"] for r in ladder], [max(r["dF"], FLOOR) for r in ladder],
                              marker=markers.get(label, "o"), ms=4, **st)
                for r in rows:
                    if r.get("case_default"):
                        ax.loglog([r["cpu_per_cycle"]], [max(r["dF"], FLOOR)], marker=markers.get(label, "o"),
                                  ms=9, mfc="none", mec=st["color"], mew=1.4, ls="")
            best = c.get("at_aim", {}).get(engine)
            if best:
                ax.loglog([best["cpu_per_cycle"]], [max(best["dF"], FLOOR)], marker="*", ms=13, ls="",
                          color=style(engine)["color"], mec="k", mew=0.6)
        ax.axhline(aim, color=RED, ls=":", lw=1.0)
        ratio = c.get("ratio_best_peer_over_in_house")
        ax.set_title(f"{c['name']}\nbest peer / in-house at the aim: {fmt(ratio, 2) if ratio else '-'}", fontsize=8.5)
        ax.set_xlabel("CPU time per cycle [s]")
        if i == 0:
            ax.set_ylabel("max |F - F_ref| / max |F_ref| [-]")
        ax.margins(x=0.1, y=0.1)
    handles = [Line2D([], [], marker=m, ms=5, **style(lbl.split()[0]), label=lbl) for lbl, m in markers.items()]
    handles += [Line2D([], [], marker="o", ms=9, mfc="none", mec=GREY, ls="", label="the case's default setting"),
                Line2D([], [], marker="*", ms=12, color=GREY, mec="k", ls="", label="cheapest at the aim"),
                Line2D([], [], color=RED, ls=":", label=f"aim {fmt(aim)}")]
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.345), ncol=7, fontsize=7.5)

    rows = []
    for c in cases:
        at = c.get("at_aim", {})
        cells = [c["name"]]
        for engine in ORDER:
            b = at.get(engine)
            cells.append(f"{fmt(b['cpu_per_cycle'], 3)} s, {fmt(b['dF'], 2)}, {_setting_text(engine, b)}"
                         if b else "not reached")
        ratio = c.get("ratio_best_peer_over_in_house")
        cells.append(fmt(ratio, 3) if ratio else "-")
        rows.append(cells)
    y = table(fig, 0.29, [("case", 12, "l"), ("in-house at the aim:\nCPU/cycle, error, setting", 30, "l"),
                          ("MuJoCo at the aim", 26, "l"), ("Exudyn at the aim", 22, "l"),
                          ("best peer /\nin-house", 10, "r")], rows, None, fontsize=7.5)
    comp = wp.get("compile") or {}
    if comp:
        parts = []
        for engine in ORDER:
            e = comp.get(engine, {})
            w, cold = e.get("warm", {}), e.get("cold", {})
            if "startup_s" in w or "startup_s" in cold:
                parts.append(f"{engine}: {fmt(cold.get('startup_s'), 2)} s compiling (empty numba cache), "
                             f"{fmt(w.get('startup_s'), 2)} s with the cache")
        fig.text(0.06, y - 0.03, "Start-up, not in the per-cycle times (first short run minus the second, fresh "
                 "process): " + "; ".join(parts), fontsize=7.5, va="top", wrap=True)
    return fig


def load_work_precision(path) -> dict | None:
    """The benchmark's JSON when present and shaped like one; None otherwise (an optional page)."""
    import json
    try:
        from nsd_core.common.files import read_regular_text
        wp = json.loads(read_regular_text(path))
    except (OSError, ValueError):
        return None
    if not isinstance(wp, dict) or not isinstance(wp.get("cases"), list):
        return None
    ok = all(isinstance(c, dict) and "name" in c and isinstance(c.get("runs", []), list) for c in wp["cases"])
    return wp if ok and wp["cases"] else None

