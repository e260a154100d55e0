"""Results kept on disk (nsd_core/compilation/result_cache.py) and the restoring-force check that uses it."""
from __future__ import annotations

import json
import os

import numpy as np
import pytest

from nsd_core.compilation import result_cache


def test_a_kept_result_is_the_computed_one_and_a_damaged_file_is_computed_again(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    calls = []

    def compute():
        calls.append(1)
        return {"F": np.float64(0.1) + np.float64(0.2), "pass": np.bool_(False), "path": (1.0, 2.0), "D": 1 / 3}

    first = result_cache.cached_json("k", {"D": 0.02}, compute)
    assert first == {"F": 0.30000000000000004, "pass": False, "path": [1.0, 2.0], "D": 1 / 3}
    assert result_cache.cached_json("k", {"D": 0.02}, compute) == first and len(calls) == 1
    result_cache.cached_json("k", {"D": 0.03}, compute)        # other inputs: computed
    assert len(calls) == 2
    path = result_cache.result_file("k", {"D": 0.02})
    path.write_text("{not json")
    assert result_cache.cached_json("k", {"D": 0.02}, compute) == first and len(calls) == 3
    assert json.loads(path.read_text()) == first
    assert not list(path.parent.glob("*.tmp"))


def test_a_failed_computation_keeps_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))

    def fail():
        raise ArithmeticError("cannot follow the path")

    with pytest.raises(ArithmeticError):
        result_cache.cached_json("k", 1, fail)
    assert not result_cache.result_file("k", 1).exists()


def test_a_bad_out_is_refused_before_the_restoring_force_check_runs(tmp_path, monkeypatch, capsys):
    """nsd seismic checks --out before it computes the check (seconds of quasi-static paths): a bad --out
    leaves no kept check behind; a good run keeps one, and a second run reads it to the same summary.
    In this process (the compiled code and records as loaded; a fresh folder for the kept results)."""
    from nsd_cli.main import main
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    kept = tmp_path / "cache" / "nsd-harness" / "results" / "restoring_force"
    (tmp_path / "file").write_text("x")
    args = ["seismic", "--record", "nearfield-pulse:2", "--window", "2,2.3", "--dt-out", "0.002"]
    assert main(args + ["--out", str(tmp_path / "file" / "out")]) == 2
    assert "--out" in capsys.readouterr().err and not kept.exists()
    summaries = []
    for name in ("a", "b"):
        assert main(args + ["--out", str(tmp_path / name)]) == 0, capsys.readouterr().err
        summaries.append(json.loads((tmp_path / name / "summary.json").read_text())["restoring_force"])
        assert len(list(kept.iterdir())) == 1
    assert summaries[0] == summaries[1]


def test_a_fifo_where_a_kept_file_goes_is_never_opened(tmp_path, monkeypatch):
    from nsd_core.ground import record_cache
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    for path in (record_cache.cache_file("nearfield_pulse"), result_cache.result_file("k", 1)):
        path.parent.mkdir(parents=True)
        os.mkfifo(path)
    assert record_cache.read("nearfield_pulse") is None                   # would block on open()
    assert result_cache.cached_json("k", 1, lambda: {"a": 1}) == {"a": 1}
