"""A first run's compilation shared with one helper process (nsd_core.compilation.first_compile): only on
a cold cache, never in a helper, a pool's worker or ``nsd warm``; the helper names the cache's
sub-folders as its parent does and is gone when the command ends."""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from nsd_core.compilation import first_compile
from nsd_core.engine.compile_once import UNITS

from tests.test_warm_all import NOTICE_START, _nsd

KEY = ("drive", "DOP853", "auto", "line")


@pytest.fixture
def folder(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv(first_compile.HELPER, raising=False)
    monkeypatch.setattr(first_compile, "_enabled", [True])
    monkeypatch.setattr(first_compile, "usable_cores", lambda: 2)
    return tmp_path


def test_a_helper_only_where_the_kind_is_not_ready(folder, monkeypatch):
    assert first_compile.worth_a_helper(KEY)
    first_compile.mark_ready(KEY)
    assert not first_compile.worth_a_helper(KEY)
    assert first_compile.worth_a_helper(("seismic",) + KEY[1:])   # another kind is not ready
    (folder / first_compile.EVERY_MODE_MARKS[1]).touch()   # nsd warm compiled every in-house mode
    assert not first_compile.worth_a_helper(("seismic",) + KEY[1:])


@pytest.mark.parametrize("why", ["helper", "disabled", "one core"])
def test_never_from_a_helper_a_pool_worker_or_one_core(folder, monkeypatch, why):
    if why == "helper":
        monkeypatch.setenv(first_compile.HELPER, "1")
    elif why == "disabled":
        first_compile.disable()
    else:
        monkeypatch.setattr(first_compile, "usable_cores", lambda: 1)
    assert not first_compile.worth_a_helper(KEY)


def test_the_items_are_the_kinds_units_its_callbacks_then_its_tiny_run():
    for mode in ("drive", "seismic"):
        names = [lock for lock, _ in first_compile.items((mode,) + KEY[1:], lambda: None)]
        assert names[-1] == f"warm-kind-{mode}" and f"first-callbacks-{mode}" in names
        units = [n.removeprefix("warm-unit-") for n in names if n.startswith("warm-unit-")]
        assert "step_loop" in units and ("seismic_outputs" in units) == (mode == "seismic")
        import nsd_core.structure.compiled_seismic  # noqa: F401 (registers the seismic outputs' unit)
        assert all(u in UNITS for u in units), units


@pytest.mark.slow
def test_a_cold_first_cycle_shares_its_compilation_and_leaves_nothing_behind(tmp_path):
    first = _nsd(["cycle", "--amplitude", "0.01", "--frequency", "10", "--out", str(tmp_path / "c")], tmp_path)
    assert first.returncode == 0, first.stderr[-2000:]
    assert len([ln for ln in first.stderr.splitlines() if ln.startswith(NOTICE_START)]) == 1, first.stderr
    folders = list((tmp_path / "nsd-harness" / "numba").iterdir())
    assert len(folders) == 1
    sub = {p.name for p in folders[0].iterdir() if p.is_dir()}
    # the helper's kernels in the package-named sub-folders, where the command loads them (before the
    # child processes' naming was fixed they also went to numba's ones, named after the hash of the
    # source folder's absolute path, "engine_<40 hex>", never found); a generated evaluation (under
    # NSD_EVALUATOR=generated, which a study command asks for while it runs) lives outside
    # the packages and keeps numba's naming ("generated_<hash>")
    package_dirs = {d.name for pkg in ("nsd_core", "comparisons")
                    for d in (Path(__file__).resolve().parents[1] / pkg).rglob("*") if d.is_dir()}
    hashed = {n for n in sub if re.fullmatch(r"(.+)_[0-9a-f]{40}", n) and n[:-41] in package_dirs}
    assert {"nsd_core_device", "nsd_core_engine"} <= sub and not hashed, sub
    assert (folders[0] / first_compile._mark(KEY)).exists()
    assert _helpers_of(tmp_path) == [], "a helper of this command outlived it"
    again = _nsd(["cycle", "--amplitude", "0.01", "--frequency", "10", "--out", str(tmp_path / "d")], tmp_path)
    assert again.returncode == 0 and NOTICE_START not in again.stderr, again.stderr


def _helpers_of(cache: Path) -> list:
    """The helper processes still alive whose cache is ``cache`` (the command's XDG_CACHE_HOME, which its
    helper inherits): another test's helper running beside this one (pytest-xdist) is not this command's."""
    found = subprocess.run(["pgrep", "-f", "first_compile_helper"], capture_output=True, text=True)
    mine = f"XDG_CACHE_HOME={cache}".encode()
    out = []
    for pid in found.stdout.split():
        try:
            environ = Path(f"/proc/{pid}/environ").read_bytes().split(b"\0")
        except OSError:   # gone meanwhile
            continue
        if mine in environ:
            out.append(int(pid))
    return out


def test_the_usable_cores_follow_the_affinity():
    import os
    if hasattr(os, "sched_getaffinity"):
        assert first_compile.usable_cores() == len(os.sched_getaffinity(0))
    assert first_compile.usable_cores() >= 1
