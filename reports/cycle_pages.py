"""The page of an ``nsd cycle`` folder (cycle.csv, summary.json): the force-displacement loop, drawn by
``nsd cycle`` itself (DIR/01_cycle_loop.png) and by ``nsd report --from DIR`` (PDF and PNG).

A line drive: F against u, every cycle thin and the steady (last) one bold, the stiffness regions of
the loading branch shaded (+ green, - red), X_max and the events marked. Any other path: the plate's
path and the force vector's components against x and y. The side column gives the summary's numbers
to 4 significant digits."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

from nsd_core.common.files import read_regular_text
from nsd_core.device.params import ParameterError
from nsd_core.device.results import last_cycle, read_csv

from reports import style

NEEDED = ("t", "u", "F", "x", "y", "F_x", "F_y")


def is_cycle(folder) -> bool:
    """An nsd cycle folder: its cycle.csv beside a summary.json that names the drive."""
    root = Path(folder)
    return (root / "cycle.csv").is_file() and (root / "summary.json").is_file()


def _load(root: Path) -> tuple[dict, object]:
    try:
        summary = json.loads(read_regular_text(root / "summary.json"))
    except (OSError, ValueError) as e:
        raise ParameterError(f"{root / 'summary.json'}: not readable JSON ({' '.join(str(e).split())[:120]})") from None
    if not isinstance(summary, dict) or not isinstance(summary.get("drive"), dict):
        raise ParameterError(f"{root / 'summary.json'}: malformed (no 'drive': not written by nsd cycle)")
    try:
        result = read_csv(root / "cycle.csv", "semirecursive")
    except (OSError, ValueError, IndexError) as e:
        raise ParameterError(f"{root / 'cycle.csv'}: not a readable cycle CSV ({' '.join(str(e).split())[:120]})") \
            from None
    missing = [c for c in NEEDED if c not in result.columns]
    if missing or len(result["t"]) < 2:
        raise ParameterError(f"{root / 'cycle.csv'}: malformed (" + (f"no column {missing[0]!r})" if missing
                                                                     else "fewer than two samples)"))
    return summary, result


def cycle_plan(folder) -> tuple[list[tuple[str, Callable]], str]:
    """[(stem, figure)] and the footer's title; everything read and checked first (ParameterError)."""
    summary, result = _load(Path(folder))
    float(summary["drive"]["frequency"])  # a damaged field is found here, before anything is written
    return [("cycle_loop", lambda: cycle_figure(summary, result))], "NSD drive cycle (nsd cycle)"


def _mm(v: float) -> str:
    """metres as mm to 0.01 mm, never '-0.00'."""
    return f"{round(v * 1e3, 2) + 0.0:.2f}"


def _side_lines(summary: dict) -> list[str]:
    d = summary["drive"]
    f4 = lambda v, unit="": "-" if v is None else f"{style.fmt(v, 4)} {unit}".rstrip()  # noqa: E731
    lines = [f"path {d.get('path', 'line')}", f"A = {f4(d.get('amplitude', 0) * 1e3, 'mm')}",
             f"f = {f4(d.get('frequency'), 'Hz')}", f"cycles = {d.get('cycles', '-')}", "",
             f"peak |F| = {f4(summary.get('peak_force'), 'N')}", f"loop area = {f4(summary.get('loop_area'), 'J')}"]
    if "initial_stiffness" in summary:
        lines.append(f"K0 = {f4(summary['initial_stiffness'] / 1e3, 'kN/m')}")
    if summary.get("x_max") is not None:
        lines.append(f"X_max = {f4(summary['x_max'] * 1e3, 'mm')}")
    regions = summary.get("stiffness_regions") or []
    if regions:
        lines += ["", "stiffness regions (loading):"]
        lines += [f" {r['sign']} {_mm(r['from'])} to {_mm(r['to'])} mm, mean {f4(r['mean_stiffness'] / 1e3)} kN/m"
                  for r in regions]
    if summary.get("outside_working_range"):
        lines += ["", "outside the working range:", " the ropes went slack"]
    return lines


def cycle_figure(summary: dict, result):
    d = summary["drive"]
    line = d.get("path", "line") == "line"
    fig = style.new_figure(title="Force-displacement loop (nsd cycle)",
                           subtitle="every cycle thin, the steady (last) one bold" +
                           ("; loading branch's stiffness regions shaded (+ green, - red)" if line else ""))
    top = fig._nsd_top
    steady = last_cycle(result["t"], float(d["frequency"]))
    if line:
        axes = [(fig.add_axes([0.07, 0.09, 0.62, top - 0.14]), "u", "F", "u [mm]", "F [N]")]
    else:
        axes = [(fig.add_axes([0.06, 0.09, 0.17, top - 0.14]), "x", "y", "x [mm]", "y [mm]"),
                (fig.add_axes([0.30, 0.09, 0.16, top - 0.14]), "x", "F_x", "x [mm]", "F_x [N]"),
                (fig.add_axes([0.53, 0.09, 0.16, top - 0.14]), "y", "F_y", "y [mm]", "F_y [N]")]
    s = style.style("semirecursive")
    for ax, xc, yc, xl, yl in axes:
        x, y = result[xc] * 1e3, result[yc] * (1e3 if yc == "y" else 1.0)
        ax.plot(x, y, color=s["color"], lw=0.6, alpha=0.35)
        ax.plot(x[steady], y[steady], color=s["color"], lw=1.6, label="steady cycle")
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
    if line:
        ax = axes[0][0]
        for r in summary.get("stiffness_regions") or []:
            ax.axvspan(r["from"] * 1e3, r["to"] * 1e3, color=style.SHADE[r["sign"]], alpha=0.6, lw=0, zorder=0)
        if summary.get("x_max") is not None:
            ax.axvline(summary["x_max"] * 1e3, color=style.GREY, ls=style.LIMIT_LS, lw=0.9)
            ax.text(summary["x_max"] * 1e3, 0.02, " X_max", transform=ax.get_xaxis_transform(), fontsize=7,
                    color=style.GREY, ha="right", va="bottom", rotation=90)
        ax.legend(loc="upper left")
    side = _side_lines(summary)
    width = (0.97 - 0.73) * style.LANDSCAPE[0] * 72
    wrapped = [w for ln in side for w in (style.wrap_width(ln, width, 8.0) or [""])]
    fig.text(0.73, top - 0.01, "\n".join(wrapped), ha="left", va="top", fontsize=8.0, family="DejaVu Sans")
    return fig

