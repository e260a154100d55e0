"""Report pages of an incremental dynamic analysis (``nsd ida --out DIR``; docs/ida.md):

- the IDA curves: intensity against peak |u| (or, for a drift limit, the peak story drift ratio) per record,
  with the device and on the supports alone,
  the limit marked (runs stopped by the rod's length drawn at the rod's length);
- the fragility: each record's limit intensity as an empirical distribution and the fitted lognormal
  per configuration (median, dispersion, censored records named);
- the cross-check: the record closest to the median re-run in MuJoCo and Exudyn (with the device,
  the seismic response page) and against the exact linear solution (supports alone), with the
  differences.

Everything is read and checked before anything is written (ParameterError, one line).
"""
from __future__ import annotations

import csv
import io
import json
import textwrap
from pathlib import Path
from typing import Callable

import numpy as np

from nsd_core.common.files import read_regular_text
from nsd_core.device.params import ParameterError
from nsd_core.device.results import read_csv
from reports.style import GREY, LANDSCAPE, distinct, fmt, new_figure, no_data, wrap_width

CONFIG_STYLE = {"device": ("with the device", "#1f4e9c"), "nodevice": ("supports alone", "#d95f02")}


def is_ida(folder) -> bool:
    return (Path(folder) / "ida.json").is_file()


def _num(v: str):
    return float(v) if v not in ("", None) else None


CSV_NEEDS = ("record", "device", "im [m/s^2]", "peak_u [m]", "limit_reached")  # ida.csv's columns the pages read


def load_ida(folder) -> tuple[dict, dict, list[dict]]:
    """(ida.json, fragility.json, ida.csv rows), checked."""
    root = Path(folder)
    try:  # regular files only (a FIFO would block), read whole; NUL bytes or a damaged field: one line
        index = json.loads(read_regular_text(root / "ida.json", "ida.json"))
        frag = json.loads(read_regular_text(root / "fragility.json", "fragility.json"))
        reader = csv.DictReader(io.StringIO(read_regular_text(root / "ida.csv", "ida.csv"), newline=""))
        missing = [c for c in CSV_NEEDS if c not in (reader.fieldnames or [])]
        if missing:  # a truncated or foreign file: no rows to draw is no report
            raise ValueError(f"ida.csv has no column {missing[0]!r}")
        rows = list(reader)
        for i, r in enumerate(rows):   # a row cut short or run on (NUL bytes, a truncated copy): one line
            if None in r or None in r.values():
                raise ValueError(f"ida.csv line {i + 2}: not one value per column of its header")
        index["traces"], frag["configurations"]  # noqa: B018 - the keys the pages need
        for r in rows:
            r["im"], r["peak_u"] = _num(r["im [m/s^2]"]), _num(r["peak_u [m]"])
            r["peak_drift_ratio"] = _num(r.get("peak_drift_ratio [-]"))   # older folders lack the column
    except (OSError, ValueError, KeyError, TypeError, AttributeError, csv.Error) as e:
        raise ParameterError(f"{root}: not a readable nsd ida folder ({' '.join(str(e).split())[:120]})") from None
    return index, frag, rows


def ida_curves_figure(index: dict, rows: list[dict]):
    fig = new_figure(LANDSCAPE, f"Incremental dynamic analysis: record set {index.get('set')}",
                     f"IM = {_im_text(index)}; filled: limit reached; X at the right edge: the run stopped "
                     "(rod's length or wire strain)")
    key, unit, xlabel, limit_u = _edp(index)   # the response the limit reads: |u| [mm], or the drift ratio [%]
    for k, (name, (label, _)) in enumerate(CONFIG_STYLE.items()):
        ax = fig.add_axes([0.07 + k * 0.47, 0.1, 0.42, 0.75])
        mine = [r for r in rows if (r["device"] == "yes") == (name == "device")]
        if not mine:
            no_data(ax, "no runs")
            continue
        finite = [r[key] for r in mine if r[key] is not None]
        right = max(finite + [limit_u or 0.0]) * 1.15 if finite else 0.03
        for j, rid in enumerate(sorted({int(r["record"]) for r in rows})):   # one style per record, both panels
            rr = sorted((r for r in mine if int(r["record"]) == rid), key=lambda r: r["im"])
            if not rr:
                continue
            line = distinct(j)
            col = line["color"]
            ok = [r for r in rr if r[key] is not None]
            ax.plot([0.0] + [r[key] * unit for r in ok], [0.0] + [r["im"] for r in ok], lw=1.1, label=str(rid), **line)
            for r in rr:
                x = r[key] * unit if r[key] is not None else right * unit
                reached = r["limit_reached"] == "yes"
                ax.plot(x, r["im"], "X" if r[key] is None else "o", color=col, ms=5,
                        mfc=col if reached else "white")
        if limit_u:
            ax.axvline(limit_u * unit, color="#c0001a", lw=1, ls="--", label="limit")
        ax.set(xlabel=xlabel, ylabel=f"IM [{index.get('measure', {}).get('unit', 'm/s^2')}]",
               title=label, xlim=(0, right * unit * 1.03))
        ax.legend(loc="lower right", ncol=2, fontsize=6, title="record")
    return fig


def fragility_figure(index: dict, frag: dict):
    from nsd_core.study.fragility import fragility_curve
    fig = new_figure(LANDSCAPE, f"Fragility: {index.get('limit')}",
                     "steps: the records' limit intensities (empirical); curves: lognormal, maximum likelihood "
                     "(records that never reached the limit right-censored)")
    ax = fig.add_axes([0.07, 0.12, 0.55, 0.72])
    top = 0.0
    texts = []
    for name, (label, col) in CONFIG_STYLE.items():
        c = frag["configurations"].get(name) or {}
        ims = sorted(r["limit_im"] for r in c.get("records", []) if r.get("limit_im") is not None)
        n = len(c.get("records", []))
        if ims:
            ax.step([0.0] + ims, np.arange(len(ims) + 1) / max(n, 1), where="post", color=col, lw=1, alpha=0.7)
            top = max(top, ims[-1])
        if c.get("median"):
            x = np.linspace(1e-6, max(top, c["median"] * 3), 300)
            ax.plot(x, fragility_curve(c["median"], c["dispersion"], x), color=col, lw=2,
                    label=f"{label}: median {fmt(c['median'], 4)}, β {fmt(c['dispersion'], 3)}")
        texts.append([f"{label}: {c.get('n_reached', 0)} reached, {c.get('n_censored', 0)} never reached"]
                     + [f"record {r['record']} censored at {fmt(r['censored_at'], 4)}"
                        for r in c.get("never_reached", [])]
                     + [f"record {r['record']} undetermined: {str(r['why'])[:60]}" for r in c.get("undetermined", [])]
                     + ([c["note"]] if c.get("note") else [])
                     + ([f"Baker (2015) moments: median {fmt(c['baker2015']['median'], 4)}, β "
                         f"{fmt(c['baker2015']['dispersion'], 3)}"] if (c.get("baker2015") or {}).get("median") else []))
    ax.set(xlabel=f"IM [{index.get('measure', {}).get('unit', 'm/s^2')}]", ylabel="P(limit reached | IM)",
           ylim=(0, 1.02), xlim=(0, max(top, 1e-9) * 1.6))
    ax.axhline(0.5, color=GREY, lw=0.6)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="lower right")
    width = (0.97 - 0.65) * LANDSCAPE[0] * 72   # the side column, to the page's right margin
    lines = []
    for block in texts:   # the first line of a configuration flush, the rest indented under it
        lines += wrap_width(block[0], width, 7.5)
        lines += [w for ln in block[1:] for w in wrap_width("- " + ln, width, 7.5, indent="  ")]
        lines.append("")
    fig.text(0.65, 0.84, "\n".join(lines[:-1]), fontsize=7.5, va="top")
    return fig


def _step(settings) -> str:
    return ", ".join(f"{k} {v:g} s" for k, v in (settings or {}).items()) or "its defaults"


def cross_check_figure(index: dict, root: Path):
    """The table of the cross-checks and, for the supports alone, u(t) against the exact solution."""
    check = index.get("cross_check") or {}
    fig = new_figure(LANDSCAPE, "IDA cross-check: the record closest to the median",
                     "device: MuJoCo, Exudyn vs in-house; supports alone: exact linear oscillator (eqsig); "
                     "du = max|Δu| / max|u|")
    lines = []
    for name, (label, _) in CONFIG_STYLE.items():
        c = check.get(name)
        if not c:
            lines.append(f"{label}: not checked")
            continue
        if "engines" not in c:
            lines.append(f"{label}: {c.get('skipped') or c.get('error')}")
            continue
        lines.append(f"{label}: record {c['record']} at IM {fmt(c['level'], 4)} (scale {fmt(c['scale'], 4)}; limit "
                     f"at {fmt(c['limit_im'], 4)}, median {fmt(c['median'], 4)}) {c['note']}")
        for e, m in c["engines"].items():
            lines.append(f"    {e}: " + (f"du {m['du']:.3e}, peak |u| rel. difference {m['peak_displacement']:+.3e}"
                                         + (f", dF {m['dF']:.3e}, da {m['da']:.3e}" if "dF" in m else "")
                                         + (f", {m['wall_time']:.1f} s" if m.get("wall_time") else "")
                                         if "du" in m else f"{m.get('status')}: {m.get('error')}"))
            if isinstance(m.get("estimates"), dict):   # its own error estimate (h and h/2) and the gate's rule
                est = ", ".join(f"{k} {v['estimate']:.1e}" for k, v in m["estimates"].items())
                need = "".join(f" (not converged: needs {k} <= {v:.2g} s)" for k, v in (m.get("step_needed") or {}).items())
                lines.append(f"    {' ' * len(e)}  own estimate ({_step(m.get('settings'))}, and half): {est}; "
                             f"{m.get('verdict')}{need}")
            b = m.get("building")
            if isinstance(b, dict) and {"dfloor", "ddrift", "dfloor_a"} <= set(b):   # the worst floor / story
                lines.append(f"    {' ' * len(e)}  building: floors {b['dfloor']:.3e}, drifts {b['ddrift']:.3e}, "
                             f"floor accelerations {b['dfloor_a']:.3e}")
    lines += _more_and_cost(index, check)
    chars = int(0.92 * LANDSCAPE[0] * 72 / (0.62 * 7.5))   # monospace: 0.6 em a glyph, a little spare
    wrapped = [w for ln in lines for w in textwrap.wrap(ln, chars, subsequent_indent=" " * (len(ln) - len(ln.lstrip())
                                                                                         + 4)) or [""]]
    fig.text(0.04, min(0.86, fig._nsd_top - 0.01), "\n".join(wrapped), fontsize=7.5, va="top", family="monospace")
    folder = root / "cross_check" / "nodevice"
    ax = fig.add_axes([0.07, 0.1, 0.88, 0.4])
    checked = "engines" in (check.get("nodevice") or {})   # (a folder left by an earlier call is not this one's)
    if checked and (folder / "seismic.csv").is_file() and (folder / "exact.csv").is_file():
        run, exact = read_csv(folder / "seismic.csv"), read_csv(folder / "exact.csv")
        ax.plot(run["t"], (run["u"] - exact["u"]) * 1e3, color=CONFIG_STYLE["nodevice"][1], lw=0.8)
        ax.set(xlabel="t [s]", ylabel="|u| in-house - exact [mm]",
               title=f"supports alone, record {check['nodevice']['record']}: peak |u| "
                     f"{np.max(exact['u']) * 1e3:.4f} mm (exact)")
    else:
        no_data(ax, "no supports-alone cross-check series")
    return fig


def _more_and_cost(index: dict, check: dict) -> list[str]:
    """The other records' checks (--cross-check all), each engine's worst, and the cross-check's time
    against the IDA's."""
    lines = []
    for name, lst in (check.get("records") or {}).items():
        done = [c for c in lst if isinstance(c, dict) and isinstance(c.get("engines"), dict)]
        worst = {}
        for c in done:
            for e, m in c["engines"].items():
                if isinstance(m.get("du"), (int, float)) and m["du"] >= worst.get(e, (-1.0, None))[0]:
                    worst[e] = (m["du"], c.get("record"))
        if lst:
            lines.append(f"{CONFIG_STYLE.get(name, (name,))[0]}: {len(done)} more record(s) checked (all): "
                         + (", ".join(f"{e} worst du {d:.3e} (record {r})" for e, (d, r) in worst.items()) or "-"))
    if isinstance(index.get("elapsed_cross_check_s"), (int, float)):
        lines.append(f"time: IDA runs {index.get('elapsed_this_run_s', 0):.1f} s, cross-check "
                     f"({index.get('cross_check_mode')}) {index['elapsed_cross_check_s']:.1f} s (this call)")
    return lines


def ida_plan(folder) -> tuple[list[tuple[str, Callable]], str]:
    """(file stem, figure function) per page and the footer's title."""
    root = Path(folder)
    index, frag, rows = load_ida(root)
    plan = [("ida_curves", lambda: ida_curves_figure(index, rows)),
            ("fragility", lambda: fragility_figure(index, frag)),
            ("ida_cross_check", lambda: cross_check_figure(index, root))]
    dev = root / "cross_check" / "device"
    if "engines" in ((index.get("cross_check") or {}).get("device") or {}) and (dev / "seismic.csv").is_file() \
            and list(dev.glob("seismic_*.csv")):
        from reports.seismic_report import _run_pages, _runs
        c = (index.get("cross_check") or {}).get("device", {})
        plan += _run_pages(f"IDA cross-check {index.get('set')}:{c.get('record')} at IM {fmt(c.get('level', 0), 4)}",
                           _runs(dev))
    return plan, f"NSD IDA report  |  record set {index.get('set')}"


def _edp(index: dict) -> tuple[str, float, str, float | None]:
    """(row key, factor to the axis unit, axis label, the limit's value or None) of the response the
    IDA's limit state reads: the story drift ratio for drift=VALUE, else the plate's |u|."""
    opt = str(index.get("limit_option", ""))
    kind, _, value = opt.partition("=")
    try:
        limit = float(value) if kind in ("stroke", "drift") else None
    except ValueError:
        limit = None
    if kind == "drift":
        return "peak_drift_ratio", 100.0, "peak story drift ratio [%] (worst story)", limit
    return "peak_u", 1e3, "peak |u| [mm]", limit


def _im_text(index: dict) -> str:
    m = index.get("measure") or {}
    if m.get("measure") == "sa":
        return (f"Sa({m.get('period', 0):.3g} s, {m.get('damping', 0):.0%}), geometric mean, model time")
    return "PGA, geometric mean"
