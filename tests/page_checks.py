"""What a reader of a report page would see wrong: a text that leaves the page
or lies on another text. Measured on the figure itself: every text artist the renderer draws (tick
labels of ticks outside the view excluded), its window extent after a draw."""
from __future__ import annotations


def _drawn_texts(fig):
    """(artist, window extent) of every non-empty text the renderer draws on ``fig``."""
    import matplotlib.text
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    tick_labels, drawn_ticks = set(), set()
    for ax in fig.findobj(lambda a: hasattr(a, "get_major_ticks") and hasattr(a, "_update_ticks")):
        for t in ax.majorTicks + ax.minorTicks:
            tick_labels.update((id(t.label1), id(t.label2)))
        for t in ax._update_ticks():
            drawn_ticks.update((id(t.label1), id(t.label2)))
    out = []
    for t in fig.findobj(matplotlib.text.Text):
        if not t.get_visible() or not t.get_text().strip() or (t.axes is not None and not t.axes.get_visible()):
            continue
        if id(t) in tick_labels and id(t) not in drawn_ticks:
            continue
        out.append((t, t.get_window_extent(renderer)))
    return out


def text_problems(fig, tol: float = 1.0, margin: float = 0.06) -> list[str]:
    """Texts closer than ``margin`` inches to the page's edge (the PDF's glyphs run a little wider
    than Agg's), and pairs of texts that overlap by more than ``tol`` pixels both ways."""
    page = fig.bbox
    m = margin * fig.dpi
    texts = _drawn_texts(fig)
    bad = [f"outside the page: {t.get_text()!r}" for t, b in texts
           if b.x0 < page.x0 + m or b.y0 < page.y0 + m or b.x1 > page.x1 - m or b.y1 > page.y1 - m]
    for i, (t, b) in enumerate(texts):
        for u, c in texts[i + 1:]:
            if min(b.x1, c.x1) - max(b.x0, c.x0) > tol and min(b.y1, c.y1) - max(b.y0, c.y0) > tol:
                bad.append(f"overlap: {t.get_text()!r} and {u.get_text()!r}")
    return bad


def figure_problems(source, only: tuple[str, ...] | None = None) -> dict[str, list[str]]:
    import matplotlib.pyplot as plt
    from reports import style
    from reports.build import source_plan
    plan, footer = source_plan(source)
    problems = {}
    with plt.rc_context(style.RC):
        for n, (stem, make) in enumerate(plan, start=1):
            if only is not None and stem not in only:
                continue
            fig = make()
            style.footer(fig, f"{footer}  |  page {n} of {len(plan)}")
            if fig.get_size_inches()[0] < fig.get_size_inches()[1]:
                problems.setdefault(stem, []).append("portrait page")
            found = text_problems(fig)
            if found:
                problems[stem] = problems.get(stem, []) + found
            plt.close(fig)
    return problems
