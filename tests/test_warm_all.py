"""Every mode compiled once per version by ``nsd warm`` (nsd_core.compilation.warm_all): one line on a cold
cache, then no compilation by any command of that version (a drive cycle, a seismic run, a building).
A command's first run does not compile every mode by itself (measured slower: docs/performance.md)."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from nsd_core.compilation import warm_all
from nsd_core.engine import compile_once

NOTICE_START = "nsd: compiling"


def _nsd(args, cache, timeout=1800):
    """``nsd ARGS`` from a copy of the packages (an edit to the working tree meanwhile would change the
    source's fingerprint, hence the cache folder, between two commands of the test)."""
    import shutil
    src = cache / "src"
    if not src.exists():
        root = Path(__file__).resolve().parents[1]
        for pkg in ("nsd_core", "comparisons", "nsd_cli"):
            shutil.copytree(root / pkg, src / pkg, ignore=shutil.ignore_patterns("__pycache__"))
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR",)}
    env.update(XDG_CACHE_HOME=str(cache), MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "nsd_cli.main", *args], cwd=src, env=env, capture_output=True,
                          text=True, timeout=timeout)


def test_the_items_cover_every_mode_and_both_peers(monkeypatch):
    # the engine's units follow NSD_EVALUATOR (a user may have set it): the default, unset, is what
    # nsd warm meets
    monkeypatch.delenv("NSD_EVALUATOR", raising=False)
    names = {lock for lock, _ in warm_all.items(peers=True)}
    assert {"warm-all-drive", "warm-all-seismic", "warm-unit-evaluate", "warm-unit-step_loop"} <= names
    assert {"warm-all-call-mujoco", "warm-all-call-exudyn"} <= names
    assert not any(n.startswith("warm-all-call") for n, _ in warm_all.items(peers=False))   # in-house alone


def test_nothing_to_do_in_a_helper_or_once_done(monkeypatch):
    monkeypatch.setattr(warm_all, "_STATE", {})
    monkeypatch.setenv(warm_all.HELPER, "1")   # a helper process shares the items out; it never starts helpers
    assert warm_all.ensure_all() == 0.0
    monkeypatch.delenv(warm_all.HELPER)
    monkeypatch.setattr(warm_all, "_STATE", {False: True})   # done once in this process
    assert warm_all.ensure_all() == 0.0


@pytest.mark.parametrize("cores, helpers", [(1, 0), (2, 1), (4, 3)])
def test_nsd_warm_starts_one_helper_per_further_core_this_process_may_use(monkeypatch, tmp_path, cores, helpers):
    """The helpers follow the process's affinity (`taskset -c 0` on a 2-core machine: none), not the
    machine's core count; the notice says how many processes share the work."""
    import io
    started = []
    monkeypatch.setattr(warm_all.first_compile, "usable_cores", lambda: cores)
    monkeypatch.setattr(warm_all.os, "cpu_count", lambda: 64)   # what the machine has is not what is used
    monkeypatch.setattr(warm_all.subprocess, "Popen", lambda *a, **k: started.append(a) or _Done())
    monkeypatch.setattr(warm_all.co, "share_work", lambda items: None)
    monkeypatch.setattr(warm_all.co, "quiet_notices", lambda: None)   # process-wide switches, kept as they are
    monkeypatch.setattr(warm_all.first_compile, "disable", lambda: None)
    monkeypatch.setattr(warm_all, "cache_dir", lambda: str(tmp_path))
    stream = io.StringIO()
    warm_all._warm_here(False, stream)
    assert len(started) == helpers
    assert f"{helpers + 1} process" in stream.getvalue(), stream.getvalue()


class _Done:
    def wait(self):
        return 0


def test_a_run_does_not_compile_every_mode_by_itself():
    """The in-house runs' and the pool workers' warm-ups compile what they use, not every mode: the
    automatic every-mode compilation made the first drive cycle slower (27.9 -> 38.7 s wall, measured)."""
    import inspect
    from nsd_core.compilation import warmup, worker_warmup
    for module in (warmup, worker_warmup):
        assert "ensure_all" not in inspect.getsource(module) and "warm_all" not in vars(module), module


@pytest.mark.slow
def test_nsd_warm_one_line_on_a_cold_cache_then_no_command_compiles(tmp_path):
    warm = _nsd(["warm"], tmp_path)
    assert warm.returncode == 0 and warm.stdout.startswith("every mode compiled"), warm.stdout + warm.stderr
    lines = [ln for ln in warm.stderr.splitlines() if ln.startswith(NOTICE_START)]
    assert len(lines) == 1 and lines[0].startswith(warm_all.NOTICE.split("{")[0]) and " done in " in lines[0], lines
    first = _nsd(["cycle", "--amplitude", "0.01", "--frequency", "10", "--out", str(tmp_path / "c")], tmp_path)
    assert first.returncode == 0, first.stderr[-2000:]
    assert NOTICE_START not in first.stderr, first.stderr
    building = _nsd(["seismic", "--ground", "harmonic:amplitude=1,frequency=2,duration=0.05", "--building",
                     "stories=3", "--out", str(tmp_path / "b")], tmp_path)
    assert building.returncode == 0, building.stderr[-2000:]
    assert NOTICE_START not in building.stderr, building.stderr
    again = _nsd(["warm"], tmp_path)
    assert again.returncode == 0 and "already compiled" in again.stdout and NOTICE_START not in again.stderr


@pytest.mark.slow
def test_without_nsd_warm_a_first_cycle_compiles_what_it_uses(tmp_path):
    """No every-mode compilation at a command's first run: the engine's own line, and no mark."""
    first = _nsd(["cycle", "--amplitude", "0.01", "--frequency", "10", "--out", str(tmp_path / "c")], tmp_path)
    assert first.returncode == 0, first.stderr[-2000:]
    lines = [ln for ln in first.stderr.splitlines() if ln.startswith(NOTICE_START)]
    assert lines == [compile_once.NOTICE.format(seconds=compile_once.NOTICE_SECONDS)], lines
    assert not list(tmp_path.rglob(warm_all.MARK_IN_HOUSE)) and not list(tmp_path.rglob(warm_all.MARK))


def test_nsd_warm_compiles_the_peer_modules_every_model_law_mechanism_shares():
    """``nsd warm``'s peer calls end with a tiny described pendulum on Exudyn and on MuJoCo; their generated
    forces and callback are the modules of the model layer's laws, which a user's mechanism of those laws
    (the worked example, Andrews' constant torque) shares: the same law set, the same generated text."""
    import tomllib
    from comparisons import warmup
    from comparisons.builders import exudyn_codegen, generated, mujoco_codegen
    from nsd_core.model.load import load_model, parse_model
    calls = warmup.every_mode_calls()
    for engine in ("exudyn", "mujoco"):
        assert any(getattr(c, "func", None) is warmup.tiny_described_run and c.args == (engine,) for c in calls)
    warmup.tiny_described_run("mujoco")   # the described builder takes the settings it is given
    assert mujoco_codegen.source(mujoco_codegen.laws_of(parse_model(tomllib.loads(warmup.TINY_MECHANISM))))[0] == \
        mujoco_codegen.source(mujoco_codegen.laws_of(load_model(Path(__file__).resolve().parents[1] / "models" / "andrews.toml")))[0]
    tiny = generated.law_set(parse_model(tomllib.loads(warmup.TINY_MECHANISM)).forces)
    root = Path(__file__).resolve().parents[1] / "models"
    for name in ("fourbar_spring.toml", "andrews.toml"):
        assert generated.law_set(load_model(root / name).forces) == tiny, name
    assert exudyn_codegen.source(tiny)[0] == exudyn_codegen.source(
        generated.law_set(load_model(root / "andrews.toml").forces))[0]
