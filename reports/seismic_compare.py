"""Report pages of ``nsd seismic --compare-supports``: the run with the device and the one
on the supports alone overlaid (orbit, |u|, |a_abs|, base shear, the restrainer's force), the ratio
table, and, on any seismic page, the time at which a run the device's failure ended (exit 4).

A compare folder holds device/ and supports/ (each as ``nsd seismic`` writes one run) and the
top-level summary.json with ``"compare_supports": true`` and the ratios.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from nsd_core.device.params import ParameterError
from reports.style import GREY, LANDSCAPE, RED, fmt, new_figure, table, wrap_width

RUNS = {"device": ("with the device", {"color": "#1f4e9c", "linestyle": "-", "linewidth": 1.5}),
        "supports": ("supports alone", {"color": "#d95f02", "linestyle": "--", "linewidth": 1.3})}


def is_compare(folder) -> bool:
    root = Path(folder)
    return (root / "device" / "seismic.csv").is_file() and (root / "summary.json").is_file()


def read_table(path: Path) -> dict:
    """A JSON object from a regular file; anything else is one line, exit 2."""
    from nsd_core.common.files import read_regular_text
    try:
        s = json.loads(read_regular_text(path))
        if not isinstance(s, dict):
            raise ValueError("not a table")
        return s
    except (OSError, ValueError) as e:
        raise ParameterError(f"{path}: malformed ({' '.join(str(e).split())[:100]})") from None


def compare_plan(folder, read_runs) -> tuple[list, str]:
    """(file stem, figure function) per page and the footer's title for a --compare-supports folder;
    ``read_runs(folder)`` reads one run folder's CSVs (reports.seismic_report._runs)."""
    root = Path(folder)
    top = read_table(root / "summary.json")
    runs, stops, warnings = {}, {}, []
    for name in RUNS:
        if (root / name / "seismic.csv").is_file():
            runs[name] = read_runs(root / name)["semirecursive"]
            s = read_table(root / name / "summary.json") if (root / name / "summary.json").is_file() else {}
            if isinstance(s.get("stopped"), dict):
                stops[name] = s["stopped"]
            warnings += [f"{RUNS[name][0]}: {w}" for w in s.get("warnings", []) if isinstance(w, str)]
    g = top.get("ground") if isinstance(top.get("ground"), dict) else {}
    label = f"{g['set']}:{g['record']}" if "set" in g and "record" in g else g.get("kind", "run")
    plan = [(f"compare_{label.replace(':', '_')}", lambda: overlay_figure(label, runs, top.get("ratios"), stops,
                                                                                warnings))]
    return plan, f"NSD seismic report  |  {label}: with the device and on the supports alone"


def overlay_figure(label: str, runs: dict, ratios: dict | None, stops: dict, warnings=()):
    """Orbit and time histories of both runs overlaid, and the ratio table (with / without)."""
    fig = new_figure(LANDSCAPE, f"With and without the device: {label}",
                     "the same structure and ground, in-house engine; ratio = with the device / supports alone")
    ax = fig.add_axes([0.06, 0.40, 0.26, 0.47])
    for name, r in runs.items():
        ax.plot(r["x"] * 1e3, r["y"] * 1e3, label=RUNS[name][0], **RUNS[name][1])
    ax.set_aspect("equal", "datalim")
    ax.set(xlabel="x [mm]", ylabel="y [mm]", title="orbit of the plate relative to the base")
    ax.legend(loc="best")
    series = [("|u| [mm]", lambda r: np.hypot(r["x"], r["y"]) * 1e3),
              ("|a_abs| [m/s²]", lambda r: np.hypot(r["ax_abs"], r["ay_abs"])),
              ("|base shear| [kN]", lambda r: np.hypot(r["base_shear_x"], r["base_shear_y"]) / 1e3
               if "base_shear_x" in r.columns else np.full(len(r["t"]), np.nan))]
    if any("restrainer_F" in r.columns for r in runs.values()):
        series.append(("restrainer F [kN]", lambda r: r["restrainer_F"] / 1e3 if "restrainer_F" in r.columns
                       else np.zeros(len(r["t"]))))
    h = 0.52 / len(series)
    axes = []
    for i, (ylab, get) in enumerate(series):
        a = fig.add_axes([0.40, 0.88 - (i + 1) * h + 0.01, 0.57, h - 0.02], sharex=axes[0] if axes else None)
        for name, r in runs.items():
            a.plot(r["t"], get(r), **RUNS[name][1])
        a.set_ylabel(ylab)
        a.tick_params(labelbottom=i == len(series) - 1)
        axes.append(a)
    axes[-1].set_xlabel("t [s]")
    for name, s in stops.items():
        mark_stop(axes, s, f"{RUNS[name][0]} stopped")
    if ratios:
        rows = [[k, fmt(v.get("with_device"), 4), fmt(v.get("supports_alone"), 4), fmt(v.get("ratio"), 4),
                 str(v.get("what", ""))] for k, v in ratios.items()]
        table(fig, 0.31, [("quantity", 1.4, "l"), ("with the device", 0.8, "r"), ("supports alone", 0.8, "r"),
                          ("ratio", 0.6, "r"), ("what", 3.6, "l")], rows, fontsize=8.0, left=0.06, right=0.97)
    lines = [ln for w in warnings for ln in wrap_width(f"warning: {w}", 0.9 * LANDSCAPE[0] * 72, 7.5, indent="   ")]
    if len(lines) > 4:   # the room above the footer: the rest on the warnings page
        lines = lines[:3] + [f"   ... {len(warnings)} warnings in all: the warnings page lists every one"]
    for k, line in enumerate(lines):   # wrapped, never cut
        fig.text(0.06, 0.10 - 0.018 * k, line, color=RED, fontsize=7.5)
    return fig


def mark_stop(axes, stopped: dict, what: str = "run stopped") -> None:
    """A vertical line at the time the run was ended (exit 4), with its kind, on time axes."""
    t = stopped.get("t") if isinstance(stopped, dict) else None
    if not isinstance(t, (int, float)):
        return
    for a in axes:
        a.axvline(t, color=RED, lw=1.0, ls="-.")
    axes[0].text(t, 1.0, f" {what}: {stopped.get('kind', '')} at t = {t:.4g} s", color=RED, fontsize=7,
                 va="bottom", ha="right", transform=axes[0].get_xaxis_transform())


def with_stop_mark(make_figure, stopped: dict):
    """The figure ``make_figure()`` draws, with the stop time marked on its time axes (all but the
    first, which is the orbit), for a run the device's failure ended."""
    def draw():
        fig = make_figure()
        time_axes = [a for a in fig.axes if getattr(a, "_nsd_time", False)] or \
            [a for a in fig.axes[1:] if a.get_xlabel() in ("t [s]", "") and a.get_lines()]
        if time_axes:
            mark_stop(time_axes, stopped)
        text = "\n".join(wrap_width(f"the run stopped (exit 4): {stopped.get('reason', '')}", 0.9 * LANDSCAPE[0] * 72, 8))
        fig.text(0.5, 0.03, text, ha="center", va="bottom", fontsize=8, color=RED)   # wrapped, never cut
        return fig
    return draw


__all__ = ["is_compare", "compare_plan", "overlay_figure", "mark_stop", "with_stop_mark", "GREY"]
