"""benchmarks/bench_test_command.py and bench_model_first.py: their input checks, and how the first reads
pytest's summary line."""
from __future__ import annotations

from benchmarks.bench_test_command import SUMMARY, counts, main


def test_zero_repeats_is_one_line_exit_2_nothing_written(tmp_path, capsys):
    assert main(["--repeats", "0", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--repeats 0" in err[0] and ">= 1" in err[0]
    assert not (tmp_path / "o").exists()


def test_a_revision_that_is_not_a_commit_is_one_line_exit_2_nothing_written(tmp_path, capsys):
    assert main(["--revision", "no-such-rev", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no-such-rev" in err[0]
    assert not (tmp_path / "o").exists()


def test_the_summary_line_is_read_with_and_without_failures():
    out = ("....x..\n== warnings summary ==\n-- Docs: ...\n"
           "2429 passed, 5 skipped, 1 xfailed, 10 warnings in 424.53s (0:07:04)\n")
    (line, seconds), = SUMMARY.findall(out)
    assert seconds == "424.53" and counts(line) == {"passed": 2429, "skipped": 5, "xfailed": 1}
    (line, seconds), = SUMMARY.findall("FAILED tests/x.py::t\n==== 2 failed, 7 passed, 1 error in 4.20s ====\n")
    assert seconds == "4.20" and counts(line) == {"failed": 2, "passed": 7, "error": 1}


def test_an_unknown_description_is_one_line_exit_2_nothing_written(tmp_path, capsys):
    from benchmarks.bench_model_first import main as model_first
    assert model_first(["--models", "fourbar_spring,nosuch", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nosuch" in err[0] and "models/NAME.toml" in err[0]
    assert not (tmp_path / "o").exists()
