"""Faults: a parent killed with SIGKILL takes its workers with it and a re-run finishes with
the same bytes as an uninterrupted run; two runs into one --out never mix (the second exits 2 at
once naming the first's pid; a stale lock is taken over); a full disk is exit 1 with one line naming
the file, and what was kept stays valid. Real processes, real signals, a real full filesystem (a
small tmpfs, where this user may mount one) or a writer whose disk fills (fault injection)."""
import errno
import fcntl
import filecmp
import glob
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

from nsd_cli.main import main

pytestmark = pytest.mark.slow

SWEEP = ["sweep", "--param", "rod_length", "--values", "0.026,0.027,0.028,0.029,0.03,0.031", "--frequency", "1",
         "--cycles", "2", "--samples-per-cycle", "100", "--workers", "2"]
SET = ["seismic", "--record-set", "farfield", "--records", "1-3", "--window", "5,6.5", "--dt-out", "0.002", "--workers", "2"]


def nsd(*args, timeout=900, **kw):
    return subprocess.run([sys.executable, "-m", "nsd_cli.main", *args], capture_output=True, text=True,
                          timeout=timeout, **kw)


def start(args):
    return subprocess.Popen([sys.executable, "-m", "nsd_cli.main", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """Uninterrupted runs (which also warm numba's cache, so the kill lands in the work)."""
    d = tmp_path_factory.mktemp("reference")
    for name, args in (("sweep", SWEEP), ("set", SET)):
        r = nsd(*args, "--out", str(d / name))
        assert r.returncode in (0, 4), r.stdout + r.stderr
    return d


def wait_for(pattern, p, seconds=400):
    t0 = time.time()
    while not glob.glob(pattern):
        assert p.poll() is None, p.communicate()
        assert time.time() - t0 < seconds, f"nothing matched {pattern} in {seconds} s"
        time.sleep(0.05)


def kill_parent_and_check_workers_end(p):
    """SIGKILL the parent alone (no tidying possible); every worker must be gone within seconds."""
    children = psutil.Process(p.pid).children(recursive=True)
    assert children, "the run had no worker processes to leave behind"
    p.kill()
    p.communicate(timeout=30)
    deadline = time.time() + 10
    alive = children
    while alive and time.time() < deadline:
        alive = [c for c in alive if c.is_running() and c.status() != psutil.STATUS_ZOMBIE]
        time.sleep(0.1)
    assert not alive, f"workers left running after SIGKILL of their parent: {[c.pid for c in alive]}"
    return len(children)


def same_files(a: Path, b: Path, patterns):
    """Every file matching ``patterns`` under a and b: the same names and the same bytes."""
    names_a = sorted(str(p.relative_to(a)) for pat in patterns for p in a.glob(pat))
    names_b = sorted(str(p.relative_to(b)) for pat in patterns for p in b.glob(pat))
    assert names_a and names_a == names_b
    differ = [n for n in names_a if not filecmp.cmp(a / n, b / n, shallow=False)]
    assert not differ, f"differ after the resumed run: {differ[:5]}"
    return len(names_a)


def test_sigkill_of_a_sweep_leaves_no_worker_and_the_rerun_gives_the_same_bytes(reference, tmp_path):
    out = tmp_path / "sweep"
    p = start([*SWEEP, "--out", str(out)])
    wait_for(str(out / "designs" / "*" / "result.json"), p)
    kill_parent_and_check_workers_end(p)
    assert not (out / "sweep.json").exists()
    kept = len(glob.glob(str(out / "designs" / "*" / "result.json")))
    assert 1 <= kept < 6
    again = nsd(*SWEEP, "--out", str(out))
    assert again.returncode == 0, again.stdout + again.stderr
    assert f"{kept} already stored" in again.stderr
    assert "lock taken over" in again.stderr  # the killed run's lock was stale
    assert not (out / ".nsd.lock").exists()
    n = same_files(reference / "sweep", out, ["designs/*/cycle.csv", "designs/*/steady.csv", "rod_length/*.csv"])
    assert n == 6 * 2 + 6


def test_sigkill_of_a_record_set_leaves_no_worker_and_the_rerun_gives_the_same_bytes(reference, tmp_path):
    out = tmp_path / "set"
    p = start([*SET, "--out", str(out)])
    wait_for(str(out / "designs" / "*" / "result.json"), p)
    kill_parent_and_check_workers_end(p)
    assert not (out / "set.json").exists()
    again = nsd(*SET, "--out", str(out))
    assert again.returncode in (0, 4), again.stdout + again.stderr
    assert "already stored" in again.stderr
    same_files(reference / "set", out, ["set.csv", "set.json", "records/*/seismic.csv"])


def test_a_second_run_into_the_same_folder_exits_2_at_once_naming_the_first(tmp_path):
    cases_a, cases_b = tmp_path / "a.toml", tmp_path / "b.toml"
    case = '[[case]]\nname = "{n}"\namplitude = {a}\nfrequency = 1.0\ncycles = {c}\n'
    # long enough to still hold the folder when the second starts (~30 ms a cycle warm with warm workers)
    cases_a.write_text("".join(case.format(n=f"a{i}", a=0.01 + 0.001 * i, c=40) for i in range(10)))
    cases_b.write_text("".join(case.format(n=f"b{i}", a=0.012, c=1) for i in range(2)))
    out = tmp_path / "out"
    first = start(["compare", "--cases", str(cases_a), "--engines", "semirecursive", "--workers", "1",
                   "--out", str(out)])
    wait_for(str(out / ".nsd.lock"), first)
    t0 = time.perf_counter()
    second = nsd("compare", "--cases", str(cases_b), "--engines", "semirecursive", "--out", str(out), timeout=60)
    took = time.perf_counter() - t0
    assert second.returncode == 2, second.stderr
    lines = second.stderr.strip().splitlines()
    assert len(lines) == 1 and f"pid {first.pid}" in lines[0], second.stderr
    assert took < 20, took  # the imports, then at once
    o, e = first.communicate(timeout=600)
    assert first.returncode == 0, o + e
    results = json.loads((out / "results.json").read_text())
    assert [c["name"] for c in results["cases"]] == [f"a{i}" for i in range(10)]
    assert not glob.glob(str(out / "cycles" / "b*")) and not (out / ".nsd.lock").exists()


CYCLE = ["cycle", "--amplitude", "0.015", "--frequency", "10", "--cycles", "1", "--samples-per-cycle", "100"]


def test_a_held_lock_names_its_pid_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    lock = out / ".nsd.lock"
    lock.write_text("4242\nnsd sweep ...\n")
    with open(lock) as f:
        fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        code = main([*CYCLE, "--out", str(out)])
        err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "pid 4242" in err[0], err
    assert sorted(os.listdir(out)) == [".nsd.lock"] and lock.read_text().startswith("4242")


def test_a_stale_lock_is_taken_over(tmp_path, capsys, figures):
    out = tmp_path / "out"
    out.mkdir()
    (out / ".nsd.lock").write_text("999999\nnsd cycle ...\n")  # no process holds it
    assert main([*CYCLE, "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "pid 999999" in err and "taken over" in err
    assert sorted(os.listdir(out)) == ["01_cycle_loop.png", "cycle.csv", "summary.json"]


@pytest.fixture
def small_disk(tmp_path):
    """A 1 MiB tmpfs (needs the right to mount: root in a container that allows it), else skip."""
    d = tmp_path / "disk"
    d.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(d)], capture_output=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({r.stderr.decode().strip()}); test_disk_full_* covers the writer")
    yield d
    subprocess.run(["umount", "-l", str(d)], capture_output=True)


def test_a_full_disk_is_exit_1_one_line_and_kept_runs_stay_valid(small_disk):
    out = small_disk / "sweep"
    args = ["sweep", "--param", "rod_length", "--values", "0.03", "--frequency", "1", "--cycles", "1",
            "--samples-per-cycle", "100", "--workers", "1"]
    first = nsd(*args, "--out", str(out))
    assert first.returncode == 0, first.stderr
    kept = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    filler = small_disk / "filler"
    with open(filler, "wb", buffering=0) as f:  # fill the disk to the last block
        try:
            while True:
                f.write(b"\0" * 4096)
                f.flush()
        except OSError as e:
            assert e.errno == errno.ENOSPC
    full = nsd(*args[:4], "0.03,0.031,0.032", *args[5:], "--out", str(out))
    lines = full.stderr.strip().splitlines()
    assert full.returncode == 1, full.stderr
    assert "Traceback" not in full.stderr
    assert re.search(r"nsd: error: cannot write .*: No space left on device", lines[-1]), lines[-1]
    assert str(out) in lines[-1]
    assert not [p for p in out.rglob("*") if ".tmp" in p.name], "a half-written file was left"
    for p, data in kept.items():  # the run kept before is intact and still reads
        assert p.read_bytes() == data, p
    json.loads((out / "sweep.json").read_text())
    filler.unlink()
    again = nsd(*args[:4], "0.03,0.031,0.032", *args[5:], "--out", str(out))
    assert again.returncode == 0, again.stderr


def test_disk_full_while_writing_a_result_is_exit_1_naming_the_file(tmp_path, capsys, monkeypatch):
    """The writer's disk fills (fault injection at the OS boundary: the file object's write raises
    ENOSPC as the kernel would): exit 1, one line naming the file, no temporary file, the result
    already there unchanged."""
    from nsd_core.common import files
    out = tmp_path / "out"
    assert main([*CYCLE, "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    capsys.readouterr()
    real_fdopen = files.os.fdopen

    class FullDisk:
        def __init__(self, f):
            self.f = f

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.f.close()

        def write(self, text):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(files.os, "fdopen", lambda fd, mode: FullDisk(real_fdopen(fd, mode)))
    code = main([*CYCLE, "--amplitude", "0.02", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and len(err) == 1, err
    assert "cycle.csv" in err[0] and "No space left on device" in err[0], err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_a_non_finite_output_is_found_and_named():
    """nsd cycle, nsd seismic, nsd polar and each sweep design or record run refuse to keep an output
    holding NaN or inf (exit 3 for the command, a failed design or record in a set); this finder
    is what they call."""
    import numpy as np
    from nsd_core.device.results import RunResult, first_nonfinite
    from nsd_cli.options import check_finite
    from nsd_core.common.errors import SolverError
    run = RunResult("semirecursive", {"t": np.array([0.0, 1.0]), "F": np.array([1.0, np.nan])}, {"t": "s", "F": "N"})
    assert first_nonfinite({"cycle.csv": run}) == "cycle.csv.F[1] = nan (1 non-finite values)"
    assert first_nonfinite({"designs": {"4": {"k_min": [1.0, -np.inf]}}}) == "designs.4.k_min[1] = -inf"
    assert first_nonfinite({"a": [1.0, 2], "b": "nan", "c": None, "d": np.arange(3.0)}) is None
    with pytest.raises(SolverError, match="polar: a non-finite output, designs.4.k_min"):
        check_finite({"designs": {"4": {"k_min": [float("nan")]}}}, "polar")
