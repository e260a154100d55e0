"""NSD_FIGURES: whether a study command draws its PNGs into its folder (nsd_cli.options)."""
from __future__ import annotations

import pytest

from nsd_cli.main import main
from nsd_cli.options import figures_wanted
from nsd_core.common.errors import ParameterError

CYCLE = ["cycle", "--amplitude", "0.015", "--frequency", "10", "--cycles", "1", "--samples", "200"]


def test_unset_empty_or_1_draws_and_0_does_not():
    assert figures_wanted({}) and figures_wanted({"NSD_FIGURES": " "}) and figures_wanted({"NSD_FIGURES": "1"})
    assert not figures_wanted({"NSD_FIGURES": "0"})


@pytest.mark.parametrize("value", ["2", "yes", "no", "-1", "0.5"])
def test_a_bad_value_is_exit_2_one_line_naming_the_variable_and_nothing_written(value, tmp_path, monkeypatch,
                                                                                capsys):
    with pytest.raises(ParameterError, match=f"NSD_FIGURES = {value!r}: must be 1"):
        figures_wanted({"NSD_FIGURES": value})
    monkeypatch.setenv("NSD_FIGURES", value)
    out = tmp_path / "out"
    assert main(CYCLE + ["--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"NSD_FIGURES = {value!r}" in err[0], err
    assert not out.exists()


def test_0_writes_the_numbers_and_no_png_and_says_so(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("NSD_FIGURES", "0")
    bare, drawn = tmp_path / "bare", tmp_path / "drawn"
    assert main(CYCLE + ["--out", str(bare)]) == 0
    assert "figures: none drawn (NSD_FIGURES=0; nsd report --from" in capsys.readouterr().out
    monkeypatch.setenv("NSD_FIGURES", "1")
    assert main(CYCLE + ["--out", str(drawn)]) == 0
    assert sorted(p.name for p in bare.iterdir()) == ["cycle.csv", "summary.json"]
    assert sorted(p.name for p in drawn.iterdir()) == ["01_cycle_loop.png", "cycle.csv", "summary.json"]
    assert (bare / "cycle.csv").read_bytes() == (drawn / "cycle.csv").read_bytes()
