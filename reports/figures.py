"""Per-case figures: force-displacement cycles with Delta F beneath (laid out like the paper's
Figure 6), tangent stiffness with the Figure 7 working regions, force breakdown, loop closure."""
from __future__ import annotations

import textwrap

import numpy as np
from matplotlib.gridspec import GridSpecFromSubplotSpec
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import FuncFormatter, MaxNLocator

from nsd_core.device.cycle import loading_quarter, phase_resample, steady_cycle, tangent_stiffness

from reports.style import GREY, LANDSCAPE, RED, SHADE, color, fmt, limit_lines, new_figure, no_data, style

CLOSURE_FLOOR = 1e-18  # [m]; exact zeros are drawn here on the log axis


def chunks(items: list, n: int) -> list[list]:
    return [items[i:i + n] for i in range(0, len(items), n)] or [[]]


def is_line(c: dict) -> bool:
    return c.get("path", "line") == "line"


def case_groups(data) -> list[dict]:
    """Pages of case panels. Line cases forming a full amplitude x frequency grid (at most 3 x 3, one
    direction) get the paper's Figure 6 layout: rows = amplitude, columns = frequency; other line
    cases four to a page; 2-D paths (circle, ellipse, figure eight, tables) two to a page, each as its
    components F_x(x) and F_y(y) ("planar")."""
    cases = [c for c in data.cases if is_line(c)]
    amps = sorted({c["amplitude"] for c in cases})
    freqs = sorted({c["frequency"] for c in cases})
    pairs = {(c["amplitude"], c["frequency"]) for c in cases}
    out = []
    if (len(cases) > 1 and len(pairs) == len(cases) == len(amps) * len(freqs) and len(amps) <= 3
            and len(freqs) <= 3 and len({c.get("direction_deg", 0.0) for c in cases}) == 1):
        cells = [(amps.index(c["amplitude"]), freqs.index(c["frequency"]), c["name"]) for c in cases]
        out.append({"shape": (len(amps), len(freqs)), "cells": sorted(cells), "grid": True, "planar": False})
    elif cases:
        for chunk in chunks([c["name"] for c in cases], 4):
            shape = {0: (1, 1), 1: (1, 1), 2: (1, 2)}.get(len(chunk), (2, 2))
            out.append({"shape": shape, "cells": [(i // shape[1], i % shape[1], n) for i, n in enumerate(chunk)],
                        "grid": False, "planar": False})
    planar = [c["name"] for c in data.cases if not is_line(c)]
    for chunk in (chunks(planar, 2) if planar else []):
        out.append({"shape": (len(chunk), 1), "cells": [(i, 0, n) for i, n in enumerate(chunk)], "grid": False,
                    "planar": True})
    return out


def _case(data, name: str) -> dict:
    return next(c for c in data.cases if c["name"] == name)


def _title(c: dict) -> str:
    psi = c.get("direction_deg", 0.0)
    return (f"{c['name']}: A = {fmt(c['amplitude'] * 1e3)} mm, f = {fmt(c['frequency'])} Hz"
            + (f", psi = {fmt(psi)} deg" if psi else ""))


def _top(fig, room: float = 0.07) -> float:
    """Top of the panels: below the headings and the engines' legend, with ``room`` for titles."""
    return min(0.86, getattr(fig, "_nsd_top", 0.95) - room)


def _engines_legend(fig, data, y: float = 0.935, extra: list | None = None) -> None:
    y = min(y, getattr(fig, "_nsd_top", y))   # below a subtitle of two lines
    handles = [Line2D([], [], **style(e), label=e + (" (reference)" if e == data.reference else ""))
               for e in data.engines] + (extra or [])
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, y), ncol=len(handles), frameon=False,
               fontsize=8.5)


def _failed_note(data, case: str) -> str:
    bad = [f"{e}: {data.run(case, e).get('message', 'not run')}" for e in data.engines
           if (case, e) not in data.results]
    return "; ".join(bad)


def _steady(data, case: str, engine: str):
    res = data.results[(case, engine)]
    m = steady_cycle(res, _case(data, case)["frequency"])
    return res, m


def _overlay(ax, axd, data, name: str, xcol: str, fcol: str) -> bool:
    """``fcol`` against ``xcol`` of every engine on ``ax``; beneath on ``axd`` the difference to the
    reference on a common phase grid, the largest |difference| per engine in its legend."""
    f = _case(data, name)["frequency"]
    drawn = False
    for e in data.engines:
        if (name, e) in data.results and fcol in data.results[(name, e)].columns:
            res, m = _steady(data, name, e)
            ax.plot(res[xcol][m] * 1e3, res[fcol][m], **style(e))
            drawn = True
    ref = data.reference
    if (name, ref) in data.results:
        Fr = phase_resample(data.results[(name, ref)], f, fcol)
        xr = phase_resample(data.results[(name, ref)], f, xcol)
        for e in data.engines:
            if e != ref and (name, e) in data.results:
                dF = phase_resample(data.results[(name, e)], f, fcol) - Fr
                axd.plot(xr * 1e3, dF, **style(e), label=f"max {fmt(np.max(np.abs(dF)), 2)} N")
        if axd.lines:
            axd.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=6.5, frameon=False, handlelength=1.5,
                       borderaxespad=0.2)
        axd.axhline(0.0, color=GREY, lw=0.6)
    else:
        axd.text(0.5, 0.5, f"reference {ref} did not run: no \u0394F", transform=axd.transAxes, ha="center",
                 va="center", fontsize=7.5, color=RED)
    axd.sharex(ax)
    axd.yaxis.set_major_formatter(FuncFormatter(lambda v, _: fmt(v, 2)))
    ax.tick_params(labelbottom=False)
    return drawn


def cycles_figure(data, group: dict):
    """F(u) of every engine overlaid per case, Delta F against the reference beneath; 2-D paths as
    their components F_x(x) and F_y(y)."""
    planar = group.get("planar")
    title = ("Force-displacement cycles of the 2-D paths, by component (steady cycle)" if planar else
             "Force-displacement cycles (steady cycle)" + (" - Figure 6 layout: rows amplitude, columns frequency"
                                                           if group["grid"] else ""))
    fig = new_figure(LANDSCAPE, title,
                     f"beneath each panel: \u0394F = F(engine) - F({data.reference}) on a common phase grid, "
                     f"against the reference's displacement; its legend: the largest |\u0394F|")
    _engines_legend(fig, data)
    rows, cols = group["shape"]
    outer = fig.add_gridspec(rows, cols, left=0.07, right=0.9, top=_top(fig), bottom=0.09, hspace=0.4, wspace=0.45)
    for r, c, name in group["cells"]:
        case = _case(data, name)
        parts = [("x", "F_x", "x"), ("y", "F_y", "y")] if planar else [("u", "F", "u")]
        inner = GridSpecFromSubplotSpec(2, len(parts), subplot_spec=outer[r, c], height_ratios=[3, 1.25],
                                        hspace=0.08, wspace=0.42)
        bad = sorted({m["metric"] for m in data.summary["metrics"]
                      if m["case"] == name and m.get("gated") and not m.get("pass")})
        for k, (xcol, fcol, lab) in enumerate(parts):
            ax, axd = fig.add_subplot(inner[0, k]), fig.add_subplot(inner[1, k])
            if not _overlay(ax, axd, data, name, xcol, fcol):
                no_data(ax, f"no engine ran this case: {_failed_note(data, name)}")
            head = _title(case) if not planar else f"{name}: {fcol} against {lab}"
            ax.set_title(head + ("  - FAIL" if bad else ""), fontsize=8.5, color=RED if bad else "black")
            ax.set_ylabel(f"force {fcol} [N]")
            axd.set_xlabel(f"displacement {lab} [mm]")
            axd.set_ylabel(f"\u0394{fcol} [N]")
        note = "; ".join(([("outside limits: " + ", ".join(bad))] if bad else []) +
                         ([f"failed: {_failed_note(data, name)}"] if _failed_note(data, name) else []))
        if note:
            ax.text(0.02, 0.03, "\n".join(textwrap.wrap(note, 50)[:4]), transform=ax.transAxes, fontsize=7,
                    color=RED, va="bottom")
    return fig


TURNING = 0.99  # fraction of A up to which dF/du is drawn (the drive's velocity is 14 % of its peak there)


def stiffness_figure(data, group: dict):
    """Tangent stiffness dF/du on the loading quarter (u: 0 -> +A) per engine, working regions of the
    reference shaded (Figure 7), X_max marked where the ropes went slack."""
    fig = new_figure(LANDSCAPE, "Tangent stiffness on the loading branch (Figure 7 working regions)",
                     "dF/du along u = 0 -> +A of the steady cycle; shaded: the reference's regions of positive "
                     "and negative stiffness; X_max: displacement at which every rope is slack;\ncurves end at "
                     f"{TURNING:g} A, where du/dt -> 0 makes dF/du noise (line drives only)")
    extra = [Patch(facecolor=SHADE["+"], label="k > 0 region"), Patch(facecolor=SHADE["-"], label="k < 0 region"),
             Line2D([], [], color="k", ls="-.", lw=1.0, label="X_max (reference)")]
    _engines_legend(fig, data, extra=extra)
    rows, cols = group["shape"]
    gs = fig.add_gridspec(rows, cols, left=0.08, right=0.98, top=_top(fig), bottom=0.09, hspace=0.35, wspace=0.22)
    for r, c, name in group["cells"]:
        ax = fig.add_subplot(gs[r, c])
        case = _case(data, name)
        ks, shown = [], []
        for e in data.engines:
            if (name, e) in data.results:
                res = data.results[(name, e)]
                q = loading_quarter(res, case["frequency"])
                u, F = res["u"][q], res["F"][q]
                keep = np.concatenate([[True], np.diff(u) > 0])  # strictly rising: a defined gradient
                k = tangent_stiffness(u[keep], F[keep])
                # the curve stops short of the turning point: there du/dt -> 0 and the quotient of two
                # vanishing differences is noise, not stiffness (it drew spikes at u = A)
                drawn = u[keep] < TURNING * case["amplitude"]
                ax.plot(u[keep][drawn] * 1e3, k[drawn] / 1e3, **style(e))
                # the y-range ignores the turning point (u -> A, du -> 0), where dF/du is noise
                ks.append(k[u[keep] < 0.97 * case["amplitude"]])
                shown.append(k[drawn & np.isfinite(k)])
        run = data.run(name, data.reference)
        summ = run.get("summary") or next((data.run(name, e).get("summary") for e in data.engines
                                          if data.run(name, e).get("summary")), None)
        if not ks:
            no_data(ax, f"no engine ran this case: {_failed_note(data, name)}")
            ax.set_title(_title(case), fontsize=9)
            continue
        allk = np.concatenate(ks) / 1e3
        lo, hi = np.percentile(allk, [1, 99])
        pad = 0.12 * (hi - lo or 1.0)
        ax.set_ylim(lo - pad, hi + pad)
        every = np.concatenate(shown) / 1e3
        if every.size and (every.max() > hi + pad or every.min() < lo - pad):  # say so, never hide it
            ax.text(0.02, 0.03, f"axis clipped to the central 98 % of the values: dF/du spans {every.min():.4g} "
                    f"to {every.max():.4g} kN/m", transform=ax.transAxes, fontsize=7,
                    va="bottom", bbox=dict(fc="white", ec="none", alpha=0.8, pad=1))
        if summ:
            regs = summ.get("stiffness_regions", [])
            for i, reg in enumerate(regs):  # each region runs on to where the next one starts
                end = regs[i + 1]["from"] if i + 1 < len(regs) else max(reg["to"], case["amplitude"] * 1.02)
                ax.axvspan(reg["from"] * 1e3, end * 1e3, color=SHADE.get(reg["sign"], "#eeeeee"), zorder=0, lw=0)
            xm = summ.get("x_max")
            if xm is not None and xm <= case["amplitude"] * (1 + 1e-9):
                ax.axvline(xm * 1e3, color="k", ls="-.", lw=1.0)
                ax.text(xm * 1e3, 0.97, f"X_max = {xm * 1e3:.2f} mm ", transform=ax.get_xaxis_transform(),
                        ha="right", va="top", fontsize=7.5, bbox=dict(fc="white", ec="none", alpha=0.8, pad=1))
        ax.axhline(0.0, color=GREY, lw=0.6)
        ax.set_xlim(0, case["amplitude"] * 1.02e3)
        ax.set_title(_title(case), fontsize=9)
        ax.set_xlabel("displacement u [mm]")
        ax.set_ylabel("tangent stiffness dF/du [kN/m]")
    return fig


PARTS = [("F_rod", "rod (F_rod)"), ("F_ropes", "ropes (F_ropes)"), ("F_wires", "SMA wires (F_wires)"),
         ("spring_push", "spring push (vertical)")]


def breakdown_figure(data, names: list[str]):
    """Per case (rows) the parts' contributions to F (columns), every engine overlaid, and beneath each
    the difference to the reference on a common phase grid (the curves overlap to the line width)."""
    fig = new_figure(LANDSCAPE, "Force breakdown over the steady cycle (line drives)",
                     "F_rod + F_ropes + F_wires = F_device (the drive force less the cap's inertia); the spring "
                     "column is the spring's push on the movable wall, not a part of F; beneath each: engine - "
                     f"{data.reference}")
    _engines_legend(fig, data)
    n = max(len(names), 1)
    outer = fig.add_gridspec(n, len(PARTS), left=0.07, right=0.985, top=_top(fig, 0.085), bottom=0.08, hspace=0.45, wspace=0.42)
    ref = data.reference
    for i, name in enumerate(names):
        case = _case(data, name)
        f = case["frequency"]
        for j, (col, label) in enumerate(PARTS):
            inner = GridSpecFromSubplotSpec(2, 1, subplot_spec=outer[i, j], height_ratios=[2.2, 1], hspace=0.08)
            ax, axd = fig.add_subplot(inner[0]), fig.add_subplot(inner[1])
            for e in data.engines:
                if (name, e) in data.results and col in data.results[(name, e)].columns:
                    res, m = _steady(data, name, e)
                    ax.plot(res["u"][m] * 1e3, res[col][m], **style(e))
            if not ax.lines:
                no_data(ax, "no engine output")
            else:
                lo, hi = ax.get_ylim()
                ax.set_title(f"{name}: {label}\naxis spans {fmt(hi - lo, 3)} N", fontsize=7.5)
            if (name, ref) in data.results and col in data.results[(name, ref)].columns:
                base = phase_resample(data.results[(name, ref)], f, col)
                ur = phase_resample(data.results[(name, ref)], f, "u")
                for e in data.engines:
                    if e != ref and (name, e) in data.results and col in data.results[(name, e)].columns:
                        axd.plot(ur * 1e3, phase_resample(data.results[(name, e)], f, col) - base, **style(e))
                axd.axhline(0.0, color=GREY, lw=0.6)
            axd.sharex(ax)
            ax.tick_params(labelbottom=False)
            ax.set_ylabel(f"{col} [N]", fontsize=7.5)
            axd.set_ylabel("\u0394 [N]", fontsize=7.5)
            axd.set_xlabel("displacement u [mm]", fontsize=7.5, labelpad=1)
            for a in (ax, axd):
                a.yaxis.set_major_formatter(FuncFormatter(lambda v, _: fmt(v, 3)))
                a.yaxis.set_major_locator(MaxNLocator(4))
            ax.set_xlim(-case["amplitude"] * 1.05e3, case["amplitude"] * 1.05e3)
    return fig


CLOSURE_BINS = 200


def _envelope(t, v, bins: int = CLOSURE_BINS):
    """(bin mid-times, largest value per bin) of a sampled trace."""
    edges = np.linspace(0, len(t), min(bins, len(t)) + 1).astype(int)
    idx = [(a, b) for a, b in zip(edges[:-1], edges[1:]) if b > a]
    return np.array([t[(a + b - 1) // 2] for a, b in idx]), np.array([np.max(v[a:b]) for a, b in idx])


def closure_figure(data, names: list[str]):
    """|loop-closure violation| against time per engine, log scale, with the gated limit."""
    applied = {(m["case"], m["engine"]): m["limit"] for m in data.summary["metrics"]
               if m["metric"] == "closure_max" and m.get("reference") is None}
    fig = new_figure(LANDSCAPE, "Loop-closure violation over time",
                     f"envelope (largest value in each of {CLOSURE_BINS} time bins) of the closed loops' constraint "
                     f"residual, whole run; exact zeros drawn at {CLOSURE_FLOOR:g} m; dotted, named: the limit "
                     "applied to each engine on the case")
    _engines_legend(fig, data)
    shape = {0: (1, 1), 1: (1, 1), 2: (1, 2)}.get(len(names), (2, 2))
    gs = fig.add_gridspec(*shape, left=0.08, right=0.98, top=_top(fig), bottom=0.09, hspace=0.35, wspace=0.2)
    for i, name in enumerate(names):
        ax = fig.add_subplot(gs[i // shape[1], i % shape[1]])
        case = _case(data, name)
        limits = {e: applied.get((name, e)) for e in data.engines}
        for e in data.engines:
            if (name, e) in data.results:
                res = data.results[(name, e)]
                # an envelope, not every sample: round-off traces drawn sample by sample fill bands
                # that hide each other
                t, v = _envelope(res["t"], np.maximum(np.abs(res["closure"]), CLOSURE_FLOOR))
                ax.semilogy(t, v, **style(e))
        if not ax.lines:
            no_data(ax, f"no engine ran this case: {_failed_note(data, name)}")
        else:
            shown = [lim for e, lim in limits.items() if lim and (name, e) in data.results]
            limit_lines(ax, {e: (lim, color(e)) for e, lim in limits.items() if lim and (name, e) in data.results}, "m")
            ax.set_ylim(CLOSURE_FLOOR / 3, max(shown + [max(np.nanmax(ln.get_ydata()) for ln in ax.lines)]) * 30)
        ax.set_title(_title(case), fontsize=9)
        ax.set_xlabel("time t [s]")
        ax.set_ylabel("|closure violation| [m]")
    return fig
