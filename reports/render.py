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
draws everything. An error in the child comes back pickled through a pipe and is raised here as it
was raised there (its type, message, errno, file name), so a bad field or a full disk reads the same
whichever process drew the page; when this process fails first, the child is stopped before their
temporary files are removed. The PNGs are the same bytes either way; the PDF's pages draw the same, its bytes
differ (two embedded font subsets instead of one, pypdf's writer).
"""
from __future__ import annotations

import contextlib
import os
import pickle
import signal
import threading
from pathlib import Path

from nsd_core.compilation.first_compile import usable_cores

MIN_PAGES = 6   # below this the fork and the merge cost more than the second process saves


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
    child_pdf, child_tag = out / f".{tmp_pdf.name}.child", f"{tag}.child"
    mine, theirs = pages[0::2], pages[1::2]   # pages 1, 3, 5, ... here; 2, 4, ... in the child
    said, tell = os.pipe()   # the child's error, pickled: raised here as it was raised there
    pid = os.fork()
    if pid == 0:   # the child: its pages, then out at once (no cleanup of the parent's state, no flush)
        os.close(said)
        code = 0
        try:
            _draw_pages(theirs, n, footer, title, child_pdf, pdf_name, child_tag, naming)
        except BaseException as e:   # noqa: BLE001 (said to the parent, which raises it)
            code = 1
            try:
                data = pickle.dumps(e)
            except Exception:   # noqa: BLE001 (an exception that does not pickle: its text)
                data = pickle.dumps(RuntimeError(f"{type(e).__name__}: {e} (in the report's second process)"))
            with contextlib.suppress(OSError):
                while data:
                    data = data[os.write(tell, data):]
        os._exit(code)
    os.close(tell)
    written, theirs_written = [], [(out / f".{png.name}.{child_tag}.tmp.png", png) for _, _, png in theirs]
    try:
        written = _draw_pages(mine, n, footer, title, tmp_pdf, pdf_name, tag, naming)
        data = b"".join(iter(lambda: os.read(said, 65536), b""))   # until the child ends
        _, status = os.waitpid(pid, 0)
        pid = 0
        if status != 0:
            raise (pickle.loads(data) if data else
                   RuntimeError(f"the report's second process ended with status {status}"))
        with naming(pdf_name):
            _merge(tmp_pdf, child_pdf, n)
        return [written[k // 2] if k % 2 == 0 else theirs_written[k // 2] for k in range(n)]
    except BaseException:
        if pid:   # this process failed first: the child is stopped before its files are removed
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            pid = 0
        for tmp, _ in written + theirs_written:
            if tmp.exists():
                tmp.unlink()
        raise
    finally:
        os.close(said)
        for f in (child_pdf, tmp_pdf.with_name(tmp_pdf.name + ".merged")):
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
