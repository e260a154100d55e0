"""Report layout a reader would see wrong (tests/page_checks.py measures the drawn figure): the IDA
pages' side and cross-check texts inside the page (a margin wide enough for the PDF's glyphs), the
IDA curves' records in colours told apart, a record set's floors page without empty difference
panels when one engine ran, and numbers at a stated precision (no 17-digit values) on every page."""
from __future__ import annotations

import re

import matplotlib.pyplot as plt
import pytest
from matplotlib.colors import to_rgb

from reports import style
from tests.page_checks import _drawn_texts, figure_problems, text_problems

class LONG_DIGITS:  # noqa: N801 - a pattern-like check: a number with more than 8 significant digits
    NUMBER = re.compile(r"\d+(?:\.\d+)?")

    @classmethod
    def search(cls, text: str) -> bool:
        return any(len(m.group(0).replace(".", "").lstrip("0")) > 8 for m in cls.NUMBER.finditer(text))


def wide_problems(fig, margin: float = 0.25) -> list[str]:
    """tests/page_checks.text_problems, and texts closer than ``margin`` inches to the page's left or
    right edge (the PDF's glyphs run wider than Agg's: a text flush with the edge is clipped there)."""
    page, m = fig.bbox, margin * fig.dpi
    return text_problems(fig) + [f"at the side edge: {t.get_text()[:60]!r}" for t, b in _drawn_texts(fig)
                                 if b.x0 < page.x0 + m or b.x1 > page.x1 - m]


def _texts(fig) -> list[str]:
    import matplotlib.text
    return [t.get_text() for t in fig.findobj(matplotlib.text.Text) if t.get_text().strip()]


def _pages(folder):
    from reports.build import source_plan
    plan, _ = source_plan(folder)
    with plt.rc_context(style.RC):
        for stem, make in plan:
            fig = make()
            yield stem, fig
            plt.close(fig)


def test_records_are_told_apart():
    """Records 1 and 2 (before: tab20's two blues) and every pair of the first ten in hues far apart;
    no two of 40 records share colour and line style."""
    styles = [style.distinct(j) for j in range(40)]
    assert len({(s["color"], s["linestyle"]) for s in styles}) == 40
    rgb = [to_rgb(s["color"]) for s in styles[:10]]
    for i in range(10):
        for j in range(i + 1, 10):
            assert sum((a - b) ** 2 for a, b in zip(rgb[i], rgb[j])) ** 0.5 > 0.25, (i, j)


@pytest.fixture(scope="module")
def ida_folder(tmp_path_factory):
    from nsd_cli.main import main
    out = tmp_path_factory.mktemp("ida") / "ida"
    assert main(["ida", "--record-set", "nearfield-pulse", "--records", "9,10", "--levels", "0.3,0.6", "--limit",
                 "stroke=0.02", "--engines", "semirecursive", "--workers", "2", "--out", str(out)]) == 0
    return out


@pytest.mark.slow
def test_ida_pages_inside_the_page_with_a_margin(ida_folder):
    """The fragility's side text was wrapped at the page's edge (clipped in the PDF): every text now
    keeps 0.25 in from the edges, and none is left to matplotlib's wrap."""
    for stem, fig in _pages(ida_folder):
        assert not wide_problems(fig), (stem, wide_problems(fig))
        assert not [t for t in fig.findobj(lambda a: hasattr(a, "get_wrap")) if t.get_wrap()], stem
        assert not [t for t in _texts(fig) if LONG_DIGITS.search(t)], stem


@pytest.mark.slow
def test_ida_cross_check_long_lines_wrap_inside_the_page(ida_folder):
    """A cross-check note as long as the bracket's ('at the bracket's lower end ...') stays on the page."""
    import json
    from pathlib import Path

    from reports.ida_pages import cross_check_figure
    index = json.loads((Path(ida_folder) / "ida.json").read_text())
    c = index["cross_check"]["nodevice"]
    c["note"] = ("at the bracket's lower end (the highest level below the limit, where every engine runs the whole "
                 "record): the limit intensity's run was stopped by the rod's length") * 2
    c["scale"] = 0.31622776601683794
    with plt.rc_context(style.RC):
        fig = cross_check_figure(index, Path(ida_folder))
        assert not wide_problems(fig), wide_problems(fig)
        assert not [t for t in _texts(fig) if LONG_DIGITS.search(t)]
        assert any("0.3162" in t for t in _texts(fig))


@pytest.fixture(scope="module")
def set_folder(tmp_path_factory):
    """A three-story building's record-set folder, for its pages. Run with the generic evaluation
    (NSD_EVALUATOR=generic, bit for bit the generated one's numbers: tests/test_codegen.py): a study
    compiles the generated one otherwise, about 30 s more CPU on a cold cache for this structure, which
    test_codegen already compiles in the slow mark (its "building" variant) and these pages do not need."""
    from nsd_cli.main import main
    out = tmp_path_factory.mktemp("set") / "set"
    mp = pytest.MonkeyPatch()
    mp.setenv("NSD_EVALUATOR", "generic")
    try:
        assert main(["seismic", "--record-set", "farfield", "--records", "1", "--window", "3,3.3",
                     "--dt-out", "0.002", "--building", "stories=3", "--workers", "1", "--out", str(out)]) == 0
    finally:
        mp.undo()
    return out


def test_floors_page_of_one_engine_has_no_empty_difference_panels(set_folder):
    floors = [(stem, fig) for stem, fig in _pages(set_folder) if stem.startswith("floors_")]
    assert floors
    for stem, fig in floors:
        axes = fig.get_axes()
        assert len(axes) == 9, (stem, len(axes))              # 3 stories x (floor, drift, acceleration)
        assert all(ax.lines for ax in axes), stem              # every panel holds a curve
        assert not any("difference" in ax.get_ylabel() for ax in axes)


def test_record_set_pages_inside_apart_and_at_a_stated_precision(set_folder):
    assert figure_problems(set_folder) == {}
    for stem, fig in _pages(set_folder):
        assert not [t for t in _texts(fig) if LONG_DIGITS.search(t)], stem


def test_nsd_params_table_prints_values_to_a_stated_precision(capsys):
    """The isolated mass was printed as 3743.7968184920674 kg: the table says its precision (5
    significant digits) and where every digit is (the TOML file)."""
    from nsd_cli.main import main
    assert main(["params"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("values to 5 significant digits; every digit: --format toml")
    assert re.search(r"\nmass +3743\.8 +kg", text)
    assert not LONG_DIGITS.search(text)


def test_compare_supports_prints_its_ratios_to_a_stated_precision(tmp_path, capsys):
    """The ratios were printed as 1.0115888970293518: now 4 significant digits, ratios.csv every digit."""
    from nsd_cli.main import main
    out = tmp_path / "cs"
    assert main(["seismic", "--record", "nearfield-pulse:1", "--window", "4.8,5.0", "--compare-supports",
                 "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    lines = [ln for ln in printed.splitlines() if "supports alone" in ln and "ratio" in ln]
    assert len(lines) >= 4 and not [ln for ln in lines if LONG_DIGITS.search(ln)], lines
    assert LONG_DIGITS.search((out / "ratios.csv").read_text())   # the file keeps every digit
