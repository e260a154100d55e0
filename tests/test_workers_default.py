"""A command's local workers when --workers is not given: NSD_WORKERS, else the usable cores
(nsd_core.engine.workers.default_workers, nsd_cli.options.resolved_workers)."""
from __future__ import annotations

import pytest

from nsd_cli.main import build_parser, main
from nsd_core.common.errors import ParameterError
from nsd_core.engine.workers import default_workers, usable_cores


def test_unset_or_empty_is_the_usable_cores_and_a_number_is_taken():
    assert default_workers({}) == usable_cores() == default_workers({"NSD_WORKERS": " "})
    assert default_workers({"NSD_WORKERS": "3"}) == 3
    assert default_workers({"NSD_WORKERS": "256"}) == 256


@pytest.mark.parametrize("value", ["0", "-1", "1.5", "two", "257"])
def test_a_bad_value_is_one_line_naming_the_variable(value):
    with pytest.raises(ParameterError) as e:
        default_workers({"NSD_WORKERS": value})
    text = str(e.value)
    assert text.startswith(f"NSD_WORKERS = {value!r}: must be a whole number in [1, 256]") and "\n" not in text


@pytest.mark.parametrize("argv", [
    ["compare", "--cases", "tests/data/short_cases.toml"],
    ["seismic", "--record-set", "nearfield-pulse", "--records", "1", "--window", "2,2.5"],
    ["sweep", "--param", "rod_length", "--values", "0.03,0.031", "--cycles", "1"],
    ["polar", "--wires", "3", "--step", "90"],
])
def test_a_bad_nsd_workers_is_exit_2_one_line_and_nothing_written(argv, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("NSD_WORKERS", "many")
    out = tmp_path / "out"
    assert main(argv + ["--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "NSD_WORKERS = 'many'" in err[0], err
    assert not out.exists()


def test_a_record_sets_workers_are_the_ones_asked_for(monkeypatch):
    """`--workers 1` on a record set was read as all cores (an operator-precedence slip); NSD_WORKERS too."""
    from nsd_cli.seismic_set import _set_request
    parser = build_parser()
    base = ["seismic", "--record-set", "farfield", "--records", "1-2", "--out", "x"]
    assert _set_request(parser.parse_args(base + ["--workers", "1"]))[3] == 1
    assert _set_request(parser.parse_args(base + ["--workers", "3"]))[3] == 3
    monkeypatch.setenv("NSD_WORKERS", "2")
    assert _set_request(parser.parse_args(base))[3] == 2
    monkeypatch.delenv("NSD_WORKERS")
    assert _set_request(parser.parse_args(base))[3] == usable_cores()
