"""Build the validation report from an ``nsd compare`` results folder.

``build_report(results_dir, out_dir)`` reads ``results.json`` and the cycle CSVs (and, when present,
``benchmark/results.json``, ``work_precision/work_precision.json`` of benchmarks/work_precision.py
and a parametric study under ``study/``), checks everything first, and
only then writes ``out_dir/validation.pdf`` and one PNG per page. Every file is rendered under a
temporary name and moved into place with ``os.replace``: a reader never sees half a report, and bad
input (raised as ParameterError, one line) leaves nothing behind.
"""
from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from nsd_core.common.files import input_stream, printable, read_regular_text
from nsd_core.device.params import ParameterError
from nsd_core.device.results import RunResult, read_csv
from nsd_core.common.files import check_output_target

from reports import render
from reports import style  # noqa: F401  (selects the Agg backend before pyplot is imported anywhere)

REQUIRED = {"verdict": str, "exit_code": int, "failures": list, "engines": list, "cases": list, "runs": dict,
            "metrics": list, "tolerances": dict}


@dataclass
class ReportData:
    root: Path
    summary: dict[str, Any]
    results: dict[tuple[str, str], RunResult] = field(default_factory=dict)
    benchmark: dict | None = None
    study: list[dict] = field(default_factory=list)
    tables: list[dict] = field(default_factory=list)  # rows of nsd tables' tables.csv, if present
    power: dict | None = None  # power.json of nsd compare --power, if present
    work_precision: dict | None = None  # benchmarks/work_precision.py's JSON, if present
    polar: dict | None = None  # nsd polar's polar.json under DIR/polar, if present

    @property
    def cases(self) -> list[dict]:
        return self.summary["cases"]

    @property
    def engines(self) -> list[str]:
        return self.summary["engines"]

    @property
    def reference(self) -> str:
        return self.summary.get("reference") or (self.engines[0] if self.engines else "")

    def run(self, case: str, engine: str) -> dict:
        return self.summary["runs"].get(case, {}).get(engine, {"status": "missing", "message": "not run"})


def _json(path: Path, what: str) -> Any:
    if not os.path.lexists(path):
        raise ParameterError(f"--from {printable(path.parent)}: no {path.name} ({what})")
    try:
        return json.loads(read_regular_text(path, str(path)))
    except json.JSONDecodeError as e:
        raise ParameterError(f"{printable(path)}: not readable JSON ({' '.join(str(e).split())})") from None
    except ValueError as e:  # InputError: not a regular file, not text, not readable
        raise ParameterError(str(e)) from None
    except OSError as e:
        raise ParameterError(f"{printable(path)}: not readable JSON ({' '.join(str(e).split())})") from None


def load(results_dir: str | Path) -> ReportData:
    """Read and check a results folder; ParameterError (one line) if it is missing or malformed."""
    root = Path(results_dir)
    if not str(results_dir).strip():
        raise ParameterError("--from '': name the --out folder of nsd compare")
    if not root.is_dir():
        raise ParameterError(f"--from {root}: no such folder (give the --out folder of nsd compare)")
    summary = _json(root / "results.json", "written by nsd compare --out")
    if not isinstance(summary, dict):
        raise ParameterError(f"{root / 'results.json'}: malformed (expected a JSON object)")
    if "verdict" not in summary and {"model_file", "rows"} <= set(summary):
        raise ParameterError(f"--from {root}: an nsd compare --model folder, whose report the compare draws: "
                             f"nsd compare --model {printable(str(summary['model_file']))} --report "
                             f"(report/model_report.pdf); nothing written")
    for key, typ in REQUIRED.items():
        if key not in summary:
            raise ParameterError(f"{root / 'results.json'}: malformed (no {key!r}); is it an nsd compare result?")
        if not isinstance(summary[key], typ) or isinstance(summary[key], bool):
            raise ParameterError(f"{root / 'results.json'}: malformed ({key!r} should be {typ.__name__})")
    names = []
    for i, c in enumerate(summary["cases"]):
        if not isinstance(c, dict) or not {"name", "amplitude", "frequency"} <= set(c):
            raise ParameterError(f"{root / 'results.json'}: malformed (cases[{i}] needs name, amplitude, frequency)")
        names.append(c["name"])
    data = ReportData(root, summary)
    for case in names:
        per = summary["runs"].get(case, {})
        if not isinstance(per, dict):
            raise ParameterError(f"{root / 'results.json'}: malformed (runs[{case!r}] should be an object)")
        for engine, run in per.items():
            if not isinstance(run, dict) or "status" not in run:
                raise ParameterError(f"{root / 'results.json'}: malformed (runs[{case!r}][{engine!r}])")
            if run["status"] != "ok":
                continue
            csv = root / str(run.get("csv", ""))
            if run.get("csv") and root.resolve() not in csv.resolve().parents:
                raise ParameterError(f"{root / 'results.json'}: malformed (cycle file {run['csv']!r} lies outside --from)")
            if not run.get("csv") or not csv.is_file():
                raise ParameterError(f"--from {root}: cycle file {run.get('csv')!r} of {case}/{engine} is missing")
            try:
                data.results[(case, engine)] = read_csv(csv, engine)
            except (OSError, ValueError, IndexError) as e:
                raise ParameterError(f"{csv}: not a readable cycle CSV ({' '.join(str(e).split())[:120]})") from None
            for col in ("t", "u", "F", "closure"):
                if col not in data.results[(case, engine)].columns:
                    raise ParameterError(f"{csv}: malformed (no column {col!r})")
    seismic_ok = any(isinstance(r, dict) and r.get("status") == "ok" for c in summary.get("seismic_cases") or []
                     if isinstance(c, dict) for r in (summary["runs"].get(c.get("name")) or {}).values())
    if not data.results and not seismic_ok:
        raise ParameterError(f"--from {root}: no engine run succeeded there; there is nothing to report "
                             "(see the errors in results.json)")
    bench = root / "benchmark" / "results.json"
    if bench.is_file():
        b = _json(bench, "written by nsd benchmark")
        data.benchmark = b if isinstance(b, dict) and isinstance(b.get("problems"), dict) else None
    power = root / "power.json"
    if power.is_file():
        pw = _json(power, "written by nsd compare --power")
        data.power = pw if isinstance(pw, dict) and isinstance(pw.get("table"), list) else None
    from reports.figures_wp import load_work_precision
    data.work_precision = load_work_precision(root / "work_precision" / "work_precision.json")
    data.study = _load_study(root / "study")
    data.tables = _load_tables(root / "study" / "tables.csv")
    polar = root / "polar" / "polar.json"
    if polar.is_file():
        p = _json(polar, "written by nsd polar")
        data.polar = p if isinstance(p, dict) and isinstance(p.get("designs"), dict) else None
    return data


def _load_tables(path: Path) -> list[dict]:
    """Rows of ``nsd tables --out DIR/study`` (Tables 5 and 6 next to the model); [] if absent."""
    if not path.is_file():
        return []
    try:
        rows = list(csv.DictReader(input_stream(path, "tables.csv", 1 << 32)))
        return [{"table": r["table"], "parameter": r["parameter"], "value": float(r["value"]),
                 "unit": r["unit"], "paper": float(r["paper_x_max [m]"]), "model": float(r["model_x_max [m]"]),
                 "diff_mm": float(r["difference [mm]"])} for r in rows]
    except (OSError, KeyError, ValueError):
        return []


def _load_study(folder: Path) -> list[dict]:
    """Per study of a parametric sweep (nsd_core.study): its summary and the steady cycles it names.
    A study folder that cannot be read is skipped (it is an optional extra, not the validation)."""
    index = folder / "sweep.json"
    if not index.is_file():
        return []
    try:
        studies = json.loads(read_regular_text(index)).get("studies", {})
        out = []
        for name, rel in studies.items():
            s = json.loads(read_regular_text(folder / rel))
            curves = []
            for d in s.get("designs", []):
                if d.get("status") == "ok" and d.get("steady_csv") and (folder / d["steady_csv"]).is_file():
                    path = folder / d["steady_csv"]
                    text = read_regular_text(path, "steady CSV")
                    names = [h.split(" [")[0] for h in text.split("\n", 1)[0].strip().split(",")]
                    with warnings.catch_warnings():   # an empty file is said in one line (malformed), not warned
                        warnings.simplefilter("ignore")   # blanks (nan) allowed
                        arr = np.genfromtxt(io.StringIO(text), delimiter=",", skip_header=1, ndmin=2)
                    cols = {n: arr[:, i] for i, n in enumerate(names)}
                    curves.append({"value": d["value"], "engine": d.get("engine", "semirecursive"), "u": cols["u"],
                                   "F": cols["F"], "design": d})
            out.append({"name": name, "summary": s, "curves": curves})
        return out
    except (OSError, ValueError, KeyError, AttributeError, TypeError):
        return []


def pages(data: ReportData) -> list[tuple[str, Callable]]:
    """(file stem, figure function) per page, in order. Each function returns one Figure."""
    from reports import figures, figures_extra, figures_wp, pages as text_pages
    out: list[tuple[str, Callable]] = []
    def numbered(stem: str, fns) -> None:
        out.extend((f"{stem}{'' if i == 0 else f'_{i + 1}'}", fn) for i, fn in enumerate(fns))
    out.append(("summary", lambda: text_pages.page_one(data)))
    numbered("what_was_run", text_pages.run_pages(data))
    numbered("metric_definitions", text_pages.definitions_pages(data))
    numbered("metric_table", text_pages.metric_table_pages(data))
    numbered("parameters", text_pages.parameter_pages(data))
    for i, group in enumerate(figures.case_groups(data)):
        tag = "" if i == 0 else f"_{i + 1}"
        out.append((f"cycles{tag}", lambda g=group: figures.cycles_figure(data, g)))
        if not group.get("planar"):   # stiffness regions and X_max are quantities of a line drive
            out.append((f"stiffness{tag}", lambda g=group: figures.stiffness_figure(data, g)))
    line = [c["name"] for c in data.cases if figures.is_line(c)]
    for i, chunk in enumerate(figures.chunks(line, 2) if line else []):
        out.append((f"breakdown{'' if i == 0 else f'_{i + 1}'}", lambda c=chunk: figures.breakdown_figure(data, c)))
    if data.power:
        from .power_page import power_figure
        out.append(("power", lambda: power_figure(data)))
    out.append(("convergence", lambda: figures_extra.convergence_figure(data)))
    out.append(("cost", lambda: figures_extra.cost_figure(data)))
    for i, chunk in enumerate(figures.chunks([c["name"] for c in data.cases], 4) if data.cases else []):
        out.append((f"closure{'' if i == 0 else f'_{i + 1}'}", lambda c=chunk: figures.closure_figure(data, c)))
    if data.benchmark:
        out.append(("benchmark", lambda: figures_extra.benchmark_figure(data)))
    if data.work_precision:
        out.append(("work_precision", lambda: figures_wp.work_precision_figure(data)))
    if data.tables:
        out.append(("tables", lambda: figures_extra.tables_figure(data)))
    for s in data.study:
        out.append((f"study_{s['name']}", lambda s=s: figures_extra.study_figure(data, s)))
    if data.polar:
        from reports.polar import polar_figure
        out.append(("polar", lambda: polar_figure(data.polar)))
    if (data.root / "seismic").is_dir():
        from reports.seismic_report import compare_seismic_pages
        out.extend(compare_seismic_pages(data.root))
    return out


def _study_plan(root: Path) -> tuple[list[tuple[str, Callable]], str]:
    """An nsd sweep (sweep.json), polar (polar.json) or cycle (cycle.csv) folder: its own pages."""
    from types import SimpleNamespace
    from nsd_core.device.params import Params
    from reports import figures_extra
    from reports.cycle_pages import cycle_plan, is_cycle
    if is_cycle(root) and not (root / "sweep.json").is_file():
        return cycle_plan(root)
    if (root / "polar.json").is_file():
        from reports.polar import polar_figure
        p = _json(root / "polar.json", "written by nsd polar")
        if not isinstance(p, dict) or not isinstance(p.get("designs"), dict):
            raise ParameterError(f"{root / 'polar.json'}: malformed (no 'designs')")
        return [("polar", lambda: polar_figure(p))], "NSD direction study (nsd polar)"
    studies = _load_study(root)
    if not studies:
        raise ParameterError(f"{root / 'sweep.json'}: malformed or without a finished study")
    stub = SimpleNamespace(summary={"params": Params().describe()})
    return ([(f"study_{st['name']}", lambda st=st: figures_extra.study_figure(stub, st)) for st in studies],
            "NSD parametric study (nsd sweep)")


def source_kind(results_dir: str | Path) -> str:
    """compare (results.json), ida (ida.json), seismic (nsd seismic, single or --set), sweep (sweep.json),
    polar (polar.json), cycle (nsd cycle: cycle.csv and summary.json)."""
    from reports.seismic_report import is_seismic
    from reports.ida_pages import is_ida
    root = Path(results_dir)
    if not str(results_dir).strip() or (root / "results.json").is_file():
        return "compare"
    if is_ida(root):
        return "ida"
    if is_seismic(root):
        return "seismic"
    if (root / "polar.json").is_file():
        return "polar"
    if (root / "sweep.json").is_file():
        return "sweep"
    from reports.cycle_pages import is_cycle
    if is_cycle(root):
        return "cycle"
    return "compare"  # load() says what is missing


def source_plan(results_dir: str | Path) -> tuple[list[tuple[str, Callable]], str]:
    """(file stem, figure function) per page and the footer of any results folder; everything is read
    and checked here, before anything is written (ParameterError, one line)."""
    from reports.seismic_report import seismic_plan
    kind = source_kind(results_dir)
    if kind == "ida":
        from reports.ida_pages import ida_plan
        plan, title = ida_plan(results_dir)
        return plan, f"{title}  |  {time.strftime('%Y-%m-%d')}"
    if kind == "seismic":
        plan, title = seismic_plan(results_dir)
        return plan, f"{title}  |  {time.strftime('%Y-%m-%d')}"
    if kind in ("sweep", "polar", "cycle"):
        plan, title = _study_plan(Path(results_dir))
        return plan, f"{title}  |  {time.strftime('%Y-%m-%d')}"
    data = load(results_dir)
    title = "NSD cross-validation report"
    return pages(data), f"{title}  |  {data.summary.get('date', '')}  |  revision {data.summary.get('git_revision', '?')}"


def checked_plan(results_dir: str | Path) -> tuple[list[tuple[str, Callable]], str]:
    """``source_plan``, a damaged field met while planning (a string where a number belongs...) made
    one line, exit 2: --from read and checked before anything is written."""
    try:
        return source_plan(results_dir)
    except (TypeError, KeyError, IndexError, AttributeError) as e:
        raise _malformed(results_dir, e) from None
    except ValueError as e:
        if type(e) is not ValueError:  # ParameterError is a ValueError: already one line
            raise
        raise _malformed(results_dir, e) from None


def draw_pngs(folder: str | Path) -> list[str]:
    """The study's own figures, one PNG per page, into its own folder (nsd sweep, nsd seismic): the
    pages ``nsd report --from FOLDER`` would draw. Returns the paths written."""
    import matplotlib.pyplot as plt
    try:
        plan, footer = source_plan(folder)
    except ParameterError:   # nothing finished to draw (every design failed): the numbers say why
        return []
    out = Path(folder)
    written = []
    with plt.rc_context(style.RC):
        for n, (stem, make) in enumerate(plan, start=1):
            fig = make()
            style.footer(fig, f"{footer}  |  figure {n} of {len(plan)}")
            png = out / f"{n:02d}_{stem}.png"
            tmp = out / f".{png.name}.{os.getpid()}.tmp.png"
            try:
                check_output_target(png)
                with naming(png):
                    fig.savefig(tmp)
                    os.replace(tmp, png)
            finally:
                plt.close(fig)
                if tmp.exists():
                    tmp.unlink()
            written.append(str(png))
    return written


@contextlib.contextmanager
def naming(path):
    """An OSError inside (a full disk while a figure is written) names ``path``, the file the user
    gets, not a temporary name or none at all (matplotlib's writers raise it without a name)."""
    try:
        yield
    except OSError as e:
        if e.errno is None:
            raise
        raise OSError(e.errno, e.strerror or str(e), str(path)) from None


def draw_study(folder, log=print) -> list[str]:
    """``draw_pngs`` for a study command: says where its figures went."""
    pngs = draw_pngs(folder)
    log(f"figures: {len(pngs)} PNG(s) in {folder}" if pngs else "figures: none (nothing finished to draw)")
    return pngs


def _malformed(results_dir, e: Exception) -> ParameterError:
    """A damaged field met while drawing (a string where a number belongs...): one line, exit 2."""
    return ParameterError(f"--from {printable(results_dir)}: malformed data ({type(e).__name__}: "
                          f"{printable(' '.join(str(e).split()))[:160]}); nothing written")


def build_report(results_dir: str | Path, out_dir: str | Path, processes: int | None = None,
                 planned: tuple[list[tuple[str, Callable]], str] | None = None) -> dict[str, Any]:
    """Write ``out_dir/validation.pdf`` and ``out_dir/NN_page.png``; returns their paths. ``processes``:
    1 or 2 processes draw the pages (reports.render; None: two where a second core is free).
    ``planned``: what ``checked_plan(results_dir)`` returned, when the caller has already read the
    folder (it is not read again)."""
    import matplotlib.pyplot as plt
    start = time.perf_counter()
    plan, footer = planned or checked_plan(results_dir)  # everything is checked before anything is written
    title = footer.split("  |  ")[0]
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    pdf_path = out / "validation.pdf"
    tmp_pdf = out / f".validation.pdf.{os.getpid()}.tmp"
    written: list[tuple[Path, Path]] = []
    for target in [pdf_path] + [out / f"{n:02d}_{stem}.png" for n, (stem, _) in enumerate(plan, start=1)]:
        check_output_target(target)   # a FIFO or a device where a page goes: refused before drawing
    try:
        written = render.draw(plan, footer, title, out, tmp_pdf, pdf_path, naming, processes)
        for tmp, png in written:
            with naming(png):
                os.replace(tmp, png)
        with naming(pdf_path):
            os.replace(tmp_pdf, pdf_path)
        keep = {png.name for _, png in written}
        for old in out.glob("[0-9][0-9]_*.png"):  # pages of an earlier report that this one no longer has
            if old.name not in keep:
                old.unlink()
    except BaseException as e:
        plt.close("all")
        for tmp in [tmp_pdf] + [t for t, _ in written]:
            if tmp.exists():
                tmp.unlink()
        if isinstance(e, (TypeError, KeyError, IndexError, AttributeError)) or type(e) is ValueError:
            raise _malformed(results_dir, e) from None
        raise
    return {"pdf": str(pdf_path), "pngs": [str(p) for _, p in written], "pages": [s for s, _ in plan],
            "seconds": time.perf_counter() - start}
