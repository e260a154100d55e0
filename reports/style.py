"""Shared look of the validation report: one colour and line style per engine, page sizes, fonts,
and a plain text-table renderer that never lets a cell run into its neighbour."""
from __future__ import annotations

import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# One fixed map for every figure: the reference is solid and drawn first, the others dashed/dotted,
# so curves that agree to the line width stay distinguishable.
ENGINE_STYLE = {
    "semirecursive": {"color": "#1f4e9c", "ls": "-", "lw": 1.8},
    "mujoco": {"color": "#d95f02", "ls": "--", "lw": 1.3},
    "exudyn": {"color": "#1b9e77", "ls": ":", "lw": 1.6},
}
_EXTRA = ["#7570b3", "#e7298a", "#66a61e", "#a6761d"]
RED, GREEN, ORANGE, GREY = "#c0001a", "#137a2a", "#b35c00", "#555555"
PORTRAIT, LANDSCAPE = (8.27, 11.69), (11.69, 8.27)  # A4, inches
SHADE = {"+": "#cfe8cf", "-": "#f6d3d3"}            # positive / negative stiffness regions

RC = {"font.size": 8.5, "axes.titlesize": 9.5, "axes.labelsize": 8.5, "legend.fontsize": 7.5,
      "xtick.labelsize": 7.5, "ytick.labelsize": 7.5, "pdf.fonttype": 42, "ps.fonttype": 42,
      "axes.grid": True, "grid.alpha": 0.3, "grid.linewidth": 0.5, "figure.dpi": 100,
      "savefig.dpi": 130, "axes.formatter.useoffset": False}


def style(engine: str) -> dict:
    if engine in ENGINE_STYLE:
        s = ENGINE_STYLE[engine]
    else:
        s = {"color": _EXTRA[sum(map(ord, engine)) % len(_EXTRA)], "ls": "-.", "lw": 1.3}
    return {"color": s["color"], "linestyle": s["ls"], "linewidth": s["lw"]}


def color(engine: str) -> str:
    return style(engine)["color"]


def new_figure(size=LANDSCAPE, title: str | None = None, subtitle: str | None = None):
    fig = plt.figure(figsize=size)
    if title:
        fig.text(0.5, 0.975, title, ha="center", va="top", fontsize=13, weight="bold")
    if subtitle:
        fig.text(0.5, 0.945, subtitle, ha="center", va="top", fontsize=8.5, color=GREY)
    return fig


def footer(fig, text: str) -> None:
    fig.text(0.5, 0.012, text, ha="center", va="bottom", fontsize=7, color=GREY)


def no_data(ax, text: str) -> None:
    ax.text(0.5, 0.5, "\n".join(textwrap.wrap(text, 50)), transform=ax.transAxes, ha="center", va="center",
            fontsize=8, color=RED)
    ax.set_xticks([])
    ax.set_yticks([])
    ax.grid(False)


def fit(text: str, chars: int) -> str:
    """Shorten ``text`` to ``chars`` characters with an ellipsis."""
    text = str(text)
    return text if len(text) <= chars else text[: max(chars - 1, 1)] + "\u2026"


def table(fig, top: float, columns: list[tuple[str, float, str]], rows: list[list[str]],
          colors: list[list[str | None]] | None = None, fontsize: float = 7.0, left: float = 0.06,
          right: float = 0.94, header_color: str = "#e6e6e6") -> float:
    """Draw rows of strings as a table in figure coordinates; returns the y below the last row.

    ``columns``: (header, relative width, alignment 'l'/'r'/'c'). Cells are cut to what fits their
    column (estimated from the font size), so no text crosses into the next column.
    """
    w_in, h_in = fig.get_size_inches()
    row_h = fontsize * 1.55 / 72 / h_in
    total = sum(c[1] for c in columns)
    span = right - left
    xs, x = [], left
    for _, w, _ in columns:
        xs.append((x, x + span * w / total))
        x += span * w / total
    pad = 0.004
    cap = [max(int((b - a - 2 * pad) * w_in * 72 / (0.53 * fontsize)), 2) for a, b in xs]
    y = top
    fig.patches.append(matplotlib.patches.Rectangle((left, y - row_h), span, row_h, transform=fig.transFigure,
                                                    facecolor=header_color, edgecolor="none", zorder=0))
    for i, row in enumerate([[c[0] for c in columns]] + rows):
        yc = y - row_h / 2
        for j, cell in enumerate(row):
            a, b = xs[j]
            al = columns[j][2]
            xt = {"l": a + pad, "r": b - pad, "c": (a + b) / 2}[al]
            col = colors[i - 1][j] if (colors and i > 0 and colors[i - 1][j]) else "black"
            fig.text(xt, yc, fit(cell, cap[j]), ha={"l": "left", "r": "right", "c": "center"}[al], va="center",
                     fontsize=fontsize, color=col, weight="bold" if i == 0 or col == RED else "normal")
        if i > 0 and i % 2 == 0:
            fig.patches.append(matplotlib.patches.Rectangle((left, y - row_h), span, row_h,
                                                            transform=fig.transFigure, facecolor="#f5f5f5",
                                                            edgecolor="none", zorder=0))
        y -= row_h
    return y


def rows_per_page(top: float, bottom: float, fontsize: float = 7.0, height_in: float = PORTRAIT[1]) -> int:
    return max(int((top - bottom) / (fontsize * 1.55 / 72 / height_in)) - 1, 1)


def fmt(v, digits: int = 3) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, (int, float)):
        if v == 0:
            return "0"
        if 1e-3 <= abs(v) < 1e5:
            return f"{v:.{digits}g}"
        return f"{v:.{max(digits - 1, 1)}e}"
    return str(v)
