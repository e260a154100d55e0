"""The report's warnings page of a seismic folder: what the runs' summaries warn of (the rules:
nsd_core.structure.seismic_warnings) — stroke exhausted or nearly, a supports-alone run beyond the
device's stroke, restrainer impacts, peaks on the last sample — one wrapped item per warning, in
front of the pages whose numbers they qualify. No warnings, no page."""
from __future__ import annotations

from reports.style import LANDSCAPE, RED, new_figure, wrap_width

SIZE = 8.5          # pt
LINE = 0.024        # figure fraction per line at SIZE
BOTTOM = 0.08       # leave the footer free


def collect(items) -> list[str]:
    """[(prefix, summary-like dict)] -> the warning texts, each with its prefix."""
    out = []
    for prefix, s in items:
        warnings = s.get("warnings") if isinstance(s, dict) else None
        for w in warnings if isinstance(warnings, list) else []:
            if isinstance(w, str) and w.strip():
                out.append(f"{prefix}{w}")
    return out


def warnings_figure(label: str, warnings: list[str], where: str = "summary.json"):
    """One page listing the warnings (cut, with the count left out and where they all are, when
    they do not fit)."""
    fig = new_figure(LANDSCAPE, f"Warnings: {label}",
                     "read these before the numbers: each says why a peak or a ratio on the following pages may "
                     "not mean what it seems")
    width = 0.88 * LANDSCAPE[0] * 72
    y, shown = 0.86, 0
    for w in warnings:
        lines = wrap_width(f"- {w}", width, SIZE, indent="   ")
        if y - LINE * len(lines) < BOTTOM + LINE:
            break
        for line in lines:
            fig.text(0.06, y, line, color=RED, fontsize=SIZE, va="top")
            y -= LINE
        y -= 0.4 * LINE
        shown += 1
    if shown < len(warnings):
        fig.text(0.06, y, f"... and {len(warnings) - shown} more warning(s): all of them are in {where}",
                 fontsize=SIZE, va="top")
    return fig


def warnings_pages(label: str, warnings: list[str], where: str = "summary.json") -> list:
    """[(file stem, figure function)]: the page, or nothing when there is no warning."""
    if not warnings:
        return []
    stem = "warnings_" + label.replace(":", "_").replace(" ", "_")
    return [(stem, lambda: warnings_figure(label, warnings, where))]
