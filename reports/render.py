"""Drawing a report's pages: one PDF of them all and one PNG per page, on two processes where a
second core is free.

Every page is drawn twice (the PDF's vector backend, then Agg for the PNG), and text-heavy pages
(the metric tables: ~400 text objects each) cost ~0.5 s of CPU: the default gate's 39 pages took
~19 s on one core, the largest part of ``nsd compare --report`` after the runs. With a second usable
core this process forks one child that draws every second page into a PDF of its own and their
PNGs, while this process draws the others; the two PDFs are then merged page by page (pypdf), so
the pages keep their order and their footers ("page n of N"). A fork, not a new interpreter: the
child has the plan (closures over the data already read and checked) without reading it again.
Only when this process runs no other thread (a fork copies the calling thread alone: a lock another
thread held would stay held in the child); otherwise, on one core, or for a short report, one process
draws everything. The PNGs are the same bytes either way; the PDF's pages draw the same, its bytes
differ (two embedded font subsets instead of one, pypdf's writer).
"""
from __future__ import annotations

import os
import threading
from pathlib import Path

from nsd_core.device.params import ParameterError

# the errors build_report turns into "malformed data" (one line, exit 2), re-raised here as their type
# when the child meets one, so that a bad field reads the same whichever process drew its page
PASSED_ON = {e.__name__: e for e in (TypeError, KeyError, IndexError, AttributeError, ValueError, ParameterError)}
MIN_PAGES = 6   # below this the fork and the merge cost more than the second process saves


def usable_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:   # not Linux
        return os.cpu_count() or 1


def processes_for(n_pages: int, processes: int | None = None) -> int:
    """1 or 2: two when asked (``processes``) or, unasked, when a second core is usable, the report is
    long enough and a fork is safe (this process runs one thread and the platform forks)."""
    if not hasattr(os, "fork") or threading.active_count() > 1:
        return 1
    if processes is not None:
        return 2 if processes >= 2 else 1
    return 2 if usable_cores() >= 2 and n_pages >= MIN_PAGES else 1


def draw(plan, footer: str, title: str, out: Path, tmp_pdf: Path, pdf_name: Path, naming,
         processes: int | None = None) -> list:
    """Draw every page of ``plan`` ([(stem, make)], make() -> figure) into ``tmp_pdf`` and one PNG each
    under a temporary name in ``out``; returns [(temporary PNG, its final path)] in page order (the
    caller moves them into place; on an error nothing of this call's is left but ``tmp_pdf``, which
    the caller removes). ``naming(path)``: the context that names ``path`` (``pdf_name`` for the PDF)
    in an OSError."""
    n = len(plan)
    pages = [(k, make, out / f"{k:02d}_{stem}.png") for k, (stem, make) in enumerate(plan, start=1)]
    tag = str(os.getpid())
    if processes_for(n, processes) == 1:
        return _draw_pages(pages, n, footer, title, tmp_pdf, pdf_name, tag, naming)
    child_pdf, error_file = out / f".{tmp_pdf.name}.child", out / f".report-error.{tag}.child"
    child_tag = f"{tag}.child"
    mine, theirs = pages[0::2], pages[1::2]   # pages 1, 3, 5, ... here; 2, 4, ... in the child
    pid = os.fork()
    if pid == 0:   # the child: its pages, then out at once (no cleanup of the parent's state, no flush)
        code = 0
        try:
            _draw_pages(theirs, n, footer, title, child_pdf, pdf_name, child_tag, naming)
        except BaseException as e:   # noqa: BLE001 (said to the parent, which raises it)
            code = 1
            try:
                said = e.args[0] if len(e.args) == 1 and isinstance(e.args[0], str) else str(e)   # KeyError's unquoted
                error_file.write_text(f"{type(e).__name__}\n{said}")
            except OSError:
                pass
        os._exit(code)
    written, theirs_written = [], [(out / f".{png.name}.{child_tag}.tmp.png", png) for _, _, png in theirs]
    try:
        written = _draw_pages(mine, n, footer, title, tmp_pdf, pdf_name, tag, naming)
        _, status = os.waitpid(pid, 0)
        pid = 0
        if status != 0:
            said = error_file.read_text() if error_file.exists() else f"RuntimeError\nits status {status}"
            name, _, message = said.partition("\n")
            raise PASSED_ON.get(name, RuntimeError)(f"{message} (in the report's second process)"
                                                    if name not in PASSED_ON else message)
        with naming(pdf_name):
            _merge(tmp_pdf, child_pdf, n)
        return [written[k // 2] if k % 2 == 0 else theirs_written[k // 2] for k in range(n)]
    except BaseException:
        for tmp, _ in written + theirs_written:
            if tmp.exists():
                tmp.unlink()
        raise
    finally:
        if pid:   # this process failed first: the child is waited for, its files removed
            os.waitpid(pid, 0)
        for f in (child_pdf, error_file, tmp_pdf.with_name(tmp_pdf.name + ".merged")):
            if f.exists():
                f.unlink()


def _draw_pages(pages, n: int, footer: str, title: str, pdf_path: Path, pdf_name: Path, tag: str, naming) -> list:
    """The pages [(number, make, png)] into ``pdf_path`` and their PNGs under temporary names (removed
    again if a page fails)."""
    import matplotlib.pyplot as plt
    from matplotlib.backends.backend_pdf import PdfPages

    from reports import style
    written = []
    try:
        with plt.rc_context(style.RC), naming(pdf_name), PdfPages(pdf_path, metadata={"Title": title}) as pdf:
            for k, make, png in pages:
                fig = make()
                try:
                    style.footer(fig, f"{footer}  |  page {k} of {n}")
                    pdf.savefig(fig)
                    tmp = png.parent / f".{png.name}.{tag}.tmp.png"
                    with naming(png):
                        fig.savefig(tmp)
                    written.append((tmp, png))
                finally:
                    plt.close(fig)
    except BaseException:
        for tmp, _ in written:
            if tmp.exists():
                tmp.unlink()
        raise
    return written


def _merge(dest: Path, child_pdf: Path, n: int) -> None:
    """``dest``'s pages (1, 3, 5, ...) and ``child_pdf``'s (2, 4, ...) in page order, written over
    ``dest`` (its metadata kept)."""
    from pypdf import PdfReader, PdfWriter
    mine, theirs = PdfReader(dest), PdfReader(child_pdf)
    writer = PdfWriter()
    for k in range(n):
        writer.add_page((mine if k % 2 == 0 else theirs).pages[k // 2])
    writer.add_metadata({k: v for k, v in (mine.metadata or {}).items()})
    merged = dest.with_name(dest.name + ".merged")
    with open(merged, "wb") as f:
        writer.write(f)
    os.replace(merged, dest)
