"""Report page "What this gate can see": the detection-power table of ``nsd compare --power``."""
from __future__ import annotations

from comparisons.power import threshold_text

from .style import GREEN, LANDSCAPE, RED, fmt, new_figure, table, wrap_width

FS = 7.0


def power_figure(data):
    """One portrait page: per injected error, whether the gate failed, by which engine and metric."""
    p = data.power
    fig = new_figure(LANDSCAPE, title="What this gate can see",
                     subtitle="small modelling errors injected into one engine's own model, one at a time")
    cases = ", ".join(c["name"] for c in p.get("cases", []))
    intro = (f"Each error below was put into the model of {' and '.join(p.get('engines', []))} only (never into the "
             f"reference or the shared force laws) and the engine was run on {cases} with its default settings; "
             "the gate then measured it against the unperturbed in-house model with its default limits. "
             "'seen' means at least one gated metric exceeded its limit in at least one case; 'value/limit' is the "
             "largest ratio over engines, cases and metrics, 'metric' the one that gave it, 'weaker engine' the largest "
             "ratio of the engine that saw it least. An error not seen at its "
             "listed size was tried 10x and 100x larger: 'smallest seen' says at which size the gate first failed. "
             "'threshold ~' is the listed size divided by value/limit: the error of that kind the gate would just "
             "see, a linear estimate (small errors move the metrics in proportion), not a measurement.")
    y = 0.90
    for line in wrap_width(intro, 0.88 * LANDSCAPE[0] * 72, 8.0):
        fig.text(0.06, y, line, fontsize=8.0, va="top")
        y -= 1.45 * 8.0 / 72 / LANDSCAPE[1]
    cols = [("injected error", 3.2, "l"), ("seen", 0.7, "c"), ("by engine", 1.6, "l"), ("metric", 2.0, "l"),
            ("value/\nlimit", 1.1, "r"), ("weaker\nengine", 1.1, "r"), ("smallest\nseen", 1.2, "r"),
            ("threshold\n~", 1.3, "r")]
    rows, colors = [], []
    for t in p["table"]:
        small = "-" if t["smallest_seen_scale"] is None else ("as listed" if t["smallest_seen_scale"] == 1
                                                              else f"{t['smallest_seen_scale']:g}x listed")
        rows.append([t["injection"], "yes" if t["seen_at_nominal"] else "NO", ", ".join(t["engines_seeing"]) or "-",
                     t["best_metric"] or "-", fmt(t["best_ratio"], 3) if t["best_ratio"] is not None else "-",
                     fmt(t.get("weakest_engine_ratio"), 3), small,
                     threshold_text(t)])
        c = GREEN if t["seen_at_nominal"] else RED
        colors.append([None, c, None, None, None, None, None, None])
    y = table(fig, y - 0.01, cols, rows, colors, fontsize=FS)
    seen = sum(t["seen_at_nominal"] for t in p["table"])
    fig.text(0.06, y - 0.015, f"{seen} of {len(p['table'])} injected errors fail the default gate at their listed size "
             f"({p.get('wall_time', 0):.0f} s).", fontsize=8.0, va="top", weight="bold")
    return fig
