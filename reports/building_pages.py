"""Report pages of the building above the isolation level (docs/building.md).

* ``nsd seismic --compare-building`` folders (fixed_base/, supports/, device/ and summary.json): the
  peak drift ratio and peak floor acceleration profiles over height for the three configurations
  (the plot isolation engineers know) and the ratio table;
* any seismic run whose columns hold floors: the floors' time histories per engine (X displacement
  relative to the ground, story drift, absolute acceleration) and, with more than one engine, each
  engine's difference from the in-house engine.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from nsd_core.device.params import ParameterError
from reports.seismic_compare import read_table
from reports.style import LANDSCAPE, fmt, new_figure, table

CONFIGS = {"fixed_base": ("fixed base", {"color": "#444444", "linestyle": ":", "marker": "s"}),
           "supports": ("isolated, supports alone", {"color": "#d95f02", "linestyle": "--", "marker": "o"}),
           "device": ("isolated, with the device", {"color": "#1f4e9c", "linestyle": "-", "marker": "^"})}
ENGINE_STYLE = {"semirecursive": {"color": "#1f4e9c", "linewidth": 1.4},
                "mujoco": {"color": "#d95f02", "linewidth": 1.0, "linestyle": "--"},
                "exudyn": {"color": "#1b9e77", "linewidth": 1.0, "linestyle": ":"}}


def is_building_compare(folder) -> bool:
    root = Path(folder)
    return (root / "fixed_base" / "seismic.csv").is_file() and (root / "summary.json").is_file()


def stories(run) -> int:
    n = 0
    while f"floor{n + 1}_x" in run.columns:
        n += 1
    return n


def compare_plan(folder, read_runs) -> tuple[list, str]:
    """(file stem, figure function) per page and the footer's title for a --compare-building folder."""
    root = Path(folder)
    top = read_table(root / "summary.json")
    summaries = {c: read_table(root / c / "summary.json") for c in CONFIGS if (root / c / "summary.json").is_file()}
    for c, s in summaries.items():
        if not isinstance(s.get("building"), dict):
            raise ParameterError(f"{root / c / 'summary.json'}: malformed (no building)")
    runs = {c: read_runs(root / c)["semirecursive"] for c in summaries if (root / c / "seismic.csv").is_file()}
    g = top.get("ground") if isinstance(top.get("ground"), dict) else {}
    label = f"{g['set']}:{g['record']}" if "set" in g and "record" in g else g.get("kind", "run")
    stem = label.replace(":", "_")
    plan = [(f"building_profiles_{stem}", lambda: profiles_figure(label, summaries, top.get("ratios") or [])),
            (f"building_histories_{stem}", lambda: configurations_figure(label, runs))]
    return plan, f"NSD seismic report  |  {label}: the building fixed-base and isolated"


def _levels(summary: dict) -> np.ndarray:
    h = summary["building"]["parameters"]["heights"]
    return np.concatenate([[0.0], np.cumsum(h)])


def profiles_figure(label: str, summaries: dict, ratios: list):
    """Peak drift ratio per story and peak floor acceleration per level over height; the ratio table."""
    fig = new_figure(LANDSCAPE, f"The building fixed-base and isolated: {label}",
                     "peak over the run, in-house engine; drift ratio = |drift| / story height (plan vector)")
    ax1 = fig.add_axes([0.07, 0.42, 0.38, 0.46])
    ax2 = fig.add_axes([0.56, 0.42, 0.38, 0.46])
    for c, s in summaries.items():
        name, style = CONFIGS[c]
        z = _levels(s)
        dr = [p["value"] for p in s["building"]["peak_drift_ratio"]]
        # a story's drift ratio drawn over its height (a step profile)
        ax1.plot(np.repeat(dr, 2), np.column_stack([z[:-1], z[1:]]).ravel(), label=name,
                 **{k: v for k, v in style.items() if k != "marker"})
        ax1.plot(dr, 0.5 * (z[1:] + z[:-1]), linestyle="none", marker=style["marker"], color=style["color"])
        slab = s["peak_absolute_acceleration"]["value"]
        acc = [slab] + [p["value"] for p in s["building"]["peak_floor_acceleration"]]
        ax2.plot(acc, z, label=name, **style)
    ax1.set_xlabel("peak drift ratio [-]")
    ax1.set_ylabel("height above the slab [m]")
    ax1.set_title("peak drift ratio per story")
    ax2.set_xlabel("peak |a_abs| [m/s^2]")
    ax2.set_title("peak floor acceleration (level 0: the slab)")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
        ax.legend(loc="best")
    n = max([r["index"] for r in ratios if isinstance(r.get("index"), int)] or [0])
    shown = set(shown_floors(n))   # a tall building's rows would run off the page: the floors drawn elsewhere
    kept = [r for r in ratios if not r.get("index") or r["index"] in shown]
    rows = [[r["quantity"] + (f" {r['index']}" if r.get("index") else ""), fmt(r["fixed_base"]), fmt(r["supports"]),
             fmt(r["device"]), fmt(r["supports_over_fixed"]), fmt(r["device_over_fixed"]),
             fmt(r["device_over_supports"])] for r in kept]
    if len(kept) < len(ratios):
        rows.append([f"(stories {', '.join(map(str, sorted(shown)))} of {n}; all in building_ratios.csv)"] + [""] * 6)
    table(fig, 0.33, [("quantity", 0.2, "l"), ("fixed base", 0.13, "r"), ("supports alone", 0.13, "r"),
                      ("with the device", 0.13, "r"), ("supports / fixed", 0.13, "r"), ("device / fixed", 0.13, "r"),
                      ("device / supports", 0.15, "r")], rows, fontsize=6.5)
    return fig


def configurations_figure(label: str, runs: dict):
    """Top floor's displacement relative to the ground and story 1's drift, X, per configuration."""
    fig = new_figure(LANDSCAPE, f"The building's response: {label}", "X components, in-house engine")
    if not runs:
        return fig
    n = min(stories(r) for r in runs.values())
    panels = [(f"floor{n}_x", f"floor {n} (top) x relative to the ground [m]"), ("drift1_x", "story 1 drift x [m]"),
              (f"floor{n}_ax_abs", f"floor {n} absolute acceleration x [m/s^2]")]
    for k, (col, title) in enumerate(panels):
        ax = fig.add_axes([0.08, 0.67 - 0.29 * k, 0.86, 0.22])
        for c, r in runs.items():
            name, style = CONFIGS[c]
            ax.plot(r["t"], r[col], label=name, color=style["color"], linestyle=style["linestyle"], linewidth=1.0)
        ax.set_title(title)
        ax.grid(alpha=0.3)
        if k == 0:
            ax.legend(loc="upper right")
    ax.set_xlabel("t [s]")
    return fig


FLOORS_SHOWN = 4  # floors drawn on the page (3 panels each): more would leave each panel too thin to read


def shown_floors(n: int) -> list[int]:
    """The floors the floors page draws: every one up to FLOORS_SHOWN, else the first, two between and
    the top (a 12-story building's 36 panels left no height for one: matplotlib refused the page)."""
    if n <= FLOORS_SHOWN:
        return list(range(1, n + 1))
    return sorted({1, *(round(1 + k * (n - 1) / (FLOORS_SHOWN - 1)) for k in range(1, FLOORS_SHOWN - 1)), n})


def floors_figure(title: str, runs: dict):
    """Every floor's X displacement, drift and absolute acceleration per engine, and each engine's
    difference from the in-house engine (the first run)."""
    names = list(runs)
    peers = len(names) > 1   # one engine alone: no difference panels (they would be empty)
    ref = runs[names[0]]
    n = stories(ref)
    shown = shown_floors(n)
    which = "" if len(shown) == n else f"; floors {', '.join(map(str, shown))} of {n}"
    fig = new_figure(LANDSCAPE, title, "X components" + ("; right: engine - in-house engine" if peers else
                                                          ", in-house engine") + which)
    cols = [("floor{}_x", "floor {}\nx [m]"), ("drift{}_x", "drift {}\nx [m]"), ("floor{}_ax_abs", "floor {}\na_abs x\n[m/s^2]")]
    height = 0.84 / (3 * len(shown))
    k = 0
    for i in shown:
        for col, text in cols:
            c = col.format(i)
            y0 = 0.9 - (k + 1) * height
            ax = fig.add_axes([0.1, y0 + 0.012, 0.39 if peers else 0.86, height - 0.024])
            axd = fig.add_axes([0.56, y0 + 0.012, 0.4, height - 0.024]) if peers else None
            for e in names:
                ax.plot(runs[e]["t"], runs[e][c], label=e, **ENGINE_STYLE.get(e, {}))
                if axd is not None and e != names[0] and len(runs[e]["t"]) == len(ref["t"]):
                    axd.plot(ref["t"], runs[e][c] - ref[c], label=e, **ENGINE_STYLE.get(e, {}))
            ax.set_ylabel(text.format(i), fontsize=6)
            if axd is not None:
                axd.set_ylabel("difference", fontsize=6)
            for a in [a for a in (ax, axd) if a is not None]:
                a.tick_params(labelsize=6, labelbottom=k == 3 * len(shown) - 1)  # time labels on the bottom row only:
                a.grid(alpha=0.3)                                         # each panel's scale sits in that gap
            if k == 3 * len(shown) - 1:
                for a in [a for a in (ax, axd) if a is not None]:
                    a.set_xlabel("t [s]", fontsize=6)
            if k == 0:  # above the first panel, over no data
                ax.legend(loc="lower right", bbox_to_anchor=(1.0, 1.15), ncol=len(names), fontsize=6, frameon=False)
            k += 1
    return fig
