"""The validation report of a described mechanism (``nsd compare --model ... --report``): a PDF and a
PNG per page. Page 1: what PASS means, the verdict of every case and engine in words, the tolerances.
Then, per case, A4 pages of at most ``PER_PAGE`` outputs: every output of every engine over time (the
converged reference dashed) and each engine's difference from the converged reference."""
from __future__ import annotations

import textwrap
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.backends.backend_pdf import PdfPages  # noqa: E402
import numpy as np  # noqa: E402


COLORS = {"semirecursive": "C0", "mujoco": "C1", "exudyn": "C2", "symbolic": "C4", "converged": "k"}
PER_PAGE = 6   # outputs on one A4 page (a building's 17 take three pages, not one page 4 m tall)


def build_model_report(model, summary: dict, folder: Path) -> dict:
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    outs = list(model.outputs)
    chunks = [outs[k:k + PER_PAGE] for k in range(0, len(outs), PER_PAGE)]
    pages = [_summary_page(model, summary)] + [_case_page(summary, c, chunk, f" ({j + 1}/{len(chunks)})"
                                                          if len(chunks) > 1 else "")
                                                for c in summary["cases"] for j, chunk in enumerate(chunks)]
    tmp = folder / ".model_report.pdf.tmp"
    with PdfPages(tmp) as pdf:
        for fig in pages:
            pdf.savefig(fig)
    tmp.replace(folder / "model_report.pdf")
    pngs = []
    for k, fig in enumerate(pages, 1):
        png = folder / f".page{k}.png.tmp"
        fig.savefig(png, dpi=110, format="png")
        png.replace(folder / f"model_page{k}.png")
        pngs.append(folder / f"model_page{k}.png")
        plt.close(fig)
    return {"pdf": folder / "model_report.pdf", "png": pngs}


def _summary_page(model, summary: dict):
    fig = plt.figure(figsize=(8.27, 11.69))
    verdict = "PASS" if summary["passed"] else "FAIL"
    lines = [f"Cross-validation of {model.name}: {verdict}", "",
             f"model file: {summary['model_file']}", f"source: {model.source}", ""]
    lines += textwrap.wrap(summary["rule"]["text"], 95) + [""]
    for name, c in summary["cases"].items():
        ref = c.get("reference")
        lines += textwrap.wrap(f"case {name}: {c['duration']:g} s, outputs every {c['dt_out']:g} s"
                               + (f"; reference solution: {ref['source']}" if ref else "; no reference solution"),
                               95, subsequent_indent="      ")
        for e, v in c["verdicts"].items():
            lines += textwrap.wrap(f"  {e}: {'PASS' if v['pass'] else 'FAIL'} - {v.get('text', '')}", 95,
                                   subsequent_indent="      ")
        lines.append("")
    lines.append("engineering tolerances (a fraction of each output's scale):")
    for o in model.outputs:
        lines.append(f"  {o.name} [{o.unit}]: {o.tolerance:g}" + (f" of {o.scale:g} {o.unit}" if o.scale else
                                                                   " of the reference's peak |value|"))
    lines.append("  closure and tracking (each engine's own check): 1e-06 m or rad")
    fig.text(0.06, 0.96, "\n".join(lines[:90]), va="top", family="monospace", fontsize=7.5)
    return fig


def _case_page(summary: dict, case: str, outs: list, part: str):
    runs = summary["runs"].get(case, {})
    n = len(outs)
    fig, axes = plt.subplots(n, 2, figsize=(8.27, 11.69 if n == PER_PAGE else max(3.0, 1.9 * n)), squeeze=False)
    conv = runs.get("converged")
    for k, o in enumerate(outs):
        ax, dx = axes[k]
        for label, r in runs.items():
            if label.endswith(("_2h", "_h2", "_tight")) or label == "converged_check":
                continue
            style = "--" if label == "converged" else "-"
            ax.plot(r.t, r.outputs[o.name], style, color=COLORS.get(label, "C3"), lw=1, label=label)
            if conv is not None and label != "converged":
                d = np.abs(r.outputs[o.name] - conv.outputs[o.name])
                dx.semilogy(r.t, np.maximum(d, 1e-17), color=COLORS.get(label, "C3"), lw=1, label=label)
        ax.set_ylabel(f"{o.name} [{o.unit}]", fontsize=7)
        dx.set_ylabel(f"|diff| [{o.unit}]", fontsize=7)
        for a in (ax, dx):
            a.tick_params(labelsize=6)
        if k == 0:
            ax.legend(fontsize=6)
            ax.set_title(f"{case}: outputs{part}", fontsize=8)
            dx.set_title("difference from the converged reference", fontsize=8)
    for a in axes[-1]:
        a.set_xlabel("t [s]", fontsize=7)
    fig.tight_layout()
    return fig
