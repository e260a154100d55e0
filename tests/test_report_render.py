"""The report's pages drawn on two processes (reports.render): the same PNGs byte for byte and the
same pages in the same order as on one, and a failure on either process reported as on one, with
nothing left behind."""
from __future__ import annotations

import os
import subprocess
import sys
import threading

import pytest

pytest.importorskip("matplotlib")

# a pytest-xdist worker runs a second thread (its channel), where a fork is unsafe and the report is
# drawn on one process: there these tests run in one single-threaded pytest process of their own
IN_WORKER = "PYTEST_XDIST_WORKER" in os.environ
forking = pytest.mark.skipif(IN_WORKER, reason="run by test_forking_tests_in_a_single_threaded_process")


@pytest.mark.skipif(not IN_WORKER, reason="the tests below run here directly")
def test_forking_tests_in_a_single_threaded_process():
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_XDIST")}   # not a worker there
    p = subprocess.run([sys.executable, "-m", "pytest", "-q", "-n", "0", "-p", "no:cacheprovider", __file__],
                       capture_output=True, text=True, timeout=600, cwd=os.path.dirname(os.path.dirname(__file__)),
                       env=env)
    assert p.returncode == 0 and " passed" in p.stdout, p.stdout[-3000:] + p.stderr[-2000:]


def _plan(n, bad=None, error=KeyError):
    import matplotlib.pyplot as plt

    def make(k):
        def draw():
            if k == bad:
                raise error(f"field of page {k}")
            fig = plt.figure(figsize=(4, 3))
            fig.text(0.1, 0.5, f"page body {k}")
            return fig
        return draw
    return [(f"p{k}", make(k)) for k in range(1, n + 1)]


def _build(monkeypatch, tmp_path, plan, processes, name):
    import reports.build as build
    from reports.render import processes_for
    assert processes_for(len(plan), processes) == processes   # two really fork (no other thread runs here)
    monkeypatch.setattr(build, "checked_plan", lambda d: (plan, "Render test  |  a footer"))
    return build.build_report(tmp_path, tmp_path / name, processes=processes)


@forking
def test_two_processes_draw_the_same_report(monkeypatch, tmp_path):
    from pypdf import PdfReader
    plan = _plan(7)
    one = _build(monkeypatch, tmp_path, plan, 1, "one")
    two = _build(monkeypatch, tmp_path, plan, 2, "two")
    assert [os.path.basename(p) for p in one["pngs"]] == [os.path.basename(p) for p in two["pngs"]]
    for a, b in zip(one["pngs"], two["pngs"]):
        assert open(a, "rb").read() == open(b, "rb").read()
    ra, rb = PdfReader(one["pdf"]), PdfReader(two["pdf"])
    assert len(rb.pages) == 7
    texts = [p.extract_text() for p in rb.pages]
    assert texts == [p.extract_text() for p in ra.pages]
    for k, text in enumerate(texts, start=1):
        assert f"page body {k}" in text and f"page {k} of 7" in text
    assert rb.metadata["/Title"] == "Render test"
    assert sorted(os.listdir(tmp_path / "two")) == sorted(os.path.basename(p) for p in two["pngs"] + [two["pdf"]])


@forking
@pytest.mark.parametrize("bad", [3, 4])   # page 3 is drawn here, page 4 by the child
def test_a_failing_page_is_said_as_on_one_process_and_nothing_is_left(monkeypatch, tmp_path, bad):
    from nsd_core.device.params import ParameterError
    real_fork, children = os.fork, []

    def fork():
        pid = real_fork()
        if pid:
            children.append(pid)
        return pid
    monkeypatch.setattr(os, "fork", fork)
    with pytest.raises(ParameterError, match=rf"malformed data \(KeyError: 'field of page {bad}'\); nothing written"):
        _build(monkeypatch, tmp_path, _plan(8, bad), 2, "out")
    assert os.listdir(tmp_path / "out") == []
    assert len(children) == 1
    with pytest.raises(ChildProcessError):   # the child was waited for (no zombie left)
        os.waitpid(children[0], os.WNOHANG)


@forking
def test_an_error_of_another_kind_in_the_child_is_raised_as_on_one_process(monkeypatch, tmp_path):
    def full(message):   # a full disk while page 2 (the child's) is drawn
        return OSError(28, "No space left on device")
    said = {}
    for processes in (1, 2):
        with pytest.raises(OSError) as err:
            _build(monkeypatch, tmp_path, _plan(6, 2, error=full), processes, f"out{processes}")
        said[processes] = (type(err.value), err.value.errno, err.value.strerror, os.path.basename(err.value.filename))
        assert os.listdir(tmp_path / f"out{processes}") == []
    assert said[2] == said[1] == (OSError, 28, "No space left on device", "validation.pdf")


@forking
def test_one_process_where_a_fork_is_unsafe_or_the_report_short():
    from reports.render import MIN_PAGES, processes_for
    assert processes_for(MIN_PAGES - 1) == 1 and processes_for(3, processes=2) == 2
    assert processes_for(40, processes=1) == 1
    stop = threading.Event()
    t = threading.Thread(target=stop.wait)
    t.start()
    try:   # another thread running: a fork would copy only this one
        assert processes_for(40, processes=2) == 1
    finally:
        stop.set()
        t.join()
