"""Report pages of the seismic mode (issue 14, item 7): the plate's orbit per engine, time histories
overlaid with their differences to the in-house run, the device's force-displacement loops during the
record, the energy balance over time, and the record-set table (with and without the device).

``runs`` is {engine: RunResult} in the columns of ``nsd seismic`` (nsd_core.device.seismic), the
in-house engine first. The same pages serve an ``nsd seismic`` folder (single run or ``--record-set``) and
the seismic cases of an ``nsd compare`` folder (``<out>/seismic/<case>__<engine>.csv``).
"""
from __future__ import annotations

import numpy as np

from reports.style import GREY, LANDSCAPE, PORTRAIT, new_figure, no_data, style

REFERENCE = "semirecursive"


def _norm(r, a, b):
    return np.hypot(r[a], r[b])


def response_figure(title: str, runs: dict, cost: dict | None = None):
    """Orbit (x, y) per engine; x, y, |a_abs|, |device force| over time, and beneath each the
    difference of every other engine to the in-house run; the engines' cost in the subtitle."""
    fig = new_figure(LANDSCAPE, title, "relative displacement of the plate (x, y), absolute acceleration, device "
                     "force; differences = engine - in-house on the same output times")
    ax = fig.add_axes([0.05, 0.1, 0.3, 0.75])
    for eng, r in runs.items():
        ax.plot(r["x"] * 1e3, r["y"] * 1e3, label=eng, **style(eng))
    ax.set_aspect("equal", "datalim")
    title = "orbit of the plate relative to the base"
    if cost:  # each engine's cost on this run, where the folder recorded it
        title += "\ncost, wall s per model s: " + ", ".join(f"{e} {v:.3g}" for e, v in cost.items())
    ax.set(xlabel="x [mm]", ylabel="y [mm]", title=title)
    ax.legend(loc="best")
    ref = runs.get(REFERENCE)
    series = [("x", 1e3, "x [mm]", lambda r: r["x"]), ("y", 1e3, "y [mm]", lambda r: r["y"]),
              ("a", 1.0, "|a_abs| [m/s²]", lambda r: _norm(r, "ax_abs", "ay_abs")),
              ("F", 1.0, "|device F| [N]", lambda r: _norm(r, "device_Fx", "device_Fy"))]
    peers = [e for e in runs if e != REFERENCE]
    h = 0.8 / len(series)
    for i, (_, scale, label, get) in enumerate(series):
        top = 0.88 - i * h
        a1 = fig.add_axes([0.43, top - h * (0.55 if peers else 0.85), 0.54, h * (0.5 if peers else 0.8)])
        for eng, r in runs.items():
            a1.plot(r["t"], get(r) * scale, **style(eng))
        a1.set_ylabel(label)
        a1.tick_params(labelbottom=not peers and i == len(series) - 1)
        if peers and ref is not None:
            a2 = fig.add_axes([0.43, top - h * 0.95, 0.54, h * 0.35], sharex=a1)
            for eng in peers:
                if len(runs[eng]["t"]) == len(ref["t"]):
                    a2.plot(ref["t"], (get(runs[eng]) - get(ref)) * scale, **style(eng))
            a2.set_ylabel("Δ " + label.split(" ")[-1], color=GREY)
            a2.tick_params(labelbottom=i == len(series) - 1)
    fig.axes[-1].set_xlabel("t [s]")
    return fig


def loops_figure(title: str, runs: dict):
    """device_F (the plate's force on the device) against the relative displacement, per direction."""
    fig = new_figure(LANDSCAPE, title, "device_F (the plate's force on the device) against the plate's displacement "
                     "relative to the base (the negative-stiffness loops the record drives)")
    for j, (f, u, lab) in enumerate((("device_Fx", "x", "X"), ("device_Fy", "y", "Y"))):
        ax = fig.add_axes([0.07 + 0.47 * j, 0.1, 0.4, 0.75])
        if all(np.max(np.abs(r[f])) == 0 for r in runs.values()):
            no_data(ax, "no device in this run (the supports alone)")
            continue
        for eng, r in runs.items():
            ax.plot(r[u] * 1e3, r[f], label=eng, **style(eng))
        ax.set(xlabel=f"{u} [mm]", ylabel=f"{f} [N]", title=f"{lab} direction")
        ax.legend(loc="best")
    return fig


ENERGY = [("E_input", "input"), ("E_kinetic", "kinetic (relative)"), ("stored", "stored (supports + gravity)"),
          ("dissipated", "device (stored + dissipated) + supports' damping"), ("E_residual", "residual")]


def energy_figure(title: str, runs: dict):
    """Energy balance over time per engine that reports it (the in-house one always does)."""
    fig = new_figure(PORTRAIT, title, "E_input = kinetic + stored + absorbed; the residual is the balance's error "
                     "(integrated with the motion, so it measures the mechanics)")
    with_energy = {e: r for e, r in runs.items() if "E_input" in r.columns}
    ax = fig.add_axes([0.1, 0.42, 0.85, 0.46])
    ax2 = fig.add_axes([0.1, 0.08, 0.85, 0.25], sharex=ax)
    colours = ["#1f4e9c", "#d95f02", "#1b9e77", "#7570b3", "#c0001a"]
    for k, (eng, r) in enumerate(with_energy.items()):
        parts = {"E_input": r["E_input"], "E_kinetic": r["E_kinetic"],
                 "stored": r["E_supports_stored"] + r["E_gravity"],
                 "dissipated": r["E_device"] + r["E_supports_dissipated"], "E_residual": r["E_residual"]}
        if "E_restrainer_stored" in r.columns:  # the displacement restrainer (issue 23)
            parts["stored"] = parts["stored"] + r["E_restrainer_stored"]
            parts["dissipated"] = parts["dissipated"] + r["E_restrainer_dissipated"]
        ls = style(eng)["linestyle"]
        for c, (name, label) in enumerate(ENERGY[:-1]):
            ax.plot(r["t"], parts[name], color=colours[c], linestyle=ls, label=f"{label} ({eng})" if k == 0 or c == 0
                    else None)
        ax2.plot(r["t"], parts["E_residual"], color=colours[-1], linestyle=ls, label=eng)
    ax.set(ylabel="energy [J]", title="energy balance")
    ax.legend(loc="upper left", fontsize=7)
    ax2.set(xlabel="t [s]", ylabel="residual [J]")
    if with_energy:
        ax2.legend(loc="best")
    return fig


SET_SHOWN = [("id", "id", "{}"), ("earthquake", "earthquake", "{}"), ("station", "station", "{}"),
             ("pga", "PGA\n[m/s²]", "{:.3g}"), ("peak_u", "peak |u|\n[mm]", "mm"),
             ("peak_u_nodevice", "supports\nalone [mm]", "mm"), ("peak_u_ratio", "ratio\n|u|", "{:.3f}"),
             ("peak_a_abs", "peak |a|\n[m/s²]", "{:.3g}"), ("peak_a_abs_nodevice", "supports\nalone", "{:.3g}"),
             ("peak_a_abs_ratio", "ratio\n|a|", "{:.3f}"), ("residual_u", "residual\n[mm]", "mm"),
             ("energy_residual", "energy\nresidual", "{:.1e}"), ("status", "status", "{}")]


def _fmt(v, f):
    if v is None or v == "":
        return "–"
    if f == "mm":
        return f"{float(v) * 1e3:.2f}"
    return f.format(v)


def _ground_text(g: dict) -> str:
    w = g.get("window")
    return (f"scale {g.get('scale', 1):g}, time factor {g.get('time_factor', 0):.4g}, "
            + (f"window {w[0]:g}-{w[1]:g} s (record time)" if w else "whole records")
            + f", rotated {g.get('rotate_deg', 0):g} deg" + ("" if g.get("normalised", True) else ", as recorded"))


def set_table_figure(index: dict):
    """The record-set table: peaks with and without the device and their ratios, one row per record."""
    rows = index["rows"]
    fig = new_figure(LANDSCAPE, f"Record set {index.get('set')}: the isolation effect",
                     f"each record with the device and on the supports alone (in-house engine); ratio = with / "
                     f"without; {_ground_text(index.get('ground') or {})}")
    ax = fig.add_axes([0.06, 0.52, 0.9, 0.36])
    ids = [str(r["id"]) for r in rows]
    xs = np.arange(len(rows))
    for k, (key, lab, col) in enumerate((("peak_u_ratio", "peak |u| ratio", "#1f4e9c"),
                                         ("peak_a_abs_ratio", "peak |a_abs| ratio", "#d95f02"))):
        vals = [r.get(key) if r.get(key) is not None else np.nan for r in rows]
        ax.bar(xs + (k - 0.5) * 0.38, vals, 0.38, color=col, label=lab)
    for x, r in zip(xs, rows):  # a record without ratios says why where its bars would be
        if r.get("peak_u_ratio") is None:
            why = r.get("status", "?") + (f"\nt = {r['rod_reach_t']:.3g} s" if r.get("rod_reach_t") is not None else "")
            ax.text(x, 0.05, why, ha="center", va="bottom", fontsize=7, color="#c0001a", rotation=90)
    ax.set_xlim(-0.7, len(rows) - 0.3)
    ax.axhline(1.0, color=GREY, lw=0.8)
    ax.set_xticks(xs, ids)
    ax.set(xlabel="record", ylabel="with device / supports alone")
    ax.legend(loc="best")
    y, x0 = 0.43, 0.03
    widths = [0.03, 0.17, 0.17, 0.055, 0.055, 0.06, 0.045, 0.055, 0.055, 0.045, 0.055, 0.055, 0.09]
    xpos = np.concatenate([[x0], x0 + np.cumsum(widths[:-1])])
    size = 7 if len(rows) <= 14 else 5.5
    for (_, head, _), xx in zip(SET_SHOWN, xpos):
        fig.text(xx, y, head, fontsize=size, weight="bold", va="bottom")
    step = min(0.026, 0.36 / max(len(rows), 1))
    for i, r in enumerate(rows):
        for (key, _, f), xx, w in zip(SET_SHOWN, xpos, widths):
            text = _fmt(r.get(key), f)
            if key in ("earthquake", "station"):
                text = text if len(text) <= 30 else text[:29] + "…"
            fig.text(xx, y - step * (i + 1), text, fontsize=size, va="bottom",
                     color="#c0001a" if key == "status" and text != "ok" else "black")
    return fig
