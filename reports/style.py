"""Shared look of the validation report: one colour and line style per engine, page sizes, fonts,
and a plain text-table renderer that never lets a cell run into its neighbour."""
from __future__ import annotations

import functools
import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.font_manager import FontProperties  # noqa: E402

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


# Series that must be told apart (one per record): ten hues far apart (matplotlib's tab10), then the
# same hues dashed, dotted, dash-dotted: no two of the first 40 share colour and line style.
DISTINCT = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22",
            "#17becf"]
DISTINCT_LS = ["-", "--", ":", "-."]


def distinct(j: int) -> dict:
    """Colour and line style of series j (0-based) of many that must be told apart."""
    return {"color": DISTINCT[j % len(DISTINCT)], "linestyle": DISTINCT_LS[(j // len(DISTINCT)) % len(DISTINCT_LS)]}


def style(engine: str) -> dict:
    if engine in ENGINE_STYLE:
        s = ENGINE_STYLE[engine]
    else:
        s = {"color": _EXTRA[sum(map(ord, engine)) % len(_EXTRA)], "ls": "-.", "lw": 1.3}
    return {"color": s["color"], "linestyle": s["ls"], "linewidth": s["lw"]}


def color(engine: str) -> str:
    return style(engine)["color"]


def new_figure(size=LANDSCAPE, title: str | None = None, subtitle: str | None = None):
    """A page; the subtitle wraps to the page's width. ``fig._nsd_top``: the y below the headings."""
    fig = plt.figure(figsize=size)
    fig._nsd_top = 0.95
    if title:
        fig.text(0.5, 0.975, title, ha="center", va="top", fontsize=13, weight="bold")
    if subtitle:
        lines = [ln for part in subtitle.split("\n") for ln in wrap_width(part, 0.92 * size[0] * 72, 8.5)]
        fig.text(0.5, 0.945, "\n".join(lines), ha="center", va="top", fontsize=8.5, color=GREY)
        fig._nsd_top = 0.945 - len(lines) * 1.2 * 8.5 / 72 / size[1] - 0.004
    return fig


def footer(fig, text: str) -> None:
    fig.text(0.5, 0.012, text, ha="center", va="bottom", fontsize=7, color=GREY)


def no_data(ax, text: str) -> None:
    ax.text(0.5, 0.5, "\n".join(textwrap.wrap(text, 50)), transform=ax.transAxes, ha="center", va="center",
            fontsize=8, color=RED)
    ax.set_xticks([])
    ax.set_yticks([])
    ax.grid(False)


CHAR = 0.6  # a safe average glyph width of DejaVu Sans, in units of the font size


@functools.lru_cache(maxsize=20000)
def text_width(text: str, size: float, bold: bool = False) -> float:
    """Width of ``text`` set in the report's font [pt], measured by the Agg renderer."""
    global _RENDERER
    if _RENDERER is None:
        from matplotlib.backends.backend_agg import RendererAgg
        _RENDERER = RendererAgg(10, 10, 720)  # fine pixels: hinting at 72 dpi understates widths by ~3 %
    prop = FontProperties(size=size, weight="bold" if bold else "normal")
    return _RENDERER.get_text_width_height_descent(text, prop, ismath=False)[0] * 0.1 * 1.03


_RENDERER = None


def fit_width(text: str, width: float, size: float, bold: bool = False) -> str:
    """``text`` shortened with an ellipsis until it is at most ``width`` points wide."""
    text = str(text)
    if text_width(text, size, bold) <= width:
        return text
    lo, hi = 0, len(text)
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if text_width(text[:mid] + "\u2026", size, bold) <= width:
            lo = mid
        else:
            hi = mid - 1
    return text[:lo] + "\u2026"


def wrap_width(text: str, width: float, size: float, bold: bool = False, indent: str = "") -> list[str]:
    """Greedy word wrap of ``text`` to lines at most ``width`` points wide; continuation lines start
    with ``indent``; words longer than a line are split."""
    lines: list[str] = []
    for para in str(text).split("\n"):
        if not para.startswith(" ") and text_width(para, size, bold) <= width:
            lines.append(para)   # what the loop below makes of it: a text's width grows as it grows
            continue
        line = ""
        for word in para.split(" "):
            cand = f"{line} {word}" if line.strip() else line + word
            if text_width(cand, size, bold) <= width:
                line = cand
                continue
            if line.strip():
                lines.append(line)
                line = indent
            word = line + word
            while text_width(word, size, bold) > width and len(word) > len(indent) + 1:
                cut = max(len(fit_width(word, width, size, bold)) - 1, len(indent) + 1)
                lines.append(word[:cut])
                word = indent + word[cut:]
            line = word
        lines.append(line)
    return lines


def _spans(fig, columns, left, right):
    total = sum(c[1] for c in columns)
    xs, x = [], left
    for _, w, _ in columns:
        xs.append((x, x + (right - left) * w / total))
        x += (right - left) * w / total
    return xs


def widths(fig, columns, left: float = 0.06, right: float = 0.94, pad: float = 0.004) -> list[float]:
    """Usable width of each column [pt]."""
    w_in = fig.get_size_inches()[0] if fig is not None else LANDSCAPE[0]
    return [(b - a - 2 * pad) * w_in * 72 for a, b in _spans(fig, columns, left, right)]


def natural(columns, rows, flex: int = -1, fontsize: float = 7.0, total: float = 0.88 * LANDSCAPE[0] * 72):
    """Columns re-sized to their content (measured; header lines in bold), column ``flex`` taking
    what is left of ``total`` points (it wraps or cuts)."""
    out = []
    for j, (head, w, al) in enumerate(columns):
        cells = [str(r[j]) for r in rows] if rows else []
        nat = max([text_width(h, fontsize, True) for h in head.split("\n")] +
                  [text_width(c, fontsize) for c in cells]) + 8
        out.append([head, nat, al])
    k = flex % len(columns)
    out[k][1] = max(total - sum(c[1] for i, c in enumerate(out) if i != k), 40.0)
    return [tuple(c) for c in out]


def fit_columns(columns, rows, fontsize: float = 7.0, total: float = 0.88 * LANDSCAPE[0] * 72, short: float = 110.0):
    """Columns sized to their content (measured, headers in bold) within ``total`` points: columns
    narrower than ``short`` keep their natural width; the wider ones share what is left in proportion
    to their natural widths (their cells then wrap, see ``wrap_rows``), never shortened."""
    nat, heads = [], []
    for j, (head, _, al) in enumerate(columns):
        cells = [str(r[j]) for r in rows]
        heads.append(max(text_width(h, fontsize, True) for h in head.split("\n")) + 8)   # headers never wrap
        nat.append(max([heads[-1]] + [text_width(c, fontsize) + 8 for c in cells]))
    if sum(nat) > total:
        long_ = [j for j, w in enumerate(nat) if w > short]
        room = total - sum(w for j, w in enumerate(nat) if j not in long_)
        want = sum(nat[j] for j in long_)
        nat = [max(room * w / want, 60.0, heads[j]) if j in long_ else w for j, w in enumerate(nat)]
    return [(head, w, al) for (head, _, al), w in zip(columns, nat)]


def wrap_rows(columns, rows, colors=None, fontsize: float = 7.0, fig=None, left: float = 0.06,
              right: float = 0.94):
    """Split cells too long for their column over several physical rows. Returns (rows, colors,
    stripe) where stripe[i] is the logical row a physical row belongs to (for the zebra shading)."""
    ws = widths(fig, columns, left, right)
    out, out_c, stripe = [], [], []
    for i, row in enumerate(rows):
        parts = [wrap_width(str(cell), ws[j], fontsize) or [""] for j, cell in enumerate(row)]
        for k in range(max(len(p) for p in parts)):
            out.append([p[k] if k < len(p) else "" for p in parts])
            out_c.append(colors[i] if colors else [None] * len(row))
            stripe.append(i)
    return out, out_c, stripe


def table(fig, top: float, columns: list[tuple[str, float, str]], rows: list[list[str]],
          colors: list[list[str | None]] | None = None, fontsize: float = 7.0, left: float = 0.06,
          right: float = 0.94, header_color: str = "#e6e6e6", stripe: list[int] | None = None) -> float:
    """Draw rows of strings as a table in figure coordinates; returns the y below the last row.

    ``columns``: (header, relative width, alignment 'l'/'r'/'c'); a header may hold a line break.
    Cells are drawn whole, never shortened: size the columns with ``natural`` and wrap
    long cells with ``wrap_rows`` first (tests/test_report.py checks that no two texts overlap).
    """
    h_in = fig.get_size_inches()[1]
    row_h = fontsize * 1.55 / 72 / h_in
    xs = _spans(fig, columns, left, right)
    pad = 0.004
    ws = widths(fig, columns, left, right, pad)
    head_lines = max(c[0].count("\n") + 1 for c in columns)
    stripe = stripe if stripe is not None else list(range(len(rows)))
    y = top
    hh = row_h * (1 + 0.85 * (head_lines - 1))
    fig.patches.append(matplotlib.patches.Rectangle((left, y - hh), right - left, hh, transform=fig.transFigure,
                                                    facecolor=header_color, edgecolor="none", zorder=0))
    for j, (head, _, al) in enumerate(columns):
        a, b = xs[j]
        xt = {"l": a + pad, "r": b - pad, "c": (a + b) / 2}[al]
        fig.text(xt, y - hh / 2, head,
                 ha={"l": "left", "r": "right", "c": "center"}[al], va="center", fontsize=fontsize, weight="bold",
                 linespacing=1.1)
    y -= hh
    for i, row in enumerate(rows):
        if stripe[i] % 2 == 1:
            fig.patches.append(matplotlib.patches.Rectangle((left, y - row_h), right - left, row_h,
                                                            transform=fig.transFigure, facecolor="#f3f3f3",
                                                            edgecolor="none", zorder=0))
        for j, cell in enumerate(row):
            a, b = xs[j]
            al = columns[j][2]
            xt = {"l": a + pad, "r": b - pad, "c": (a + b) / 2}[al]
            col = colors[i][j] if (colors and colors[i][j]) else "black"
            bold = col == RED
            fig.text(xt, y - row_h / 2, str(cell),
                     ha={"l": "left", "r": "right", "c": "center"}[al], va="center", fontsize=fontsize, color=col,
                     weight="bold" if bold else "normal")
        y -= row_h
    return y


def rows_per_page(top: float, bottom: float, fontsize: float = 7.0, height_in: float = LANDSCAPE[1]) -> int:
    return max(int((top - bottom) / (fontsize * 1.55 / 72 / height_in)) - 1, 1)


def fmt_full(v) -> str:
    """A number in full: the shortest text that reads back as the same double (None: "none")."""
    if v is None:
        return "none"
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return str(v)
    if isinstance(v, int):
        return str(v)
    text = repr(float(v))   # Python's shortest round-trip text
    return text[:-2] if text.endswith(".0") else text


def fmt(v, digits: int = 3) -> str:
    """A number as a reader wants it: 3 significant digits, plain between 1e-3 and 1e5, else 1.2e-07."""
    if v is None:
        return "-"
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return str(v)
    if v != v or v in (float("inf"), float("-inf")):
        return str(v)
    if v == 0:
        return "0"
    if 1e-3 <= abs(v) < 1e5:
        text = f"{v:.{digits}g}"
        return f"{v:.0f}" if "e" in text else text
    return f"{v:.{max(digits - 1, 1)}e}"


LIMIT_LS = (0, (1, 2))   # limit lines: thin dotted, a style no data series uses


def limit_lines(ax, limits: dict, unit: str = "", x: float = 0.99, ha: str = "right", fontsize: float = 6.5) -> None:
    """Horizontal limit lines, named in their panel: ``limits`` is {name: (value, colour)}. Values
    close on the axis (within 3x on a log axis, 8 % of the range on a linear one) share one label
    above the highest of them ("limits: a 7.1e-05, b 7.9e-05"), so labels never overprint."""
    items = sorted((float(v), name, col) for name, (v, col) in limits.items() if v)
    if not items:
        return
    log = ax.get_yscale() == "log"
    span = (items[-1][0] - items[0][0]) or abs(items[-1][0]) or 1.0
    clusters: list[list] = [[items[0]]]
    for it in items[1:]:
        last = clusters[-1][-1][0]
        if (it[0] / last < 3.0) if log and last > 0 else (it[0] - last) < 0.08 * span:
            clusters[-1].append(it)
        else:
            clusters.append([it])
    u = f" {unit}" if unit else ""
    for cl in clusters:
        for value, _, col in cl:
            ax.axhline(value, color=col, ls=LIMIT_LS, lw=0.9)
        cols = {c for _, _, c in cl}
        col = cl[0][2] if len(cols) == 1 else GREY
        if len(cl) == 1:
            label = f"{cl[0][1]} limit {fmt(cl[0][0], 2)}{u}"
        elif len({v for v, _, _ in cl}) == 1:
            label = f"{', '.join(n for _, n, _ in cl)} limit {fmt(cl[0][0], 2)}{u}"
        else:
            label = "limits: " + ", ".join(f"{n} {fmt(v, 2)}{u}" for v, n, _ in cl)
        # above the highest line of the cluster, or below the lowest where that is near the panel's top
        top = ax.transAxes.inverted().transform(ax.transData.transform((1.0, cl[-1][0])))[1]
        y, va = (cl[0][0], "top") if top > 0.85 else (cl[-1][0], "bottom")
        ax.annotate(label, (x, y), xycoords=ax.get_yaxis_transform(), xytext=(0, -2 if va == "top" else 2),
                    textcoords="offset points", ha=ha, va=va, fontsize=fontsize, color=col,
                    bbox=dict(fc="white", ec="none", alpha=0.85, pad=0.4))   # no line strikes it through
