"""nsd cycle draws its force-displacement loop (DIR/01_cycle_loop.png), and nsd report --from a cycle
folder writes it as a PDF and PNG; the page's texts stay inside it and apart (tests/page_checks.py)."""
from __future__ import annotations

import pytest

from tests.page_checks import figure_problems


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    from nsd_cli.main import main
    root = tmp_path_factory.mktemp("cycles")
    line, circle = root / "line", root / "circle"
    with pytest.MonkeyPatch.context() as mp:   # the loop's PNG drawn (tests/conftest.py: NSD_FIGURES)
        mp.setenv("NSD_FIGURES", "1")
        assert main(["cycle", "--amplitude", "0.0255", "--frequency", "10", "--out", str(line)]) == 0
        assert main(["cycle", "--path", "circle", "--amplitude", "0.015", "--frequency", "10", "--out", str(circle)]) == 0
    return line, circle


def test_nsd_cycle_draws_its_loop(folders):
    for folder in folders:
        png = folder / "01_cycle_loop.png"
        assert png.is_file() and png.stat().st_size > 20_000, folder


def test_report_from_a_cycle_folder(folders, tmp_path, capsys):
    from nsd_cli.main import main
    for folder in folders:
        out = tmp_path / folder.name
        assert main(["report", "--from", str(folder), "--out", str(out)]) == 0
        assert (out / "validation.pdf").stat().st_size > 10_000 and (out / "01_cycle_loop.png").is_file()
    from pypdf import PdfReader
    text = PdfReader(str(tmp_path / "line" / "validation.pdf")).pages[0].extract_text()
    assert "Force-displacement loop" in text and "X_max = 25.4" in text and "stiffness regions" in text


def test_cycle_pages_keep_their_texts_inside_and_apart(folders):
    for folder in folders:
        assert figure_problems(folder) == {}, folder


def test_a_damaged_cycle_folder_is_one_line_exit_2(folders, tmp_path, capsys):
    import shutil
    from nsd_cli.main import main
    bad = tmp_path / "bad"
    shutil.copytree(folders[0], bad)
    (bad / "cycle.csv").write_text("t [s],u [m]\n0,0\n")
    out = tmp_path / "report"
    assert main(["report", "--from", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "cycle.csv" in err and "no column" in err, err
    assert not out.exists()
