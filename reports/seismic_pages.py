"""Report pages of the seismic mode: the ground acceleration (model time,
record seconds on a second axis) and the plate's orbit per engine, time histories overlaid with their
differences to the in-house run, the device's force-displacement loops with their differences, the
energy balance over time with the residual on the gate's relative scale, and the record-set table.

``runs`` is {engine: RunResult} in the columns of ``nsd seismic`` (nsd_core.structure.seismic), the
in-house engine first; ``nodevice`` the in-house run on the supports alone where one exists; ``ground``
the ground motion's description (window in record seconds, time factor). The same pages serve an
``nsd seismic`` folder (single run or ``--record-set``) and the seismic cases of an ``nsd compare``
folder (``<out>/seismic/<case>__<engine>.csv``).
"""
from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.ticker import FuncFormatter, MaxNLocator

from reports.style import GREY, LANDSCAPE, RED, fmt, natural, new_figure, no_data, style, table, wrap_rows

REFERENCE = "semirecursive"
NODEVICE = {"color": "#888888", "linestyle": "-", "linewidth": 0.9}


def _norm(r, a, b):
    return np.hypot(r[a], r[b])


def _legend(fig, runs: dict, nodevice=None, y: float = 0.925) -> None:
    y = min(y, getattr(fig, "_nsd_top", y))   # below a subtitle of two lines
    handles = [Line2D([], [], **style(e), label=e + (" (reference)" if e == REFERENCE else "")) for e in runs]
    if nodevice is not None:
        handles.append(Line2D([], [], **NODEVICE, label="supports alone (no device, in-house)"))
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, y), ncol=len(handles), frameon=False,
               fontsize=8.5)


def _record_axis(ax, ground: dict | None) -> None:
    """Record seconds on a second (top) axis: t_record = window start + t / time factor."""
    g = ground or {}
    tf, w = g.get("time_factor"), g.get("window")
    if not tf:
        return
    t0 = float(w[0]) if w else 0.0
    top = ax.secondary_xaxis("top", functions=(lambda t: t0 + t / tf, lambda s: (s - t0) * tf))
    top.set_xlabel("record time [s] (full scale)", fontsize=7.5)
    top.tick_params(labelsize=7)


def _ground_panel(ax, runs: dict, ground: dict | None) -> None:
    ref = runs.get(REFERENCE) or next(iter(runs.values()))
    if "ax_g" not in ref.columns:
        no_data(ax, "no ground acceleration column in this run")
        return
    ax.plot(ref["t"], ref["ax_g"], color="#444444", lw=0.9, label="a_g,x")
    ax.plot(ref["t"], ref["ay_g"], color="#b35c00", lw=0.9, label="a_g,y")
    ax.set(xlabel="model time t [s]", ylabel="ground acceleration [m/s²]")
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=7, frameon=False)
    _record_axis(ax, ground)
    ax.set_title("ground acceleration (the base's input)", fontsize=8.5, pad=22)


def response_figure(title: str, runs: dict, cost: dict | None = None, ground: dict | None = None, nodevice=None):
    """Ground input and orbit (x, y) on the left; x, y, |a_abs|, |device force| over time on the right,
    beneath each the difference of every other engine to the in-house run."""
    sub = "relative displacement of the plate (x, y), absolute acceleration, device force; differences = engine " \
          "- in-house on the same output times"
    if cost:
        sub += "\nwarm cost (compilation timed apart), wall s per model s: " + ", ".join(
            f"{e} {fmt(v, 3)}" for e, v in cost.items())
    fig = new_figure(LANDSCAPE, title, sub)
    _legend(fig, runs, nodevice, y=0.9)
    ax = fig.add_axes([0.06, 0.47, 0.26, 0.34])
    if nodevice is not None:
        ax.plot(nodevice["x"] * 1e3, nodevice["y"] * 1e3, **NODEVICE)
    for eng, r in runs.items():
        ax.plot(r["x"] * 1e3, r["y"] * 1e3, **style(eng))
    ax.set_aspect("equal", "datalim")
    ax.set(xlabel="x [mm]", ylabel="y [mm]")
    ax.set_title("orbit of the plate relative to the base", fontsize=8.5)
    _ground_panel(fig.add_axes([0.06, 0.08, 0.22, 0.2]), runs, ground)
    ref = runs.get(REFERENCE)
    series = [(1e3, "x [mm]", lambda r: r["x"]), (1e3, "y [mm]", lambda r: r["y"]),
              (1.0, "|a_abs| [m/s²]", lambda r: _norm(r, "ax_abs", "ay_abs")),
              (1.0, "|device F| [N]", lambda r: _norm(r, "device_Fx", "device_Fy"))]
    peers = [e for e in runs if e != REFERENCE]
    h = 0.78 / len(series)
    for i, (scale, label, get) in enumerate(series):
        top = 0.86 - i * h
        a1 = fig.add_axes([0.43, top - h * (0.55 if peers else 0.85), 0.52, h * (0.5 if peers else 0.8)])
        if nodevice is not None and i < 3:
            a1.plot(nodevice["t"], get(nodevice) * scale, **NODEVICE)
        for eng, r in runs.items():
            a1.plot(r["t"], get(r) * scale, **style(eng))
        a1.set_ylabel(label, fontsize=7.5)
        a1._nsd_time = True   # a time axis: reports.seismic_compare.with_stop_mark marks the stop on it
        a1.tick_params(labelbottom=not peers and i == len(series) - 1)
        if peers and ref is not None:
            a2 = fig.add_axes([0.43, top - h * 0.95, 0.52, h * 0.35], sharex=a1)
            for eng in peers:
                if len(runs[eng]["t"]) == len(ref["t"]):
                    a2.plot(ref["t"], (get(runs[eng]) - get(ref)) * scale, **style(eng))
            a2.set_ylabel("Δ " + label.split(" ")[-1], color=GREY, fontsize=7)
            a2._nsd_time = True
            a2.tick_params(labelbottom=i == len(series) - 1, labelsize=6.5)
            a2.yaxis.set_major_formatter(FuncFormatter(lambda v, _: fmt(v, 2)))   # no offset text over the panel above
            a2.yaxis.set_major_locator(MaxNLocator(3))
    fig.axes[-1].set_xlabel("model time t [s]")
    return fig


def loops_figure(title: str, runs: dict, nodevice=None):
    """device_F (the plate's force on the device) against the relative displacement, per direction, with
    the difference of every other engine to the in-house run beneath."""
    fig = new_figure(LANDSCAPE, title, "device_F (the plate's force on the device) against the plate's displacement "
                     "relative to the base (the negative-stiffness loops the record drives); beneath: engine - in-house")
    _legend(fig, runs)
    ref = runs.get(REFERENCE)
    peers = [e for e in runs if e != REFERENCE]
    for j, (f, u, lab) in enumerate((("device_Fx", "x", "X"), ("device_Fy", "y", "Y"))):
        ax = fig.add_axes([0.07 + 0.48 * j, 0.36, 0.4, 0.5])
        axd = fig.add_axes([0.07 + 0.48 * j, 0.08, 0.4, 0.2], sharex=ax)
        if all(np.max(np.abs(r[f])) == 0 for r in runs.values()):
            no_data(ax, "no device in this run (the supports alone)")
            axd.set_visible(False)
            continue
        for eng, r in runs.items():
            ax.plot(r[u] * 1e3, r[f], **style(eng))
        ax.set(ylabel=f"{f} [N]", title=f"{lab} direction")
        ax.tick_params(labelbottom=False)
        if ref is not None:
            for eng in peers:
                if len(runs[eng]["t"]) == len(ref["t"]):
                    axd.plot(ref[u] * 1e3, runs[eng][f] - ref[f], **style(eng))
            axd.axhline(0.0, color=GREY, lw=0.6)
        axd.set(xlabel=f"{u} [mm] (in-house)", ylabel=f"Δ{f} [N]")
        axd.yaxis.set_major_formatter(FuncFormatter(lambda v, _: fmt(v, 2)))
    return fig


ENERGY = [("E_input", "input"), ("E_kinetic", "kinetic (relative)"), ("stored", "stored (supports, gravity,\nrestrainer if any)"),
          ("dissipated", "device (stored + dissipated)\n+ supports' (restrainer's) damping")]
COLOURS = ["#1f4e9c", "#d95f02", "#1b9e77", "#7570b3"]


def energy_figure(title: str, runs: dict):
    """Energy balance over time per engine that reports it, the residual as the gate sees it:
    E_residual / max |E_input| (energy_residual_rel is its largest magnitude)."""
    fig = new_figure(LANDSCAPE, title, "E_input = kinetic + stored + absorbed; the residual is the balance's error "
                     "(integrated with the motion, so it measures the mechanics); line style: engine")
    with_energy = {e: r for e, r in runs.items() if "E_input" in r.columns}
    ax = fig.add_axes([0.08, 0.45, 0.64, 0.42])
    ax2 = fig.add_axes([0.08, 0.08, 0.64, 0.27], sharex=ax)
    for eng, r in with_energy.items():
        parts = {"E_input": r["E_input"], "E_kinetic": r["E_kinetic"],
                 "stored": r["E_supports_stored"] + r["E_gravity"],
                 "dissipated": r["E_device"] + r["E_supports_dissipated"]}
        if "E_restrainer_stored" in r.columns:  # the displacement restrainer
            parts["stored"] = parts["stored"] + r["E_restrainer_stored"]
            parts["dissipated"] = parts["dissipated"] + r["E_restrainer_dissipated"]
        ls = style(eng)["linestyle"]
        for c, (name, _) in enumerate(ENERGY):
            ax.plot(r["t"], parts[name], color=COLOURS[c], linestyle=ls)
        scale = float(np.max(np.abs(r["E_input"]))) or 1.0
        ax2.plot(r["t"], r["E_residual"] / scale, color=style(eng)["color"], linestyle=ls)
    ax._nsd_time = ax2._nsd_time = True
    ax.set(ylabel="energy [J]", title="energy balance")
    ax.tick_params(labelbottom=False)
    ax2.set(xlabel="model time t [s]", ylabel="E_residual / max |E_input| [-]",
            title="residual on the gate's scale (energy_residual_rel = its largest magnitude)")
    handles = [Line2D([], [], color=COLOURS[c], label=label) for c, (_, label) in enumerate(ENERGY)]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7.5, frameon=False)
    ax2.legend(handles=[Line2D([], [], **style(e), label=e) for e in with_energy], loc="upper left",
               bbox_to_anchor=(1.01, 1.0), fontsize=7.5, frameon=False)
    return fig


SET_SHOWN = [("id", "id", "{}"), ("earthquake", "earthquake", "{}"), ("station", "station", "{}"),
             ("pga", "PGA\n[m/s²]", "g"), ("peak_u", "peak |u|\n[mm]", "mm"),
             ("peak_u_nodevice", "supports\nalone [mm]", "mm"), ("peak_u_ratio", "ratio\n|u|", "g"),
             ("peak_a_abs", "peak |a|\n[m/s²]", "g"), ("peak_a_abs_nodevice", "supports\nalone [m/s²]", "g"),
             ("peak_a_abs_ratio", "ratio\n|a|", "g"), ("residual_u", "residual\n[mm]", "mm"),
             ("energy_residual", "energy\nresidual", "g"), ("cost", "wall / CPU s per\nmodel s (warm)", "{}"),
             ("status", "status", "{}")]


def _fmt(v, f):
    if v is None or v == "":
        return "-"
    if f == "mm":
        return fmt(float(v) * 1e3, 4)
    if f == "g":
        return fmt(v, 4) if isinstance(v, (int, float)) else str(v)
    return f.format(v)


def _ground_text(g: dict) -> str:
    w = g.get("window")
    return (f"scale {fmt(g.get('scale', 1), 5)}, time factor {fmt(g.get('time_factor'), 5)}, "
            + (f"window {fmt(w[0], 5)} to {fmt(w[1], 5)} s (record time)" if w else "whole records")
            + f", rotated {fmt(g.get('rotate_deg', 0), 5)} deg" + ("" if g.get("normalised", True) else ", as recorded"))


def _restoring_lines(fig, check) -> None:
    """The restoring-force verdict of each configuration (nsd_core.structure.restoring_force), a FAIL in red."""
    from nsd_core.structure.restoring_force import verdict_line
    if not isinstance(check, dict):
        return
    for k, c in enumerate([check] + ([check["baseline"]] if isinstance(check.get("baseline"), dict) else [])):
        line = verdict_line(c) if "directions" in c or "skipped" in c else f"restoring force: pass = {c.get('pass')}"
        fig.text(0.06, getattr(fig, "_nsd_top", 0.92) - 0.02 * k, line, fontsize=7.5, va="top", color=RED if c.get("pass") is False else "black")


def set_table_figure(index: dict):
    """The record-set table: peaks with and without the device and their ratios, one row per record."""
    rows = index["rows"]
    fig = new_figure(LANDSCAPE, f"Record set {index.get('set')}: the isolation effect",
                     f"each record with the device and on the supports alone (in-house engine); ratio = with / "
                     f"without; {_ground_text(index.get('ground') or {})}")
    ax = fig.add_axes([0.06, 0.6, 0.8, 0.24])
    ids = [str(r["id"]) for r in rows]
    xs = np.arange(len(rows))
    for k, (key, lab, col) in enumerate((("peak_u_ratio", "peak |u| ratio", "#1f4e9c"),
                                         ("peak_a_abs_ratio", "peak |a_abs| ratio", "#d95f02"))):
        vals = [r.get(key) if r.get(key) is not None else np.nan for r in rows]
        ax.bar(xs + (k - 0.5) * 0.38, vals, 0.38, color=col, label=lab)
    for x, r in zip(xs, rows):  # a record without ratios says why where its bars would be
        if r.get("peak_u_ratio") is None:
            why = r.get("status", "?") + (f"\nt = {r['rod_reach_t']:.3g} s" if r.get("rod_reach_t") is not None else "")
            ax.text(x, 0.05, why, ha="center", va="bottom", fontsize=7, color=RED, rotation=90)
    ax.set_xlim(-0.7, len(rows) - 0.3)
    ax.axhline(1.0, color=GREY, lw=0.8)
    ax.set_xticks(xs, ids)
    ax.set(xlabel="record", ylabel="with device / supports alone")
    _restoring_lines(fig, index.get("restoring_force"))
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=7.5, frameon=False)
    cells = [[_fmt(r.get(key), f) for key, _, f in SET_SHOWN] for r in rows]
    colors = [[RED if key == "status" and r.get("status") != "ok" else None for key, _, _ in SET_SHOWN] for r in rows]
    fs = 7 if len(rows) <= 14 else 6
    cols = natural([(h, 1, "l" if k in ("earthquake", "station", "status") else "r") for k, h, _ in SET_SHOWN],
                   cells, flex=2, fontsize=fs)
    cells, colors, stripe = wrap_rows(cols, cells, colors, fs)
    table(fig, 0.48, cols, cells, colors, fontsize=fs, stripe=stripe)
    return fig
