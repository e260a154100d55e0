"""The direction study's page (``nsd polar``): X_max, K0, |K_min| and the loop area versus the drive's
azimuth psi, one curve per number of wires n = n_w = n_r, and each quantity's spread over the turn.

It answers "how many wires, and does direction matter?": a circle means the design responds the
same in every direction; petals show the directions it favours.
"""
from __future__ import annotations

import numpy as np

from reports.style import GREY, LANDSCAPE, fmt, new_figure

COLORS = ["#7570b3", "#1f4e9c", "#d95f02", "#1b9e77", "#e7298a", "#66a61e"]
PANELS = [("x_max", 1e3, "working range X_max [mm]"), ("k0", 1e-3, "initial stiffness K0 [kN/m]"),
          ("k_min", -1e-3, "most negative stiffness |K_min| [kN/m]"), ("loop_area", 1.0, "loop area [J]")]


def polar_figure(polar: dict):
    designs = polar["designs"]
    fig = new_figure(LANDSCAPE, "Direction study: does direction matter, and how many wires?",
                     f"quasi-static, n_w = n_r = n, drive along psi (0 = the first wire), every "
                     f"{fmt(polar['step_deg'])} deg; loop area and K_min at A = {fmt(polar['amplitude'] * 1e3)} mm. "
                     "A circle: the same in every direction.")
    for i, (key, scale, label) in enumerate(PANELS):
        ax = fig.add_axes([0.04 + 0.245 * i, 0.36, 0.2, 0.48], projection="polar")
        for j, (n, d) in enumerate(designs.items()):
            psi = np.radians(np.append(d["psi_deg"], d["psi_deg"][0]))
            v = scale * np.append(d[key], d[key][0])
            ax.plot(psi, v, color=COLORS[j % len(COLORS)], lw=1.4, label=f"n = {n}")
        lo = min(scale * min(d[key]) for d in designs.values())
        hi = max(scale * max(d[key]) for d in designs.values())
        pad = 0.1 * (hi - lo) if hi > lo else 0.05 * abs(hi) or 1.0
        ax.set_ylim(max(0.0, lo - 3 * pad) if lo > 0 else lo - pad, hi + pad)  # zoomed: spreads are small
        ax.set_title(label, fontsize=9, pad=14)
        ax.tick_params(labelsize=6.5)
        if i == 0:
            ax.legend(loc="upper left", bbox_to_anchor=(-0.25, 1.25), fontsize=7.5, frameon=False)
    # the spreads as a table: (max - min) / |mean| over the full turn, per design and quantity
    rows = [["n"] + [p[2].split(" [")[0] for p in PANELS] + ["peak force"]]
    for n, d in designs.items():
        rows.append([n] + [f"{100 * d['spread'][k]:.2f} %" for k, _, _ in PANELS] + [f"{100 * d['spread']['peak_force']:.2f} %"])
    y = 0.27
    fig.text(0.06, y + 0.035, "Spread over the turn, (max - min) / |mean|:", fontsize=9, weight="bold")
    for r, row in enumerate(rows):
        for c, cell in enumerate(row):
            fig.text(0.06 + (0.05 if c else 0) + 0.16 * max(c - 0, 0) * (1 if c else 0), y - 0.03 * r, cell,
                     fontsize=8.5, weight="bold" if r == 0 else "normal")
    fig.text(0.06, y - 0.03 * len(rows) - 0.02,
             "Reading: a design whose spreads are ~0 responds alike in every direction of the plane; the paper's "
             "guideline (multiples of 4 wires) predicts n = 4 and 8 symmetric about X and Y.", fontsize=8, color=GREY)
    return fig
