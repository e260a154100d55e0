"""The direction study's page (``nsd polar``): X_max, K0, K_min, the loop area and the peak force
versus the drive's azimuth psi, one curve per number of wires n = n_w = n_r.

It answers "how many wires, and does direction matter?" at a glance: each polar panel shows a
quantity divided by its mean over the turn (a circle of radius 1: the same in every direction;
petals: the directions the design favours), and the table beneath gives each design's mean and
spread, (max - min) / |mean| over the turn.
"""
from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from reports.style import GREY, LANDSCAPE, fmt, new_figure

COLORS = ["#7570b3", "#1f4e9c", "#d95f02", "#1b9e77", "#e7298a", "#66a61e"]
PANELS = [("x_max", 1e3, "X_max", "mm"), ("k0", 1e-3, "K0", "kN/m"), ("k_min", 1e-3, "K_min", "kN/m"),
          ("loop_area", 1.0, "loop area", "J"), ("peak_force", 1.0, "peak force", "N")]


def polar_figure(polar: dict):
    designs = polar["designs"]
    fig = new_figure(LANDSCAPE, "Direction study: does direction matter, and how many wires?",
                     f"quasi-static, n_w = n_r = n, drive along psi (0 = the first wire), every "
                     f"{fmt(polar['step_deg'])} deg; K_min, loop area and peak force at A = "
                     f"{fmt(polar['amplitude'] * 1e3)} mm.\nEach curve is divided by its mean over the turn: "
                     "a unit circle = the same in every direction.")
    for i, (key, _scale, name, _unit) in enumerate(PANELS):
        ax = fig.add_axes([0.035 + 0.197 * i, 0.45, 0.14, 0.34], projection="polar")
        lo, hi = 1.0, 1.0
        for j, (n, d) in enumerate(designs.items()):
            v = np.asarray(d[key], dtype=float)
            rel = v / v.mean() if v.mean() else v  # K_min < 0 too: its magnitude relative to the mean
            psi = np.radians(np.append(d["psi_deg"], d["psi_deg"][0]))
            ax.plot(psi, np.append(rel, rel[0]), color=COLORS[j % len(COLORS)], lw=1.4)
            lo, hi = min(lo, rel.min()), max(hi, rel.max())
        # a ratio below 0 (a quantity that changes sign over the turn) stays outside the centre: the
        # radial axis starts below the smallest value instead of at 0
        r0, top = min(0.0, lo - 0.1), max(1.3, hi + 0.05)
        ax.set_ylim(r0, top)
        ticks = sorted([1.0] + ([0.0] if r0 < 0 else [0.5]) + ([2.0] if top >= 2.0 else []))
        ax.set_yticks(ticks, [fmt(t) for t in ticks])   # a "0" ring: the centre lies below zero
        ax.set_xticks(np.radians([0, 90, 180, 270]), ["0°", "90°", "180°", "270°"])
        ax.set_title(f"{name} / its mean" + (f"\n(centre = {fmt(r0, 2)}: it changes sign)" if r0 < 0 else ""),
                     fontsize=9.5 if r0 >= 0 else 8.5, pad=16)
        ax.tick_params(labelsize=6.5, pad=1)
        ax.set_rlabel_position(112)
    fig.legend(handles=[Line2D([], [], color=COLORS[j % len(COLORS)], lw=1.6, label=f"n = {n}")
                        for j, n in enumerate(designs)], loc="upper center", bbox_to_anchor=(0.5, 0.905),
               ncol=len(designs), frameon=False, fontsize=9)
    top = 0.33
    fig.text(0.06, top + 0.04, "Mean over the turn (spread = (max - min) / |mean|):", fontsize=9.5, weight="bold")
    cols = [0.06] + [0.13 + 0.165 * i for i in range(len(PANELS))]
    head = ["n"] + [f"{name} [{unit}]" for _, _, name, unit in PANELS]
    for c, h in enumerate(head):
        fig.text(cols[c], top, h, fontsize=9, weight="bold")
    for r, (n, d) in enumerate(designs.items(), start=1):
        fig.text(cols[0], top - 0.032 * r, n, fontsize=9, color=COLORS[(r - 1) % len(COLORS)], weight="bold")
        for c, (key, scale, _, _) in enumerate(PANELS, start=1):
            mean = scale * float(np.mean(d[key]))
            fig.text(cols[c], top - 0.032 * r, f"{mean:.4g}  ({100 * d['spread'][key]:.1f} %)", fontsize=9)
    worst = {n: max(d["spread"].values()) for n, d in designs.items()}
    best = min(worst, key=worst.get)
    fig.text(0.06, top - 0.032 * (len(designs) + 1) - 0.02,
             "Reading: the smaller a design's spreads, the less the drive's direction matters.\nLargest spread per "
             "design: " + ", ".join(f"n = {n}: {100 * w:.1f} %" for n, w in worst.items())
             + f"; the most isotropic is n = {best}.", fontsize=8.5, color=GREY)
    return fig
